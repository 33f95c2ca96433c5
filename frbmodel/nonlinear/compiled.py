"""Compiled time integration of the monolithic model: no Python call per right-hand-side evaluation.

The run-up's stiff, error-controlled integration by scipy's LSODA calls back into Python for every evaluation of
the right-hand side (~1 million per run-up, 3-5 µs of interpreter overhead each, on a RHS that itself costs
1.5 µs). Here the same RHS, :func:`frbmodel.physics.dynamics.monolithic_rhs` (the one implementation), is wrapped in a
numba C callback and handed to CyRK's compiled implicit Runge-Kutta solver (Radau IIA, order 5, with error
control and its own finite-difference Jacobian), which runs the whole integration loop in C++.

The callback receives its constant data as one flat float64 array (:func:`pack_problem`): a header of sizes and scalars,
then every array of :attr:`frbmodel.nonlinear.runup.Problem.args` flattened in a fixed order. :func:`solve_chunk`
integrates from one output time to the next few (a *chunk*); the run-up records, checks wall contact, progress and
signals between chunks (:func:`frbmodel.nonlinear.runup.runup` with ``integrator="radau"``).

>>> import numpy as np, frbmodel as frb
>>> from frbmodel.nonlinear.runup import SpeedProfile, build_problem, initial_state, atol_vector
>>> p = build_problem(frb.turbocharger(), SpeedProfile.constant(30e3, 1e-3), "short")
>>> y0 = initial_state(p)
>>> packed = pack_problem(p)
>>> out = np.empty_like(y0)
>>> want = p.rhs(0.0, y0, np.empty_like(y0)).copy()
>>> bool(np.allclose(rhs_packed(0.0, y0, out, packed), want, rtol=1e-9, atol=0))  # the same RHS (to round-off)
True
"""
from __future__ import annotations

import functools

import numpy as np
from numba import carray, cfunc, njit, types

from ..physics.dynamics import monolithic_rhs
from .rosenbrock import OMEGA_MAX

#: header of the packed array: n_r, number of unbalances, profile points, torque-driven flag (0/1), spring
#: stiffness [N/m], ε cap [-], gravity [m/s²], polar inertia [kg m²], viscosity-table speeds (0: constant
#: viscosities; the thermal model's quasi-static table otherwise)
HEADER = 9
#: integration methods of the compiled path (CyRK's name)
METHOD = "RADAU"

_SIG = types.void(types.CPointer(types.float64), types.float64, types.CPointer(types.float64),
                  types.CPointer(types.float64))


def pack_problem(problem):
    """The constant data of a run-up problem as one flat float64 array (the compiled callback's ``args``).

    Parameters
    ----------
    problem : frbmodel.nonlinear.runup.Problem
        The problem (:func:`frbmodel.nonlinear.runup.build_problem`).

    Returns
    -------
    ndarray (m,)
        Header (:data:`HEADER` values) followed by M⁻¹, M⁻¹K, M⁻¹G, gravity load, journal nodes, film data,
        correction polynomials, ring masses and inertias, unbalance nodes, m e [kg m] and phases [rad], and the
        profile's time [s], speed [rad/s], acceleration [rad/s²] (and drive torque [N m]) grids.
    """
    (eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, grav, unb_node, unb_me, unb_phase, tg, wg, wdg, springs,
     eps_cap) = problem.args[:17]
    torque = problem.torque_driven
    v_speeds, v_table = problem.args[22], problem.args[23]
    nv = 0 if v_table is None else v_speeds.size
    head = [n_r, unb_node.size, tg.size, 1.0 if torque else 0.0, springs, eps_cap, grav, problem.polar_inertia, nv]
    parts = [np.array(head, dtype=float), *(m.ravel() for m in eom), f_grav, jn, geom.ravel(), polys.ravel(), ring_m,
             ring_i, unb_node, unb_me, unb_phase, tg, wg, wdg]
    if torque:
        parts.append(problem.args[21])
    if nv:
        parts += [v_speeds, v_table.ravel()]
    return np.ascontiguousarray(np.concatenate([np.asarray(a, dtype=float).ravel() for a in parts]))


