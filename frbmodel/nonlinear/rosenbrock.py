"""Compiled Rosenbrock integrator (RODAS, order 4(3), stiffly accurate, L-stable) for the monolithic model.

A Rosenbrock method solves linear systems with the matrix W = I/(hγ) − J instead of iterating Newton to
convergence: one Jacobian and one LU factorization per step, six right-hand sides, no convergence failures when the
film forces are strongly nonlinear (the implicit Radau solver's Newton iteration limits its step there and makes it
refresh its Jacobian on most steps). The coefficients are those of Hairer & Wanner's RODAS (Solving ODEs II,
Sect. VI.4), with its embedded third-order error estimate and its continuous output of order 3, so that output
times do not cut the steps. The Jacobian is the rotor's constant block exactly plus forward differences only in the
columns the films depend on (journal and ring displacements and velocities, ring speeds, and the rotor speed of a
torque-driven rotor), each bearing's columns by differences of that bearing's kernel alone: :func:`jacobian`. The
linear systems are solved reduced to the states after the rotor displacements, whose rows of the Jacobian are
q' = q̇ exactly (:func:`_factor`).

Everything runs in numba-compiled code; one call integrates through a chunk of output times.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.errors import MAX_SPEED_RPM
from ..core.linalg import lu_factor, lu_solve
from ..physics.bearing import ring_rhs_kernel
from ..physics.dynamics import film_data_at_speed, interp_uniform, monolithic_rhs
from ..physics.losses import journal_torque_kernel

#: typical displacement [m] (about a film clearance) that sets the difference steps of the film columns: step
#: 1.5e-8 x max(|y_k|, typical_k), the other states' typical sizes scaled from it as their tolerances are
#: (:func:`frbmodel.nonlinear.runup.atol_vector`); smaller steps drown in round-off (measured: 1 % error in a
# journal-velocity
#: column at 1e-12 m/s steps, 2e-6 at 1e-9 m/s)
FD_TYPICAL_M = 1e-5
#: failure reasons by status code of :func:`rodas_chunk`
STATUS = {1: "step budget exhausted", 2: "step size underflow", 3: "singular iteration matrix",
          4: f"torque-driven rotor speed left 0 < speed <= {MAX_SPEED_RPM:.0e} rpm"}
#: largest rotor speed [rad/s] of a torque-driven run, checked at every step (not only at the output samples: a
#: huge drive torque drives the speed far beyond it between two samples, in millions of ever shorter steps)
OMEGA_MAX = MAX_SPEED_RPM * math.pi / 30.0

#: no modal error norm (:func:`rodas_chunk`'s default)
NO_MODAL = np.zeros((0, 0))

# RODAS (Hairer & Wanner), gamma = 1/4
GAMMA = 0.25
A21, A31, A32 = 1.544, 0.9466785280815826, 0.2557011698983284
A41, A42, A43 = 3.314825187068521, 2.896124015972201, 0.9986419139977817
A51, A52, A53, A54 = 1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950
C21, C31, C32 = -5.6688, -2.430093356833875, -0.2063599157091915
C41, C42, C43 = -0.1073529058151375, -9.594562251023355, -20.47028614809616
C51, C52, C53, C54 = 7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160
C61, C62, C63, C64, C65 = 8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, \
    -6.058818238834054
CC2, CC3, CC4 = 0.386, 0.21, 0.63
D1, D2, D3, D4 = 0.25, -0.1043, 0.1035, -0.03620000000000023
H21, H22, H23, H24, H25 = 10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823, \
    1.025137723295662
H31, H32, H33, H34, H35 = -0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386, \
    -6.594389125716872


@njit(cache=True)
def film_columns(n_r, jn, torque, unbalance):
    """State indices whose Jacobian columns are taken by differences: the journals' x, y and their velocities, both
    rings' x, y, vx, vy, the ring speeds, the rotation angle (with unbalance) and the rotor speed (torque-driven);
    every other column is the rotor's constant block."""
    cols = []
    for b in range(2):
        cols.append(4 * jn[b])
        cols.append(4 * jn[b] + 1)
        cols.append(n_r + 4 * jn[b])
        cols.append(n_r + 4 * jn[b] + 1)
    for k in range(2 * n_r, 2 * n_r + 10):
        cols.append(k)
    if unbalance:
        cols.append(2 * n_r + 10)
    if torque:
        cols.append(2 * n_r + 11)
    return np.array(cols, dtype=np.int64)


