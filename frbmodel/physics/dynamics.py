"""Compiled equations of motion: the rotor acceleration kernel and the monolithic model
(docs/theory/equations-of-motion.md#equations-of-motion).

:func:`rotor_acceleration` is the one implementation of the rotor's equation of motion in compiled code,
q̈ = M⁻¹f − (M⁻¹K + Ω̇ M⁻¹G) q − Ω M⁻¹G q̇, with the constant matrices of :attr:`Rotor.acceleration_matrices`;
the monolithic run-up (:func:`monolithic_rhs`) and the co-simulation rotor step
(:mod:`frbmodel.nonlinear.components`) both call it, the latter with its linearized bearing terms added to the same
matrices. :func:`monolithic_rhs` is dy/dt of the full state [q, q̇, ring_b (x, y, vx, vy) for b = 0, 1, ring
speeds, rotation angle] for a prescribed rotor speed, :func:`monolithic_jac` its finite-difference Jacobian and
:func:`add_unbalance_forces` the rotating unbalance load. The rotor speed is either prescribed (a table) or, for a
torque-driven rotor, a state appended to that layout whose rate is :func:`spin_acceleration`, the one spin
equation (also used by the co-simulation rotor).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.linalg import SUM_FLAGS
from .bearing import ring_rhs_kernel
from .losses import journal_torque_kernel


@njit(cache=True)
def interp_uniform(t, tg, yg):
    """Linear interpolation of ``yg`` on the uniform grid ``tg`` at ``t`` (held constant outside the grid).

    Parameters
    ----------
    t : float
        Time [s] (or any abscissa in the unit of ``tg``).
    tg : ndarray (nt,)
        Uniform, ascending grid [s], nt >= 2.
    yg : ndarray (nt,)
        Values on the grid (any unit, e.g. rotor speed [rad/s]).

    Returns
    -------
    float
        The interpolated value, in the unit of ``yg``.
    """
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
def film_data_at_speed(geom, omega, viscosity_speeds, viscosity_table):
    """The film data at rotor speed ``omega`` [rad/s]: ``geom`` itself without a viscosity table (constant
    viscosities: the same array, so the arithmetic is bit for bit that of the constant films), else a copy whose
    viscosity μ of bearing b's film f is ``viscosity_table[2 b + f]`` interpolated linearly at ``omega`` on the
    uniform speed grid ``viscosity_speeds`` [rad/s] (held constant outside it): quasi-static film temperatures
    (docs/theory/thermal.md#run-ups).

    Parameters
    ----------
    geom : ndarray (2, 2, 4)
        (bearing, film, [R, L, c, μ]) [m, m, m, Pa s].
    omega : float
        Rotor speed [rad/s].
    viscosity_speeds : ndarray (nv,) or None
        Uniform, ascending rotor-speed grid [rad/s].
    viscosity_table : ndarray (4, nv) or None
        Film viscosities [Pa s] on that grid (turbine inner, outer, compressor inner, outer).

    Returns
    -------
    ndarray (2, 2, 4)
    """
    if viscosity_table is None:
        return geom
    g = geom.copy()
    for b in range(2):
        for f in range(2):
            g[b, f, 3] = interp_uniform(omega, viscosity_speeds, viscosity_table[2 * b + f])
    return g


@njit(cache=True)
def add_unbalance_forces(f, phi, w, wd, unb_node, unb_me, unb_phase):
    """Add the rotating unbalance forces m e (Ω² cos θ + Ω̇ sin θ, Ω² sin θ − Ω̇ cos θ), θ = φ + phase, to the
    nodal load vector ``f`` [N] (the one implementation; run-up and rotor FMU both call it).

    Parameters
    ----------
    f : ndarray (n,)
        Nodal load vector [N, N m], 4 DoFs (x, y, θx, θy) per node; modified in place.
    phi : float
        Rotation angle φ of the rotor [rad].
    w, wd : float
        Rotor speed Ω [rad/s] and acceleration Ω̇ [rad/s²].
    unb_node : ndarray (nu,) of int
        Rotor node of each unbalance.
    unb_me : ndarray (nu,)
        Unbalance m e [kg m] of each.
    unb_phase : ndarray (nu,)
        Angular position of each unbalance at φ = 0 [rad].
    """
    for d in range(unb_node.size):
        th = phi + unb_phase[d]
        c, s = math.cos(th), math.sin(th)
        j = 4 * unb_node[d]
        f[j] += unb_me[d] * (w * w * c + wd * s)
        f[j + 1] += unb_me[d] * (w * w * s - wd * c)


@njit(cache=True)
def rotor_operators(minv_k, minv_g, omega, omega_dot, minv_c=None):
    """Stiffness and velocity operators ``(S, D)`` of the rotor acceleration q̈ = M⁻¹f − S q − D q̇.

    Parameters
    ----------
    minv_k, minv_g : ndarray (n, n)
        M⁻¹K and M⁻¹G (:attr:`Rotor.acceleration_matrices`); ``minv_k`` may include linear support stiffness
        M⁻¹K_s (the co-simulation's bearing interface terms).
    omega, omega_dot : float
        Rotor speed Ω [rad/s] and acceleration Ω̇ [rad/s²].
    minv_c : ndarray (n, n), optional
        M⁻¹C_s of linear support damping (none by default).

    Returns
    -------
    S, D : ndarray (n, n)
        S = M⁻¹K + Ω̇ M⁻¹G, D = Ω M⁻¹G (+ M⁻¹C_s).
    """
    s = minv_k + omega_dot * minv_g
    if minv_c is None:
        d = omega * minv_g
    else:
        d = minv_c + omega * minv_g
    return s, d


@njit(cache=True, fastmath=SUM_FLAGS)
def rotor_acceleration(minv, minv_k, minv_g, f, q, qd, omega, omega_dot, minv_c=None):
    """Rotor acceleration of M q̈ + Ω G q̇ + (K + Ω̇ G) q = f (docs/theory/equations-of-motion.md#rotor): the one
    compiled kernel.

    Parameters
    ----------
    minv, minv_k, minv_g : ndarray (n, n)
        M⁻¹, M⁻¹K, M⁻¹G (:attr:`Rotor.acceleration_matrices`); see :func:`rotor_operators` for support terms.
    f : ndarray (n,)
        Nodal load [N, N m] (gravity, unbalance, bearing forces).
    q, qd : ndarray (n,)
        Displacements [m, rad] and velocities [m/s, rad/s].
    omega, omega_dot : float
        Rotor speed [rad/s] and acceleration [rad/s²].
    minv_c : ndarray (n, n), optional
        M⁻¹C_s of linear support damping.

    Returns
    -------
    ndarray (n,)
        q̈ = M⁻¹f − (M⁻¹K + Ω̇ M⁻¹G) q − (Ω M⁻¹G + M⁻¹C_s) q̇ [m/s², rad/s²].
    """
    n = q.size
    acc = np.empty(n)
    for i in range(n):  # one pass without temporaries, vectorized (SUM_FLAGS): 0.11 µs for the 16-DoF rotor (measured)
        a = 0.0
        for j in range(n):
            a += minv[i, j] * f[j] - (minv_k[i, j] + omega_dot * minv_g[i, j]) * q[j] - omega * minv_g[i, j] * qd[j]
            if minv_c is not None:
                a -= minv_c[i, j] * qd[j]
        acc[i] = a
    return acc


def rotor_polar_inertia(rotor):
    """Polar moment of inertia J_p [kg m²] of the rotor about its spin axis: discs plus shaft elements,
    J_p = Σ I_p,disc + Σ ρ (π/32)(D_o⁴ − D_i⁴) l (docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up).

    Parameters
    ----------
    rotor : Rotor
        The rotor.

    Returns
    -------
    float
        J_p [kg m²].

    Examples
    --------
    >>> import frbmodel as frb
    >>> round(rotor_polar_inertia(frb.turbocharger().rotor), 10)
    0.0001261863
    """
    shaft = sum(e.density * 2.0 * e.second_moment * e.length for e in rotor.shaft)
    return float(shaft + sum(d.polar_inertia for d in rotor.discs))


@njit(cache=True)
def spin_acceleration(drive_torque, journal_torques, polar_inertia):
    """Rotor angular acceleration [rad/s²] of the torque-driven spin, J_p Ω̇ = T_drive + Σ_b T_J,b
    (docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up):
    the one implementation of the spin equation (monolithic run-up and co-simulation rotor).

    Parameters
    ----------
    drive_torque : float
        Net external torque about +z [N m] (e.g. turbine minus compressor).
    journal_torques : ndarray (nb,)
        Inner-film torques on the journals about +z [N m] (negative: braking),
        :func:`frbmodel.physics.losses.journal_torque_kernel`.
    polar_inertia : float
        Rotor polar moment of inertia J_p [kg m²] (:func:`rotor_polar_inertia`).

    Returns
    -------
    float
        Ω̇ [rad/s²].
    """
    total = drive_torque
    for b in range(journal_torques.size):
        total += journal_torques[b]
    return total / polar_inertia


@njit(cache=True)
def _bearing_loads(y, f, out, n_r, jn, geom, polys, ring_m, ring_i, grav, w, springs, eps_cap, diag, tj, ax, ay):
    """Add the journal forces of both bearings to ``f`` and write the rings' derivatives into ``out`` (housing
    acceleration ``ax``, ``ay`` [m/s²]); with a ``tj`` of size 2, also the film torques on the journals [N m] (zero
    on springs)."""
    base = 2 * n_r
    ring = np.empty(5)
    dring = np.empty(5)
    for b in range(2):
        j = 4 * jn[b]
        r0 = base + 4 * b
        if tj.size:
            tj[b] = 0.0
        if springs > 0.0:
            f[j] -= springs * y[j]
            f[j + 1] -= springs * y[j + 1]
            for k in range(4):
                out[r0 + k] = 0.0
            out[base + 8 + b] = 0.0
            continue
        for k in range(4):
            ring[k] = y[r0 + k]
        ring[4] = y[base + 8 + b]
        fix, fiy, ei, eo = ring_rhs_kernel(geom[b], polys[b], ring_m[b], ring_i[b], grav, y[j], y[j + 1], y[n_r + j],
                                           y[n_r + j + 1], ring, w, eps_cap, dring, ax, ay)
        diag[2 * b] = ei
        diag[2 * b + 1] = eo
        f[j] += fix
        f[j + 1] += fiy
        for k in range(4):
            out[r0 + k] = dring[k]
        out[base + 8 + b] = dring[4]
        if tj.size:
            tj[b] = journal_torque_kernel(geom[b, 0], y[j] - ring[0], y[j + 1] - ring[1], fix, fiy, w, ring[4],
                                          eps_cap)


@njit(cache=True)
def monolithic_rhs(t, y, out, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me, unb_phase,
                   tg, wg, wdg, springs, eps_cap, diag, housing_acc, housing_mass, polar_inertia=0.0,
                   drive_torque=None, viscosity_speeds=None, viscosity_table=None):
    """dy/dt of the monolithic model for the state [q, q̇, ring_b (x, y, vx, vy) for b = 0, 1, ring speeds,
    rotation angle (, rotor speed)], written into ``out`` and returned.

    Journal, ring and rotor displacements are relative to the rigid bearing housing, which may translate with the
    acceleration ``housing_acc``: every mass then carries the inertial load −m a_h (docs/theory/housing.md);
    ``housing_acc = (0, 0)`` is the fixed housing, bit for bit.

    Parameters
    ----------
    t : float
        Time [s].
    y : ndarray (N,)
        State: q [m, rad], q̇ [m/s, rad/s] (n_r each), ring_b x, y [m], vx, vy [m/s] for b = 0, 1, ring speeds
        [rad/s] (2), rotation angle φ [rad] and, torque-driven, the rotor speed Ω [rad/s]; N = 2 n_r + 11 (+ 1).
    out : ndarray (N,)
        Receives dy/dt.
    eom : tuple of ndarray (n_r, n_r)
        (M⁻¹, M⁻¹K, M⁻¹G) (:attr:`Rotor.acceleration_matrices`).
    f_grav : ndarray (n_r,)
        Nodal gravity load [N].
    n_r : int
        Number of rotor DoFs (4 per node).
    jn : ndarray (2,) of int
        Rotor node of each bearing's journal.
    geom : ndarray (2, 2, 4)
        (bearing, film, [R, L, c, μ]) [m, m, m, Pa s].
    polys : ndarray (2, 2, 2, 5)
        Film correction polynomials (bearing, film, radial/tangential, coefficients).
    ring_m, ring_i : ndarray (2,)
        Ring mass [kg] and polar moment of inertia [kg m²] of each bearing.
    grav : float
        Gravitational acceleration on the rings [m/s²] (along −y).
    unb_node, unb_me, unb_phase : ndarray (nu,)
        Unbalances: node (int), m e [kg m] and phase [rad] (:func:`add_unbalance_forces`).
    tg, wg, wdg : ndarray (nt,)
        Speed profile on a uniform grid: time [s], Ω [rad/s], Ω̇ [rad/s²] (unused when torque-driven, except ``tg``).
    springs : float
        > 0: journals on isotropic linear springs of this stiffness [N/m] instead of films (rings idle); 0: films.
    eps_cap : float
        Eccentricity ratio [-] at which film positions are capped.
    diag : ndarray (4,)
        Receives the film eccentricity ratios [-] (turbine inner, outer, compressor inner, outer).
    housing_acc : ndarray (2,)
        Translational acceleration (a_x, a_y) of the bearing housing [m/s²] (held over an integration call; the
        turbocharger FMU's input).
    housing_mass : ndarray (2, n_r)
        M T_x and M T_y: the rotor mass matrix times the rigid translations along x and y [kg, kg m]
        (:meth:`frbmodel.system.rotor.Rotor.translation_load` of a unit acceleration); unused while ``housing_acc`` is
        0.
    polar_inertia : float
        Rotor polar moment of inertia J_p [kg m²] (torque-driven only).
    drive_torque : ndarray (nt,), optional
        Drive torque [N m] on the grid ``tg``; given, the rotor is torque-driven and its speed is the last state,
        with rate :func:`spin_acceleration`.
    viscosity_speeds, viscosity_table : ndarray, optional
        Film viscosities over rotor speed (:func:`film_data_at_speed`): the thermal model's quasi-static film
        temperatures. None: the constant viscosities of ``geom``, bit for bit.

    Returns
    -------
    ndarray (N,)
        ``out``, holding dy/dt (SI units: the time derivative of each state's unit).
    """
    fb = np.zeros(n_r)
    ax, ay = housing_acc[0], housing_acc[1]
    if drive_torque is None:
        tj = np.empty(0)
        w = interp_uniform(t, tg, wg)
        g = film_data_at_speed(geom, w, viscosity_speeds, viscosity_table)
        _bearing_loads(y, fb, out, n_r, jn, g, polys, ring_m, ring_i, grav, w, springs, eps_cap, diag, tj, ax, ay)
        wd = interp_uniform(t, tg, wdg)
    else:
        tj = np.empty(2)
        w = y[2 * n_r + 11]
        g = film_data_at_speed(geom, w, viscosity_speeds, viscosity_table)
        _bearing_loads(y, fb, out, n_r, jn, g, polys, ring_m, ring_i, grav, w, springs, eps_cap, diag, tj, ax, ay)
        wd = spin_acceleration(interp_uniform(t, tg, drive_torque), tj, polar_inertia)
        out[2 * n_r + 11] = wd
    f = f_grav.copy()
    if ax != 0.0 or ay != 0.0:  # the housing frame's inertial load −M T a_h (skipped at rest: bit for bit as before)
        for i in range(n_r):
            f[i] -= housing_mass[0, i] * ax + housing_mass[1, i] * ay
    add_unbalance_forces(f, y[2 * n_r + 10], w, wd, unb_node, unb_me, unb_phase)
    f += fb  # the bearing loads after the unbalance, as before the torque-driven option (same rounding)
    q = y[:n_r]
    qd = y[n_r:2 * n_r]
    out[:n_r] = qd
    out[n_r:2 * n_r] = rotor_acceleration(eom[0], eom[1], eom[2], f, q, qd, w, wd)
    out[2 * n_r + 10] = w
    return out


@njit(cache=True)
def monolithic_jac(t, y, jac, f0, work, scale, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node,
                   unb_me, unb_phase, tg, wg, wdg, springs, eps_cap, diag, housing_acc, housing_mass, polar_inertia=0.0,
                   drive_torque=None, viscosity_speeds=None, viscosity_table=None):
    """Forward-difference Jacobian of :func:`monolithic_rhs` into ``jac`` (all in compiled code: one RHS call per
    state; step 1.5e-8 · max(|y_k|, scale_k)).

    Parameters
    ----------
    t : float
        Time [s].
    y : ndarray (N,)
        State (as in :func:`monolithic_rhs`).
    jac : ndarray (N, N)
        Receives ∂(dy/dt)/∂y (SI units).
    f0, work : ndarray (N,)
        Work arrays: dy/dt at ``y`` and at the perturbed state.
    scale : ndarray (N,)
        Typical magnitude of each state (its unit), the floor of the difference step.
    eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav
        As in :func:`monolithic_rhs`.
    unb_node, unb_me, unb_phase, tg, wg, wdg, springs, eps_cap, diag, housing_acc, housing_mass, polar_inertia
        As in :func:`monolithic_rhs`; ``drive_torque``, ``viscosity_speeds`` and ``viscosity_table`` too.

    Returns
    -------
    ndarray (N, N)
        ``jac``.
    """
    n = y.size
    monolithic_rhs(t, y, f0, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me, unb_phase,
                   tg, wg, wdg, springs, eps_cap, diag, housing_acc, housing_mass, polar_inertia, drive_torque,
                   viscosity_speeds, viscosity_table)
    yp = y.copy()
    for k in range(n):
        h = 1.5e-8 * max(abs(y[k]), scale[k])
        yp[k] = y[k] + h
        monolithic_rhs(t, yp, work, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me,
                       unb_phase, tg, wg, wdg, springs, eps_cap, diag, housing_acc, housing_mass, polar_inertia,
                       drive_torque, viscosity_speeds, viscosity_table)
        for i in range(n):
            jac[i, k] = (work[i] - f0[i]) / h
        yp[k] = y[k]
    return jac
