"""Benchmark of the monolithic nonlinear run-up (issue #3).

Usage::

    python benchmarks/runup.py [--duration 1.0]

Runs the 20k -> 250k rpm, 1 s simulated run-up of the Table 2 turbocharger at c_o = 36 um (after a short
warm-up that compiles the numba kernels) and prints wall time, simulated seconds per wall second, RHS and
Jacobian evaluations, and the share of the time spent in film-force evaluation (measured with the same
compiled kernels in this run). Reference point from the issue: a public numba + LSODA FRB Jeffcott run-up
(14 states, 10 s simulated) takes 19 s on this machine; ours has 43 states and must stay <= 20 s per 1 s.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

import frbmodel as frb
from frbmodel.dynamics import monolithic_rhs as _rhs
from frbmodel.film import NO_CORRECTION, film_force_kernel
from frbmodel.runup import runup


@njit(cache=True)
def _film_loop(n, geom, y):
    acc = 0.0
    for k in range(n):
        for b in range(2):
            for m in range(2):
                g = geom[b, m]
                fx, fy, e = film_force_kernel(g[0], g[1], g[2], g[3], NO_CORRECTION, NO_CORRECTION,
                                              y[0] + 1e-12 * k, y[1], y[2], y[3], 5000.0, 0.999)
                acc += fx
    return acc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=1.0)
    args = ap.parse_args(argv)
    tc = frb.turbocharger(36e-6)
    runup(tc, speed_rpm=(20e3, 25e3), duration=0.005, progress=False)  # compile / load numba cache
    t0 = time.perf_counter()
    run = runup(tc, speed_rpm=(20e3, 250e3), duration=args.duration, progress=False)
    wall = time.perf_counter() - t0
    nf, nj = run.meta["rhs_evaluations"], run.meta["jacobian_evaluations"]
    n_state = 2 * tc.rotor.n_dof + 11

    # cost of one RHS (compiled, called from compiled code) and of the four film evaluations inside it
    geom = np.array([[[f.radius, f.length, f.clearance, f.viscosity] for f in (b.inner, b.outer)]
                     for b in tc.bearings])
    y = np.array([5e-6, -3e-6, 1e-3, 2e-3])
    _film_loop(10, geom, y)
    reps = 200_000
    t1 = time.perf_counter()
    _film_loop(reps, geom, y)
    t_films = (time.perf_counter() - t1) / reps  # four films
    from frbmodel import runup as runup_mod  # noqa: F401  (the module, for the argument tuple below)

    rotor = tc.rotor
    args_rhs = (rotor.acceleration_matrices, rotor.gravity_load(), rotor.n_dof,
                np.array([1, 2]), geom, np.tile(np.r_[0, 0, 0, 0, 1.0], (2, 2, 2, 1)),
                np.full(2, 7.2e-3), np.full(2, 33.641e-8), 9.81, np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0),
                np.array([0.0, 1.0]), np.array([2e3, 2e4]), np.array([1.8e4, 1.8e4]), 0.0, 0.999, np.zeros(4))
    ys = np.zeros(n_state)
    ys[2 * rotor.n_dof + 8:2 * rotor.n_dof + 10] = 1000.0
    out = np.zeros(n_state)
    _rhs(0.1, ys, out, *args_rhs)
    t1 = time.perf_counter()
    for _ in range(20000):
        _rhs(0.1, ys, out, *args_rhs)
    t_rhs_py = (time.perf_counter() - t1) / 20000  # includes the Python -> numba call overhead

    film_time = (nf + nj * (n_state + 1)) * t_films
    print(f"run-up 20k -> 250k rpm, {args.duration:g} s simulated, c_o = 36 um, short films, {n_state} states")
    print(f"{'wall time [s]':<40}{wall:10.2f}")
    print(f"{'simulated s per wall s':<40}{args.duration / wall:10.4f}")
    print(f"{'RHS evaluations':<40}{nf:10d}")
    print(f"{'Jacobian evaluations (FD, compiled)':<40}{nj:10d}")
    print(f"{'RHS call from Python [us]':<40}{t_rhs_py * 1e6:10.2f}")
    print(f"{'4 film forces, compiled [us]':<40}{t_films * 1e6:10.3f}")
    print(f"{'share of wall time in film evaluation':<40}{film_time / wall:10.1%}")
    print(f"target: <= 20 s wall for 1 s simulated -> ratio {wall / (20.0 * args.duration):.2f} of the budget")


if __name__ == "__main__":
    main()
