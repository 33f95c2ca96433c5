"""Compiled Rosenbrock integrator (RODAS, order 4(3), stiffly accurate, L-stable) for the monolithic model.

A Rosenbrock method solves linear systems with the matrix W = I/(hγ) − J instead of iterating Newton to
convergence: one Jacobian and one LU factorization per step, six right-hand sides, no convergence failures when the
film forces are strongly nonlinear (the implicit Radau solver's Newton iteration limits its step there and makes it
refresh its Jacobian on most steps). The coefficients are those of Hairer & Wanner's RODAS (Solving ODEs II,
Sect. VI.4), with its embedded third-order error estimate and its continuous output of order 3, so that output
times do not cut the steps. The Jacobian is the rotor's constant block exactly plus forward differences only in the
columns the films depend on (journal and ring displacements and velocities, ring speeds, and the rotor speed of a
torque-driven rotor): :func:`jacobian`.

Everything runs in numba-compiled code; one call integrates through a chunk of output times.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .dynamics import interp_uniform, monolithic_rhs
from .errors import MAX_SPEED_RPM
from .linalg import lu_factor, lu_solve

#: typical displacement [m] (about a film clearance) that sets the difference steps of the film columns: step
#: 1.5e-8 x max(|y_k|, typical_k), the other states' typical sizes scaled from it as their tolerances are
#: (:func:`frbmodel.runup.atol_vector`); smaller steps drown in round-off (measured: 1 % error in a journal-velocity
#: column at 1e-12 m/s steps, 2e-6 at 1e-9 m/s)
FD_TYPICAL_M = 1e-5
#: failure reasons by status code of :func:`rodas_chunk`
STATUS = {1: "step budget exhausted", 2: "step size underflow", 3: "singular iteration matrix",
          4: f"torque-driven rotor speed left 0 < speed <= {MAX_SPEED_RPM:.0e} rpm"}
#: largest rotor speed [rad/s] of a torque-driven run, checked at every step (not only at the output samples: a
#: huge drive torque drives the speed far beyond it between two samples, in millions of ever shorter steps)
OMEGA_MAX = MAX_SPEED_RPM * math.pi / 30.0

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
def jacobian(t, y, f0, jac, work, yp, cols, scale, omega, omega_dot, args):
    """∂(dy/dt)/∂y of :func:`frbmodel.dynamics.monolithic_rhs` into ``jac``: the rotor rows of the columns not in
    ``cols`` exactly (q̇' = −(M⁻¹K + Ω̇ M⁻¹G) q − Ω M⁻¹G q̇ + films that do not depend on them; q' = q̇), the columns
    ``cols`` by forward differences (step 1.5e-8 · max(|y_k|, scale_k)). ``f0`` = dy/dt at (t, y)."""
    n = y.size
    n_r = args[2]
    minv_k, minv_g = args[0][1], args[0][2]
    is_fd = np.zeros(n, dtype=np.bool_)
    for c in cols:
        is_fd[c] = True
    for k in range(n):
        if is_fd[k]:
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
    for c in cols:
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
def _error_norm(err, y0, y1, rtol, atol):
    s = 0.0
    for i in range(err.size):
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
def _stages(t, h, y, f0, fx, w, piv, ks, coef, ynew, rhs, args):
    """The six stages of one RODAS step from (t, y) with the factored W = I/(hγ) − J (``w``, ``piv``): the stage
    vectors into ``ks``, the new solution into ``ynew`` (``ks[5]`` is the embedded error estimate)."""
    n = y.size
    # stage 1
    for i in range(n):
        ks[0, i] = f0[i] + h * D1 * fx[i]
    lu_solve(w, piv, ks[0])
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
        lu_solve(w, piv, ks[s])
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
def rodas_chunk(y0, t_eval, h, rtol, atol, scale, cols, max_steps, max_step, args):
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
    w = np.empty((n, n))
    piv = np.empty(n, dtype=np.int64)
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
        fac = 1.0 / (h * GAMMA)
        for i in range(n):
            for j in range(n):
                w[i, j] = -jac[i, j]
            w[i, i] += fac
        if not lu_factor(w, piv):
            status = 3
            break
        _stages(t, h, y, f0, fx, w, piv, ks, coef, ynew, rhs, args)
        err = _error_norm(ks[5], y, ynew, rtol, atol)
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