@njit(cache=True)
def _packed_size(head):
    n_r, nu, nt = int(head[0]), int(head[1]), int(head[2])
    return HEADER + 3 * n_r * n_r + n_r + 2 + 16 + 40 + 4 + 3 * nu + (4 if head[3] > 0 else 3) * nt + 5 * int(head[8])


@njit(cache=True)
def rhs_packed(t, y, out, p):
    """dy/dt of :func:`frbmodel.physics.dynamics.monolithic_rhs` with its data unpacked from ``p``
    (:func:`pack_problem`), written into ``out`` and returned.

    Parameters
    ----------
    t : float
        Time [s].
    y, out : ndarray (N,)
        State and its derivative (SI units; layout of :class:`frbmodel.nonlinear.runup.Problem`).
    p : ndarray (m,)
        Packed problem data.

    Returns
    -------
    ndarray (N,)
        ``out``.
    """
    n_r, nu, nt = int(p[0]), int(p[1]), int(p[2])
    k, nn = HEADER, n_r * n_r
    eom = (p[k:k + nn].reshape((n_r, n_r)), p[k + nn:k + 2 * nn].reshape((n_r, n_r)),
           p[k + 2 * nn:k + 3 * nn].reshape((n_r, n_r)))
    k += 3 * nn
    f_grav = p[k:k + n_r]
    k += n_r
    jn = p[k:k + 2].astype(np.int64)
    geom = p[k + 2:k + 18].reshape((2, 2, 4))
    polys = p[k + 18:k + 58].reshape((2, 2, 2, 5))
    ring_m, ring_i = p[k + 58:k + 60], p[k + 60:k + 62]
    k += 62
    unb_node, unb_me, unb_phase = p[k:k + nu].astype(np.int64), p[k + nu:k + 2 * nu], p[k + 2 * nu:k + 3 * nu]
    k += 3 * nu
    tg, wg, wdg = p[k:k + nt], p[k + nt:k + 2 * nt], p[k + 2 * nt:k + 3 * nt]
    diag = np.empty(4)
    at_rest, no_mass = np.zeros(2), np.zeros((2, n_r))  # a fixed housing (the Radau path has no housing motion)
    nv = int(p[8])
    kv = k + (4 if p[3] > 0 else 3) * nt  # the viscosity table (thermal model) after the profile grids
    if p[3] > 0:
        if not 0.0 < y[y.size - 1] <= OMEGA_MAX:  # torque-driven speed out of range: NaN ends the solver's step
            out[:] = np.nan
            return out
        if nv:
            return monolithic_rhs(t, y, out, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, p[6], unb_node,
                                  unb_me, unb_phase, tg, wg, wdg, p[4], p[5], diag, at_rest, no_mass, p[7],
                                  p[k + 3 * nt:k + 4 * nt], p[kv:kv + nv], p[kv + nv:kv + 5 * nv].reshape((4, nv)))
        return monolithic_rhs(t, y, out, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, p[6], unb_node, unb_me,
                              unb_phase, tg, wg, wdg, p[4], p[5], diag, at_rest, no_mass, p[7],
                              p[k + 3 * nt:k + 4 * nt])
    if nv:
        return monolithic_rhs(t, y, out, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, p[6], unb_node, unb_me,
                              unb_phase, tg, wg, wdg, p[4], p[5], diag, at_rest, no_mass, p[7], None, p[kv:kv + nv],
                              p[kv + nv:kv + 5 * nv].reshape((4, nv)))
    return monolithic_rhs(t, y, out, eom, f_grav, n_r, jn, geom, polys, ring_m, ring_i, p[6], unb_node, unb_me,
                          unb_phase, tg, wg, wdg, p[4], p[5], diag, at_rest, no_mass)


