"""Co-simulation driven by a user speed profile (issue 12 item 6): ``Master(profile=...)``, ``cosimulate(profile=)``,
``frb cosim --profile FILE.csv``.

The profile drives the rotor FMU's ``speed_in`` (speed_source = "input"). A CSV that encodes the parameter set's
ramp must give the ramp-driven co-simulation's run: the expected values are that run's, computed through the
rotor FMU's independent "ramp" speed source; the kinked profile is checked against its own table (np.interp).
"""
import json

import numpy as np
import pytest

import frbmodel as frb

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from frbmodel.cli import main  # noqa: E402
from frbmodel.core.errors import ParameterError  # noqa: E402
from frbmodel.cosim.master import PRIME_STEP_S, Master, cosimulate, operating_point_overrides  # noqa: E402
from frbmodel.nonlinear.recorder import RunupResult  # noqa: E402
from frbmodel.nonlinear.runup import SpeedProfile  # noqa: E402

START, END, RAMP_S = 20e3, 250e3, 1.0  # the main job's ramp [rpm, rpm, s]
T, H = 0.005, 1e-5  # 5 ms at the SSP's macro step: 500 steps, the start transient of the 5 % offset
CLEARANCE = 36e-6  # [m], c_o of the parameter set co36: the scale of the orbit tolerances


def _csv(path, rows):
    path.write_text("time [s], speed [rpm]\n" + "".join(f"{t!r}, {s!r}\n" for t, s in rows))
    return path


def _positions(run):
    """Journal and ring x, y of both bearings [m], one column each."""
    return np.column_stack([a[b] for a in (run.journal, run.ring) for b in ("turbine", "compressor")])


@pytest.fixture(scope="module")
def runs(built, tmp_path_factory):
    """The main job's start (co36, equilibrium at 20 krpm + 5 % offset) for T: driven by the parameter set's ramp,
    and by a CSV profile of the same ramp."""
    tc = frb.turbocharger(36e-6)
    ov = operating_point_overrides(tc, START, end_rpm=END, ramp_time=RAMP_S, perturbation=0.05)
    ssp = built / "turbocharger.ssp"
    ramp = cosimulate(ssp, "co36", stop_time=T, progress=False, overrides=ov)
    csv = _csv(tmp_path_factory.mktemp("profile") / "ramp.csv", [(0.0, START), (RAMP_S, END)])
    prof = SpeedProfile.from_csv(csv)
    profiled = cosimulate(ssp, "co36", stop_time=T, progress=False, overrides=ov, profile=prof)
    return ssp, ov, prof, ramp, profiled


def test_csv_of_the_ramp_reproduces_the_ramp_driven_cosimulation(runs):
    _, _, prof, ramp, profiled = runs
    assert profiled.status == "finished" and profiled.time.size == ramp.time.size
    np.testing.assert_array_equal(profiled.time, ramp.time)
    # speeds: the ramp mode computes w0 + a t, the input mode w(t - H) + (w(t - H) - w(t - 2 H)) / H * H from the
    # same table: a few roundings of numbers ~ 2e3 rad/s, 1e-12 relative is round-off
    np.testing.assert_allclose(profiled.speed_rpm, ramp.speed_rpm, rtol=1e-12, atol=0)
    a, b = _positions(ramp), _positions(profiled)
    assert np.abs(a - a[0]).max() > 0.05 * CLEARANCE  # a transient to follow (the 5 % start offset)
    # The one difference between the runs is the first macro step: the profile-driven one starts with a sub-step
    # of PRIME_STEP_S (so the rotor has the profile's slope; test below), after which the bearings already integrate
    # along the quadratic journal path, while the ramp run's bearings take the whole first step on the linear path
    # (no journal history yet). Measured 2.7e-5 of the clearance over these 5 ms; 1e-4 bounds it and is 1/1500 of
    # the transient, so a wrong speed (half a step of the ramp missing: 3e-5 c) or a step late profile would show.
    assert np.abs(b - a).max() < 1e-4 * CLEARANCE
    assert profiled.meta["speed_profile"] == prof.description and profiled.meta["speed_source"] == "input"
    assert profiled.meta["steps_taken"] == ramp.meta["steps_taken"] + 1  # the priming sub-step