@njit(cache=True)
def _bearing_eval(b, y, n_r, jn, geom, polys, ring_m, ring_i, grav, w, eps_cap, ax, ay, torque, dring, ring):
    """Bearing ``b``'s kernel at the state ``y``: journal force (fx, fy) [N], the ring's derivatives into ``dring``
    and, for a torque-driven rotor, the film torque on the journal [N m] (the terms of
    :func:`frbmodel.physics.dynamics.monolithic_rhs` that depend on this bearing's journal, ring and ring speed)."""
    j = 4 * jn[b]
    r0 = 2 * n_r + 4 * b
    for k in range(4):
        ring[k] = y[r0 + k]
    ring[4] = y[2 * n_r + 8 + b]
    fx, fy, _, _ = ring_rhs_kernel(geom[b], polys[b], ring_m[b], ring_i[b], grav, y[j], y[j + 1], y[n_r + j],
                                   y[n_r + j + 1], ring, w, eps_cap, dring, ax, ay)
    tj = 0.0
    if torque:
        tj = journal_torque_kernel(geom[b, 0], y[j] - ring[0], y[j + 1] - ring[1], fx, fy, w, ring[4], eps_cap)
    return fx, fy, tj


@njit(cache=True)
def _bearing_columns(y, jac, yp, scale, omega, omega_dot, args):
    """The Jacobian columns of both bearings' journal (x, y, vx, vy), ring (x, y, vx, vy) and ring-speed states,
    added to ``jac``: forward differences of each bearing's kernel alone (:func:`_bearing_eval`, step 1.5e-8 ·
    max(|y_k|, scale_k)), carried to the rotor's acceleration rows exactly through M⁻¹ (the journal force enters
    q̈ = M⁻¹ f − ... linearly), and, torque-driven, through Ω̇ = (T + Σ T_J) / J_p into the spin row, the rotor's
    Ω̇ M⁻¹G q term and the unbalance's Ω̇ term. The same derivatives as differencing the whole right-hand side, at a
    tenth of its cost and without its cancellation in q̈ (which holds the large M⁻¹K q)."""
    n_r = args[2]
    minv, minv_g = args[0][0], args[0][2]
    jn, polys, ring_m, ring_i, grav = args[3], args[5], args[6], args[7], args[8]
    geom = film_data_at_speed(args[4], omega, args[22], args[23])  # quasi-static viscosities (None: args[4] itself)
    unb_node, unb_me, unb_phase, eps_cap, housing = args[9], args[10], args[11], args[16], args[18]
    torque = y.size > 2 * n_r + 11
    jp = args[20] if torque else 1.0
    dring0, dring, ring = np.empty(5), np.empty(5), np.empty(5)
    # torque-driven: d(q̈)/d(Ω̇) = M⁻¹ (∂f_unbalance/∂Ω̇) − M⁻¹G q
    sens = np.zeros(n_r)
    if torque:
        fu = np.zeros(n_r)
        phi = y[2 * n_r + 10]
        for d in range(unb_node.size):
            th = phi + unb_phase[d]
            fu[4 * unb_node[d]] += unb_me[d] * math.sin(th)
            fu[4 * unb_node[d] + 1] -= unb_me[d] * math.cos(th)
        for i in range(n_r):
            acc = 0.0
            for k in range(n_r):
                acc += minv[i, k] * fu[k] - minv_g[i, k] * y[k]
            sens[i] = acc
    for b in range(2):
        j = 4 * jn[b]
        r0 = 2 * n_r + 4 * b
        local = (j, j + 1, n_r + j, n_r + j + 1, r0, r0 + 1, r0 + 2, r0 + 3, 2 * n_r + 8 + b)
        fx0, fy0, tj0 = _bearing_eval(b, y, n_r, jn, geom, polys, ring_m, ring_i, grav, omega, eps_cap,
                                      housing[0], housing[1], torque, dring0, ring)
        for c in local:
            for i in range(y.size):
                yp[i] = y[i]
            h = 1.5e-8 * max(abs(y[c]), scale[c])
            yp[c] = y[c] + h
            fx, fy, tj = _bearing_eval(b, yp, n_r, jn, geom, polys, ring_m, ring_i, grav, omega, eps_cap,
                                       housing[0], housing[1], torque, dring, ring)
            dfx, dfy, dwd = (fx - fx0) / h, (fy - fy0) / h, (tj - tj0) / (h * jp)
            for i in range(n_r):
                jac[n_r + i, c] += minv[i, j] * dfx + minv[i, j + 1] * dfy + dwd * sens[i]
            for k in range(5):
                jac[r0 + k if k < 4 else 2 * n_r + 8 + b, c] += (dring[k] - dring0[k]) / h
            if torque:
                jac[2 * n_r + 11, c] += dwd


