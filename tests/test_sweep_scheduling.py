"""Scheduling of Dask studies (issue 13 item 3): longest-first order from the case options, every worker prepared
(kernels loaded) once however many studies it serves, each worker running its cases longest-first, and the run
summary's busy times. No timing is asserted: the machine is shared."""
import json

import pytest

from frbmodel.studies.sweep import (
    COST_UNBALANCE_FACTOR,
    Case,
    estimated_cost_s,
    longest_first,
    run_study,
    run_summary,
    worker_state,
)


def test_longest_first_order_from_the_options():
    def runup(d, speeds=(20e3, 250e3), profile="ramp"):
        return Case({}, "runup", {"speed_rpm": speeds, "duration": d, "profile": profile})

    # a run-up's estimate is proportional to its simulated time, whatever its speeds and profile (exact ratios up to
    # rounding: 1e-12)
    a, b, c = runup(0.5), runup(1.0, (250e3, 20e3), "exponential"), runup(0.5, (20e3, 30e3))
    assert estimated_cost_s(b) == pytest.approx(2 * estimated_cost_s(a), rel=1e-12)
    assert estimated_cost_s(c) == pytest.approx(estimated_cost_s(a), rel=1e-12)
    # an unbalance (any unbalance_* > 0) makes a run-up dearer by the measured factor; a zero unbalance does not
    forced = Case({"unbalance_compressor": 1e-6}, "runup", dict(a.options))
    zero = Case({"unbalance_turbine": 0.0}, "runup", dict(a.options))
    assert estimated_cost_s(forced) == pytest.approx(COST_UNBALANCE_FACTOR * estimated_cost_s(a), rel=1e-12)
    assert estimated_cost_s(zero) == estimated_cost_s(a)
    assert longest_first([a, zero, forced]) == [forced, a, zero]
    # a Campbell case costs speeds x methods
    small = Case({}, "campbell", {"methods": ["J"], "speeds_rpm": (1e3, 250e3, 50)})
    big = Case({}, "campbell", {"methods": ["J", "F"], "speeds_rpm": (1e3, 250e3, 100)})
    assert estimated_cost_s(big) == pytest.approx(4 * estimated_cost_s(small), rel=1e-12)
    # longest first by simulated time; equal estimates keep their given order (a before c, c before a)
    short = runup(0.04)
    assert longest_first([short, a, b, c]) == [b, a, c, short]
    assert longest_first([short, c, b, a]) == [b, c, a, short]
    # a study mixing analyses: non-increasing estimates, every case once
    mixed = [small, short, big, a, b, Case({}, "cosim", {"duration": 0.01})]
    est = [estimated_cost_s(x) for x in longest_first(mixed)]
    assert est == sorted(est, reverse=True) and sorted(map(id, longest_first(mixed))) == sorted(map(id, mixed))


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A 2-worker LocalCluster of this test module (its workers live across studies, as on a shared cluster)."""
    dist = pytest.importorskip("distributed")
    with dist.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cl, \
            dist.Client(cl, set_as_default=False) as client:
        yield cl, client


def _records(out):
    return [json.loads(f.read_text()) for f in (out / "cases").glob("*.json")]


def test_workers_prepared_once_and_cases_longest_first(cluster, tmp_path):
    cl, client = cluster
    counts = [10, 20, 30, 40, 50, 60]  # speed-grid sizes, given shortest first
    study = [Case({"outer_clearance": 40e-6}, "campbell", {"methods": ["J"], "speeds_rpm": (1e3, 250e3, n)})
             for n in counts]
    idx = run_study(study, tmp_path / "a", scheduler=cl.scheduler_address)
    assert (idx["status"] == "finished").all()
    second = [Case({"outer_clearance": 44e-6}, "campbell", {"methods": ["J"], "speeds_rpm": (1e3, 250e3, n)})
              for n in counts[:2]]
    run_study(second, tmp_path / "b", scheduler=cl.scheduler_address)

    states = client.run(worker_state)
    assert len(states) == 2
    for st in states.values():  # two studies prepared each worker twice; its kernels were loaded once
        assert st["prepare_calls"] == 2 and st["warmups"] == 1 and st["warmup_s"] > 0
    pids = {st["pid"] for st in states.values()}
    recs = _records(tmp_path / "a")
    assert {r["pid"] for r in recs} <= pids
    for pid in pids:  # each worker took the longest case left whenever it became free
        mine = sorted((r for r in recs if r["pid"] == pid), key=lambda r: r["started"])
        sizes = [r["options"]["speeds_rpm"][2] for r in mine]
        assert sizes == sorted(sizes, reverse=True)
    # the summary: both workers, their case counts and busy times from the case files of this run
    s = run_summary(tmp_path / "a")
    assert s["scheduler"] == "dask" and s["cases_run"] == 6 and len(s["workers"]) == 2
    for name, w in s["workers"].items():
        host, pid = name.rsplit(":", 1)
        mine = [r for r in recs if r["pid"] == int(pid)]
        assert w["cases"] == len(mine)
        assert w["busy_s"] == pytest.approx(sum(r["wall_time_s"] for r in mine), rel=1e-9)  # 1e-9: summation order
        assert w["cpu_s"] == pytest.approx(sum(r["cpu_time_s"] for r in mine), rel=1e-9)
        assert w["busy_fraction"] == pytest.approx(w["busy_s"] / s["elapsed_s"], rel=1e-12)
        assert 0 <= w["busy_fraction"] <= 1  # a worker cannot be busy longer than the run
