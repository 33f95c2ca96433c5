"""Speed of the limit-cycle tools (issue #14's performance targets), measured in one run on this machine.

Usage::

    python benchmarks/continuation.py [--points 50] [--segments 1]

Prints, for the 36 um system:

* a limit cycle from a good guess: the 61 krpm orbit from the 60 krpm one (target < 2 s);
* a branch through the 60 krpm orbit over 5-150 krpm with ``--points`` points in each direction (the default 2 x 50
  + the start: 101 points; target 100 points < 2 min), its time per point;
* as the same-run baseline, one flow over one period and one Newton step's flows (monodromy + residual), so that the
  per-point cost reads in flows (machines differ; the ratio does not).
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _cli import count, run_script  # (benchmarks/ is the script's folder)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=count, default=50, help="branch points per direction")
    ap.add_argument("--segments", type=count, default=1, help="shooting segments of the branch")
    args = ap.parse_args(argv)

    import frbmodel as frb
    from frbmodel.cycles.continuation import continuation
    from frbmodel.cycles.flow import WORKERS
    from frbmodel.cycles.limitcycle import limit_cycle
    from frbmodel.cycles.shooting import monodromy

    tc = frb.turbocharger(36e-6)
    lc60 = limit_cycle(tc, 60e3)
    t0 = time.perf_counter()
    lc61 = limit_cycle(tc, 61e3, guess=lc60)
    t_orbit = time.perf_counter() - t0

    from frbmodel.cycles.flow import SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, ConstantSpeedFlow
    from frbmodel.nonlinear.runup import SpeedProfile, atol_vector, build_problem

    prob = build_problem(tc, SpeedProfile.constant(61e3, 1.0), tc.film_model)
    flow = ConstantSpeedFlow(prob, SHOOT_RTOL, SHOOT_ATOL_M)
    flow(lc61.state, lc61.period)  # chooses the integrator
    t0 = time.perf_counter()
    end = flow(lc61.state, lc61.period)
    t_flow = time.perf_counter() - t0
    scale = atol_vector(prob, SCALE_M)[0][:-1]
    t0 = time.perf_counter()
    monodromy(flow, lc61.state, lc61.period, scale, end, 1e-4, WORKERS)
    t_newton = time.perf_counter() - t0

    t0 = time.perf_counter()
    bd = continuation(tc, (5e3, 150e3), start=lc60, max_points=args.points, segments=args.segments)
    t_branch = time.perf_counter() - t0
    n = len(bd.points)
    print(f"{'one flow over the period (61 krpm) [s]':<52}{t_flow:8.3f}   ({flow.method})")
    label = f"one monodromy ({scale.size} flows, {WORKERS} threads) [s]"
    print(f"{label:<52}{t_newton:8.3f}   ({t_newton / t_flow:.0f} flow times)")
    print(f"{'limit cycle from a neighbouring orbit [s]':<52}{t_orbit:8.3f}   (target < 2 s; "
          f"{t_orbit / t_flow:.0f} flows)")
    print(f"{'branch, ' + str(n) + ' points, segments = ' + str(args.segments) + ' [s]':<52}{t_branch:8.1f}   "
          f"(target 100 points < 120 s; {t_branch / n:.2f} s = {t_branch / n / t_flow:.0f} flows per point)")
    s = np.array([p.speed_rpm for p in bd.points])
    print(f"{'branch speed range [rpm]':<52}{s.min():8.0f} ... {s.max():.0f}")


if __name__ == "__main__":
    run_script(main)
