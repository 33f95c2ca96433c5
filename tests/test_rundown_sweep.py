"""Run-downs and study input through compare and sweep: descending speed grids, names from the system, clean
failures (ParameterError / exit code 2 naming the quantity, the value and the valid range) and the progress
protocol (silent by default)."""
import socket
import sys
from dataclasses import replace

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.signals.tracking import NO_ONSET_PRESENT, ONSET_TURNING_POINT, Component
from frbmodel.studies.compare import associate, compare
from frbmodel.studies.sweep import build_case_system, grid, run_study, stability_map


def _renamed(tc, bearings=("front", "rear"), discs=("impeller_a", "impeller_b")):
    rotor = replace(tc.rotor, discs=tuple(replace(d, name=n) for d, n in zip(tc.rotor.discs, discs)))
    return tc.with_(rotor=rotor, bearings=tuple(replace(b, name=n) for b, n in zip(tc.bearings, bearings)))


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# ---------------------------------------------------------------------------------------------------- bad input
def test_unknown_campbell_method_is_refused_before_any_case_runs(tmp_path, capsys):
    with pytest.raises(frb.ParameterError, match=r"method = 'Q' is unknown; valid methods are A, B, C, D, E, F, G, I"):
        grid({"outer_clearance": [36e-6]}, "campbell", methods=["J", "Q"])
    out = tmp_path / "s"
    assert main(["sweep", "--param", "outer_clearance=36e-6", "--methods", "Q", "--serial", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "method = 'Q' is unknown" in err and "Traceback" not in err
    assert not (out / "cases").exists()  # nothing ran


@pytest.mark.parametrize("workers", [0, -3])
def test_workers_below_one_are_refused(tmp_path, capsys, workers):
    cases = grid({"outer_clearance": [36e-6]}, "campbell", speeds_rpm=(1e3, 250e3, 5))
    with pytest.raises(frb.ParameterError, match=rf"workers = {workers} is invalid: valid range integer >= 1"):
        run_study(cases, tmp_path / "api", n_workers=workers)
    assert main(["sweep", "--param", "outer_clearance=36e-6", "--workers", str(workers), "--out",
                 str(tmp_path / "cli")]) == 2
    assert f"workers = {workers} is invalid" in capsys.readouterr().err


def test_unreachable_scheduler_fails_fast_naming_the_address(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    import frbmodel.studies.sweep

    monkeypatch.setattr(frbmodel.studies.sweep, "SCHEDULER_TIMEOUT_S", 1.0)  # the default 5 s, shortened for the suite
    SCHEDULER_TIMEOUT_S = frbmodel.studies.sweep.SCHEDULER_TIMEOUT_S

    address = f"tcp://127.0.0.1:{_free_port()}"  # a port nobody listens on
    cases = grid({"outer_clearance": [36e-6]}, "campbell", speeds_rpm=(1e3, 250e3, 5))
    with pytest.raises(frb.ParameterError, match=f"scheduler = '{address}' is unreachable"):
        run_study(cases, tmp_path, scheduler=address)
    # fails fast: the probe of the address waits at most SCHEDULER_TIMEOUT_S (the timeout it passes is checked, not
    # the wall clock), and no Dask client is made for an address that does not answer
    import socket

    import distributed

    timeouts = []

    def silent(addr, timeout=None, *args, **kwargs):
        timeouts.append(timeout)
        raise TimeoutError("timed out")

    def no_client(*args, **kwargs):
        raise AssertionError("a Dask client was made for an unreachable scheduler")

    monkeypatch.setattr(socket, "create_connection", silent)
    monkeypatch.setattr(distributed, "Client", no_client)
    with pytest.raises(frb.ParameterError, match=f"scheduler = '{address}' is unreachable: timed out"):
        run_study(cases, tmp_path, scheduler=address)
    assert timeouts == [SCHEDULER_TIMEOUT_S]
    with pytest.raises(frb.ParameterError, match="scheduler = 'nonsense' is unreachable"):
        run_study(cases, tmp_path, scheduler="nonsense")


def test_missing_dist_extra_names_the_extra_and_serial_still_works(tmp_path, capsys, monkeypatch):
    for mod in ("dask", "distributed", "dask.distributed"):
        monkeypatch.setitem(sys.modules, mod, None)  # as after an install without the [dist] extra
    out = tmp_path / "s"
    assert main(["sweep", "--param", "outer_clearance=36e-6", "--speeds", "1000:250000:5", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "'dask'" in err and "frbmodel[dist]" in err and "Traceback" not in err
    assert not (out / "cases").exists()  # refused before anything was written
    # the serial scheduler needs no Dask
    idx = run_study(grid({"outer_clearance": [36e-6]}, "campbell", speeds_rpm=(1e3, 250e3, 5)), out,
                    scheduler="serial")
    assert list(idx["status"]) == ["finished"]


@pytest.mark.parametrize("options,match", [
    (dict(speeds_rpm=(0.0, 250e3, 10)), r"campbell start speed = 0.0 rpm is invalid"),
    (dict(speeds_rpm=(1e3, 1e9, 10)), r"campbell stop speed = 1000000000.0 rpm is invalid: valid range 0 < speed"),
    (dict(speeds_rpm=(1e3, 250e3, 1)), r"campbell speed count = 1 is invalid: valid range integer >= 2"),
])
def test_bad_campbell_grid_is_refused(options, match):
    with pytest.raises(frb.ParameterError, match=match):
        grid({"outer_clearance": [36e-6]}, "campbell", **options)


# ---------------------------------------------------------------------------------------------------- names
def test_study_parameters_refer_to_the_systems_bearing_and_disc_names():
    tc = frb.turbocharger()
    # the bearings in the other order: the turbine viscosity must still land in the bearing named "turbine"
    swapped = tc.with_(bearings=tuple(reversed(tc.bearings)))
    sys_, unb = build_case_system({"viscosity_turbine": 7e-3, "unbalance_compressor": 2e-6}, base=swapped)
    by_name = {b.name: b for b in sys_.bearings}
    assert by_name["turbine"].inner.viscosity == 7e-3 and by_name["turbine"].outer.viscosity == 7e-3
    assert by_name["compressor"].inner.viscosity == tc.bearings[1].inner.viscosity
    assert [(u.disc, u.amount) for u in unb] == [("compressor_wheel", 2e-6)]
    renamed = _renamed(tc)
    with pytest.raises(frb.ParameterError, match=r"needs a bearing named 'turbine'; .* \['front', 'rear'\]"):
        build_case_system({"viscosity_turbine": 7e-3}, base=renamed)
    with pytest.raises(frb.ParameterError, match=r"needs a disc named 'turbine_wheel' or 'turbine'; .*'impeller_a'"):
        build_case_system({"unbalance_turbine": 1e-6}, base=renamed)


# ---------------------------------------------------------------------------------------------------- speed order
def test_descending_campbell_grid_gives_the_ascending_grids_onsets(tmp_path):
    up = grid({"outer_clearance": [40e-6]}, "campbell", methods=["J"], speeds_rpm=(1e3, 250e3, 30))
    down = grid({"outer_clearance": [40e-6]}, "campbell", methods=["J"], speeds_rpm=(250e3, 1e3, 30))
    run_study(up, tmp_path / "up", scheduler="serial")
    run_study(down, tmp_path / "down", scheduler="serial")
    a, b = (stability_map(tmp_path / k).drop(columns="case_id").sort_values("item").reset_index(drop=True)
            for k in ("up", "down"))
    assert len(a) > 0
    # the same speeds in the other order: the same linear results, to the last bit
    np.testing.assert_array_equal(a["onset [rpm]"], b["onset [rpm]"])
    assert list(a["item"]) == list(b["item"])
    # the onsets are the lower ends of the unstable ranges, not the grid's first speed (250 krpm)
    assert (b["onset [rpm]"] <= b["end [rpm]"]).all() and b["onset [rpm]"].min() < 30e3


def test_associate_reads_a_campbell_result_in_either_speed_order():
    cd = frb.campbell(frb.turbocharger(40e-6), "J", np.linspace(5e3, 150e3, 30))
    ur = cd.unstable_ranges()
    r = ur.iloc[-1]  # a range that starts inside the grid
    j = int(r["mode"])
    s_on = float(r["from [rpm]"]) * 1.02
    f_on = float(np.interp(s_on, cd.speeds_rpm, cd.frequencies_hz[:, j]))
    comp = Component("sub1", np.array([s_on, s_on * 1.01]), np.array([f_on, f_on * 1.01]), np.ones(2), "forward",
                     onset_interp_rpm=s_on, onset_estimate=ONSET_TURNING_POINT)
    flipped = replace(cd, **{k: getattr(cd, k)[::-1] for k in (
        "speeds_rpm", "frequencies_hz", "damping", "precession", "mode_kind", "ring_fraction", "eigenvalues",
        "ring_speed_ratio", "eccentricity", "whirl_hz", "whirl_margin")})
    a, b = associate(comp, cd), associate(comp, flipped)
    assert a is not None and a["mode"] == j and a["linear onset [rpm]"] == r["from [rpm]"]
    assert b == a  # same data in the other order: same pairing
    # a run-down enters the range at its upper end
    down = associate(comp, flipped, descending=True)
    assert down["linear onset [rpm]"] == max(ur.loc[ur["mode"] == down["mode"], "to [rpm]"])
    # no onset (there from the start): paired only with a mode unstable where it was first detected
    present = replace(comp, onset_interp_rpm=float("nan"), onset_estimate=NO_ONSET_PRESENT)
    assert r["from [rpm]"] <= s_on <= r["to [rpm]"]
    p = associate(present, cd)
    assert p["mode"] == j and p["linear onset [rpm]"] == r["from [rpm]"]


# ---------------------------------------------------------------------------------------------------- progress
def test_study_is_silent_by_default_and_reports_with_progress(tmp_path, capsys):
    cases = grid({"outer_clearance": [36e-6, 40e-6]}, "campbell", speeds_rpm=(1e3, 250e3, 5))
    run_study(cases, tmp_path, scheduler="serial")
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""
    run_study(cases + grid({"outer_clearance": [42e-6]}, "campbell", speeds_rpm=(1e3, 250e3, 5)), tmp_path,
              scheduler="serial", progress=True)
    cap = capsys.readouterr()
    assert "study: 3 cases, 2 already finished, 1 to run" in cap.out
    assert "study" in cap.err and "1/1" in cap.err  # the bar over the cases to run: done / total


def test_compare_run_down_of_a_renamed_system_is_silent_by_default(tmp_path, capsys):
    tc = _renamed(frb.turbocharger())
    table, paths = compare(tc, clearances=(40e-6,), speed_rpm=(30e3, 20e3), duration=0.08, profile="ramp",
                           out_dir=tmp_path, n_speeds=8, runup_kw={"output_rate_hz": 10000})
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""
    assert all(p.exists() for p in paths) and (tmp_path / "co40um" / "composite.png").exists()
    run = frb.RunupResult.load(tmp_path / "co40um")
    assert run.bearing_names == ("front", "rear") and run.speed_rpm[0] > run.speed_rpm[-1]
    # the default node is the system's first disc; a run-down's status column says so
    comps = (tmp_path / "co40um" / "components.csv").read_text()
    assert "vanishes at [rpm]" in comps and "onset estimate" in comps
    # 30 krpm lies above the inner films' whirl onsets (11.0 / 11.7 krpm at c_O = 40 um,
    # docs/theory/parameters.md#reference-numbers): the run
    # starts inside an unstable range, so it shows sub-synchronous whirl that is there from the start (no onset)
    sub = table[table["component"].str.startswith("sub")]
    assert len(sub) >= 1 and set(table["run-down"]) == {"finished"} and "run-up" not in table.columns
    assert sub["onset estimate"].str.startswith("none").any()