@njit(cache=True)
def jacobian(t, y, f0, jac, work, yp, cols, scale, omega, omega_dot, args):
    """∂(dy/dt)/∂y of :func:`frbmodel.physics.dynamics.monolithic_rhs` into ``jac``: the rotor rows exactly (q' = q̇,
    q̇' = −(M⁻¹K + Ω̇ M⁻¹G) q − Ω M⁻¹G q̇ + ...) in every column, the bearings' journal, ring and ring-speed columns
    added by differences of the bearing kernels (:func:`_bearing_columns`), the remaining columns of ``cols`` (the
    rotation angle with unbalance, a torque-driven rotor speed) by forward differences of the whole right-hand side
    (step 1.5e-8 · max(|y_k|, scale_k)). Journals on linear springs: all of ``cols`` by whole differences. ``f0`` =
    dy/dt at (t, y)."""
    n = y.size
    n_r = args[2]
    minv_k, minv_g = args[0][1], args[0][2]
    springs = args[15] > 0.0
    whole = np.zeros(n, dtype=np.bool_)
    for c in cols:
        whole[c] = springs or c >= 2 * n_r + 10
    for k in range(n):
        if whole[k]:
            continue
        for i in range(n):
            jac[i, k] = 0.0
        if k < n_r:  # displacement column: the stiffness operator
            for i in range(n_r):
                jac[n_r + i, k] = -(minv_k[i, k] + omega_dot * minv_g[i, k])
        elif k < 2 * n_r:  # velocity column: q' = q̇ and the gyroscopic operator
            jac[k - n_r, k] = 1.0
            for i in range(n_r):
                jac[n_r + i, k] = -omega * minv_g[i, k - n_r]
    if not springs:
        _bearing_columns(y, jac, yp, scale, omega, omega_dot, args)
    for c in cols:
        if not whole[c]:
            continue
        for i in range(n):
            yp[i] = y[i]
        h = 1.5e-8 * max(abs(y[c]), scale[c])
        yp[c] = y[c] + h
        monolithic_rhs(t, yp, work, *args)
        for i in range(n):
            jac[i, c] = (work[i] - f0[i]) / h


@njit(cache=True)
def _omegas(t, y, f0, n_r, args):
    """Rotor speed Ω [rad/s] (= dφ/dt) and acceleration Ω̇ [rad/s²] at (t, y)."""
    omega = f0[2 * n_r + 10]
    if y.size > 2 * n_r + 11:  # torque-driven: Ω̇ is the last derivative
        return omega, f0[2 * n_r + 11]
    return omega, interp_uniform(t, args[12], args[14])


@njit(cache=True)
def _error_norm(err, y0, y1, rtol, atol, modal):
    """RMS of err / (atol + rtol max(|y0|, |y1|)); with ``modal`` (m x m, m > 0) the first 2 m entries (the rotor's
    displacements and velocities) are taken in the coordinates ``modal @ q`` and ``modal @ q̇`` first."""
    s = 0.0
    m = modal.shape[0]
    for blk in range(2 if m > 0 else 0):
        off = blk * m
        for k in range(m):
            e, a, b = 0.0, 0.0, 0.0
            for i in range(m):
                e += modal[k, i] * err[off + i]
                a += modal[k, i] * y0[off + i]
                b += modal[k, i] * y1[off + i]
            sc = atol[off + k] + rtol * max(abs(a), abs(b))
            s += (e / sc) ** 2
    for i in range(2 * m, err.size):
        sc = atol[i] + rtol * max(abs(y0[i]), abs(y1[i]))
        s += (err[i] / sc) ** 2
    return math.sqrt(s / err.size)


