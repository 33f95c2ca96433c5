"""Trustworthy by default (issue #10): each row of the README's bad-input table is a test here — the user gets a
clear message naming the quantity, its value and the valid range (exit code 2 in the CLI), interrupted runs keep
their data, and the cases that used to give silent wrong answers are refused or computed correctly."""
import json
import os
import signal
import subprocess
import sys
import time
import warnings
import zipfile

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.core.errors import ParameterError
from frbmodel.nonlinear.runup import SpeedProfile


def run_cli(capsys, *argv):
    code = main(list(argv))
    err = capsys.readouterr().err
    return code, err


# ------------------------------------------------------------------ speed profiles
@pytest.mark.parametrize("call, message", [
    (lambda: SpeedProfile.exponential(0.0, 20e3, 1.0), "start speed = 0.0 rpm is invalid"),
    (lambda: SpeedProfile.ramp(20e3, 250e3, 0.0), "duration = 0.0 s is invalid"),
    (lambda: SpeedProfile.ramp(20e3, 1e9, 1.0), "end speed = 1000000000.0 rpm is invalid: valid range 0 < speed"),
    (lambda: SpeedProfile.constant(float("nan"), 1.0), "start speed = nan rpm is invalid"),
    (lambda: SpeedProfile.from_function(lambda t: 1e3 - 2e3 * t, 1.0), "speed = 0.0 rpm at t = 0.5 s"),
    # trust4: "" is the current folder: "cannot read the speed profile: Is a directory"
    (lambda: SpeedProfile.from_csv(""), "speed profile file = '' is invalid: give the path of a CSV file"),
    (lambda: SpeedProfile.from_csv("."), "speed profile file = '.' is a folder; expected a CSV file"),
    # trust4: an infinite phase ended the run-up at t = 0 ("singular iteration matrix", exit 3)
    (lambda: __import__("frbmodel.nonlinear.runup").nonlinear.runup.Unbalance("turbine_wheel", 1e-6, float("inf")),
     "unbalance phase of turbine_wheel = inf rad is invalid"),
])
def test_speed_profiles_refuse_bad_speeds_with_the_value_and_range(call, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(".", r"\.")):
        call()


def test_run_down_is_labelled_as_such():
    p = SpeedProfile.ramp(250e3, 20e3, 1.0)
    assert p.direction == "down" and "run-down" in p.description
    assert SpeedProfile.exponential(20e3, 250e3, 1.0).direction == "up"


def test_bad_integrator_tolerance_is_refused_before_integrating():
    with pytest.raises(ParameterError, match="rtol = -1.0 is invalid"):
        frb.runup(frb.turbocharger(), duration=0.01, rtol=-1.0)


# ------------------------------------------------------------------ command line
def test_cli_refuses_an_unwritable_out_before_computing(capsys, tmp_path, monkeypatch):
    """Refused before the Campbell diagram is computed: the analysis is replaced by one that fails the test if it
    is ever called (a check of the order, not of the time it takes)."""
    import frbmodel.linear.campbell

    def computed(*args, **kwargs):
        raise AssertionError("the Campbell diagram was computed before --out was checked")

    monkeypatch.setattr(frbmodel.linear.campbell, "campbell", computed)
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, err = run_cli(capsys, "campbell", "--speeds", "1000:250000:400", "--out", str(blocker / "sub"))
    assert code == 2 and "--out" in err and "is not a writable folder" in err and "Traceback" not in err


def test_cli_from_fmu_refuses_options_it_cannot_apply(capsys, tmp_path):
    code, err = run_cli(capsys, "campbell", "--from-fmu", str(tmp_path / "x.ssp"), "--outer-clearance", "46e-6",
                        "--out", str(tmp_path / "c"))
    assert code == 2 and "--outer-clearance cannot apply" in err and "parameter set" in err


def test_cli_negative_fmax_is_refused(capsys, tmp_path):
    code, err = run_cli(capsys, "campbell", "--fmax=-5", "--speeds", "1000:2000:2", "--out", str(tmp_path))
    assert code == 2 and "--fmax = -5.0 Hz is invalid" in err


def test_cli_names_the_extra_of_a_missing_optional_package(capsys, tmp_path, monkeypatch, built):
    monkeypatch.setitem(sys.modules, "fmpy", None)  # as if installed without the [fmi] extra
    ssp = built / "turbocharger.ssp"
    code, err = run_cli(capsys, "cosim", str(ssp), "--stop-time", "0.001", "--out", str(tmp_path))
    assert code == 2 and "optional package 'fmpy'" in err and "frbmodel[fmi]" in err


@pytest.mark.parametrize("sig, code", [pytest.param(signal.SIGINT, 130, marks=pytest.mark.slow),  # same path
                                       (signal.SIGTERM, 143)])