def test_profile_run_is_the_ramp_run_stepped_alike(runs):
    """Stepped like the profile-driven run (a first sub-step of PRIME_STEP_S, then the rest of the first macro step),
    the ramp-driven run is the profile-driven one: speeds to round-off, journal and ring positions within 1e-7 of
    the clearance — the ring integrator converges each stage to 1e-9 of the ring state, so runs whose inputs differ
    by round-off differ at that level (measured 1.4e-8 c after 500 steps)."""
    ssp, ov, _, _, profiled = runs
    rows, every = [], 5  # 20 kHz output at H = 10 µs
    with Master(ssp, "co36", stop_time=T, overrides=ov) as m:
        m.initialize()
        rows.append(m.sample(0.0))
        t = m.step(m.step(0.0, PRIME_STEP_S), H - PRIME_STEP_S)
        for k in range(2, int(round(T / H)) + 1):
            t = m.step(t, H)
            if k % every == 0:
                rows.append(m.sample(k * H))
    rows = np.array(rows)
    np.testing.assert_allclose(rows[:, 1], profiled.speed_rpm, rtol=1e-12, atol=0)
    cols = slice(6, 14)  # journal x, y (turbine, compressor), ring x, y (turbine, compressor): RunupSchema order
    assert np.abs(rows[:, cols] - _positions(profiled)).max() < 1e-7 * CLEARANCE


def test_stop_time_beyond_the_profile_and_other_speed_sources_are_refused(built):
    ssp = built / "turbocharger.ssp"
    prof = SpeedProfile.piecewise_linear([0.0, 0.004], [START, 21e3])
    with pytest.raises(ParameterError, match=r"stop time = 0\.005 s is beyond the speed profile's last time 0\.004 s"):
        Master(ssp, "co36", stop_time=0.005, profile=prof)
    assert Master(ssp, "co36", profile=prof).stop_time == 0.004  # default: the profile's last time
    with pytest.raises(ParameterError, match="speed_source = 'torque' conflicts with the speed profile"):
        Master(ssp, "co36", profile=prof, overrides={"rotor": {"speed_source": ("String", "torque")}})
    with pytest.raises(ParameterError, match="torque-driven"):
        Master(ssp, "co36", profile=SpeedProfile.torque(1e-3, START, 0.01))


def test_cli_profile_with_a_kink_follows_the_table(built, tmp_path, capsys):
    """frb cosim --profile: up and down again (a kink at 1 ms), stop time from the table, metadata. The rotor takes
    the slope of its last two speed inputs, so after the kink its speed is extrapolated with the old slope for one
    macro step: the recorded speed is the table's within |Δslope| H = 460 000 rpm/s x 10 µs = 4.6 rpm."""
    csv = _csv(tmp_path / "updown.csv", [(0.0, START), (0.001, START + 230.0), (0.002, START)])
    out = tmp_path / "out"
    assert main(["cosim", str(built / "turbocharger.ssp"), "--profile", str(csv), "--no-figure",
                 "--out", str(out)]) == 0
    run = RunupResult.load(out)
    meta = json.loads((out / "runup.json").read_text())
    assert meta["stop_time_s"] == 0.002 and run.time[-1] == pytest.approx(0.002, abs=1e-12)
    assert "updown.csv" in meta["speed_profile"] and meta["status"] == "finished"
    want = np.interp(run.time, [0.0, 0.001, 0.002], [START, START + 230.0, START])
    assert np.abs(run.speed_rpm - want).max() < 4.6
    assert "rotor speed: speed profile updown.csv" in capsys.readouterr().out


@pytest.mark.parametrize("text, extra, message", [
    ("time [s], speed [rpm]\n0, 20000\n0.001, -5\n", [], "line 3: speed = -5.0 rpm is invalid"),
    ("t, n\n0, 20000\n0.001, 21000\n", [], "header"),
    ("time [s], speed [rpm]\n0, 20000\n0.001, 21000\n", ["--speed-source", "torque"],
     "--speed-source torque are mutually exclusive"),
    ("time [s], speed [rpm]\n0, 20000\n0.001, 21000\n", ["--stop-time", "0.002"],
     "stop time = 0.002 s is beyond the speed profile's last time 0.001 s"),
])
def test_cli_bad_profile_exits_2_with_the_message(built, tmp_path, capsys, text, extra, message):
    csv = tmp_path / "bad.csv"
    csv.write_text(text)
    code = main(["cosim", str(built / "turbocharger.ssp"), "--profile", str(csv), "--no-figure",
                 "--out", str(tmp_path / "out"), *extra])
    err = capsys.readouterr().err
    assert code == 2 and message in err, err
    assert not (tmp_path / "out").exists()  # (the stop time was refused after the folder was made: it stayed, empty)


def test_building_and_cosimulating_leave_sys_path_as_it_was(built):
    """pythonfmu puts the build script's folder and each extracted FMU's resources folder (which holds a copy of
    frbmodel) on sys.path; left there, processes spawned later (Dask workers) import that copy — without a numba
    cache, every kernel recompiles (~40 s per worker, measured in the suite). The session's in-process build must
    have left no fmu_src folder on sys.path, and a co-simulation must give sys.path back unchanged."""
    import sys
    from pathlib import Path

    assert not [p for p in sys.path if Path(p).name == "fmu_src"]
    before = list(sys.path)
    cosimulate(built / "turbocharger.ssp", stop_time=2e-5)
    assert sys.path == before
