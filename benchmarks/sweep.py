"""Benchmark of parameter studies (issues #5 and #13): an 8-case run-up study, serial vs a Dask LocalCluster with
2 worker processes, measured in the same run on this machine.

Usage::

    python benchmarks/sweep.py [--duration 0.5] [--no-running-cluster]

Cases: the outer clearances 36, 38, 40, 42 um x unbalance 0 and 1e-6 kg m, each a 20k -> 250k rpm ramp of
``--duration`` seconds. Every run starts from an empty output folder.

* serial: in this process, after loading the compiled kernels here (:func:`frbmodel.studies.sweep.prepare_worker`, as
the
  Dask workers do), so its time is the cases' alone;
* Dask, new cluster: ``run_study(..., n_workers=2)`` as ``frb sweep`` does it, starting the cluster, loading the
  kernels on each worker once and closing the cluster all included;
* Dask, running cluster (unless ``--no-running-cluster``): the same study on a 2-worker cluster that is already up
  and prepared (``--scheduler tcp://...``): the cases, their scheduling and the two cores' contention only;
* two plain processes (no Dask): the cases split in two by their serial times, run side by side after loading the
  kernels — what two cores give for this work whatever the scheduler (the cases take more CPU time each when both
  cores work).

Printed: wall times, speed-ups, the new cluster's fixed costs, each worker's busy time (its case wall times / the
study's elapsed time) and the cases' CPU times (wall above CPU = waiting for a core).
"""
from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from _cli import positive, run_script  # (benchmarks/ is the script's folder)

from frbmodel.studies.sweep import estimated_cost_s, grid, prepare_worker, run_study, run_summary


def _timed_study(cases, out, **kw):
    """(wall time [s], run summary with this process's CPU time during the study and the index's case times)."""
    t0, c0 = time.perf_counter(), time.process_time()
    idx = run_study(cases, out, progress=False, **kw)
    wall = time.perf_counter() - t0
    assert (idx["status"] == "finished").all(), idx[["case_id", "status", "error"]]
    return wall, run_summary(out) | {"this_process_cpu_s": time.process_time() - c0,
                                     "case_wall_s": idx["wall time [s]"].tolist()}


def _running_cluster_study(cases, out):
    """The study on a 2-worker LocalCluster started before the clock starts and prepared by an earlier (tiny)
    study, as a shared cluster would be."""
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cl:
        tiny = grid({"outer_clearance": [40e-6]}, "campbell", methods=["J"], speeds_rpm=(1e3, 250e3, 10))
        _timed_study(tiny, out.with_name(out.name + "_prep"), scheduler=cl.scheduler_address)
        return _timed_study(cases, out, scheduler=cl.scheduler_address)


def _plain_worker(cases, out, barrier, results):
    """One of two plain processes: load the kernels, wait for the other, run its cases; report (start, end) [s]."""
    from frbmodel.studies.sweep import run_case

    prepare_worker()
    barrier.wait()
    t0 = time.time()
    for case in cases:
        run_case(case, out)
    results.put((t0, time.time()))


def _plain_processes(cases, case_times, out):
    """The machine's bound for any scheduler: the cases split over two plain processes by the serial run's case
    times (longest first onto the less loaded one), both started at once after loading the kernels; returns the
    wall time [s] from the first start to the last end."""
    import multiprocessing as mp

    halves, load = ([], []), [0.0, 0.0]
    for t, case in sorted(zip(case_times, cases), key=lambda x: -x[0]):
        k = int(load[1] < load[0])
        halves[k].append(case)
        load[k] += t
    ctx = mp.get_context("spawn")
    barrier, results = ctx.Barrier(2), ctx.Queue()
    out.mkdir(parents=True, exist_ok=True)
    procs = [ctx.Process(target=_plain_worker, args=(h, out, barrier, results)) for h in halves]
    for p in procs:
        p.start()
    spans = [results.get() for _ in procs]
    for p in procs:
        p.join()
    return max(e for _, e in spans) - min(s for s, _ in spans)


