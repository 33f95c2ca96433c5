"""Error-controlled macro step of the co-simulation master (issue 13 item 2): ``Master(adaptive=True)``,
``frb cosim --adaptive [--coupling-tol X]``.

Expected values come from fixed-step runs of the same master (the 10 µs run and, for its own error, a 5 µs run:
step halving) and from replaying the accepted steps without any rollback.
"""
import json

import numpy as np
import pytest

import frbmodel as frb

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from frbmodel.cli import main  # noqa: E402
from frbmodel.core.errors import ParameterError  # noqa: E402
from frbmodel.cosim.master import ADAPTIVE_MAX_STEP_S, Master, cosimulate, operating_point_overrides  # noqa: E402

START, END, RAMP_S = 20e3, 250e3, 1.0  # the main job's ramp [rpm, rpm, s]
CLEARANCE = 36e-6  # [m], c_o of co36: the scale of the orbit comparisons


def _positions(run):
    """Journal and ring x, y of both bearings [m], one column each."""
    return np.column_stack([a[b] for a in (run.journal, run.ring) for b in ("turbine", "compressor")])


@pytest.fixture(scope="module")
def main_job_start():
    tc = frb.turbocharger(36e-6)
    return operating_point_overrides(tc, START, end_rpm=END, ramp_time=RAMP_S, perturbation=0.05)


def test_adaptive_agrees_with_the_fixed_step_and_takes_fewer_steps(built, main_job_start):
    """The main job's first 10 ms (the decaying start transient, 20 -> 22.3 krpm) with the default tolerance, against
    the fixed 10 µs run, sampled at the same times."""
    kw = dict(stop_time=0.01, progress=False, overrides=main_job_start)
    ssp = built / "turbocharger.ssp"
    f10 = cosimulate(ssp, "co36", step_size=1e-5, **kw)
    f5 = cosimulate(ssp, "co36", step_size=5e-6, **kw)
    a = cosimulate(ssp, "co36", adaptive=True, **kw)
    np.testing.assert_allclose(a.time, f10.time, rtol=0, atol=1e-12)  # the steps land on the output times
    assert a.meta["adaptive"] and a.meta["steps_taken"] < 0.9 * f10.meta["steps_taken"]  # measured 801 vs 1000
    assert a.meta["longest_step_s"] <= ADAPTIVE_MAX_STEP_S * (1 + 1e-12)
    pf10 = _positions(f10)
    assert np.abs(pf10 - pf10[0]).max() > 0.1 * CLEARANCE  # a transient to follow
    # Tolerance from the fixed run's own error: for the first-order coupling (tests/test_fmi.py: error ratio > 1.6
    # per step halving) e10 <= 2 |f10 - f5|; the adaptive steps are at most 1.25 x 10 µs, so e_a <= 1.25 e10, and
    # |a - f10| <= e_a + e10 <= 4.5 |f10 - f5| (measured: |f10 - f5| = 3.6e-5 c, |a - f10| = 2.2e-5 c).
    bound = 4.5 * np.abs(pf10 - _positions(f5)).max()
    assert np.abs(_positions(a) - pf10).max() <= bound
    assert bound < 1e-3 * np.abs(pf10 - pf10[0]).max()  # and that bound is far below the transient


def test_rejected_steps_are_rolled_back_transparently(built, main_job_start):
    """A tolerance 70 x tighter than the default rejects steps in the start transient. Replaying the accepted steps
    with plain fixed steps (no state saved or restored) gives the same samples: the rolled-back attempts left no
    trace. Within 1e-9 of the clearance (measured 2e-15): the replayed steps are t + h - t long, which differs from
    h by round-off, and the ring integrator converges each stage to 1e-9 of the ring state, which bounds what such
    round-off can grow to (tests/test_fmu_drive.py); a rolled-back attempt left behind would show at the scale of
    one step's motion (~5e-4 of the clearance here)."""
    ssp, T = built / "turbocharger.ssp", 0.002
    m = Master(ssp, "co36", stop_time=T, overrides=main_job_start, adaptive=True, tolerance=3e-6)
    a = m.run()
    steps = m.accepted_steps
    assert a.meta["rejected_steps"] > 0 and a.meta["shortest_step_s"] < 1e-5  # the controller did shrink
    assert a.meta["steps_taken"] == len(steps) and a.meta["forced_steps"] == 0
    np.testing.assert_allclose([t + h for t, h in steps[:-1]], [t for t, _ in steps[1:]], rtol=0, atol=1e-15)
    assert steps[0][0] == 0.0 and steps[-1][0] + steps[-1][1] == pytest.approx(T, abs=1e-15)
    rows = []
    with Master(ssp, "co36", stop_time=T, overrides=main_job_start) as replay:
        replay.initialize()
        rows.append(replay.sample(0.0))
        for t, h in steps:
            t_end = replay.step(t, h)
            k = round(t_end / 5e-5)  # output interval: 20 kHz
            if abs(t_end - k * 5e-5) < 1e-12:
                rows.append(replay.sample(t_end))
    rows = np.array(rows)
    assert rows.shape[0] == a.time.size
    np.testing.assert_allclose(rows[:, 0], a.time, rtol=0, atol=1e-12)
    assert np.abs(rows[:, 6:14] - _positions(a)).max() < 1e-9 * CLEARANCE


