"""Benchmark of the two-parameter stability chart (issue #14 item 4): the Hopf points of the full model over outer
clearance x viscosity scale, serially and on a 2-worker LocalCluster, in the same run.

Usage::

    python benchmarks/stability_chart.py [--clearances 8] [--viscosities 5] [--out results/bench_chart]

Prints the wall time of each, the speed-up, and writes the chart (stability_chart.png/.csv) of the Dask run.
"""
from __future__ import annotations

import argparse
import shutil
import time
from pathlib import Path

import numpy as np
from _cli import count, run_script  # (benchmarks/ is the script's folder)

from frbmodel.studies.sweep import grid, plot_stability_chart, run_study


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clearances", type=count, default=8, help="outer clearances, 30 ... 50 um")
    ap.add_argument("--viscosities", type=count, default=5, help="viscosity scales, 0.5 ... 2 (geometric)")
    ap.add_argument("--out", default="results/bench_chart")
    args = ap.parse_args(argv)
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    cases = grid({"outer_clearance": list(np.linspace(30e-6, 50e-6, args.clearances)),
                  "viscosity_scale": list(np.geomspace(0.5, 2.0, args.viscosities))}, "hopf", speed_rpm=(1e3, 250e3))
    walls = {}
    for name, kw in (("serial", {"scheduler": "serial"}), ("dask, 2 workers", {"n_workers": 2})):
        t0 = time.perf_counter()
        run_study(cases, out / name.split(",")[0], **kw)
        walls[name] = time.perf_counter() - t0
    plot_stability_chart(out / "dask", "outer_clearance", "viscosity_scale")
    print(f"stability chart: {len(cases)} cases (Hopf points 1 ... 250 krpm), outer clearance x viscosity scale")
    for name, w in walls.items():
        print(f"{name:<20}{w:8.1f} s   {w / len(cases):6.2f} s per case")
    print(f"speed-up on 2 workers: {walls['serial'] / walls['dask, 2 workers']:.2f}x; chart in {out / 'dask'}")


if __name__ == "__main__":
    run_script(main)