def _worker_lines(summary):
    lines = []
    for name, w in summary["workers"].items():
        lines.append(f"  {name:<38}{w['busy_s']:10.1f}   ({w['cases']} cases; busy {w['busy_fraction']:.0%} of "
                     f"{summary['elapsed_s']:.1f} s; CPU {w['cpu_s']:.1f} s)")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=positive, default=0.5)
    ap.add_argument("--no-running-cluster", action="store_true", help="skip the study on an already running cluster")
    args = ap.parse_args(argv)
    cases = grid({"outer_clearance": [36e-6, 38e-6, 40e-6, 42e-6], "unbalance_turbine": [0.0, 1e-6]}, "runup",
                 speed_rpm=(20e3, 250e3), duration=args.duration, profile="ramp")
    tmp = Path(tempfile.mkdtemp(prefix="frb_sweep_bench_"))
    try:
        t_prep = prepare_worker()["warmup_s"]
        t_ser, s_ser = _timed_study(cases, tmp / "serial", scheduler="serial")
        t_dask, s_dask = _timed_study(cases, tmp / "dask", n_workers=2)
        warm = None if args.no_running_cluster else _running_cluster_study(cases, tmp / "warm")
        t_plain = _plain_processes(cases, s_ser["case_wall_s"], tmp / "plain")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    est = {round(estimated_cost_s(c), 6) for c in cases}
    print(f"{len(cases)} run-up cases (20k -> 250k rpm ramp, {args.duration:g} s simulated each; estimated cost "
          f"{' / '.join(f'{e:.1f}' for e in sorted(est))} s without / with unbalance: those go first)")
    print(f"{'serial, one process [s]':<40}{t_ser:10.1f}   (kernels loaded before: {t_prep:.1f} s)")
    print(f"{'  case wall times [s]':<40}{' '.join(f'{t:.1f}' for t in s_ser['case_wall_s'])}")
    print(f"{'Dask, new LocalCluster, 2 workers [s]':<40}{t_dask:10.1f}")
    print(f"{'speed-up, new cluster':<40}{t_ser / t_dask:10.2f}   (2 cores; ideal 2.0)")
    print(f"{'  cluster start [s]':<40}{s_dask['cluster_start_s']:10.1f}")
    print(f"{'  kernel warm-up on the workers [s]':<40}{s_dask['warmup_s']:10.1f}")
    print(f"{'  cases, first submitted to last done [s]':<40}{s_dask['cases_s']:10.1f}   (half the serial time: "
          f"{t_ser / 2:.1f})")
    print(f"{'  cluster close [s]':<40}{s_dask['close_s']:10.1f}")
    print(f"{'  CPU of this process (client, scheduler)':<40}{s_dask['this_process_cpu_s']:10.1f}")
    print(f"{'  case wall times per worker [s]':<40}")
    print("\n".join(_worker_lines(s_dask)))
    if warm is not None:
        t_warm, s_warm = warm
        print(f"{'Dask, running prepared cluster [s]':<40}{t_warm:10.1f}")
        print(f"{'speed-up, running cluster':<40}{t_ser / t_warm:10.2f}   (2 cores; ideal 2.0)")
        print(f"{'  case wall times per worker [s]':<40}")
        print("\n".join(_worker_lines(s_warm)))
    print(f"{'two plain processes, no Dask [s]':<40}{t_plain:10.1f}   (the cases split by their serial times, "
          "kernels loaded before: the machine's bound for any scheduler)")
    print(f"{'speed-up, plain processes':<40}{t_ser / t_plain:10.2f}")
    if warm is not None:
        print(f"{'Dask running cluster / plain processes':<40}{t_plain / warm[0]:10.2f}   (scheduling efficiency)")
    print(f"{'sum of case wall times, serial [s]':<40}{s_ser['case_wall_sum_s']:10.1f}   (CPU "
          f"{s_ser['case_cpu_sum_s']:.1f} s; Dask, new cluster: wall {s_dask['case_wall_sum_s']:.1f} s, CPU "
          f"{s_dask['case_cpu_sum_s']:.1f} s)")
    print("(a case's wall time above its CPU time is time spent waiting for a core: other processes on the machine)")


if __name__ == "__main__":
    run_script(main)