@pytest.mark.parametrize("kw, message", [
    (dict(tolerance=0.0), "coupling tolerance = 0.0 is invalid"),
    # trust6: 10 was accepted and ran as the fixed run at the step cap (no step could exceed it)
    (dict(tolerance=10.0), "coupling tolerance = 10.0 is invalid: valid range 0 < tolerance <= 0.001"),
    (dict(min_step=1e-5, max_step=5e-6), "min_step = 1e-05 s is above max_step = 5e-06 s"),
    (dict(max_step=5e-5), "outside the validated range"),
    (dict(coupling="force"), "coupling = 'force' has none"),
    # the adaptive step never read rollback (it retries every discarded step itself): refused, not ignored
    (dict(rollback=True), r"rollback = True \(--rollback\) does not apply with adaptive = True"),
])
def test_bad_adaptive_settings_are_refused(built, kw, message):
    with pytest.raises(ParameterError, match=message):
        Master(built / "turbocharger.ssp", "co36", adaptive=True, **kw)


def test_adaptive_step_beyond_the_validated_range_only_when_asked(built):
    m = Master(built / "turbocharger.ssp", "co36", adaptive=True, max_step=5e-5, unvalidated_step=True)
    assert m.max_step == 5e-5
    m.close()


def test_cli_adaptive_with_a_profile(built, tmp_path, capsys):
    """frb cosim --adaptive --profile: the profile's priming sub-step, then adaptive steps landing on the output
    times; the speeds are the table's (a linear ramp: round-off, 1e-9 rpm on 20 krpm)."""
    csv = tmp_path / "ramp.csv"
    csv.write_text("time [s], speed [rpm]\n0, 20000\n0.002, 20460\n")
    out = tmp_path / "out"
    assert main(["cosim", str(built / "turbocharger.ssp"), "--profile", str(csv), "--adaptive", "--coupling-tol",
                 "1e-4", "--no-figure", "--out", str(out)]) == 0
    meta = json.loads((out / "runup.json").read_text())
    assert meta["adaptive"] and meta["coupling_tol"] == 1e-4 and meta["status"] == "finished"
    assert meta["steps_taken"] < 200 + 1  # fewer than the fixed 10 µs run's 200 steps and its priming sub-step
    from frbmodel.nonlinear.recorder import RunupResult

    run = RunupResult.load(out)
    np.testing.assert_allclose(run.time, np.arange(41) * 5e-5, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.speed_rpm, 20000 + 230e3 * run.time, rtol=0, atol=1e-9)
    assert "adaptive macro step" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["--coupling-tol", "1e-4"], "--coupling-tol 0.0001 applies only with --adaptive"),
    (["--adaptive", "--coupling-tol", "-1"], "--coupling-tol = -1.0 is invalid"),
    (["--adaptive", "--rollback"], "rollback = True (--rollback) does not apply with adaptive = True (--adaptive)"),
    # trust5: 333.33 steps of 3 us ran 333 of them and reported the stop time 1 ms (it ended at 0.999 ms)
    (["--step", "3e-6"], "stop time = 0.001 s is not a whole number of macro steps of 3e-06 s (333.333 steps): the "
                         "run would end at 0.000999 s; valid: a multiple of the step as --stop-time, e.g. 0.000999 "
                         "or 0.001002 s"),
    # trust5: a folder with one sample and exit 3 (the rotor FMU discarded the first step); a MemoryError traceback
    (["--speed-source", "torque", "--drive-torque", "1e9"], "drive torque = 1e+09 N m is invalid: valid range "
                                                            "|torque| <= 1.32e+04 N m"),
    (["--stop-time", "1e4"], "stop time = 10000 s is invalid at output_rate_hz = 20000 Hz: 2e+08 samples, valid "
                             "range <= 1e+07 samples (stop time <= 500 s)"),
])
def test_cli_bad_adaptive_options_exit_2(built, tmp_path, capsys, args, message):
    code = main(["cosim", str(built / "turbocharger.ssp"), "--stop-time", "0.001", "--no-figure",
                 "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 2 and message in err, err
    assert not (tmp_path / "out").exists()


def test_cli_cosim_too_short_for_figures_names_its_own_option(built, tmp_path, capsys):
    """trust5: the hint named frb runup's --duration and --rate, which frb cosim does not have."""
    assert main(["cosim", str(built / "turbocharger.ssp"), "--stop-time", "0.0001", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "the spectrogram figures need at least 64 (a longer --stop-time)" in out and "--duration" not in out


def test_cli_profile_ending_between_macro_steps_names_the_profile(built, tmp_path, capsys):
    """trust5: the stop time defaults to a profile's last time; one between two macro steps is named as such."""
    csv = tmp_path / "odd.csv"
    csv.write_text("time [s], speed [rpm]\n0, 20000\n0.0012345, 20100\n")
    out = tmp_path / "out"
    assert main(["cosim", str(built / "turbocharger.ssp"), "--profile", str(csv), "--no-figure", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert "stop time (the speed profile's last time) = 0.0012345 s is not a whole number of macro steps" in err
    assert "as --stop-time, e.g. 0.00123 or 0.00124 s" in err and not out.exists()