@njit(cache=True)
def _stage(y, coef, ks, nk, out):
    """out = y + Σ_j coef[j] ks[j] over the first nk stages."""
    for i in range(y.size):
        s = y[i]
        for j in range(nk):
            s += coef[j] * ks[j, i]
        out[i] = s


@njit(cache=True)
def _factor(jac, hg, n_r, w, piv):
    """Factor the iteration matrix W = I/(hγ) − J reduced to the states after the n_r displacements: their rows of
    J are q' = q̇ exactly (:func:`jacobian`), so W x = b gives x_q = hγ (b_q + x_v) and, for the rest z = (q̇, rings,
    spins, angle), R x_z = b_z + hγ J_zq b_q with R = I/(hγ) − J_zz − hγ J_zq (in the q̇ columns): an LU of
    n − n_r instead of n unknowns (a quarter of the work for the Table 2 rotor). ``hg`` = hγ; R and its LU go into
    ``w`` (m, m), m = n − n_r; returns False for a singular matrix."""
    m = w.shape[0]
    fac = 1.0 / hg
    for a in range(m):
        for b in range(m):
            w[a, b] = -jac[n_r + a, n_r + b]
        w[a, a] += fac
        for b in range(n_r):
            w[a, b] -= hg * jac[n_r + a, b]
    return lu_factor(w, piv)


@njit(cache=True)
def _solve(w, piv, jac, hg, n_r, x):
    """Solve W x = b in place (``x`` holds b) with the reduced factors of :func:`_factor`."""
    m = w.shape[0]
    z = np.empty(m)
    for a in range(m):
        acc = x[n_r + a]
        for b in range(n_r):
            acc += hg * jac[n_r + a, b] * x[b]
        z[a] = acc
    lu_solve(w, piv, z)
    for i in range(n_r):
        x[i] = hg * (x[i] + z[i])
    for a in range(m):
        x[n_r + a] = z[a]


@njit(cache=True)
def _stages(t, h, y, f0, fx, w, piv, jac, ks, coef, ynew, rhs, args):
    """The six stages of one RODAS step from (t, y) with the factored W = I/(hγ) − J (``w``, ``piv`` of
    :func:`_factor`, and ``jac``): the stage vectors into ``ks``, the new solution into ``ynew`` (``ks[5]`` is the
    embedded error estimate)."""
    n = y.size
    n_r = args[2]
    hg = h * GAMMA
    # stage 1
    for i in range(n):
        ks[0, i] = f0[i] + h * D1 * fx[i]
    _solve(w, piv, jac, hg, n_r, ks[0])
    # stages 2-5: y + Σ a_ij k_j, f there, + Σ (C_ij / h) k_j (+ h d_i f_t)
    for s in range(1, 6):
        if s == 1:
            coef[0] = A21
            cs, ci, di = CC2, (C21, 0.0, 0.0, 0.0, 0.0), D2
        elif s == 2:
            coef[0], coef[1] = A31, A32
            cs, ci, di = CC3, (C31, C32, 0.0, 0.0, 0.0), D3
        elif s == 3:
            coef[0], coef[1], coef[2] = A41, A42, A43
            cs, ci, di = CC4, (C41, C42, C43, 0.0, 0.0), D4
        elif s == 4:
            coef[0], coef[1], coef[2], coef[3] = A51, A52, A53, A54
            cs, ci, di = 1.0, (C51, C52, C53, C54, 0.0), 0.0
        else:  # s == 5: the embedded stage on y_new = stage-5 point + k5
            cs, ci, di = 1.0, (C61, C62, C63, C64, C65), 0.0
        if s < 5:
            _stage(y, coef, ks, s, ynew)
        else:
            for i in range(n):
                ynew[i] += ks[4, i]
        monolithic_rhs(t + cs * h, ynew, rhs, *args)
        for i in range(n):
            acc = rhs[i] + h * di * fx[i]
            for j in range(s):
                acc += ci[j] / h * ks[j, i]
            ks[s, i] = acc
        _solve(w, piv, jac, hg, n_r, ks[s])
    for i in range(n):
        ynew[i] += ks[5, i]


