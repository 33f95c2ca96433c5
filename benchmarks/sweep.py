"""Benchmark of parameter studies (issue #5): an 8-case run-up study, Dask LocalCluster with 2 worker processes
vs serial, measured in the same run on this machine.

Usage::

    python benchmarks/sweep.py [--duration 0.5]

Cases: outer clearance 36, 38, 40, 42, 44, 46 um x unbalance 0 and 1e-6 kg m would be 12; we take the 8 cases
36..42 um x {0, 1e-6} kg m, each a 20k -> 250k rpm run-up of ``--duration`` seconds. Both runs start from empty
output folders; the Dask run includes starting the cluster (and the workers' numba cache loading).
"""
from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from frbmodel.sweep import grid, run_study


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=0.5)
    args = ap.parse_args(argv)
    cases = grid({"outer_clearance": [36e-6, 38e-6, 40e-6, 42e-6], "unbalance_turbine": [0.0, 1e-6]}, "runup",
                 speed_rpm=(20e3, 250e3), duration=args.duration, profile="ramp")
    tmp = Path(tempfile.mkdtemp(prefix="frb_sweep_bench_"))
    run_study(cases[:1], tmp / "warm", scheduler="serial", progress=lambda m: None)  # numba cache warm
    t0 = time.perf_counter()
    run_study(cases, tmp / "serial", scheduler="serial", progress=lambda m: None)
    t_ser = time.perf_counter() - t0
    t0 = time.perf_counter()
    idx = run_study(cases, tmp / "dask", n_workers=2, progress=lambda m: None)
    t_dask = time.perf_counter() - t0
    case_sum = float(idx["wall time [s]"].sum())
    shutil.rmtree(tmp, ignore_errors=True)
    print(f"{len(cases)} run-up cases (20k -> 250k rpm, {args.duration:g} s simulated each)")
    print(f"{'serial, one process [s]':<40}{t_ser:10.1f}")
    print(f"{'Dask LocalCluster, 2 workers [s]':<40}{t_dask:10.1f}")
    print(f"{'speed-up':<40}{t_ser / t_dask:10.2f}   (2 cores; ideal 2.0)")
    print(f"{'sum of case wall times on the workers [s]':<40}{case_sum:10.1f}   (parallel efficiency "
          f"{case_sum / (2 * t_dask):.0%}; first case per worker loads the compiled kernels)")


if __name__ == "__main__":
    main()