def _rhs_callback(dy, t, y, args):
    """C callback (dy, t, y, args) of the compiled solver around :func:`rhs_packed` (compiled by
    :func:`rhs_callback_address`)."""
    head = carray(args, (HEADER,))
    n = 2 * int(head[0]) + 11 + (1 if head[3] > 0 else 0)
    p = carray(args, (_packed_size(head),))
    rhs_packed(t, carray(y, (n,)), carray(dy, (n,)), p)


@functools.cache
def rhs_callback_address():
    """Address of :func:`_rhs_callback` compiled as a C callback, made (or loaded from numba's cache, ~0.1 s) on first
    use rather than when the module is imported."""
    return cfunc(_SIG, cache=True)(_rhs_callback).address


def solve_chunk(packed, y0, t_eval, rtol, atol, max_steps=10**8, max_step=0.0):
    """Integrate from ``t_eval[0]`` (state ``y0``) through the times ``t_eval`` with the compiled Radau IIA solver.

    CyRK's C entry point is called directly through ctypes (its numba wrapper would be compiled anew in every
    process: ~6 s); the solver then runs without returning to Python until the chunk is done.

    Parameters
    ----------
    packed : ndarray
        Packed problem data (:func:`pack_problem`).
    y0 : ndarray (N,)
        State at ``t_eval[0]`` (SI units).
    t_eval : ndarray (k,)
        Increasing output times [s], k >= 2.
    rtol : float
        Relative tolerance [-].
    atol : ndarray (N,)
        Absolute tolerance per state (each state's unit; :func:`frbmodel.nonlinear.runup.atol_vector`).
    max_steps : int
        Step budget of the chunk.
    max_step : float
        Largest step [s]; 0: unbounded.

    Returns
    -------
    y : ndarray (k', N)
        States at the first k' <= k output times (k' < k when the solver failed).
    steps : int
        Steps the solver took.
    message : str
        "" on success, else the solver's reason.
    """
    from CyRK.cy.common import MAX_SIZE
    from CyRK.cy.pyhelpers import find_ode_method_int
    from CyRK.nb import numba_solver as cy

    y0, t_eval = np.ascontiguousarray(y0, dtype=float), np.ascontiguousarray(t_eval, dtype=float)
    atol, rtols = np.ascontiguousarray(atol, dtype=float), np.array([float(rtol)])
    ptr = cy.c_numba_cysolve_ivp(
        rhs_callback_address(), float(t_eval[0]), float(t_eval[-1]), y0.ctypes.data, y0.size,
        find_ode_method_int(METHOD), 0, 0, packed.ctypes.data, packed.nbytes, int(max_steps), 2000, False,
        t_eval.ctypes.data, t_eval.size, None, None, 0, rtols.ctypes.data, 1, atol.ctypes.data, atol.size,
        float(max_step) if max_step else float(MAX_SIZE), 0.0, True)
    if not ptr:
        raise MemoryError("compiled Radau solver: no result (out of memory?)")
    try:
        size, steps = int(cy.c_get_size(ptr)), int(cy.c_get_steps(ptr))
        y = np.ctypeslib.as_array(cy.c_get_y_ptr(ptr), shape=(size, y0.size)).copy() if size else np.empty((0, y0.size))
        ok = bool(cy.c_get_success(ptr)) and size == t_eval.size
        message = "" if ok else _status_text(int(cy.c_get_status(ptr)))
    finally:
        cy.c_free(ptr)
    return y, steps, message


def _status_text(status):
    """The compiled solver's reason for a status code."""
    from CyRK.nb import numba_solver as cy

    buf = np.zeros(256, dtype=np.uint8)
    cy.c_get_status_msg_buf(status, buf.ctypes.data, buf.size)
    text = bytes(buf[:int(np.argmin(buf))]).decode("ascii", "replace") if buf.any() else ""
    return f"compiled Radau solver: {text or 'failed'} (status {status})"