@njit(cache=True)
def _dense_output(t, h, y, ynew, ks, t_eval, k_out, out):
    """Continuous output (order 3) of the step (t, y) -> (t + h, ynew) at the output times inside (t, t + h], from
    ``t_eval[k_out]`` on, into ``out``; returns the next output index."""
    n = y.size
    while k_out < t_eval.size and t_eval[k_out] <= t + h * (1 + 1e-12):
        th = (t_eval[k_out] - t) / h
        for i in range(n):
            k2 = H21 * ks[0, i] + H22 * ks[1, i] + H23 * ks[2, i] + H24 * ks[3, i] + H25 * ks[4, i]
            k3 = H31 * ks[0, i] + H32 * ks[1, i] + H33 * ks[2, i] + H34 * ks[3, i] + H35 * ks[4, i]
            out[k_out, i] = y[i] + th * ((ynew[i] - y[i]) + (1 - th) * (k2 + th * k3))
        k_out += 1
    return k_out


@njit(cache=True, nogil=True)  # the shooting flows integrate monodromy columns in threads
def rodas_chunk(y0, t_eval, h, rtol, atol, scale, cols, max_steps, max_step, args, modal):
    """Integrate from t_eval[0] through the times t_eval with RODAS (see the module docstring).

    Returns (states at t_eval (k, n), number of rows filled, next step size [s], steps, rejected steps, status:
    0 done, 1 step budget exhausted, 2 step size underflow, 3 singular matrix, 4 a torque-driven speed out of
    range, :data:`OMEGA_MAX`)."""
    n = y0.size
    n_r = args[2]
    out = np.empty((t_eval.size, n))
    out[0] = y0
    ks = np.zeros((6, n))
    f0, fx, work, yp, ynew, rhs = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    jac = np.empty((n, n))
    w = np.empty((n - n_r, n - n_r))
    piv = np.empty(n - n_r, dtype=np.int64)
    coef = np.zeros(5)
    y = y0.copy()
    t = t_eval[0]
    k_out, steps, rejected, status = 1, 0, 0, 0
    t_end = t_eval[-1]
    need_jac = True
    while k_out < t_eval.size:
        if steps >= max_steps:
            status = 1
            break
        h = min(h, t_end - t, max_step)
        if h < 1e-14 * max(abs(t), 1e-3):
            status = 2
            break
        if need_jac:
            monolithic_rhs(t, y, f0, *args)
            omega, omega_dot = _omegas(t, y, f0, n_r, args)
            jacobian(t, y, f0, jac, work, yp, cols, scale, omega, omega_dot, args)
            dt = 1e-7 * max(h, 1e-9)
            monolithic_rhs(t + dt, y, work, *args)
            for i in range(n):
                fx[i] = (work[i] - f0[i]) / dt
            need_jac = False
        if not _factor(jac, h * GAMMA, n_r, w, piv):
            status = 3
            break
        _stages(t, h, y, f0, fx, w, piv, jac, ks, coef, ynew, rhs, args)
        err = _error_norm(ks[5], y, ynew, rtol, atol, modal)
        steps += 1
        if not (err <= 1.0):  # rejected (also NaN)
            rejected += 1
            h *= max(0.2, 0.9 * err ** -0.25) if err == err else 0.25
            continue
        k_out = _dense_output(t, h, y, ynew, ks, t_eval, k_out, out)
        t += h
        for i in range(n):
            y[i] = ynew[i]
        if n > 2 * n_r + 11 and not 0.0 < y[n - 1] <= OMEGA_MAX:  # torque-driven: the speed is the last state
            status = 4
            break
        need_jac = True
        h *= min(5.0, max(0.2, 0.9 * max(err, 1e-10) ** -0.25))
    return out, k_out, h, steps, rejected, status