def test_interrupted_runup_keeps_its_data_marks_it_and_draws_its_figures(tmp_path, sig, code):
    out = tmp_path / "run"
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.Popen([sys.executable, "-m", "frbmodel.cli", "runup", "--speeds", "20000:60000", "--duration", "2",
                          "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    csv = out / "runup.csv"
    deadline = time.time() + 60
    while time.time() < deadline and (not csv.exists() or csv.stat().st_size < 200_000):
        time.sleep(0.2)  # wait until a few thousand samples are on disk
    p.send_signal(sig)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == code, stderr.decode()[-2000:]
    assert b"Traceback" not in stderr
    meta = json.loads((out / "runup.json").read_text())
    assert meta["status"] == "interrupted" and 0 < meta["time_reached_s"] < 2.0
    run = frb.RunupResult.load(out)
    assert run.time[-1] == pytest.approx(meta["time_reached_s"])  # everything computed is on disk
    assert (out / "composite_turbine_wheel.png").exists()


def test_cosim_refuses_a_macro_step_outside_the_validated_range(built):
    from frbmodel.cosim.master import Master

    ssp = built / "turbocharger.ssp"
    with pytest.raises(ParameterError, match=r"macro step = 0\.001 s is outside the validated range"):
        Master(ssp, "co36", stop_time=0.05, step_size=1e-3)


def test_linearization_works_over_the_speed_range_for_every_parameter_set(built):
    """`frb linearize --parameter-set co46 --speed-rpm 190000` used to fail with eps = 1.01: the bearing inputs kept
    the parameter set's start position (20 krpm) next to the operating point's ring position. The FMU eigenvalues
    must equal the library's Campbell analysis of the same system (independent assembly: frbmodel.linear.assembly)."""
    from frbmodel.cosim.linearize import linearize
    from frbmodel.linear.modal import modes_from_state

    for pset in ("co36", "co40", "co42", "co46"):
        for rpm in (1000.0, 190e3, 250e3):
            A, system = linearize(built / "turbocharger.ssp", rpm, "J", pset)
            lam = np.sort_complex(modes_from_state(A, A.shape[0] // 2).eigenvalues)
            cd = frb.campbell(system, "J", [rpm], whirl=False)
            f_ref = np.sort(cd.frequencies_hz[0][np.isfinite(cd.frequencies_hz[0])])
            f_fmu = np.sort(lam.imag[lam.imag > 0] / (2 * np.pi))
            # same modes: the FMU matrices are central differences of the same films (h = 1e-6 c): 1e-5 relative
            np.testing.assert_allclose(f_fmu[:f_ref.size], f_ref, rtol=1e-5)


def _component(label, onset_rpm, f_hz, direction="forward"):
    from frbmodel.signals.tracking import Component

    c = Component(label, np.array([onset_rpm, 1.1 * onset_rpm]), np.array([f_hz, 1.1 * f_hz]),
                  np.array([1e-6, 2e-6]), direction)
    c.onset_interp_rpm = onset_rpm
    return c


def test_convergence_check_labels_onsets_that_move_as_seeded_by_round_off():
    """The labels of frb runup --check-convergence: an onset that moves by 0.5 % is converged, one that moves by 8 %
    (the main job's sub4 between rtol 1e-7/atol 1e-10 and 1e-8/1e-11 moved 2.5 %, the old defaults 8 %) is not, and
    a component missing from the tightened run is not either; components are matched by direction, onset and
    f/f_rot, not by their labels (which depend on the order of onsets)."""
    from frbmodel.signals.convergence import convergence_table

    ref = [_component("sub1", 2000.0, 20.0), _component("sub2", 35000.0, 41.7, "backward"),
           _component("sub3", 100000.0, 180.0)]
    tight = [_component("sub1", 2010.0, 20.1), _component("sub2", 108000.0, 194.4),
             _component("sub3", 35100.0, 41.8, "backward")]
    tab = convergence_table(ref, tight).set_index("component")
    assert tab.loc["sub1", "converged"] and tab.loc["sub2", "converged"]
    assert tab.loc["sub2", "onset tightened [rpm]"] == 35100.0  # matched across labels
    assert not tab.loc["sub3", "converged"] and "round-off" in tab.loc["sub3", "note"]
    assert tab.loc["sub3", "onset moved [%]"] == pytest.approx(8.0)
    tab = convergence_table(ref, tight[:1]).set_index("component")
    assert not tab.loc["sub2", "converged"] and "not found" in tab.loc["sub2", "note"]


def test_warmup_marks_the_kernels_ready_for_these_sources(tmp_path, monkeypatch):
    """frb warmup compiles/loads every kernel group and stamps a marker with the hash of the kernel sources: a
    changed kernel source means a new stamp (the next command compiles first and says so)."""
    import frbmodel.studies.warmup as w

    monkeypatch.setattr(w, "warmup_marker", lambda: tmp_path / f"kernels-{w._stamp()}.ok")
    assert not w.kernels_ready()
    assert w.warmup(progress=False) > 0
    assert w.kernels_ready()
    monkeypatch.setattr(w, "_stamp", lambda: "changed-sources")
    assert not w.kernels_ready()


def test_first_run_notice_compiles_once_and_says_so(monkeypatch, capsys, tmp_path):
    """A kernel command whose kernels are not ready compiles them first and says so, one line on stderr, before its
    own output; a mistyped system file or SSP is named before that (it was named after the ~40 s of compiling); a
    command without kernels does not compile."""
    import frbmodel.cli as cli

    calls = []
    monkeypatch.setattr(cli, "kernels_ready", lambda: False)
    monkeypatch.setattr(cli, "warmup", lambda progress: calls.append(progress) or 0.0)
    for argv in (["equilibrium", "--system", "no-such-file.toml"], ["cosim", "no-such.ssp"], ["plot", "nofolder"],
                 ["campbell", "--oil", "SAE 99"]):
        assert cli.main(argv) == 2 and calls == []
        assert len(capsys.readouterr().err.splitlines()) == 1
    assert cli.main(["equilibrium", "--speed-rpm", "50000", "--out", str(tmp_path / "eq")]) == 0
    err = capsys.readouterr().err.splitlines()
    assert calls == [True] and err == ["frb: compiling the numba kernels (first run only, ~40 s on 2 cores; "
                                       "`frb warmup` does it on purpose)"]


def test_a_run_longer_than_its_speed_profile_is_refused():
    """Beyond its table a profile would keep its last acceleration at a constant speed (gyroscopic and unbalance
    terms then disagree with the speed): refused, naming both lengths."""
    with pytest.raises(ParameterError, match=r"duration = 0\.2 s is longer than the speed profile \(0\.1 s\)"):
        frb.runup(frb.turbocharger(), profile=SpeedProfile.ramp(20e3, 30e3, 0.1), duration=0.2)


# ------------------------------------------------------------------------------------ round 3 (issue #24 items 2-3)
@pytest.mark.parametrize("argv, words", [
    (["runup", "--rtol", "5", "--duration", "0.01"], ["--rtol = 5.0 is invalid", "valid range"]),
    (["runup", "--rtol", "1", "--duration", "0.01"], ["--rtol = 1.0 is invalid"]),
    (["runup", "--atol", "1", "--duration", "0.01"], ["--atol = 1.0 m is invalid", "smallest film clearance"]),
    (["runup", "--outer-clearance", "1e-12", "--duration", "0.01"], ["outer film clearance = 1e-12 m is invalid",
                                                                     "roughness"]),
    (["campbell", "--outer-clearance", "1e-12"], ["outer film clearance = 1e-12 m is invalid"]),
    (["runup", "--rate", "1", "--duration", "0.001"], ["records no sample after t = 0"]),
    (["runup", "--duration", "1e-9"], ["records no sample after t = 0"]),
    (["runup", "--unbalance", "turbine_wheel:1e-6:0:7", "--duration", "0.01"], ["2 or 3 fields, 4 given"]),
    (["runup", "--speeds", "20000:30000:7", "--duration", "0.01"], ["takes a speed range, START:END", "no COUNT"]),
    (["bifurcation", "--speeds", "1000:120000:5", "--hopf-only"], ["takes a speed range, START:END", "no COUNT"]),
    (["bifurcation", "--supply-temperature", "363.15", "--hopf-only"], ["--supply-temperature needs an oil"]),
    (["runup", "--ring-heat-capacity", "2.7", "--duration", "0.01"], ["--ring-heat-capacity needs an oil"]),
    (["runup", "--oil", "SAE 5W-30", "--ring-heat-capacity", "2.7", "--profile", "torque", "--drive-torque", "0.05",
      "--duration", "0.01"], ["--profile = torque-driven", "cannot take --ring-heat-capacity"]),
    (["runup", "--oil", "SAE 5W-30", "--ring-heat-capacity", "-2", "--duration", "0.01"],
     ["--ring-heat-capacity = -2.0 J/K is invalid"]),
    (["bifurcation", "--oil", "SAE 5W-30", "--supply-temperature", "90", "--hopf-only"],
     ["--supply-temperature = 90", "K"]),
    (["runup", "--drive-torque", "0.05", "--duration", "0.01"], ["--drive-torque = 0.05 N m applies only with "
                                                                  "--profile torque"]),
    (["runup", "--system", "", "--duration", "0.01"], ["--system = '' is invalid"]),
    # 1.32e4 N m = J_p (1e6 rpm = 1.047e5 rad/s) / 1 ms with J_p = 1.2619e-4 kg m², the Table 2 rotor's polar inertia
    # by hand (discs plus shaft, docs/theory/parameters.md); 1e9 N m overshot the speed bound inside one sample
    (["runup", "--profile", "torque", "--drive-torque", "1e9", "--integrator", "lsoda", "--duration", "0.01"],
     ["--drive-torque = 1e+09 N m is invalid: valid range |torque| <= 1.32e+04 N m"]),
    (["campbell", "--system", ""], ["--system = '' is invalid"]),
    # trust4: options that were dropped without a word
    (["runup", "--profile", "ramp", "--drive-torque", "0", "--duration", "0.01"],
     ["--drive-torque = 0.0 N m applies only with --profile torque"]),
    (["runup", "--profile", "constant", "--speeds", "20000:30000", "--duration", "0.01"],
     ["--speeds = '20000:30000' is invalid with --profile constant", "END would be ignored", "give --speeds 20000"]),
    (["runup", "--profile", "torque", "--speeds", "20000:30000", "--duration", "0.01"],
     ["--speeds = '20000:30000' is invalid with --profile torque", "give --speeds 20000"]),
    (["runup", "--profile", "torque", "--speeds", "fast", "--duration", "0.01"], ["--speeds = 'fast' is invalid"]),
    (["bifurcation", "--hopf-only", "--speeds", "1000:5000", "--start", "3000", "--max-points", "3"],
     ["--start, --max-points cannot be combined with --hopf-only"]),
    (["bifurcation", "--hopf-only", "--speeds", "1000:5000", "--segments", "4"],
     ["--segments cannot be combined with --hopf-only"]),
    (["bifurcation", "--start", "", "--speeds", "1000:5000"], ["--start = '' is invalid"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "hopf", "--methods", "B", "--serial"],
     ["--methods cannot apply to --analysis hopf: it is an option of --analysis campbell"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "hopf", "--duration", "5", "--serial"],
     ["--duration cannot apply to --analysis hopf", "runup / cosim"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--ssp", "x.ssp", "--serial"],
     ["--ssp cannot apply to --analysis campbell"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--param", "outer_clearance=40e-6", "--serial"],
     ["outer_clearance is given twice"]),
    (["sweep", "--example", "outer-clearance", "--oil", "SAE 5W-30", "--serial"],
     ["--oil cannot be combined with --example outer-clearance"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--serial", "--workers", "2"],
     ["--workers 2 cannot be combined with --serial"]),
    # trust4: an empty value was replaced by the default
    (["losses", "--oil", "SAE 5W-30", "--supply-temperature", "", "--speeds", "100000"],
     ["--supply-temperature = '' is invalid"]),
    (["runup", "--speeds", "", "--duration", "0.01"], ["--speeds = '' is invalid"]),
    (["unbalance", "--locations", ",", "--speeds", "10000:20000:2"], ["--locations = ',' names no location"]),
    (["runup", "--unbalance", "turbine_wheel:1e-6:inf", "--duration", "0.01"],
     ["--unbalance 'turbine_wheel:1e-6:inf': unbalance phase of turbine_wheel = inf rad is invalid"]),
    # trust4: repeated values computed the same speed, supply, clearance or case twice (a diagram over 0 rpm)
    (["campbell", "--speeds", "10000:10000:3"], ["--speeds = '10000:10000:3' repeats 10000 rpm"]),
    (["unbalance", "--speeds", "10000,20000,10000"], ["repeats 10000 rpm: give distinct speeds"]),
    (["losses", "--oil", "SAE 5W-30", "--supply-temperature", "363.15,363.15", "--speeds", "100000"],
     ["--supply-temperature = '363.15,363.15' repeats 363.15 K"]),
    (["compare", "--clearances", "36e-6,36e-6", "--duration", "0.01"], ["--clearances = '36e-6,36e-6' repeats"]),
    # trust4: refused by the first run-up, after the thermal tables and the linear onsets were computed and written
    (["losses", "--oil", "SAE 5W-30", "--supply-temperature", "363.15", "--speeds", "100000", "--onsets",
      "--runup-onsets", "--runup-duration", "1e-9"], ["--runup-duration = 1e-09 s: ", "records no sample"]),
    (["compare", "--duration", "1e-9"], ["duration = 1e-09 s is invalid at output_rate_hz = 20000 Hz"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "runup", "--duration", "1e-9", "--serial"],
     ["duration = 1e-09 s is invalid at output_rate_hz = 10000 Hz"]),
    # trust4: a range of one speed: every case failed (exit 4); four run-ups and an empty table (exit 0)
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "hopf", "--speeds", "5000:5000", "--serial"],
     ["hopf speed_rpm = (5000, 5000) rpm is invalid: START and END must differ"]),
    (["compare", "--speeds", "20000:20000", "--duration", "0.01"],
     ["speed_rpm = (20000.0, 20000.0) is invalid", "START != END"]),
    (["sweep", "--param", "outer_clearance=36e-6,36e-6", "--serial"], ["repeats 3.6e-05: give distinct values"]),
    (["unbalance", "--method", "J,j", "--speeds", "10000:20000:2"], ["--method J,J repeats method J"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--methods", "J,J", "--serial"], ["--methods J,J repeats a method"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--methods", "", "--serial"], ["method = '' is unknown"]),
    # trust4: refused while computing, after the folder was made: it was left behind, empty
    (["campbell", "--oil", "SAE 5W-30", "--supply-temperature", "473.15", "--speeds", "10000"],
     ["turbine inner film temperature at 10000 rpm", "beyond the oil's viscosity law"]),
])
def test_inputs_that_were_accepted_and_meaningless_or_dropped_are_refused(argv, words, tmp_path, capsys):
    """Issue #24 items 2-3: each case ran (exit 0) with a meaningless result or dropped the input; now exit 2 with
    one line naming the option, its value and the valid range, and nothing written."""
    from frbmodel.cli import main

    out = tmp_path / "out"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert "Traceback" not in err and not out.exists()


@pytest.mark.parametrize("argv, words", [
    (["campbell", "--speeds", "1000:inf:3"], ["--speeds = '1000:inf:3' contains inf rpm"]),
    (["campbell", "--speeds", "10000:250000:100000000"], ["has 100000000 speeds: valid range 1 ... 10000"]),
    (["campbell", "--mode-shapes", "999999999"], ["--mode-shapes = 999999999.0 rpm is invalid"]),
    (["sweep", "--param", "outer_clearance=36e-6", "--workers", "100000"],
     ["--workers = 100000 is invalid: valid range >= 1 and <= 256"]),
    (["bifurcation", "--segments", "1000000"], ["--segments = 1000000 is invalid: valid range >= 1 and <= 64"]),
    (["paper-figures", "--n-speeds", "100000000"],
     ["--n-speeds = 100000000 is invalid: valid range >= 2 and <= 10000"]),
    # trust4: refused after the whole diagram was computed and written ("mode 0 is not present at 5000 rpm")
    (["campbell", "--mode-shapes", "5000", "--speeds", "10000:20000:2"],
     ["--mode-shapes = 5000 rpm is outside --speeds 10000:20000:2 (10000 ... 20000 rpm)"]),
    (["unbalance", "--method", "B", "--k", "5e6"], ["sets a spring of methods A, E (method B takes --kx, --ky)"]),
    (["unbalance", "--method", "J", "--kx", "5e6"], ["sets a spring of method B (method J takes no spring)"]),
    (["sweep", "--param", "outer_clearance=40e-6,-1e-6"], ["study parameter outer_clearance = -1e-06 [m]",
                                                          "film clearance = -1e-06 m is invalid: valid range"]),
    (["sweep", "--param", "ring_mass=0"], ["study parameter ring_mass = 0 [kg]", "ring_mass = 0.0 kg is invalid"]),
    (["sweep", "--param", "unbalance_turbine=-1"], ["unbalance_turbine = -1.0 kg m is invalid"]),
    # a folder was made before these were refused (the check sat in the analysis, after --out)
    (["campbell", "--speeds", "0:1000:3"], ["--speeds = '0:1000:3'", "invalid for method J", "speeds > 0"]),
    (["unbalance", "--speeds", "0:1000:3"], ["--speeds = '0:1000:3'", "speeds > 0"]),
    (["losses", "--speeds", "0:1000:3"], ["--speeds = '0:1000:3'", "speeds > 0"]),
    (["equilibrium", "--speed-rpm", "0"], ["--speed-rpm = 0.0 rpm is invalid: valid range is finite and > 0"]),
    (["cosim", "nofile.ssp"], ["SSP = 'nofile.ssp' does not exist"]),
    (["linearize", "nofile.ssp"], ["SSP = 'nofile.ssp' does not exist"]),
])
def test_misleading_or_late_messages_are_clear_and_early(argv, words, tmp_path, capsys):
    """Issue #24 item 7: an infinite speed gave a numpy RuntimeWarning and then 'contains nan'; a grid of 1e8
    speeds started (ETA 29 h); --mode-shapes 999999999 was refused only after the whole diagram was written; --k
    with method B was refused as 'a spring of methods A, B, E'; a study parameter the system refuses ran every case
    and exited 4 (a negative unbalance was dropped). Now one line at once, and nothing written (the Campbell diagram
    is replaced by one that fails the test if it is computed)."""
    import frbmodel.linear.campbell
    from frbmodel.cli import main

    def computed(*args, **kwargs):
        raise AssertionError("the analysis ran before the input was checked")

    out = tmp_path / "out"
    with pytest.MonkeyPatch.context() as mp, warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy RuntimeWarning on the way fails the test
        mp.setattr(frbmodel.linear.campbell, "campbell", computed)
        assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert "Traceback" not in err and "Warning" not in err and not out.exists()


def test_a_folder_given_as_system_file_is_named_as_a_folder(tmp_path, capsys):
    from frbmodel.cli import main

    assert main(["campbell", "--system", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert f"system file = '{tmp_path}' is a folder; expected a .toml or .json file" in capsys.readouterr().err
    with pytest.raises(frb.ParameterError, match="cannot be written: it is a folder"):
        frb.turbocharger().save(tmp_path)


def test_api_refuses_meaningless_tolerances_and_runs_that_record_nothing(built):
    tc = frb.turbocharger()
    for kw in ({"rtol": 5.0}, {"atol": 1.0}, {"duration": 1e-9}, {"output_rate_hz": 1.0, "duration": 1e-3}):
        with pytest.raises(frb.ParameterError):
            frb.runup(tc, **{"duration": 0.01, **kw})
    with pytest.raises(frb.ParameterError, match="shorter than the macro step"):
        from frbmodel.cosim.master import Master

        Master(built / "turbocharger.ssp", stop_time=1e-6, step_size=1e-5)


def test_a_system_file_with_a_clearance_below_the_roughness_is_refused(tmp_path):
    """The physical bound on a film's clearance (1e-4 of its radius) holds for system files too, naming the place."""
    import tomllib

    path = frb.turbocharger().save(tmp_path / "tc.toml")
    text = path.read_text()
    d = tomllib.loads(text)
    assert d["bearings"][1]["outer"]["clearance"] == 3.6e-05
    path.write_text(text.replace("clearance = 3.6e-05", "clearance = 1e-12", 2))
    with pytest.raises(frb.ParameterError, match=r"outer: film clearance = 1e-12 m is invalid.*roughness"):
        frb.load_system(path)


def test_the_former_tracebacks_are_one_line_errors(tmp_path, capsys, built):
    """Issue #24 item 6: each case ended in a traceback; now exit 2 and one line naming the file or option."""
    import shutil
    import zipfile

    from frbmodel.cli import main

    corrupt = tmp_path / "corrupt"
    corrupt.mkdir()
    (corrupt / "runup.csv").write_text("time [s]\n")
    (corrupt / "runup.json").write_text('{"status": ')
    ssp = tmp_path / "ssp"
    with zipfile.ZipFile(built / "turbocharger.ssp") as z:
        z.extractall(ssp)
    fmu = ssp / "resources" / "FloatingRingBearing.fmu"
    fmu.write_bytes(fmu.read_bytes()[:1000])  # a truncated copy
    cases = [(["plot", str(corrupt)], "runup.json is not valid JSON: line 1, column 12"),
             (["cosim", str(ssp), "--stop-time", "1e-4", "--out", str(tmp_path / "o1")], "is not a valid FMU"),
             (["build-fmus", "--out", "/proc/frb-x"], "is not a writable folder"),
             (["sweep", "--param", "outer_clearance=36e-6", "--scheduler", "notanaddress", "--out",
               str(tmp_path / "o2")], "scheduler = 'notanaddress' is unreachable: not an address")]
    for argv, words in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err, (argv, err[-500:])
    assert not (tmp_path / "o2").exists()  # the study's folder is not made for a scheduler that is not there
    with pytest.raises(frb.ParameterError, match="bearing = 'turbine' is a str; expected a FloatingRingBearing"):
        frb.ring_speed_ratio("turbine")
    shutil.rmtree(ssp)


def test_bifurcation_hopf_only_writes_the_hopf_points_it_prints(tmp_path, capsys):
    """Issue #24 item 8: ``frb bifurcation --hopf-only --out DIR`` printed the Hopf points and wrote nothing into DIR.
    Now DIR/hopf_points.csv holds the printed rows (speed to the printed 0.1 rpm, frequency to 0.01 Hz), its order
    column consistent with speed and frequency (f 60 / n, to round-off)."""
    import pandas as pd

    from frbmodel.cli import main

    out = tmp_path / "hopf"
    assert main(["bifurcation", "--hopf-only", "--speeds", "1000:5000", "--out", str(out)]) == 0
    printed = [line.split() for line in capsys.readouterr().out.splitlines() if line.strip().endswith(("loses",
                                                                                                      "regains"))]
    tab = pd.read_csv(out / "hopf_points.csv")
    assert list(tab.columns) == ["speed [rpm]", "frequency [Hz]", "frequency [X]", "with rising speed"]
    assert len(tab) == len(printed) >= 1  # the compressor bearing's film loses stability near 2 krpm
    for (_, row), words in zip(tab.iterrows(), printed):
        assert row["speed [rpm]"] == pytest.approx(float(words[0]), abs=0.05 + 1e-9)
        assert row["frequency [Hz]"] == pytest.approx(float(words[2]), abs=0.005 + 1e-9)
        assert row["with rising speed"] == words[-1]
    np.testing.assert_allclose(tab["frequency [X]"], tab["frequency [Hz]"] * 60 / tab["speed [rpm]"], rtol=1e-12)


def _problem_opts(rtol=1e-7, nsteps=500_000):
    """A main-job problem and the solver options of frb.runup's integrators, for driving them one call at a time."""
    from frbmodel.nonlinear.runup import DEFAULT_ATOL_M, SpeedProfile, atol_vector, build_problem, initial_state

    problem = build_problem(frb.turbocharger(36e-6), SpeedProfile.ramp(20e3, 250e3, 1.0), "short")
    opts = {"atol": atol_vector(problem, DEFAULT_ATOL_M), "rtol": rtol, "nsteps": nsteps, "max_step": 0.0}
    return problem, initial_state(problem), opts


def test_lsoda_takes_a_stop_request_inside_a_solver_call():
    """Ctrl-C / SIGTERM reached LSODA only between output samples, so a run whose sample interval takes millions of
    steps could not be stopped. Its right-hand side now asks at every evaluation: a request that is pending at the
    50th evaluation ends the call there, long before the first 5 ms sample (which takes thousands)."""
    from frbmodel.nonlinear.runup import _lsoda_samples

    problem, y0, opts = _problem_opts()
    counts = {"rhs_evaluations": 0, "jacobian_evaluations": 0}

    def check():
        raise KeyboardInterrupt

    opts.update(check=check, pending=lambda: counts["rhs_evaluations"] >= 50)
    with pytest.raises(KeyboardInterrupt):
        next(_lsoda_samples(problem, y0, np.array([0.0, 5e-3]), opts, counts))
    assert counts["rhs_evaluations"] == 50


def test_compiled_solvers_return_to_take_stop_requests_within_a_step_budget(monkeypatch):
    """The compiled solvers ran CHUNK_SAMPLES x nsteps steps per call (5e7 by default) without returning, deaf to
    Ctrl-C. Now a call returns after CALL_STEPS steps: with a 20-step budget a 5 ms chunk of the main job (~90 steps
    at its start) takes several calls, the stop request is checked after each, and the samples reached are kept; a call
    without progress doubles the budget, and an interval that needs more than nsteps fails with that reason."""
    import frbmodel.nonlinear.runup as ru

    monkeypatch.setattr(ru, "CALL_STEPS", 20)
    t_out = np.arange(101) / 20e3
    for stepper in (ru._rodas_samples, ru._radau_samples):
        problem, y0, opts = _problem_opts()
        counts = {"solver_steps": 0, "rejected_steps": 0}
        checks = []
        opts.update(check=lambda c=checks, n=counts: c.append(n["solver_steps"]), pending=lambda: False)
        got = list(stepper(problem, y0, t_out, opts, counts))
        assert sum(ys.shape[0] for _, ys, _ in got) == 100 and not any(m for _, _, m in got)
        assert len(checks) >= counts["solver_steps"] // 20 - 1 and len(checks) > 3, (stepper, checks)
        assert max(np.diff([0, *checks])) <= 20 + 1, checks  # never more than the budget between two checks
    problem, y0, opts = _problem_opts(rtol=1e-12, nsteps=60)
    opts.update(check=lambda: None, pending=lambda: False)
    counts = {"solver_steps": 0, "rejected_steps": 0}
    (k, ys, message), = ru._rodas_samples(problem, y0, np.array([0.0, 5e-3]), opts, counts)
    assert "more than nsteps = 60 solver steps in one output interval" in message and ys.shape[0] == 0
    assert counts["solver_steps"] == 20 + 40 + 60  # the budget doubled from 20, capped at nsteps


def test_an_interrupted_campbell_diagram_writes_the_speeds_it_has(monkeypatch, tmp_path, capsys):
    """Interrupted, `frb campbell` left an empty folder. Now a Ctrl-C / SIGTERM during the sweep returns the speeds
    done (their modes equal to a diagram computed over just those speeds), written and marked "interrupted", exit
    code 130 / 143. The interruption is raised at the 6th speed by a wrapped per-speed step."""
    import frbmodel.linear.campbell as cm
    from frbmodel.core.interrupt import Terminated

    real, calls = cm._speed_row, []

    def interrupted_at_6th(*a, **k):
        calls.append(1)
        if len(calls) == 6:
            raise Terminated()
        return real(*a, **k)

    monkeypatch.setattr(cm, "_speed_row", interrupted_at_6th)
    code, err = run_cli(capsys, "campbell", "--speeds", "20000:120000:11", "--out", str(tmp_path / "c"))
    assert code == 143 and "interrupted (SIGTERM) after 5 of 11 speeds" in err, err
    meta = json.loads((tmp_path / "c" / "campbell_J.json").read_text())
    assert meta["status"] == "interrupted" and meta["speeds_requested"] == 11
    part = frb.CampbellResult.load(tmp_path / "c" / "campbell_J.nc")
    monkeypatch.setattr(cm, "_speed_row", real)
    whole = frb.campbell(frb.turbocharger(36e-6), "J", np.linspace(20e3, 120e3, 11)[:5])
    np.testing.assert_allclose(part.speeds_rpm, whole.speeds_rpm)
    np.testing.assert_allclose(part.frequencies_hz, whole.frequencies_hz, rtol=1e-12)  # netCDF stores float64


def test_api_inputs_that_were_misread_or_ignored_are_refused():
    """runup(speed_rpm="fast") was read character by character ("start speed = 'f'"); speed_rpm given with a
    profile was ignored; spectrogram(segment_s=-1) (or 0) silently fell back to the default segment. Each is now
    one ParameterError naming the argument."""
    tc = frb.turbocharger()
    with pytest.raises(ParameterError, match=r"speed_rpm = 'fast' is invalid: give \(start, end\) in rpm"):
        frb.runup(tc, speed_rpm="fast", duration=0.01)
    with pytest.raises(ParameterError, match="speed_rpm = .* and profile are mutually exclusive"):
        frb.runup(tc, speed_rpm=(2e4, 3e4), profile=SpeedProfile.constant(2e4, 0.01), duration=0.01)
    t = np.arange(0.0, 0.1, 1e-4)
    run = frb.RunupResult(t, np.full(t.size, 3e4), np.zeros((t.size, 1)), {"b": np.zeros((t.size, 2))},
                          {"b": np.zeros((t.size, 2))}, np.zeros((t.size, 2)), {"w": np.zeros((t.size, 2))})
    for bad in (-1.0, 0.0):
        with pytest.raises(ParameterError, match="segment_s = "):
            frb.spectrogram(run, "w", segment_s=bad)


def test_runup_profile_options_that_were_ignored_are_refused_and_one_speed_profiles_take_one_speed(tmp_path, capsys):
    """trust4: with --profile FILE.csv, --speeds and --drive-torque were ignored (the run followed the table); with
    --profile constant (torque), --speeds START:END ran at (from) START and dropped END. Now the CSV cases are
    refused with nothing written, and a one-speed profile takes --speeds START: the run holds exactly that speed."""
    table = tmp_path / "p.csv"
    table.write_text("time [s],speed [rpm]\n0,20000\n0.01,21000\n")
    for extra, option in ((["--speeds", "50000:60000"], "--speeds"), (["--drive-torque", "0.05"], "--drive-torque")):
        out = tmp_path / option.strip("-")
        assert main(["runup", "--profile", str(table), *extra, "--no-figure", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"{option} cannot be combined with --profile {table}" in err and "Traceback" not in err, err
        assert not out.exists()
    out = tmp_path / "held"
    assert main(["runup", "--profile", "constant", "--speeds", "25000", "--duration", "0.005", "--no-figure",
                 "--out", str(out)]) == 0
    assert "constant-speed run: constant 25000 rpm" in capsys.readouterr().out
    np.testing.assert_array_equal(frb.RunupResult.load(out).speed_rpm, 25000.0)


def test_plot_refuses_a_file_and_the_options_of_another_kind_of_folder(tmp_path, capsys):
    """trust4: `frb plot DIR/runup.csv` (the file, not its folder) ended in a FileExistsError traceback; --locations
    (unbalance folders) and --runs (bifurcation folders) on a run-up folder, --orders / --xscale on an unbalance
    folder were ignored. Now each is one line, exit 2, with nothing added to the folder."""
    run = tmp_path / "run"
    assert main(["runup", "--duration", "0.005", "--no-figure", "--out", str(run)]) == 0
    capsys.readouterr()
    before = sorted(p.name for p in run.iterdir())
    cases = [([str(run / "runup.csv")], f"DIR = '{run / 'runup.csv'}' is a file; give the results folder"),
             ([str(run), "--locations", "turbine_wheel"], "--locations cannot apply to"),
             ([str(run), "--runs", str(run)], "--runs needs a bifurcation folder")]
    for argv, words in cases:
        assert main(["plot", *argv]) == 2, argv
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err, err
    assert sorted(p.name for p in run.iterdir()) == before
    ub = tmp_path / "ub"
    assert main(["unbalance", "--method", "A", "--speeds", "3000:30000:3", "--out", str(ub)]) == 0
    capsys.readouterr()
    assert main(["plot", str(ub), "--orders", "1", "--xscale", "log"]) == 2
    assert "--xscale, --orders cannot apply to" in capsys.readouterr().err


def test_a_refused_command_removes_the_folders_it_made_and_keeps_those_that_were_there(tmp_path, capsys):
    """trust4: a command refused while computing (here a supply temperature at the oil's limit: the first film is
    beyond it) left the --out folder it had made, empty, with its parents. Now it removes the folders it made; a
    folder that was there stays, with its files."""
    argv = ["campbell", "--oil", "SAE 5W-30", "--supply-temperature", "473.15", "--speeds", "10000"]
    assert main([*argv, "--out", str(tmp_path / "a" / "b" / "c")]) == 2
    assert "beyond the oil's viscosity law" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "note.txt").write_text("mine")
    assert main([*argv, "--out", str(kept)]) == 2
    assert sorted(p.name for p in kept.iterdir()) == ["note.txt"]


def test_commands_at_constant_viscosities_refuse_a_system_with_an_oil(tmp_path, capsys):
    """trust4: `frb compare`, `frb paper-figures` and `frb build-fmus --rotor-file` of a system file with an [oil]
    table ran at the films' constant viscosities, the oil ignored without a word (and build-fmus left its folder).
    Now each is refused before any folder is made; the library functions refuse it too."""
    from frbmodel.cosim.fmu_system import check_rotor_system
    from frbmodel.studies.compare import compare
    from frbmodel.studies.paper import paper_figures

    path = frb.turbocharger().save(tmp_path / "oily.toml")
    path.write_text(path.read_text() + '\n[oil]\nname = "SAE 5W-30"\n')
    assert frb.load_system(path).oil.name == "SAE 5W-30"
    for argv in (["compare", "--system", str(path), "--duration", "0.01"], ["paper-figures", "--system", str(path)],
                 ["build-fmus", "--rotor-file", str(path)]):
        out = tmp_path / argv[0]
        assert main([*argv, "--out", str(out)]) == 2, argv
        err = capsys.readouterr().err
        assert "has an oil (SAE 5W-30, its [oil] table)" in err and "would ignore it" in err, err
        assert "Traceback" not in err and not out.exists()
    tc = frb.load_system(path)
    for call in (lambda: compare(tc, out_dir=tmp_path / "c"), lambda: paper_figures(tc, tmp_path / "p"),
                 lambda: check_rotor_system(tc)):
        with pytest.raises(ParameterError, match="has an oil"):
            call()
    assert check_rotor_system(frb.turbocharger()).oil is None
    # the oil of a system file refused with a spring method: the message said "an oil" without naming where it was
    assert main(["equilibrium", "--system", str(path), "--method", "A"]) == 2
    assert f"--method A cannot be combined with an oil (the [oil] table of --system {path})" in capsys.readouterr().err


def test_study_options_an_analysis_does_not_take_are_refused():
    """trust4: grid() kept options its analysis never reads (a duration for Hopf points, methods for a run-up) and
    ran a runup study with profile = 'constant' as a ramp. Now each is refused, naming the analysis' options."""
    from frbmodel.studies.sweep import grid

    for analysis, opts, words in (("hopf", {"duration": 1.0}, "sweep option duration = 1.0 does not apply to "
                                                              "analysis 'hopf': its options are speed_rpm, oil"),
                                  ("runup", {"methods": ["J"]}, "sweep option methods"),
                                  ("runup", {"profile": "constant"}, "runup profile = 'constant' is unknown"),
                                  ("runup", {"output_rate_hz": 0.0}, "runup output_rate_hz = 0.0 Hz is invalid")):
        with pytest.raises(ParameterError, match=words.replace("(", r"\(")):
            grid({"outer_clearance": [36e-6]}, analysis, **opts)
    assert grid({"outer_clearance": [36e-6]}, "runup", profile="ramp", duration=0.1)[0].options["profile"] == "ramp"


def test_campbell_from_fmu_names_an_unknown_parameter_set_of_the_users_ssp_first(built, tmp_path, capsys):
    """trust4: `frb campbell --from-fmu X.ssp --parameter-set co99` built the linearization variant, made the folder
    and then named a temporary SSP; `--parameter-set ''` fell back to co36. Now both are refused at once, naming
    the user's SSP, with nothing written."""
    for pset in ("co99", ""):
        out = tmp_path / f"c{pset}"
        assert main(["campbell", "--from-fmu", str(built / "turbocharger.ssp"), "--parameter-set", pset,
                     "--speeds", "100000", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"parameter set = {pset!r} is not in SSP '{built / 'turbocharger.ssp'}'" in err, err
        assert not out.exists()


def _ring_lag(**kw):
    from frbmodel.linear.thermal import ring_lag
    from frbmodel.physics.thermal import ThermalModel

    args = dict(system=frb.turbocharger(), time_s=[0.0, 1.0], speed_rpm=[2e4, 3e4],
                oil_supply=frb.OilSupply(frb.OILS["SAE 5W-30"], model=ThermalModel(ring_heat_capacity_J_K=2.7)))
    return ring_lag(**{**args, **kw})


def _thermal_model(**kw):
    from frbmodel.physics.thermal import ThermalModel

    return ThermalModel(**kw)


@pytest.mark.parametrize("call, message", [
    # thermal_losses without an oil returned the constant-viscosity table and dropped the supply
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], None, 333.15), "supply_temperature_K needs an oil"),
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], None, supply_pressure_Pa=4e5),
     "supply_pressure_Pa needs an oil"),
    # an empty table (0 rows, 0 columns) for no speed or no supply temperature; text converted to numbers
    (lambda: frb.thermal_losses(frb.turbocharger(), [], frb.OILS["SAE 5W-30"]), "speed_rpm = [] is invalid"),
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], frb.OILS["SAE 5W-30"], []),
     "supply_temperature_K = [] is invalid"),
    (lambda: frb.thermal_losses(frb.turbocharger(), "1e5", frb.OILS["SAE 5W-30"]), "speed_rpm = '1e5' is invalid"),
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], frb.OILS["SAE 5W-30"], "333"),
     "supply_temperature_K = '333' is invalid"),
    # ThermalModel: a wall temperature of a path that is off had no effect; 'no' switched the centrifugal feed on;
    # a tolerance of 1e9 K accepted any unconverged operating point
    (lambda: _thermal_model(shaft_temperature_K=400.0), "shaft_temperature_K = 400.0 K has no effect with "
                                                         "shaft_heat_transfer_W_m2K = 0"),
    (lambda: _thermal_model(housing_temperature_K=400.0), "housing_temperature_K = 400.0 K has no effect"),
    (lambda: _thermal_model(centrifugal_feed="no"), "centrifugal_feed = 'no' is a str; expected True or False"),
    (lambda: _thermal_model(tolerance_K=1e9), "tolerance_K = 1000000000.0 K is invalid: valid range 0 < "
                                              "tolerance_K <= 0.001 K"),
    # feed holes that do not fit the ring: a 1 m hole flooded the inner film at the supply temperature
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], frb.OILS["SAE 5W-30"],
                                model=_thermal_model(feed_hole_diameter_m=1.0)),
     "feed_hole_diameter_m = 1 m is invalid for the turbine bearing's ring: valid range < its wall thickness"),
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], frb.OILS["SAE 5W-30"],
                                model=_thermal_model(feed_holes=40, feed_hole_diameter_m=1e-3)),
     "feed_holes = 40 of 0.001 m do not fit around the turbine bearing's ring"),
    # OilSupply.from_dict of an incomplete table: KeyError / TypeError
    (lambda: frb.OilSupply.from_dict({"oil": {"name": "SAE 5W-30"}}), "oil_supply = {'oil': "),
    (lambda: frb.OilSupply.from_dict("x"), "oil_supply = 'x' is invalid: expected a table with the keys"),
    # ring_lag: rtol 0 / -1 / 10 taken by LSODA (10 changed the temperatures), text times converted, a string system
    # an AttributeError
    (lambda: _ring_lag(rtol=0.0), "rtol = 0.0 is invalid"),
    (lambda: _ring_lag(rtol=10.0), "rtol = 10.0 is invalid: valid range 1e-13 ... 1e-3"),
    (lambda: _ring_lag(time_s=["0", "1"]), "time_s = ['0', '1'] is invalid"),
    (lambda: _ring_lag(system="tc"), "system = 'tc' is a str; expected a Turbocharger"),
    # a nan supply temperature was named without the temperatures' range
    (lambda: frb.OilSupply(frb.OILS["SAE 5W-30"], float("nan")), "supply_temperature_K = nan K is invalid: valid "
                                                                  "range 243.15 ... 473.15 K"),
])
def test_thermal_api_inputs_that_were_dropped_converted_or_accepted_are_refused(call, message):
    """trust4: each call returned a result (or a traceback of another kind); now a ParameterError naming the
    argument, its value and what is valid."""
    with pytest.raises(ParameterError) as exc:
        call()
    assert message in str(exc.value), str(exc.value)


