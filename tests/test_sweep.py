"""Parameter studies on Dask: equality with serial runs, resume after a kill, failing cases (input validation, the
[dist] extra and descending grids: test_rundown_sweep.py)."""
import json
import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

pytest.importorskip("distributed")

from frbmodel.studies.sweep import grid, run_study, run_summary, stability_map  # noqa: E402

SMALL_RUNUP = ["--analysis", "runup", "--speeds", "20000:30000", "--duration", "0.04"]


def _rows(out):
    sm = stability_map(out)
    return sm.drop(columns=[]).sort_values(["case_id", "item"]).reset_index(drop=True)


def test_local_cluster_equals_serial(tmp_path):
    cases = grid({"outer_clearance": [36e-6, 40e-6, 42e-6, 46e-6]}, "campbell", methods=["J"],
                 speeds_rpm=(1e3, 250e3, 40))
    run_study(cases, tmp_path / "serial", scheduler="serial")
    idx = run_study(cases, tmp_path / "dask", n_workers=2)
    assert (idx["status"] == "finished").all() and len(idx) == 4
    summary = run_summary(tmp_path / "dask")  # the new cluster's two workers, each warmed up before its cases
    assert summary["cases_run"] == 4 and len(summary["workers"]) == 2
    assert all(w["warmup_s"] is not None for w in summary["workers"].values())
    a, b = _rows(tmp_path / "serial"), _rows(tmp_path / "dask")
    assert len(a) > 0
    pd.testing.assert_frame_equal(a, b)  # same code, same inputs: identical results, wherever they ran
    # the larger outer clearance destabilises the second forward conical mode earlier (the literature's trend)
    c = a[a["item"] == "forward conical #2"].sort_values("outer_clearance [m]")
    assert c["onset [rpm]"].iloc[0] > c["onset [rpm]"].iloc[-1]


@pytest.mark.slow  # long (4-6 s); run with -m slow (README: the suite's slow checks)
def test_killed_study_resumes_without_recomputing(tmp_path):
    out = tmp_path / "study"
    cmd = [sys.executable, "-m", "frbmodel.cli", "sweep", "--param",
           "outer_clearance=36e-6,38e-6,40e-6,42e-6,44e-6,46e-6", *SMALL_RUNUP, "--serial", "--out", str(out)]
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and len(list((out / "cases").glob("*.json"))) < 2:
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGKILL)  # kill the study mid-way
    p.wait()
    first = {f.name: json.loads(f.read_text())["started"] for f in (out / "cases").glob("*.json")}
    assert 2 <= len(first) < 6, "the kill should land mid-study"
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert f"{len(first)} already finished" in r.stdout
    after = {f.name: json.loads(f.read_text())["started"] for f in (out / "cases").glob("*.json")}
    assert len(after) == 6
    assert all(after[k] == v for k, v in first.items())  # finished cases were not recomputed
    # complete and equal to an uninterrupted run
    ref = tmp_path / "ref"
    cases = grid({"outer_clearance": [36e-6, 38e-6, 40e-6, 42e-6, 44e-6, 46e-6]}, "runup", speed_rpm=(20e3, 30e3),
                 duration=0.04)
    run_study(cases, ref, scheduler="serial")
    pd.testing.assert_frame_equal(_rows(out), _rows(ref))
    assert (pd.read_csv(out / "index.csv")["status"] == "finished").all()


def test_failing_case_is_recorded_and_others_finish(tmp_path):
    # a viscosity this low cannot carry the turbine's load: the equilibrium (eps -> 1) fails for that case only
    cases = grid({"viscosity_turbine": [1e-7, 4.9e-3]}, "runup", speed_rpm=(20e3, 30e3), duration=0.04)
    idx = run_study(cases, tmp_path, scheduler="serial")  # the Dask path is test_local_cluster_equals_serial's
    st = dict(zip(idx["viscosity_turbine [Pa s]"], idx["status"]))
    summary = run_summary(tmp_path)  # one worker, this process, busy for both cases (failed ones count)
    assert summary["scheduler"] == "serial" and list(summary["workers"]) == [f"{os.uname().nodename}:{os.getpid()}"]
    assert summary["workers"][f"{os.uname().nodename}:{os.getpid()}"]["busy_s"] == pytest.approx(
        idx["wall time [s]"].sum(), rel=1e-9)  # the index's wall times are the case files'; 1e-9: summation order
    assert st == {1e-7: "failed", 4.9e-3: "finished"}
    err = idx.loc[idx["status"] == "failed", "error"].iloc[0]
    assert "turbine bearing" in err and "rpm" in err
    # a rerun leaves the failed case alone unless asked to retry it
    idx2 = run_study(cases, tmp_path, scheduler="serial")
    assert list(idx2["status"]) == list(idx["status"])


def test_bad_study_input(tmp_path):
    from frbmodel import ParameterError

    with pytest.raises(ParameterError, match="study parameter"):
        grid({"clearance": [1e-6]})
    with pytest.raises(ParameterError, match="analysis"):
        grid({"outer_clearance": [36e-6]}, "fem")


def test_workers_import_the_clients_frbmodel(tmp_path, monkeypatch):
    """Another frbmodel copy at the head of sys.path (as building FMUs in-process leaves pythonfmu's staging folder)
    must not become the workers' package: they would recompile every kernel (no numba cache) and could run other
    code than the client."""
    from pathlib import Path

    import frbmodel
    from frbmodel.studies.sweep import _client

    decoy = tmp_path / "decoy" / "frbmodel"
    decoy.mkdir(parents=True)
    (decoy / "__init__.py").write_text("raise ImportError('the decoy copy was imported')\n")
    monkeypatch.syspath_prepend(str(decoy.parent))
    client, cluster = _client(None, 1)
    try:
        packages = client.run(lambda: __import__("frbmodel.studies.sweep").studies.sweep.worker_state()["package"])
    finally:
        client.close()
        cluster.close()
    assert set(packages.values()) == {str(Path(frbmodel.__file__).resolve().parent)}


def test_a_study_folder_loads_as_a_result(tmp_path):
    """The folder run_study writes reads back as a StudyResult (the one result contract) whose table is the
    stability map of that folder; saved and loaded again, the table is the same."""
    from frbmodel.studies.result import StudyResult

    cases = grid({"outer_clearance": [36e-6, 46e-6]}, "campbell", methods=["J"], speeds_rpm=(1e3, 250e3, 20))
    run_study(cases, tmp_path / "s", scheduler="serial")
    study = StudyResult.load(tmp_path / "s")
    pd.testing.assert_frame_equal(study.to_dataframe(), stability_map(tmp_path / "s"))
    assert study.parameter == "outer_clearance [m]" and study.meta["cases"] == 2
    study.save(tmp_path / "copy")
    pd.testing.assert_frame_equal(StudyResult.load(tmp_path / "copy").to_dataframe(), study.to_dataframe(),
                                  check_dtype=False)
