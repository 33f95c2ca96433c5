"""Compiled equations of motion of the monolithic model (physics.md §7): the one place where the rotor, both
rings and the nonlinear films are put together.

``rhs`` is dy/dt of the full state [q, q̇, ring_b (x, y, vx, vy) for b = 0, 1, ring speeds, rotation angle]
for a prescribed rotor speed; ``jac`` its finite-difference Jacobian; :func:`add_unbalance_forces` the rotating
unbalance load, shared with the rotor co-simulation component.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .bearing import ring_rhs_kernel


@njit(cache=True)
def interp_uniform(t, tg, yg):
    if t <= tg[0]:
        return yg[0]
    if t >= tg[-1]:
        return yg[-1]
    dt = tg[1] - tg[0]
    k = int((t - tg[0]) / dt)
    if k >= tg.size - 1:
        k = tg.size - 2
    w = (t - tg[k]) / dt
    return yg[k] * (1.0 - w) + yg[k + 1] * w


@njit(cache=True)
def add_unbalance_forces(f, phi, w, wd, unb_node, unb_me, unb_phase):
    """Add the rotating unbalance forces m e (Ω² cos θ + Ω̇ sin θ, Ω² sin θ − Ω̇ cos θ), θ = φ + phase, to the
    nodal load vector ``f`` [N] (the one implementation; run-up and rotor FMU both call it)."""
    for d in range(unb_node.size):
        th = phi + unb_phase[d]
        c, s = math.cos(th), math.sin(th)
        j = 4 * unb_node[d]
        f[j] += unb_me[d] * (w * w * c + wd * s)
        f[j + 1] += unb_me[d] * (w * w * s - wd * c)


@njit(cache=True)
def rhs(t, y, out, minv, k_mat, g_mat, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me,
         unb_phase, tg, wg, wdg, springs, eps_cap, diag):
    """dy/dt for the state [q, q̇, ring_b (x, y, vx, vy) for b = 0, 1, ring speeds, rotation angle].

    ``geom`` (2, 2, 4): (bearing, film, [R, L, c, μ]); ``polys`` (2, 2, 2, 5): correction polynomials;
    ``springs`` > 0: journals on isotropic linear springs of that stiffness [N/m] instead of films (rings idle).
    ``diag`` (4,) receives the film eccentricity ratios (turbine inner, outer, compressor inner, outer).
    """
    w = interp_uniform(t, tg, wg)
    wd = interp_uniform(t, tg, wdg)
    f = f_grav.copy()
    add_unbalance_forces(f, y[2 * n_r + 10], w, wd, unb_node, unb_me, unb_phase)
    base = 2 * n_r
    ring = np.empty(5)
    dring = np.empty(5)
    for b in range(2):
        j = 4 * jn[b]
        r0 = base + 4 * b
        if springs > 0.0:
            f[j] -= springs * y[j]
            f[j + 1] -= springs * y[j + 1]
            out[r0] = 0.0
            out[r0 + 1] = 0.0
            out[r0 + 2] = 0.0
            out[r0 + 3] = 0.0
            out[base + 8 + b] = 0.0
            continue
        for k in range(4):
            ring[k] = y[r0 + k]
        ring[4] = y[base + 8 + b]
        fix, fiy, ei, eo = ring_rhs_kernel(geom[b], polys[b], ring_m[b], ring_i[b], grav, y[j], y[j + 1], y[n_r + j],
                                           y[n_r + j + 1], ring, w, eps_cap, dring)
        diag[2 * b] = ei
        diag[2 * b + 1] = eo
        f[j] += fix
        f[j + 1] += fiy
        for k in range(4):
            out[r0 + k] = dring[k]
        out[base + 8 + b] = dring[4]
    q = y[:n_r]
    qd = y[n_r:2 * n_r]
    for i in range(n_r):
        out[i] = qd[i]
    acc = f - k_mat @ q - (w * g_mat) @ qd - (wd * g_mat) @ q
    out[n_r:2 * n_r] = minv @ acc
    out[base + 10] = w
    return out


@njit(cache=True)
def jac(t, y, jac, f0, work, scale, minv, k_mat, g_mat, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node,
         unb_me, unb_phase, tg, wg, wdg, springs, eps_cap, diag):
    """Forward-difference Jacobian of :func:`rhs` (all in compiled code: one RHS call per state)."""
    n = y.size
    rhs(t, y, f0, minv, k_mat, g_mat, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me,
         unb_phase, tg, wg, wdg, springs, eps_cap, diag)
    yp = y.copy()
    for k in range(n):
        h = 1.5e-8 * max(abs(y[k]), scale[k])
        yp[k] = y[k] + h
        rhs(t, yp, work, minv, k_mat, g_mat, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me,
             unb_phase, tg, wg, wdg, springs, eps_cap, diag)
        for i in range(n):
            jac[i, k] = (work[i] - f0[i]) / h
        yp[k] = y[k]
    return jac
