"""Benchmark of the monolithic nonlinear run-up: the compiled integrators against scipy's LSODA, in the same run.

Usage::

    python benchmarks/runup.py [--duration 1.0] [--repeats 1]

Runs the 20k -> 250k rpm, 1 s simulated run-up of the Table 2 turbocharger at c_o = 36 um with every integrator of
:func:`frbmodel.nonlinear.runup.runup` (after a short warm-up that loads the numba kernels), alternating them
``--repeats``
times, and prints for each the wall time (min over the repeats), solver work, the cost of one compiled RHS, and
the whirl onsets of the runs side by side (the same to 1 % is what the test suite checks on a short run).
Issue #13 targets: compiled path <= 5 s and >= 2x faster than LSODA.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _cli import count, positive, run_script  # (benchmarks/ is the script's folder)
from numba import njit

import frbmodel as frb
from frbmodel.nonlinear.runup import INTEGRATORS, SpeedProfile, build_problem, initial_state, runup
from frbmodel.physics.dynamics import monolithic_rhs
from frbmodel.signals.spectral import spectrogram


@njit(cache=True)
def _rhs_loop(n, y, out, args):
    acc = 0.0
    for _ in range(n):
        monolithic_rhs(0.3, y, out, *args)
        acc += out[0]
    return acc


def _rhs_cost_us(tc):
    """Cost of one compiled RHS [µs], called from compiled code (no interpreter overhead)."""
    p = build_problem(tc, SpeedProfile.ramp(20e3, 250e3, 1.0), tc.film_model)
    y = initial_state(p)
    out = np.empty_like(y)
    _rhs_loop(10, y, out, p.args)
    t0 = time.perf_counter()
    _rhs_loop(200_000, y, out, p.args)
    return (time.perf_counter() - t0) / 200_000 * 1e6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=positive, default=1.0)
    ap.add_argument("--repeats", type=count, default=1)
    args = ap.parse_args(argv)
    tc = frb.turbocharger(36e-6)
    for integrator in INTEGRATORS:  # compile / load the numba kernels of both paths
        runup(tc, speed_rpm=(20e3, 25e3), duration=0.005, integrator=integrator)
    walls, runs = {k: [] for k in INTEGRATORS}, {}
    for _ in range(args.repeats):
        for integrator in INTEGRATORS:
            t0 = time.perf_counter()
            runs[integrator] = runup(tc, speed_rpm=(20e3, 250e3), duration=args.duration, integrator=integrator)
            walls[integrator].append(time.perf_counter() - t0)
    ref = runs["lsoda"]
    print(f"run-up 20k -> 250k rpm, {args.duration:g} s simulated, c_o = 36 um, {tc.film_model} films, "
          f"{2 * tc.rotor.n_dof + 11} states, rtol {ref.meta['rtol']:g}, atol {ref.meta['atol_displacement_m']:g} m; "
          f"wall = min of {args.repeats}")
    names = {"rodas": "rodas (compiled)", "radau": "radau (CyRK)", "lsoda": "lsoda (scipy)"}
    print(f"{'':<30}" + "".join(f"{names[k]:>18}" for k in INTEGRATORS))
    print(f"{'wall time [s]':<30}" + "".join(f"{min(walls[k]):18.2f}" for k in INTEGRATORS))
    lsoda = min(walls["lsoda"])
    print(f"{'speed-up over lsoda':<30}" + "".join(f"{lsoda / min(walls[k]):17.2f}x" for k in INTEGRATORS))
    work = {k: runs[k].meta.get("solver_steps", runs[k].meta.get("rhs_evaluations")) for k in INTEGRATORS}
    print(f"{'steps (lsoda: RHS evaluations)':<30}" + "".join(f"{work[k]:18d}" for k in INTEGRATORS))
    comps = {k: spectrogram(r, "turbine_wheel").components() for k, r in runs.items()}
    for i in range(max(len(c) for c in comps.values())):
        cells = [f"{comps[k][i].label} {comps[k][i].onset_rpm:7.0f}" if i < len(comps[k]) else "-" for k in INTEGRATORS]
        print(f"{'onset [rpm], turbine wheel':<30}" + "".join(f"{c:>18}" for c in cells))
    print(f"{'one compiled RHS [us]':<30}{_rhs_cost_us(tc):18.2f}")
    best = INTEGRATORS[0]
    print(f"default ({best}): {min(walls[best]):.2f} s wall (target <= 5 s), "
          f"{min(walls['lsoda']) / min(walls[best]):.2f}x faster than scipy's LSODA (target >= 2)")

if __name__ == "__main__":
    run_script(main)
