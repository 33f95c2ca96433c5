"""Benchmark of the FMI co-simulation (issue #4): co-simulated vs monolithic run-up of the same system.

Usage::

    python benchmarks/cosim.py [--duration 1.0] [--build build]

Builds the FMUs if needed, then runs the 20k -> 250k rpm run-up at c_o = 36 um both monolithically
(frb.runup) and through the FMUs (frbmodel.cosim, fmpy FMU2Slave, interface-Jacobian coupling, macro step from
the SSP) in the same process, after warm-up runs that compile the numba kernels. Prints wall times, their ratio
(target <= 3) and the share of the co-simulation wall time spent inside FMI calls.
"""
from __future__ import annotations

import argparse
import time

import frbmodel as frb
from frbmodel.cosim.build import built_ssp
from frbmodel.cosim.master import CosimStopped, cosimulate


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--build", default="build")
    args = ap.parse_args(argv)
    ssp = built_ssp(args.build)
    tc = frb.turbocharger(36e-6)
    frb.runup(tc, speed_rpm=(20e3, 21e3), duration=0.002, progress=False)
    cosimulate(ssp, "co36", stop_time=0.002, progress=False)
    t0 = time.perf_counter()
    mono = frb.runup(tc, speed_rpm=(20e3, 250e3), duration=args.duration, progress=False)
    t_mono = time.perf_counter() - t0
    t0 = time.perf_counter()
    status = "finished"
    try:
        co = cosimulate(ssp, "co36", stop_time=args.duration, progress=False)
    except CosimStopped as exc:
        co, status = exc.result, f"stopped: {exc}"
    t_co = time.perf_counter() - t0
    n = int(round(co.time[-1] / co.meta["step_size_s"]))
    print(f"run-up 20k -> 250k rpm, {args.duration:g} s simulated, c_o = 36 um")
    print(f"{'monolithic (LSODA, numba) wall [s]':<46}{t_mono:10.2f}")
    print(f"{'co-simulation (3 FMUs, fmpy) wall [s]':<46}{t_co:10.2f}   ({status})")
    print(f"{'ratio co-sim / monolithic':<46}{t_co / t_mono:10.2f}   (target <= 3)")
    print(f"{'macro step [s]':<46}{co.meta['step_size_s']:10.2g}")
    print(f"{'communication points':<46}{n:10d}")
    print(f"{'wall per macro step [ms]':<46}{t_co / max(n, 1) * 1e3:10.3f}")
    print(f"{'share inside FMI calls (incl. FMU physics)':<46}{co.meta['fmi_time_s'] / co.meta['wall_time_s']:10.1%}")
    print(f"{'max eps (4 films), co-sim':<46}{str(co.eccentricity.max(axis=0).round(3)):>30}")
    print(f"{'max eps (4 films), monolithic':<46}{str(mono.eccentricity.max(axis=0).round(3)):>30}")


if __name__ == "__main__":
    main()