def test_thermal_losses_defaults_are_the_documented_supply():
    """Without supply arguments thermal_losses is at 363.15 K and 3e5 Pa (the defaults now None in the signature);
    the two calls give the same table to the last bit."""
    oil = frb.OILS["SAE 5W-30"]
    a = frb.thermal_losses(frb.turbocharger(), [1e5], oil)
    b = frb.thermal_losses(frb.turbocharger(), [1e5], oil, 363.15, 3e5)
    assert (a["supply temperature [K]"] == 363.15).all() and (a["supply pressure [Pa]"] == 3e5).all()
    assert a.drop(columns="iterations [-]").equals(b.drop(columns="iterations [-]"))


@pytest.mark.parametrize("argv", [["campbell", "--speeds", "100000"], ["losses", "--speeds", "100000"],
                                  ["equilibrium", "--speed-rpm", "50000"], ["build-fmus"]])
def test_an_empty_out_is_refused_not_the_current_folder(argv, tmp_path, monkeypatch, capsys):
    """trust4: `--out ""` is Path("") = the current folder: campbell and losses wrote their results (and a manifest
    that a later run would clean) there, equilibrium dropped it. Now it is refused, and nothing is written."""
    monkeypatch.chdir(tmp_path)
    assert main([*argv, "--out", ""]) == 2
    err = capsys.readouterr().err
    assert "--out = '' is invalid: give a folder" in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_losses_refuses_a_run_of_another_system_to_overlay(tmp_path, capsys):
    """trust4: `frb losses --run DIR --outer-clearance 46e-6` drew the 36 um run's recorded losses beside the 46 um
    curves, exit 0. Now a run of another system is refused before any folder is made; the run's own system works."""
    run = tmp_path / "run"
    assert main(["runup", "--duration", "0.005", "--no-figure", "--out", str(run)]) == 0
    capsys.readouterr()
    for extra, differ in ((["--outer-clearance", "46e-6"], "bearings"), (["--film-model", "short_corrected"],
                                                                        "film_model")):
        out = tmp_path / differ
        assert main(["losses", "--run", str(run), *extra, "--speeds", "20000:30000:3", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"--run {run}: the run was computed for another system (they differ in {differ})" in err, err
        assert not out.exists()
    out = tmp_path / "bif"
    assert main(["bifurcation", "--runs", str(run), "--outer-clearance", "46e-6", "--out", str(out)]) == 2
    assert f"--runs {run}: the run was computed for another system" in capsys.readouterr().err
    assert not out.exists()
    assert main(["losses", "--run", str(run), "--speeds", "20000:30000:3", "--out", str(tmp_path / "same")]) == 0


@pytest.mark.parametrize("kw, message", [
    ({"ds": 0.0}, "ds = 0.0 is invalid: valid range is finite and > 0"),
    ({"ds": -1.0}, "ds = -1.0 is invalid"),
    ({"ds": float("nan")}, "ds = nan is invalid"),
    ({"ds": 5.0, "ds_max": 1.0}, "ds = 5 is invalid with ds_max = 1: valid range 0 < ds <= ds_max"),
    ({"max_points": 0}, "max_points = 0 is invalid: valid range integer 1 ... 10000"),
    ({"max_points": 2.5}, "max_points = 2.5 is invalid"),
    ({"speeds_rpm": (3e3,)}, "speeds_rpm = (3000.0,) is invalid: give the speed range (START, END) in rpm"),
    ({"speeds_rpm": (3e3, 3e3)}, "START and END must differ"),
    ({"speeds_rpm": (1e3, 5e6)}, "speeds_rpm END = 5000000.0 rpm is invalid"),
])
def test_continuation_refuses_meaningless_steps_and_ranges_before_any_work(kw, message, monkeypatch):
    """trust4: continuation(ds=0 / -1 / nan, ds > ds_max) returned a diagram; a range of one speed raised an unpacking
    ValueError, (3e3, 3e3) returned an empty diagram. Now each is one ParameterError before the Hopf points are
    searched (replaced here by a function that fails the test if it is called)."""
    import frbmodel.cycles.continuation as cc

    def searched(*args, **kwargs):
        raise AssertionError("the Hopf points were searched before the arguments were checked")

    monkeypatch.setattr(cc, "hopf_points", searched)
    with pytest.raises(ParameterError) as exc:
        cc.continuation(frb.turbocharger(), **{"speeds_rpm": (1e3, 3e3), **kw})
    assert message in str(exc.value), str(exc.value)


@pytest.mark.parametrize("kw, message", [
    ({"tol": 0.0}, "tol = 0.0 is invalid"),
    ({"tol": 1e3}, "tol = 1000.0 is invalid: valid range 0 < tol <= 0.001"),
    ({"samples": 1}, "samples = 1 is invalid: valid range integer >= 16"),
    ({"max_iter": 0}, "max_iter = 0 is invalid: valid range integer >= 1"),
])
def test_limit_cycle_checks_its_newton_options_before_the_settling_run(kw, message, monkeypatch):
    """trust4: tol, samples and max_iter were first used after the settling run (seconds), which then failed with
    an unrelated ConvergenceError; tol = 1e3 would accept any orbit. Now refused before the guess is made (replaced
    by a function that fails the test if it is called)."""
    import frbmodel.cycles.limitcycle as lcm

    def settled(*args, **kwargs):
        raise AssertionError("the guess was settled before the options were checked")

    monkeypatch.setattr(lcm, "_initial_guess", settled)
    with pytest.raises(ParameterError) as exc:
        frb.limit_cycle(frb.turbocharger(), 3e4, **kw)
    assert message in str(exc.value), str(exc.value)


def test_hopf_points_refuses_a_degenerate_search_before_any_equilibrium(monkeypatch):
    """trust4: hopf_points(tc, (3e3,)) was a TypeError of numpy, n_grid = 1 returned [] (one speed crosses nothing),
    restabilizing = "no" was truthy. Now one ParameterError each, before any equilibrium is computed."""
    import frbmodel.cycles.branch as br

    def computed(*args, **kwargs):
        raise AssertionError("an equilibrium was computed before the arguments were checked")

    monkeypatch.setattr(br, "_unstable_pairs", computed)
    for kw, message in (({"speeds_rpm": (3e3,)}, "speeds_rpm = (3000.0,) is invalid"),
                        ({"n_grid": 1}, "n_grid = 1 is invalid: valid range integer >= 2"),
                        ({"restabilizing": "no"}, "restabilizing = 'no' is a str; expected True or False")):
        with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
            br.hopf_points(frb.turbocharger(), **{"speeds_rpm": (1e3, 3e3), **kw})


def test_a_run_too_short_for_figures_says_so(tmp_path, capsys):
    """trust4: `frb runup --duration 1e-3` (21 samples) wrote no figure and said nothing about it. Now it says why
    (still exit 0: the run's data are complete)."""
    assert main(["runup", "--duration", "1e-3", "--out", str(tmp_path / "short")]) == 0
    assert "no figures: 21 samples recorded, the spectrogram figures need at least 64" in capsys.readouterr().out
    assert not list((tmp_path / "short").glob("composite_*"))


def test_linearize_names_a_system_ssp_and_the_users_ssp(built, tmp_path, capsys):
    """trust5: `frb linearize engine_turbocharger.ssp` was refused for its 1 ms macro step, naming
    --unvalidated-step (an option linearize does not have); an SSP broken at set-up was named by its temporary
    linearization copy."""
    out = tmp_path / "out"
    assert main(["linearize", str(built / "engine_turbocharger.ssp"), "--speed-rpm", "60000", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "runs the whole-turbocharger FMU" in err and "turbocharger.ssp of frb build-fmus" in err, err
    assert "--unvalidated-step" not in err and not out.exists()
    d = tmp_path / "ssp"
    with zipfile.ZipFile(built / "turbocharger.ssp") as z:
        z.extractall(d)
    for ssd in d.glob("*.ssd"):
        ssd.write_text(ssd.read_text().replace('<ssd:Connection startElement="rotor" startConnector="turbine_bearing.'
                                               'journal.x" endElement="turbine" endConnector="journal.x" />', ""))
    assert main(["linearize", str(d), "--speed-rpm", "60000", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{d}: the connected output turbine.force.x depends on the input turbine.journal.x" in err, err
    assert "frb_linearization_" not in err


# ------------------------------------------------------------------ trust6: repeated values, bounds, one rule, early
@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    """A 5 ms run-up folder (100 samples at 20 kHz) for the ``frb plot`` and ``--runs`` cases."""
    run = tmp_path_factory.mktemp("trust6") / "run"
    assert main(["runup", "--duration", "0.005", "--no-figure", "--out", str(run)]) == 0
    return run


@pytest.fixture(scope="module")
def thin_ring(tmp_path_factory):
    """A system file: the Table 2 system with the turbine ring's wall 1.2 mm thick (R_O = R_I + c_I + 1.2 mm), so
    the default thermal model's 1.5 mm feed holes do not fit it."""
    from dataclasses import replace

    tc = frb.turbocharger()
    b = tc.bearings[0]
    thin = replace(b, outer=replace(b.outer, radius=b.inner.radius + b.inner.clearance + 1.2e-3))
    return tc.with_(bearings=(thin, tc.bearings[1])).save(tmp_path_factory.mktemp("thin") / "thin.toml")


#: the one line of each trust6 CLI case (RUN: the short run's folder, THIN: the thin-ring system file, SSP: the
#: built turbocharger.ssp, NOSSP: a path without one)
UNBALANCE_10 = ("unbalance of turbine_wheel = 10.0 kg m is invalid: valid range 0 ... 0.00514 kg m = sqrt(m I_p) of "
                "the disc (0.326 kg, 8.1e-05 kg m^2; a larger m e needs more mass farther from the axis than the disc "
                "has; 1e-6 kg m = 1 g mm)")
FEED_HOLES = ("thermal model feed_hole_diameter_m = 0.0015 m is invalid for the turbine bearing's ring: valid range < "
              "its wall thickness 0.0012 m (the holes' length)")
TRUST6_CLI = [
    # case 1: the window was drawn and its files written twice
    (["plot", "RUN", "--orbit-times", "0:0.002,0:0.002"],
     "--orbit-times = '0:0.002,0:0.002' repeats 0:0.002 s: give distinct values"),
    # case 2: 10 ran as the fixed 12.5 us run (the tolerance was capped by the step bound without a word)
    (["cosim", "nofile.ssp", "--adaptive", "--coupling-tol", "10"],
     "--coupling-tol = 10.0 is invalid: valid range is finite and > 0 and <= 0.001"),
    # case 3: a branch of a million points (days)
    (["bifurcation", "--max-points", "1000000"], "--max-points = 1000000 is invalid: valid range >= 2 and <= 10000"),
    # case 3: 10 kg m on a 0.326 kg wheel (6.9e9 N at 250 krpm)
    (["runup", "--unbalance", "turbine_wheel:10", "--duration", "0.01"], f"--unbalance 'turbine_wheel:10': "
                                                                         f"{UNBALANCE_10}"),
    (["unbalance", "--unbalance", "turbine_wheel:10", "--speeds", "1000:2000:2"], f"--unbalance 'turbine_wheel:10': "
                                                                                  f"{UNBALANCE_10}"),
    # case 5: refused inside the first thermal balance, after the folder was made
    (["campbell", "--system", "THIN", "--oil", "SAE 5W-30", "--speeds", "100000"], FEED_HOLES),
    (["losses", "--system", "THIN", "--oil", "SAE 5W-30", "--speeds", "100000"], FEED_HOLES),
    (["runup", "--system", "THIN", "--oil", "SAE 5W-30", "--duration", "0.01"], FEED_HOLES),
    (["bifurcation", "--system", "THIN", "--oil", "SAE 5W-30", "--hopf-only", "--speeds", "1000:30000"], FEED_HOLES),
    (["unbalance", "--system", "THIN", "--oil", "SAE 5W-30", "--speeds", "1000:2000:2"], FEED_HOLES),
    (["equilibrium", "--system", "THIN", "--oil", "SAE 5W-30", "--speed-rpm", "100000"], FEED_HOLES),
    # more repeated values: an order line, a location, a run's envelope drawn twice
    (["plot", "RUN", "--orders", "1,1"], "--orders = '1,1' repeats 1: give distinct values"),
    (["unbalance", "--method", "A", "--speeds", "3000:30000:3", "--locations", "turbine_wheel,turbine_wheel"],
     "--locations = 'turbine_wheel,turbine_wheel' repeats turbine_wheel: give distinct values"),
    (["bifurcation", "--runs", "RUN,RUN", "--speeds", "1000:30000"], "--runs = 'RUN,RUN' repeats RUN: give distinct "
                                                                     "values"),
    # the same branch followed twice (hours)
    (["bifurcation", "--start", "25000,25000", "--speeds", "1000:30000"], "--start repeats 25000 rpm: give distinct "
                                                                          "values"),
    # two unbalances on one disc were summed (the dict form and the FMUs take one per disc)
    (["runup", "--unbalance", "turbine_wheel:1e-6", "--unbalance", "turbine_wheel:1e-6:1", "--duration", "0.01"],
     "--unbalance 'turbine_wheel:1e-6:1': unbalance discs ['turbine_wheel', 'turbine_wheel'] repeats turbine_wheel: "
     "give distinct values"),
    # a spring of 1e40 N/m gave wrong modes without a warning
    (["unbalance", "--method", "A", "--k", "1e40", "--speeds", "3000:30000:3"],
     "--k = 1e+40 N/m is invalid: valid range is finite and > 0 and <= 1e+15 N/m"),
    (["campbell", "--method", "B", "--ky", "1e40"], "--ky = 1e+40 N/m is invalid: valid range is finite and > 0 and "
                                                    "<= 1e+15 N/m"),
    # a cosim study of a missing SSP, a duration off the macro steps or one recording 2e7 samples: every case failed
    # (exit 4, a study folder written) where frb cosim refuses the same at once
    # frb compare: a clearance the films refuse was refused after the Campbell diagrams and run-ups of the ones before
    # it (their files left in the folder); two clearances within a µm wrote one result folder, the second over the first
    (["compare", "--clearances", "36e-6,1e-12", "--duration", "0.01"],
     "--clearances = '36e-6,1e-12': turbine outer film clearance = 1e-12 m is invalid for radius 0.008 m: valid range "
     ">= 0.0001 * radius = 8e-07 m (a thinner film is below the surfaces' roughness: no hydrodynamic film forms)"),
    (["compare", "--clearances", "36.2e-6,36.2000001e-6", "--duration", "0.01"],
     "--clearances = '36.2e-6,36.2000001e-6': clearances = [3.62e-05, 3.62000001e-05]: their result folders "
     "['co36.2um', 'co36.2um'] repeats co36.2um: give distinct values"),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "cosim", "--ssp", "NOSSP", "--serial"],
     "SSP = 'NOSSP' does not exist"),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "cosim", "--ssp", "SSP", "--duration", "0.0012345",
      "--serial"], "cosim duration = 0.0012345 s is not a whole number of macro steps of 1e-05 s (123.45 steps): the "
                   "run would end at 0.00123 s; valid: a multiple of the step as the option duration (frb sweep "
                   "--duration), e.g. 0.00123 or 0.00124 s"),
    (["sweep", "--param", "outer_clearance=36e-6", "--analysis", "cosim", "--ssp", "SSP", "--duration", "1000",
      "--serial"], "cosim duration = 1000 s is invalid at output_rate_hz = 20000 Hz: 2e+07 samples, valid range <= "
                   "1e+07 samples (cosim duration <= 500 s)"),
]


@pytest.mark.parametrize("argv, message", TRUST6_CLI)
def test_repeated_values_unbounded_numbers_and_late_checks_are_refused_first(argv, message, short_run, thin_ring,
                                                                             built, tmp_path, capsys, monkeypatch):
    """trust6: each case ran (exit 0) with a value drawn or computed twice, a number past any meaning, or was refused
    only inside the computation. Now exit 2 with the one line naming the option, its value and the valid range,
    before any work (the analyses are replaced by functions that fail the test if they are called) and with nothing
    written: no --out folder, the run folder's files unchanged."""
    import frbmodel.cli as cli
    import frbmodel.linear.thermal as lt

    def computed(*args, **kwargs):
        raise AssertionError("the analysis ran before the input was checked")

    for name in ("campbell", "unbalance_response", "runup", "hopf_points", "continuation", "thermal_losses",
                 "cosimulate", "write_composites", "write_orbits", "run_study", "compare"):
        monkeypatch.setattr(cli, name, computed)
    monkeypatch.setattr(lt, "_operating_point", computed)
    subs = {"RUN": str(short_run), "THIN": str(thin_ring), "SSP": str(built / "turbocharger.ssp"),
            "NOSSP": str(short_run.parent / "none.ssp")}
    argv = [",".join(subs.get(x, x) for x in a.split(",")) for a in argv]
    for token in ("NOSSP", "RUN"):
        message = message.replace(token, subs[token])
    before = {p.name: p.read_bytes() for p in short_run.iterdir()}
    out = tmp_path / "out"
    assert main(argv if argv[0] == "plot" else [*argv, "--out", str(out)]) == 2
    assert capsys.readouterr().err.splitlines() == [f"frb {argv[0]}: error: {message}"]
    assert not out.exists() and {p.name: p.read_bytes() for p in short_run.iterdir()} == before


def _supply(**model):
    from frbmodel.physics.thermal import ThermalModel

    return frb.OilSupply(frb.OILS["SAE 5W-30"], model=ThermalModel(**model))


def _unbalances(*items):
    from frbmodel.nonlinear.runup import Unbalance

    return [Unbalance(*it) for it in items]


def _grid(params, analysis="runup", **options):
    from frbmodel.studies.sweep import grid

    return grid(params, analysis, **options)


TRUST6_API = [
    # case 3: a branch of 1e9 points; the API and the studies took any number of shooting segments
    (lambda: __import__("frbmodel.cycles.continuation").cycles.continuation.continuation(
        frb.turbocharger(), (1e3, 3e3), max_points=10**9),
     "max_points = 1000000000 is invalid: valid range integer 1 ... 10000 (points per branch and direction: the "
     "speed-grid bound)"),
    (lambda: _grid({"outer_clearance": [36e-6]}, "bifurcation", max_points=10**9),
     "bifurcation max_points = 1000000000 is invalid: valid range integer 2 ... 10000"),
    (lambda: __import__("frbmodel.cycles.continuation").cycles.continuation.continuation(
        frb.turbocharger(), (1e3, 3e3), segments=10**6),
     "segments = 1000000 is invalid: valid range integer 1 ... 64 (shooting segments per orbit)"),
    (lambda: _grid({"outer_clearance": [36e-6]}, "bifurcation", segments=10**6),
     "bifurcation segments = 1000000 is invalid: valid range integer 1 ... 64"),
    # case 3: the unbalance's amount was checked by the run-up only, after its thermal tables, and never bounded
    (lambda: frb.runup(frb.turbocharger(), duration=0.01, unbalance=_unbalances(("turbine_wheel", 10.0))),
     UNBALANCE_10),
    (lambda: frb.unbalance_response(frb.turbocharger(), "A", [1e4], {"turbine_wheel": 10.0}),
     UNBALANCE_10.replace("unbalance of", "unbalance m e of")),
    (lambda: _grid({"unbalance_turbine": [10.0]}), "study parameter unbalance_turbine = 10 [kg m]: "
                                                   + UNBALANCE_10.replace("unbalance of turbine_wheel",
                                                                          "unbalance_turbine")),
    (lambda: _unbalances(("turbine_wheel", -1e-6)), "unbalance of turbine_wheel = -1e-06 kg m is invalid: valid range "
                                                    "is a finite real number >= 0 kg m"),
    # case 4: the API took a known oil's name over other numbers (the [oil] parser alone refused it)
    (lambda: frb.Oil(60e-6, 11e-6, 852.0, 6.5e-4, 2000.0, "SAE 5W-30"),
     "oil name = 'SAE 5W-30' is a known oil, but nu40_m2_s = 6e-05 (not 6.4e-05): its results would be labelled "
     "'SAE 5W-30'; give another name for these numbers, or the known oil itself (frbmodel.OILS['SAE 5W-30'], or "
     "name = 'SAE 5W-30' alone in an [oil] table)"),
    # case 5: feed holes that do not fit the ring were refused inside the first thermal balance
    (lambda: frb.campbell(frb.turbocharger(), "J", [1e5], oil_supply=_supply(feed_hole_diameter_m=1.0)),
     "thermal model feed_hole_diameter_m = 1 m is invalid for the turbine bearing's ring: valid range < its wall "
     "thickness 0.002466 m (the holes' length)"),
    (lambda: frb.runup(frb.turbocharger(), duration=0.01, oil_supply=_supply(feed_holes=40, feed_hole_diameter_m=1e-3)),
     "thermal model feed_holes = 40 of 0.001 m do not fit around the turbine bearing's ring: valid range feed_holes x "
     "feed_hole_diameter_m < 2 pi R_I = 0.0345575 m"),
    (lambda: frb.thermal_losses(frb.turbocharger(), [1e5], frb.OILS["SAE 5W-30"],
                                model=_supply(feed_hole_diameter_m=1.0).model),
     "feed_hole_diameter_m = 1 m is invalid"),
    (lambda: __import__("frbmodel.cycles.branch").cycles.branch.hopf_points(
        frb.turbocharger(), (1e3, 3e3), oil_supply=_supply(feed_hole_diameter_m=1.0)),
     "feed_hole_diameter_m = 1 m is invalid"),
    # the same branch followed twice
    (lambda: __import__("frbmodel.cycles.continuation").cycles.continuation.continuation(
        frb.turbocharger(), (1e3, 3e3), start=[2e3, 2e3]), "start repeats 2000 rpm: give distinct values"),
    (lambda: _grid({"outer_clearance": [36e-6]}, "bifurcation", speed_rpm=(1e3, 3e3), start=["hopf", "hopf"]),
     "bifurcation start repeats hopf: give distinct values"),
    # two unbalances on one disc were summed
    (lambda: frb.runup(frb.turbocharger(), duration=0.01, unbalance=_unbalances(("turbine_wheel", 1e-6),
                                                                                 ("turbine_wheel", 1e-6, 1.0))),
     "unbalance discs ['turbine_wheel', 'turbine_wheel'] repeats turbine_wheel: give distinct values"),
    (lambda: frb.unbalance_response(frb.turbocharger(), "A", [1e4], _unbalances(("turbine_wheel", 1e-6),
                                                                                ("turbine_wheel", 1e-6))),
     "unbalance discs ['turbine_wheel', 'turbine_wheel'] repeats turbine_wheel: give distinct values"),
    # a spring of 1e40 N/m gave wrong modes without a warning
    (lambda: frb.campbell(frb.turbocharger(), "A", [1e4], k=1e40),
     "method A k = 1e+40 N/m is invalid: valid range 0 < k <= 1e+15 N/m (a rigid support; stiffer springs lose the "
     "rotor's modes to round-off)"),
    (lambda: frb.runup(frb.turbocharger(), duration=0.01, linear_springs=1e40),
     "linear_springs = 1e+40 N/m is invalid: valid range 0 < k <= 1e+15 N/m"),
    # a study's Campbell grid of 1e8 speeds: every case failed (the CLI's grid bound)
    (lambda: _grid({"outer_clearance": [36e-6]}, "campbell", speeds_rpm=(1e3, 2.5e5, 10**8)),
     "campbell speeds_rpm = (1000.0, 250000.0, 100000000) has 100000000 speeds: valid range 1 ... 10000 speeds"),
    # compare: the second clearance refused after the first's Campbell diagram and run-up
    (lambda: __import__("frbmodel.studies.compare").studies.compare.compare(frb.turbocharger(), (36e-6, 1e-12)),
     "turbine outer film clearance = 1e-12 m is invalid for radius 0.008 m"),
    # a cosim study without an SSP: every case failed with a KeyError
    (lambda: _grid({"outer_clearance": [36e-6]}, "cosim"), "analysis 'cosim' needs the option ssp: the SSP of the FMUs "
                                                          "(frb build-fmus writes build/turbocharger.ssp)"),
]


@pytest.mark.parametrize("call, message", TRUST6_API)
def test_api_refuses_the_same_values_as_the_cli_before_any_work(call, message, monkeypatch):
    """trust6: the library took what the CLI refuses, or refused it only inside the computation. Now one
    ParameterError, before any work: the thermal balance, the run-up's tables and integration and the Hopf search
    are replaced by functions that fail the test if they are called."""
    import frbmodel.cycles.branch as br
    import frbmodel.cycles.continuation as cc
    import frbmodel.linear.thermal as lt
    import frbmodel.nonlinear.runup as ru
    import frbmodel.studies.compare as cm

    def computed(*args, **kwargs):
        raise AssertionError("the computation started before the input was checked")

    monkeypatch.setattr(lt, "_operating_point", computed)
    monkeypatch.setattr(cc, "hopf_points", computed)
    monkeypatch.setattr(br, "_unstable_pairs", computed)
    monkeypatch.setattr(cm, "campbell", computed)
    for name in ("viscosity_table", "lagged_viscosity_table", "_integrate", "initial_state"):
        monkeypatch.setattr(ru, name, computed)
    with pytest.raises(ParameterError) as exc:
        call()
    assert message in str(exc.value), str(exc.value)


def test_compare_writes_each_clearance_to_its_own_folder():
    """trust6: the result folder of a clearance was named by the whole µm (co36um for 36.2 and 36.4 µm: the second's
    files over the first's, while the table listed both). Now 6 significant digits name it."""
    from frbmodel.studies.compare import clearance_tag

    assert [clearance_tag(c) for c in (36e-6, 36.2e-6, 36.4e-6, 46e-6)] == ["co36um", "co36.2um", "co36.4um", "co46um"]
