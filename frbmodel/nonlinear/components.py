"""Co-simulation components: one floating-ring bearing and the FE rotor as separately steppable models.

These are the physics behind the FMUs (``fmu_src/``), kept here free of any FMI import. Coupling scheme (the staggered
variant of docs/guides/fmus.md): at a communication point the rotor's journal state goes to each bearing, whose force F0
and interface Jacobian K = −∂F/∂x_J, C = −∂F/∂v_J are evaluated at that state. Each bearing first integrates its ring
(lateral and spin; 2-stage L-stable SDIRK substeps with Newton iterations) over the macro step with the journal on a
quadratic path x_p(τ) = x0 + v0 τ + a τ²/2, where a is the backward difference of the journal velocity
(:class:`JournalHistory`), and reports the force F1 at the end of that path. The rotor then integrates its step
(trapezoidal rule, linear-implicitly) with the force interpolated along the path and corrected for the deviation from
it, F(τ) = F0 + (F1 − F0) τ/H + K a τ (H − τ)/2 − K (x − x_p) − C (v − v_p) (:meth:`RotorComponent.step`). Both sides
use :func:`frbmodel.physics.bearing.ring_rhs_kernel` and :func:`frbmodel.physics.film.film_force_kernel`, the same code
as the monolithic run-up; the rotor's accelerations are :func:`frbmodel.physics.dynamics.rotor_acceleration` with the
bearing interface terms added to its matrices.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.errors import (
    ConvergenceError,
    FilmContactError,
    IntegrationError,
    ParameterError,
    check_finite,
    check_positive,
)
from ..core.linalg import lu_factor, lu_solve
from ..core.units import rad_s_to_rpm, rpm_to_rad_s
from ..linear.equilibrium import bearing_equilibrium
from ..linear.thermal import bearing_operating_point, check_oil_supply
from ..physics.bearing import ring_rhs_kernel, ring_speed_ratio
from ..physics.dynamics import (
    add_unbalance_forces,
    rotor_acceleration,
    rotor_operators,
    rotor_polar_inertia,
    spin_acceleration,
)
from ..physics.film import check_model, film_force_kernel
from ..physics.losses import bearing_loss_kernel, film_arrays
from ..system.rotor import GRAVITY
from .runup import check_drive_torque_value, unbalance_arrays

#: default ring integration substep [s] of :class:`BearingComponent` (and of the bearing FMU)
BEARING_SUBSTEP = 5e-6
#: default eccentricity ratio treated as wall contact by :class:`BearingComponent` (and the bearing FMU)
CONTACT_EPS = 0.98
#: default trapezoidal substep [s] of :class:`RotorComponent` (and of the rotor FMU)
ROTOR_SUBSTEP = 5e-6


# --------------------------------------------------------------------------------------------------
# bearing
# --------------------------------------------------------------------------------------------------
@njit(cache=True)
def _bearing_force(geom, polys, ring_m, ring_i, grav, j, ring, omega_r, eps_cap):
    d = np.empty(5)
    fx, fy, ei, eo = ring_rhs_kernel(geom, polys, ring_m, ring_i, grav, j[0], j[1], j[2], j[3], ring, omega_r,
                                     eps_cap, d)
    return fx, fy, ei, eo


@njit(cache=True)
def _inner_film_force(geom, polys, j, ring, omega_r, eps_cap):
    """The film force on the journal [N]: the inner film's force of :func:`frbmodel.physics.bearing.ring_rhs_kernel`
    (the same call of :func:`frbmodel.physics.film.film_force_kernel` with the same relative state), without the outer
    film and the ring's equations, which do not act on the journal."""
    g = geom[0]
    fx, fy, _ = film_force_kernel(g[0], g[1], g[2], g[3], polys[0, 0], polys[0, 1], j[0] - ring[0], j[1] - ring[1],
                                  j[2] - ring[2], j[3] - ring[3], omega_r + ring[4], eps_cap)
    return fx, fy


@njit(cache=True)
def _interface_jacobian(geom, polys, ring_m, ring_i, grav, j, ring, omega_r, eps_cap, K, C):
    """K = −∂F/∂(jx, jy), C = −∂F/∂(jvx, jvy) by central differences of the film force (ring held)."""
    jp = j.copy()
    for k in range(4):
        h = 1e-7 * geom[0, 2] if k < 2 else 1e-7 * geom[0, 2] * max(abs(omega_r), 1.0)
        jp[k] = j[k] + h
        fxp, fyp = _inner_film_force(geom, polys, jp, ring, omega_r, eps_cap)
        jp[k] = j[k] - h
        fxm, fym = _inner_film_force(geom, polys, jp, ring, omega_r, eps_cap)
        jp[k] = j[k]
        if k < 2:
            K[0, k] = -(fxp - fxm) / (2 * h)
            K[1, k] = -(fyp - fym) / (2 * h)
        else:
            C[0, k - 2] = -(fxp - fxm) / (2 * h)
            C[1, k - 2] = -(fyp - fym) / (2 * h)


#: the values of :meth:`BearingComponent.exchange`, in its order (named as the bearing FMU's outputs)
EXCHANGE_OUTPUTS = ("force.x", "force.y", "stiffness.xx", "stiffness.xy", "stiffness.yx", "stiffness.yy",
                    "damping.xx", "damping.xy", "damping.yx", "damping.yy", "eps_inner", "eps_outer",
                    "journal_torque", "power_loss")


#: statuses of :func:`_bearing_exchange`: done, non-finite inputs, a film at its wall (or a non-finite output)
EXCHANGE_OK, EXCHANGE_BAD_INPUT, EXCHANGE_CONTACT = 0, 1, 2


@njit(cache=True)
def _bearing_exchange(geom, polys, ring_m, ring_i, grav, j, ring, omega_r, out):
    """Everything a bearing outputs at a communication point, in one compiled call (layout
    :data:`EXCHANGE_OUTPUTS`): the film force on the journal [N] and the eccentricity ratios (uncapped, as
    :func:`_bearing_force` with ``eps_cap = inf``), K and C (:func:`_interface_jacobian`, ε capped at 0.999, row-major)
    and the journal torque [N m] and friction power of both films [W]
    (:func:`frbmodel.physics.losses.bearing_loss_kernel`,
    uncapped). Returns ``(status, eps_inner, eps_outer)``, status :data:`EXCHANGE_OK`, :data:`EXCHANGE_BAD_INPUT`
    (then ``out`` is not written) or :data:`EXCHANGE_CONTACT`."""
    if not math.isfinite(j[0] + j[1] + j[2] + j[3] + omega_r):
        return EXCHANGE_BAD_INPUT, math.nan, math.nan
    fx, fy, ei, eo = _bearing_force(geom, polys, ring_m, ring_i, grav, j, ring, omega_r, math.inf)
    K = np.empty((2, 2))
    C = np.empty((2, 2))
    _interface_jacobian(geom, polys, ring_m, ring_i, grav, j, ring, omega_r, 0.999, K, C)
    t_j, p_i, p_o = bearing_loss_kernel(geom, polys, j[0], j[1], j[2], j[3], ring, omega_r, math.inf)
    out[0], out[1] = fx, fy
    for i in range(2):
        for k in range(2):
            out[2 + 2 * i + k] = K[i, k]
            out[6 + 2 * i + k] = C[i, k]
    out[10], out[11] = ei, eo
    out[12], out[13] = t_j, p_i + p_o
    total = 0.0
    for k in range(out.size):
        total += out[k]
    return (EXCHANGE_OK if ei < 1.0 and eo < 1.0 and math.isfinite(total) else EXCHANGE_CONTACT), ei, eo


SDIRK_GAMMA = 1.0 - 1.0 / math.sqrt(2.0)  # Alexander's 2-stage SDIRK: L-stable, second order, stiffly accurate


@njit(cache=True)
def _journal_on_path(j0, t, jj):
    """Journal state at time ``t`` on the path x = j0[:2] + j0[2:4] t + j0[4:6] t²/2 (into ``jj``)."""
    jj[0] = j0[0] + j0[2] * t + 0.5 * j0[4] * t * t
    jj[1] = j0[1] + j0[3] * t + 0.5 * j0[5] * t * t
    jj[2] = j0[2] + j0[4] * t
    jj[3] = j0[3] + j0[5] * t


#: largest number of modified-Newton iterations of one SDIRK stage of the ring integrator
NEWTON_MAX_ITER = 12
#: status codes of the ring integrator (:func:`_ring_step`): done; Newton iteration not converged; a non-finite
#: iterate or a singular Newton matrix; non-finite inputs; a non-finite path acceleration; a non-finite result; a
#: film's ε above the contact limit
RING_OK, RING_NOT_CONVERGED, RING_NOT_FINITE, RING_BAD_INPUT, RING_BAD_ACCEL, RING_NON_FINITE_RESULT, RING_CONTACT = \
    0, 1, 2, 3, 4, 5, 6


@njit(cache=True)
def _ring_stage(geom, polys, ring_m, ring_i, grav, jj, w, base, yn, gh, lu, piv, refresh, eps_cap, free_spin,
                rsr_fixed, max_iter, work):
    """Solve Y = base + gh·f(Y) for the ring state (in place in ``yn``, start value on entry) by modified Newton;
    ``lu``, ``piv`` hold the LU factors (:func:`lu_factor`) of J = I − gh ∂f/∂y, recomputed when ``refresh`` or
    when convergence stalls, and reused otherwise (also by the next stages). Without ``free_spin`` the ring speed
    is held at ``rsr_fixed``·w (not iterated). Converged when the last correction is below 1e-10 of the outer
    clearance in position and 1e-9 of the ring speed (at least 1 rad/s) in speed. ``work`` (4, 5): scratch.

    Returns ``(eps_inner, eps_outer, fresh, status, position_correction, speed_correction)``: both ε at the
    solution, whether J was (re)computed, :data:`RING_OK` / :data:`RING_NOT_CONVERGED` / :data:`RING_NOT_FINITE`
    (a non-finite residual or a singular J), and the last correction (|Δx| + |Δy| [m], |Δω_FR| [rad/s])."""
    f, fp, yp, dy = work[0], work[1], work[2], work[3]
    ei, eo = 0.0, 0.0
    fresh = False
    dpos, dspeed = math.inf, math.inf
    for it in range(max_iter):
        if not free_spin:
            yn[4] = rsr_fixed * w
        _, _, ei, eo = ring_rhs_kernel(geom, polys, ring_m, ring_i, grav, jj[0], jj[1], jj[2], jj[3], yn, w,
                                       eps_cap, f)
        total = 0.0
        for k in range(5):
            dy[k] = -((yn[k] - base[k]) - gh * f[k])  # −residual
            total += dy[k]
        if not free_spin:
            dy[4] = 0.0  # prescribed ring speed: row 4 of J is the identity, so Δω_FR = 0
        if not math.isfinite(total):
            return ei, eo, fresh, RING_NOT_FINITE, dpos, dspeed
        if refresh or it >= 4:
            for k in range(5):
                typ = geom[1, 2] if k < 2 else (geom[1, 2] * 1e3 if k < 4 else 10.0)
                d = 1e-7 * max(abs(yn[k]), typ)
                yp[:] = yn
                yp[k] += d
                ring_rhs_kernel(geom, polys, ring_m, ring_i, grav, jj[0], jj[1], jj[2], jj[3], yp, w, eps_cap, fp)
                if not free_spin:
                    fp[4] = f[4]
                for i in range(5):
                    lu[i, k] = (1.0 if i == k else 0.0) - gh * (fp[i] - f[i]) / d
            if not lu_factor(lu, piv):
                return ei, eo, fresh, RING_NOT_FINITE, dpos, dspeed
            refresh = False
            fresh = True
        lu_solve(lu, piv, dy)
        for k in range(5):
            yn[k] += dy[k]
        dpos, dspeed = abs(dy[0]) + abs(dy[1]), abs(dy[4])
        if dpos < 1e-10 * geom[1, 2] and dspeed < 1e-9 * max(abs(yn[4]), 1.0):
            return ei, eo, fresh, RING_OK, dpos, dspeed
    return ei, eo, fresh, RING_NOT_CONVERGED, dpos, dspeed


@njit(cache=True)
def _ring_step(geom, polys, ring_m, ring_i, grav, j, ax, ay, ring, omega_r, omega_r_dot, H, n_sub, eps_cap,
               free_spin, rsr_fixed, max_iter, contact_eps):
    """Integrate the ring ``ring`` over [0, H] with the journal on the path x(t) = j[:2] + j[2:4] t + (ax, ay) t²/2
    (velocity j[2:4] + (ax, ay) t), ``n_sub`` substeps of the 2-stage SDIRK method (L-stable, second order: the
    ring-in-film modes reach ~20 kHz at high speed, where backward Euler's numerical damping shifts the whirl limit
    cycles); modified Newton with one FD Jacobian (LU-factored once) per macro step, refreshed when convergence
    stalls. ``free_spin``: ring speed is a state; else ω_FR = rsr_fixed·ω_R. One compiled call per macro step, with
    the checks of the inputs and of the result: ``ring`` is overwritten with the new state only when the status is
    :data:`RING_OK` (no ε above ``contact_eps``, everything finite).

    Returns ``(status, eps_max, fx, fy, at, dpos, dspeed)``: one of the ``RING_*`` statuses, the largest ε seen and
    the force on the journal [N] at the end of the step (end of the path, new ring state); for
    :data:`RING_NOT_CONVERGED` / :data:`RING_NOT_FINITE`, the stage time ``at`` [s] in the step and the last Newton
    corrections ``dpos`` [m], ``dspeed`` [rad/s]."""
    if not math.isfinite(j[0] + j[1] + j[2] + j[3] + omega_r + omega_r_dot):
        return RING_BAD_INPUT, 0.0, math.nan, math.nan, 0.0, 0.0, 0.0
    if not (math.isfinite(ax) and math.isfinite(ay)):
        return RING_BAD_ACCEL, 0.0, math.nan, math.nan, 0.0, 0.0, 0.0
    g = SDIRK_GAMMA
    h = H / n_sub
    j0 = np.empty(6)
    j0[:4] = j
    j0[4], j0[5] = ax, ay
    work = np.empty((4, 5))
    buf = np.empty((4, 5))
    y, y1, y2, base = buf[0], buf[1], buf[2], buf[3]
    lu = np.empty((5, 5))
    piv = np.empty(5, np.int64)
    jj = np.empty(4)
    y[:] = ring
    eps_max = 0.0
    have_jac = False
    k_end = np.zeros(5)  # f at the end of the last substep (stiffly accurate: (Y2 − base) / γh), the predictor
    for s in range(n_sub):
        # stage 1 at t + γh: Y1 = y + γh f(Y1), started at y + γh f(y) with f(y) from the last substep
        ta = (s + g) * h
        _journal_on_path(j0, ta, jj)
        for k in range(5):
            y1[k] = y[k] + g * h * k_end[k]
        ei, eo, fresh, st, dpos, dspeed = _ring_stage(geom, polys, ring_m, ring_i, grav, jj,
                                                      omega_r + omega_r_dot * ta, y, y1, g * h, lu, piv,
                                                      not have_jac, eps_cap, free_spin, rsr_fixed, max_iter, work)
        if st != RING_OK:
            return st, eps_max, math.nan, math.nan, ta, dpos, dspeed
        have_jac = have_jac or fresh
        eps_max = max(eps_max, ei, eo)
        # stage 2 at t + h: Y2 = y + (1 − γ) h k1 + γh f(Y2), k1 = (Y1 − y) / (γh); y_new = Y2
        c = (1.0 - g) / g
        for k in range(5):
            base[k] = y[k] + c * (y1[k] - y[k])
        tb = (s + 1) * h
        _journal_on_path(j0, tb, jj)
        for k in range(5):  # started at y + h k1 (f(Y2) ≈ k1 = (Y1 − y) / γh)
            y2[k] = y[k] + (y1[k] - y[k]) / g
        ei, eo, _, st, dpos, dspeed = _ring_stage(geom, polys, ring_m, ring_i, grav, jj, omega_r + omega_r_dot * tb,
                                                  base, y2, g * h, lu, piv, False, eps_cap, free_spin, rsr_fixed,
                                                  max_iter, work)
        if st != RING_OK:
            return st, eps_max, math.nan, math.nan, tb, dpos, dspeed
        for k in range(5):
            k_end[k] = (y2[k] - base[k]) / (g * h)
        y[:] = y2
        eps_max = max(eps_max, ei, eo)
    _journal_on_path(j0, H, jj)
    fx, fy, _, _ = ring_rhs_kernel(geom, polys, ring_m, ring_i, grav, jj[0], jj[1], jj[2], jj[3], y,
                                   omega_r + omega_r_dot * H, eps_cap, work[0])
    if not math.isfinite(fx + fy + y[0] + y[1] + y[2] + y[3] + y[4]):
        return RING_NON_FINITE_RESULT, eps_max, fx, fy, H, 0.0, 0.0
    if eps_max > contact_eps:
        return RING_CONTACT, eps_max, fx, fy, H, 0.0, 0.0
    ring[:] = y
    return RING_OK, eps_max, fx, fy, -1.0, 0.0, 0.0


class JournalHistory:
    """Journal acceleration estimate for the bearing's quadratic journal path: the backward difference of the
    journal velocity between the last two communication points, a = (v_n − v_{n−1}) / (t_n − t_{n−1}).

    The bearing integrates its ring over a macro step along an extrapolated journal path; with the linear path
    x_n + v_n τ the ring sees a journal that misses the curvature of the whirl orbit (error a τ²/2), which over
    many steps acts like a change of film damping. The backward-difference acceleration (the mean acceleration
    over the last step) removes that error to O(H³) and is insensitive to the journal's high-frequency content,
    unlike the instantaneous acceleration. Needs only the bearing's own inputs, so it works with any master.
    A first call, a gap longer than ``max_gap`` steps or a non-increasing time give zero (linear path).

    Parameters
    ----------
    max_gap : float
        Largest time between two communication points, in macro steps ``H``, over which the backward difference
        is still used.

    Examples
    --------
    >>> h = JournalHistory()
    >>> h.acceleration(0.0, [0.0, 0.0, 1e-3, 0.0], 1e-5)  # first call: linear path
    array([0., 0.])
    >>> h.update(0.0, [0.0, 0.0, 1e-3, 0.0])
    >>> h.acceleration(1e-5, [0.0, 0.0, 2e-3, 0.0], 1e-5)  # (2e-3 - 1e-3) m/s / 1e-5 s
    array([100.,   0.])
    """

    def __init__(self, max_gap=4.0):
        self.max_gap = float(max_gap)
        self.t = None
        self._vx, self._vy = 0.0, 0.0

    @property
    def v(self):
        """The remembered journal velocity (vx, vy) [m/s] (ndarray (2,)), or None for an empty history."""
        return None if self.t is None else np.array([self._vx, self._vy])

    def acceleration(self, t, journal, H):
        """Journal acceleration [m/s²] (2,) at time ``t`` [s] for the input ``journal`` (x, y, vx, vy).

        Parameters
        ----------
        t : float
            Time of the communication point [s].
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s] at ``t``.
        H : float
            Macro step [s] (sets the largest gap, ``max_gap * H``).

        Returns
        -------
        ndarray (2,)
            a_x, a_y [m/s²]; zero without a usable previous point.
        """
        return np.array(self.acceleration_xy(t, float(journal[2]), float(journal[3]), H))

    def acceleration_xy(self, t, vx, vy, H):
        """:meth:`acceleration` from the journal velocity as plain floats (the per-step path of the bearing).

        Parameters
        ----------
        t : float
            Time of the communication point [s].
        vx, vy : float
            Journal velocity [m/s] at ``t``.
        H : float
            Macro step [s].

        Returns
        -------
        tuple of float
            a_x, a_y [m/s²]; zero without a usable previous point.
        """
        if self.t is None or not (0.0 < t - self.t <= self.max_gap * H):
            return 0.0, 0.0
        dt = t - self.t
        return (vx - self._vx) / dt, (vy - self._vy) / dt

    def update(self, t, journal):
        """Remember the journal velocity at time ``t`` [s] for the next :meth:`acceleration`.

        Parameters
        ----------
        t : float
            Time of the communication point [s].
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s] at ``t``.
        """
        self.t = float(t)
        self._vx, self._vy = float(journal[2]), float(journal[3])

    def state(self):
        """The history as plain data (for FMU get/set state).

        Returns
        -------
        list of float or None
            ``[t [s], vx [m/s], vy [m/s]]``, or None for an empty history.
        """
        return None if self.t is None else [self.t, self._vx, self._vy]

    def set_state(self, st):
        """Restore a state from :meth:`state`.

        Parameters
        ----------
        st : list of float or None
            ``[t [s], vx [m/s], vy [m/s]]``, or None for an empty history.
        """
        if st is None:
            self.t, self._vx, self._vy = None, 0.0, 0.0
        else:
            self.t, self._vx, self._vy = float(st[0]), float(st[1]), float(st[2])


class BearingComponent:
    """One floating-ring bearing for co-simulation: ring lateral + spin state, nonlinear films.

    Parameters
    ----------
    bearing : FloatingRingBearing
        The bearing (films, ring mass and inertia).
    film_model : {"short", "short_corrected"}
        Film model.
    ring_speed_model : {"free", "rsr_eq6", "rsr_eq7"}
        "free": ring speed is a state driven by the film torques (method J in the linear analysis);
        "rsr_eq6": ω_FR = RSR(6)·ω_R; "rsr_eq7": eq. (7) at the current ε's (evaluated per step).
    gravity : float
        Gravitational acceleration on the ring [m/s²].
    substep : float
        Ring integration substep [s] of the 2-stage SDIRK method (default 5e-6: at 150 krpm in the developed whirl
        the limit cycle changes by < 0.1 % between 5e-6 and 1e-6; backward Euler needed < 5e-7 for that).
    contact_eps : float
        Eccentricity ratio [-] treated as wall contact by :meth:`step`.

    Examples
    --------
    At the method-J equilibrium the film force on the journal carries the journal's static load:

    >>> import frbmodel as frb
    >>> from frbmodel.core.units import rpm_to_rad_s
    >>> tc = frb.turbocharger()
    >>> bc = BearingComponent(tc.bearings[0])
    >>> x, y = bc.initialize_equilibrium(tc.bearing_loads[0], rpm_to_rad_s(100e3))
    >>> force, K, C, eps = bc.outputs([x, y, 0.0, 0.0], rpm_to_rad_s(100e3))
    >>> bool(abs(force[1] - tc.bearing_loads[0]) < 1e-9 * tc.bearing_loads[0]), K.shape
    (True, (2, 2))
    """

    def __init__(self, bearing, film_model="short", ring_speed_model="free", gravity=GRAVITY, substep=BEARING_SUBSTEP,
                 contact_eps=CONTACT_EPS):

        self.bearing = bearing
        self.film_model = check_model(film_model)
        if ring_speed_model not in ("free", "rsr_eq6", "rsr_eq7"):
            raise ParameterError(f"ring_speed_model = {ring_speed_model!r} is unknown; valid: 'free', 'rsr_eq6', "
                                 "'rsr_eq7'")
        self.ring_speed_model = ring_speed_model
        self.gravity = float(gravity)
        self.substep = float(substep)
        self.contact_eps = float(contact_eps)
        self.geom, self.polys = film_arrays(bearing, self.film_model)
        self.ring = np.zeros(5)  # x, y [m], vx, vy [m/s], ω_FR [rad/s]
        self.rsr6 = ring_speed_ratio(bearing)
        self.eps = (0.0, 0.0)
        self.force_end = np.zeros(2)
        self.history = JournalHistory()
        self.path_accel = np.zeros(2)
        self.newton_max_iter = NEWTON_MAX_ITER
        self._thermal = None  # the thermal model's table (use_oil), None: constant viscosities

    def use_oil(self, oil_supply, load_N, speeds_rad_s):
        """Switch the thermal model on: the films' viscosities follow the rotor speed through the thermal operating
        points of this bearing (:func:`frbmodel.linear.thermal.bearing_operating_point`, quasi-static temperatures,
        docs/theory/thermal.md#bearing-fmu) at ``speeds_rad_s``, interpolated linearly (held outside the grid).

        Parameters
        ----------
        oil_supply : OilSupply
            Oil, supply temperature [K] and pressure [Pa], coefficients.
        load_N : float
            The bearing's static load [N] (the operating point is the method-J equilibrium under it).
        speeds_rad_s : array_like
            Ascending rotor speeds [rad/s] of the table (> 0).
        """

        sup = check_oil_supply(oil_supply, bearings=(self.bearing,))
        speeds = np.asarray(speeds_rad_s, dtype=float)
        if speeds.ndim != 1 or speeds.size < 2 or not np.all(np.diff(speeds) > 0) or not speeds[0] > 0:
            raise ParameterError(f"{self.bearing.name} bearing thermal table speeds are invalid: at least 2 ascending "
                                 "speeds > 0 rad/s")
        self._thermal = {"speeds": speeds, "load": float(load_N)}
        self.set_supply(sup)

    def set_supply(self, oil_supply):
        """Recompute the thermal table for a new supply state (:meth:`use_oil` first)."""

        if self._thermal is None:
            raise ParameterError(f"{self.bearing.name} bearing: an oil supply needs the thermal model (use_oil): "
                                 "the component has constant viscosities")
        th = self._thermal
        rows = [bearing_operating_point(self.bearing, th["load"], rad_s_to_rpm(w), oil_supply, self.film_model,
                                        self.gravity) for w in th["speeds"]]
        for key, cols in (("viscosity", ("inner viscosity [Pa s]", "outer viscosity [Pa s]")),
                          ("temperature", ("inner film temperature [K]", "outer film temperature [K]"))):
            th[key] = np.array([[r[c] for r in rows] for c in cols])
        th["flow"] = np.array([r["inner flow [m^3/s]"] + r["outer flow [m^3/s]"] for r in rows])
        th["supply"] = oil_supply

    @property
    def supply(self):
        """The :class:`~frbmodel.linear.thermal.OilSupply` of the thermal table (None: constant viscosities)."""
        return None if self._thermal is None else self._thermal["supply"]

    def _at_speed(self, omega_rotor):
        """With the thermal model, the films' viscosities [Pa s] of the table at ``omega_rotor`` into the film data
        (constant viscosities: nothing, the arithmetic is unchanged)."""
        th = self._thermal
        if th is not None:
            for f in range(2):
                self.geom[f, 3] = np.interp(float(omega_rotor), th["speeds"], th["viscosity"][f])

    def thermal_outputs(self, omega_rotor):
        """Inner and outer film temperatures [K] and the oil flow through both films [m³/s] of the thermal operating
        point at ``omega_rotor`` [rad/s] (the table interpolated linearly; thermal model on)."""
        th = self._thermal
        if th is None:
            raise ParameterError(f"{self.bearing.name} bearing: thermal outputs need the thermal model (use_oil)")
        w = float(omega_rotor)
        return (float(np.interp(w, th["speeds"], th["temperature"][0])),
                float(np.interp(w, th["speeds"], th["temperature"][1])), float(np.interp(w, th["speeds"], th["flow"])))

    def initialize_equilibrium(self, load, omega_rotor):
        """Put the ring at the method-J equilibrium for a vertical journal load at a rotor speed.

        Parameters
        ----------
        load : float
            Static journal load [N] (downward, as ``Turbocharger.bearing_loads``).
        omega_rotor : float
            Rotor speed [rad/s].

        Returns
        -------
        ndarray (2,)
            The journal position x, y [m] of that equilibrium.
        """
        from dataclasses import replace


        self._at_speed(omega_rotor)
        b = self.bearing
        if self._thermal is not None:  # the films at the table's viscosities of this speed
            b = replace(b, inner=replace(b.inner, viscosity=float(self.geom[0, 3])),
                        outer=replace(b.outer, viscosity=float(self.geom[1, 3])))
        eq = bearing_equilibrium(b, load, omega_rotor, "J", self.film_model, self.gravity)
        self.ring[:] = [eq.ring[0], eq.ring[1], 0.0, 0.0, eq.ring_speed]
        return eq.journal

    def _args(self):
        return self.geom, self.polys, self.bearing.ring_mass, self.bearing.ring_inertia, self.gravity

    def _check(self, journal, omega_rotor):
        j = self._vector(journal, omega_rotor)
        if not math.isfinite(j.sum() + omega_rotor):
            raise self._bad_inputs(journal, omega_rotor)
        return j

    def _vector(self, journal, omega_rotor):
        """``journal`` as an ndarray (4,) of float (finiteness is checked by the caller or its kernel)."""
        j = np.asarray(journal, dtype=float)
        if j.shape != (4,):
            raise self._bad_inputs(journal, omega_rotor)
        return j

    def _bad_inputs(self, journal, omega_rotor):
        return ParameterError(f"{self.bearing.name} bearing inputs must be finite: journal = {journal!r} "
                              f"[m, m, m/s, m/s], rotor speed = {omega_rotor!r} rad/s")

    def _ring_for_force(self, omega_rotor):
        """The ring state the film forces are evaluated with: the state itself for a free ring (not a copy: the
        kernels do not write it), else a copy with the ring speed of the ring speed model."""
        if self.ring_speed_model == "free":
            return self.ring
        ring = self.ring.copy()
        ring[4] = self._speed_ratio() * omega_rotor
        return ring

    def _speed_ratio(self):
        """ω_FR / ω_R of the "rsr_eq6" / "rsr_eq7" ring speed models (eq. (7) at the last ε's)."""
        if self.ring_speed_model == "rsr_eq6":
            return self.rsr6

        return ring_speed_ratio(self.bearing, min(self.eps[0], 0.99), min(self.eps[1], 0.99))

    def ring_speed(self, omega_rotor):
        """The ring speed the forces are evaluated with.

        Parameters
        ----------
        omega_rotor : float
            Rotor speed [rad/s].

        Returns
        -------
        float
            ω_FR [rad/s]: the state's for a free ring, else the ring speed model's at ``omega_rotor``.
        """
        return float(self.ring[4] if self.ring_speed_model == "free" else self._speed_ratio() * omega_rotor)

    def exchange(self, journal, omega_rotor, out=None):
        """Everything the bearing outputs at a communication point, at the current inputs and ring state, in one
        compiled call: force, interface Jacobian, eccentricities and losses (layout :data:`EXCHANGE_OUTPUTS`).

        The same kernels as :meth:`outputs` and :meth:`losses` (bit for bit); sets :attr:`eps`.

        Parameters
        ----------
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s].
        omega_rotor : float
            Rotor speed [rad/s].
        out : ndarray (14,), optional
            Written and returned (default: a new array).

        Returns
        -------
        ndarray (14,)
            force x, y [N]; K = −∂F/∂(x, y) [N/m] and C = −∂F/∂(vx, vy) [N s/m] row-major (ring held); ε inner,
            outer [-]; inner-film torque on the journal about +z [N m]; friction power of both films [W].

        Raises
        ------
        ParameterError
            Non-finite inputs.
        FilmContactError
            When an ε reaches 1 (or an output is not finite).
        """
        j = self._vector(journal, omega_rotor)
        out = np.empty(len(EXCHANGE_OUTPUTS)) if out is None else out
        w = float(omega_rotor)
        self._at_speed(w)
        status, ei, eo = _bearing_exchange(*self._args(), j, self._ring_for_force(w), w, out)
        if status == EXCHANGE_BAD_INPUT:
            raise self._bad_inputs(journal, omega_rotor)
        if status != EXCHANGE_OK:
            raise FilmContactError(f"{self.bearing.name} bearing, {'inner' if not ei < 1 else 'outer'} film: "
                                   f"eccentricity ratio {max(ei, eo):.4g} >= 1 (the member touches its wall)")
        self.eps = (ei, eo)
        return out

    def outputs(self, journal, omega_rotor):
        """Force on the journal and interface Jacobians at the current inputs and ring state.

        Parameters
        ----------
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s].
        omega_rotor : float
            Rotor speed [rad/s].

        Returns
        -------
        force : ndarray (2,)
            Film force on the journal [N].
        K : ndarray (2, 2)
            −∂F/∂(x, y) of the journal [N/m] (ring held).
        C : ndarray (2, 2)
            −∂F/∂(vx, vy) of the journal [N s/m] (ring held).
        eps : tuple of float
            Eccentricity ratios (inner, outer) [-].

        Raises
        ------
        ParameterError
            Non-finite inputs.
        FilmContactError
            When an ε reaches 1.
        """
        out = self.exchange(journal, omega_rotor)
        return out[0:2].copy(), out[2:6].reshape(2, 2).copy(), out[6:10].reshape(2, 2).copy(), self.eps

    def losses(self, journal, omega_rotor):
        """Film torque on the journal and friction power of both films at the current inputs and ring state.

        Parameters
        ----------
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s].
        omega_rotor : float
            Rotor speed [rad/s].

        Returns
        -------
        journal_torque : float
            Inner-film torque on the journal about +z [N m] (negative: it brakes the rotor).
        power_loss : float
            Friction power of the inner and outer film [W] (:func:`frbmodel.physics.losses.bearing_loss_kernel`).

        Raises
        ------
        FilmContactError
            When an ε reaches 1.
        """
        j = self._check(journal, omega_rotor)
        self._at_speed(omega_rotor)
        ring = self._ring_for_force(omega_rotor)
        t_j, p_i, p_o = bearing_loss_kernel(self.geom, self.polys, j[0], j[1], j[2], j[3], ring, float(omega_rotor),
                                            math.inf)
        if not (math.isfinite(t_j) and math.isfinite(p_i) and math.isfinite(p_o)):
            raise FilmContactError(f"{self.bearing.name} bearing: a film's eccentricity ratio is >= 1 (the member "
                                   "touches its wall)")
        return float(t_j), float(p_i + p_o)

    def step(self, journal, omega_rotor, omega_rotor_dot, H, t=None, accel=None):
        """Advance the ring by ``H`` [s] with the journal extrapolated quadratically from ``journal``.

        By default the journal acceleration is the :class:`JournalHistory` estimate at time ``t`` (zero, i.e. a
        linear path, when ``t`` is None). Afterwards ``force_end`` [N] is the force on the journal at the end of
        the step on that path and ``path_accel`` [m/s²] the acceleration used. The ring integration is one
        compiled call (:func:`_ring_step`); on any error the component's state is left at the start of the step.

        Parameters
        ----------
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s] at the start of the step.
        omega_rotor : float
            Rotor speed at the start of the step [rad/s].
        omega_rotor_dot : float
            Rotor angular acceleration over the step [rad/s²].
        H : float
            Macro step [s].
        t : float, optional
            Time at the start of the step [s] (for the :class:`JournalHistory`).
        accel : array_like (2,), optional
            Journal acceleration [m/s²] of the path (overrides the history estimate).

        Returns
        -------
        float
            Largest eccentricity ratio [-] of both films during the step.

        Raises
        ------
        ParameterError
            Non-finite inputs.
        IntegrationError
            The ring state became non-finite (left at the start of the step).
        ConvergenceError
            The ring integrator's Newton iteration did not converge (the ring state is left unchanged; an FMU
            reports Discard, so that a master can retry with a smaller step).
        FilmContactError
            A film's ε exceeded ``contact_eps``."""
        j = self._vector(journal, omega_rotor)
        if accel is not None:
            ax, ay = float(accel[0]), float(accel[1])
        else:
            ax, ay = self.history.acceleration_xy(t, j[2], j[3], H) if t is not None else (0.0, 0.0)
        n_sub = max(1, int(math.ceil(H / self.substep - 1e-9)))
        rsr = self.rsr6 if self.ring_speed_model != "rsr_eq7" else self._speed_ratio()
        self._at_speed(omega_rotor)  # thermal model: the viscosities of the step's start speed (quasi-static)
        status, eps_max, fx, fy, at, dpos, dspeed = _ring_step(
            *self._args(), j, ax, ay, self.ring, float(omega_rotor), float(omega_rotor_dot), float(H), n_sub, 0.999,
            self.ring_speed_model == "free", rsr, int(self.newton_max_iter), self.contact_eps)
        if status != RING_OK:
            self._ring_failure(status, (journal, omega_rotor, accel), eps_max, at, t, H, n_sub, dpos, dspeed)
        self.force_end = np.array([fx, fy])  # at the end of the extrapolated path (staggered coupling)
        self.path_accel = np.array([ax, ay])
        if t is not None:
            self.history.update(t, j)
        return eps_max

    def _ring_failure(self, status, inputs, eps_max, at, t, H, n_sub, dpos, dspeed):
        """Raise the error of a failed ring integration (``status`` of :func:`_ring_step` at ``at`` [s] into the
        step; ``inputs`` = journal, rotor speed and acceleration argument of :meth:`step`)."""
        journal, omega_rotor, accel = inputs
        if status == RING_BAD_INPUT:
            raise self._bad_inputs(journal, omega_rotor)
        if status == RING_BAD_ACCEL:
            raise ParameterError(f"{self.bearing.name} bearing: journal acceleration must be finite, got {accel!r} "
                                 "m/s2")
        if status == RING_NON_FINITE_RESULT:
            raise FilmContactError(f"{self.bearing.name} bearing: ring state became non-finite")
        if status == RING_CONTACT:
            raise FilmContactError(f"{self.bearing.name} bearing: eccentricity ratio {eps_max:.4f} exceeds "
                                   f"contact_eps = {self.contact_eps} (a member reaches its wall)")
        rpm = rad_s_to_rpm(float(omega_rotor))
        if status == RING_NOT_FINITE:
            raise IntegrationError(f"{self.bearing.name} bearing: the ring state became non-finite in the step at "
                                   f"{rpm:.0f} rpm (macro step {H:.3g} s); the ring state is left at the start of "
                                   "the step")
        when = f"t = {t + at:.9g} s" if t is not None else f"{at:.3g} s into the step"
        raise ConvergenceError(
            f"{self.bearing.name} bearing: the ring integrator's Newton iteration did not converge in "
            f"{self.newton_max_iter} iterations at {when}, rotor speed {rpm:.0f} rpm "
            f"(macro step {H:.3g} s, substep {H / n_sub:.3g} s): last correction {dpos:.3g} m in position "
            f"(tolerance {1e-10 * self.bearing.outer.clearance:.3g} m), {dspeed:.3g} rad/s in ring speed; the "
            "ring state is left at the start of the step")

    def linearization(self, journal, omega_rotor):
        """Local state space of the bearing at the current state (ring speed held, as the linear methods do).

        States x = (ring x, y, vx, vy), inputs u = (journal x, y, vx, vy), outputs y = force on the journal;
        central differences of the same kernels.

        Parameters
        ----------
        journal : array_like (4,)
            Journal x, y [m], vx, vy [m/s].
        omega_rotor : float
            Rotor speed [rad/s].

        Returns
        -------
        A : ndarray (4, 4)
            ∂ẋ/∂x [SI].
        B : ndarray (4, 4)
            ∂ẋ/∂u [SI].
        C : ndarray (2, 4)
            ∂F/∂x [N/m, N s/m].
        D : ndarray (2, 4)
            ∂F/∂u [N/m, N s/m].
        """
        j = self._check(journal, omega_rotor)
        self._at_speed(omega_rotor)
        ring = self._ring_for_force(omega_rotor)
        A = np.zeros((4, 4))
        B = np.zeros((4, 4))
        Cm = np.zeros((2, 4))
        D = np.zeros((2, 4))
        d = np.empty(5)

        def ev(rg, jj):
            fx, fy, _, _ = ring_rhs_kernel(*self._args(), jj[0], jj[1], jj[2], jj[3], rg, float(omega_rotor),
                                           math.inf, d)
            return d[:4].copy(), np.array([fx, fy])

        c = self.bearing.inner.clearance
        for k in range(4):
            h = 1e-6 * c * (1.0 if k < 2 else max(abs(omega_rotor), 1.0))
            for perturb_ring, dxdt, force in ((True, A, Cm), (False, B, D)):
                xp, xm = (ring if perturb_ring else j).copy(), (ring if perturb_ring else j).copy()
                xp[k] += h
                xm[k] -= h
                (dp, fp), (dm, fm) = (ev(xp, j), ev(xm, j)) if perturb_ring else (ev(ring, xp), ev(ring, xm))
                dxdt[:, k] = (dp - dm) / (2 * h)
                force[:, k] = (fp - fm) / (2 * h)
        return A, B, Cm, D


# --------------------------------------------------------------------------------------------------
# rotor
# --------------------------------------------------------------------------------------------------
@njit(cache=True)
def _rotor_forcing(f_grav, jdofs, fb, fbr, tau, unb_node, unb_me, unb_phase, ph, w, wd):
    f = f_grav.copy()
    for b in range(jdofs.shape[0]):
        f[jdofs[b, 0]] += fb[b, 0] + fbr[b, 0] * tau
        f[jdofs[b, 1]] += fb[b, 1] + fbr[b, 1] * tau
    add_unbalance_forces(f, ph, w, wd, unb_node, unb_me, unb_phase)
    return f


@njit(cache=True)
def _bearing_force_model(kb, cb, f0, refs, f1, acc, use_path, H):
    """Constant and linear-in-τ parts ``(fb, fbr)`` (nb, 2) of the bearing force model
    f_b(τ) = fb + fbr τ − K_b x − C_b v (see :meth:`RotorComponent.step`)."""
    nb = f0.shape[0]
    fb = np.zeros((nb, 2))
    fbr = np.zeros((nb, 2))
    for b in range(nb):
        for i in range(2):
            fb[b, i] = f0[b, i]
            for k in range(2):
                fb[b, i] += kb[b, i, k] * refs[b, k] + cb[b, i, k] * refs[b, 2 + k]
                if use_path:
                    fbr[b, i] += kb[b, i, k] * (refs[b, 2 + k] + 0.5 * H * acc[b, k]) + cb[b, i, k] * acc[b, k]
            if use_path:
                fbr[b, i] += (f1[b, i] - f0[b, i]) / H
    return fb, fbr


@njit(cache=True)
def _with_supports(minv, minv_k, jdofs, kb, cb):
    """M⁻¹(K + K_b) and M⁻¹C_b: the bearing interface terms added to the rotor's matrices (journal columns)."""
    n = minv_k.shape[0]
    mk = minv_k.copy()
    mc = np.zeros((n, n))
    for b in range(jdofs.shape[0]):
        for i in range(2):
            for k in range(2):
                col = jdofs[b, k]
                for r in range(n):
                    mk[r, col] += minv[r, jdofs[b, i]] * kb[b, i, k]
                    mc[r, col] += minv[r, jdofs[b, i]] * cb[b, i, k]
    return mk, mc


#: the columns of the per-bearing coupling array of :meth:`RotorComponent.step_coupled` (named as the rotor FMU's
#: inputs after ``<bearing>_bearing.``): F0 [N], K [N/m] and C [N s/m] row-major, the journal state they belong to
#: [m, m/s], and the staggered coupling's end-of-path force F1 [N] and path acceleration a [m/s²]
COUPLING_COLUMNS = ("force.x", "force.y", "stiffness.xx", "stiffness.xy", "stiffness.yx", "stiffness.yy",
                    "damping.xx", "damping.xy", "damping.yx", "damping.yy", "journal_ref.x", "journal_ref.y",
                    "journal_ref.vx", "journal_ref.vy", "force_end.x", "force_end.y", "journal_accel.x",
                    "journal_accel.y")


#: statuses of :func:`_rotor_macro_step`: done, non-finite bearing inputs, a non-finite state
ROTOR_OK, ROTOR_BAD_INPUT, ROTOR_NOT_FINITE = 0, 1, 2


@njit(cache=True)
def _unpack_coupling(coupling):
    """``(kb, cb, f0, refs, f1, acc)`` of :func:`_rotor_macro_step` from the (nb, 18) array laid out as
    :data:`COUPLING_COLUMNS`."""
    nb = coupling.shape[0]
    kb = np.empty((nb, 2, 2))
    cb = np.empty((nb, 2, 2))
    f0 = np.empty((nb, 2))
    refs = np.empty((nb, 4))
    f1 = np.empty((nb, 2))
    acc = np.empty((nb, 2))
    for b in range(nb):
        for i in range(2):
            f0[b, i] = coupling[b, i]
            f1[b, i] = coupling[b, 14 + i]
            acc[b, i] = coupling[b, 16 + i]
            for k in range(2):
                kb[b, i, k] = coupling[b, 2 + 2 * i + k]
                cb[b, i, k] = coupling[b, 6 + 2 * i + k]
        for k in range(4):
            refs[b, k] = coupling[b, 10 + k]
    return kb, cb, f0, refs, f1, acc


@njit(cache=True)
def _rotor_macro_step(y, phi, H, n_sub, minv, minv_k, minv_g, f_grav, jdofs, coupling, use_path, w0, wd, unb_node,
                      unb_me, unb_phase, y_out):
    """Trapezoidal rule for M q̈ + (ΩG + C_b) q̇ + (K + Ω̇G + K_b) q = f_g + f_unb + f_b over one macro step H, in one
    compiled call.

    ``jdofs`` (nb, 2) journal DoFs; ``coupling`` (nb, 18) per bearing (:data:`COUPLING_COLUMNS`): the force F0 [N] at
    the journal state ``ref`` at which the interface Jacobians K, C were evaluated; with ``use_path``, F1 is the
    force at the end of the bearing's journal path x_p = x_ref + v_ref τ + a τ²/2 (see
    :meth:`RotorComponent.step`). ``minv``, ``minv_k``, ``minv_g``: :attr:`Rotor.acceleration_matrices`; the
    accelerations are those of :func:`frbmodel.physics.dynamics.rotor_acceleration` with the bearing terms added to its
    matrices. Ω(τ) = w0 + wd τ. Writes the new state into ``y_out``; returns ``(rotation angle, status)``:
    :data:`ROTOR_OK`, :data:`ROTOR_BAD_INPUT` (a non-finite coupling value among those used: F1 and a only with
    ``use_path``; nothing computed) or :data:`ROTOR_NOT_FINITE` (a state or the step's matrix became non-finite or
    singular).
    """
    n = minv_k.shape[0]
    total = 0.0
    for b in range(coupling.shape[0]):
        for k in range(18 if use_path else 14):
            total += coupling[b, k]
    if not math.isfinite(total):
        return math.nan, ROTOR_BAD_INPUT
    kb, cb, f0, refs, f1, acc = _unpack_coupling(coupling)
    fb, fbr = _bearing_force_model(kb, cb, f0, refs, f1, acc, use_path, H)
    mk, mc = _with_supports(minv, minv_k, jdofs, kb, cb)
    h = H / n_sub
    eye = np.eye(n)
    piv = np.empty(n, np.int64)
    q = y[:n].copy()
    v = y[n:].copy()
    ph = phi
    for s in range(n_sub):
        # trapezoidal rule on q' = v, v' = a(t, q, v) = M⁻¹f(t) − S q − D(Ω) v, with q1 eliminated:
        # [I + h/2 D1 + h²/4 S] v1 = v0 + h/2 a0 + h/2 (M⁻¹f1 − S (q0 + h/2 v0)),  q1 = q0 + h/2 (v0 + v1)
        wa = w0 + wd * s * h
        wb = w0 + wd * (s + 1) * h
        phb = ph + 0.5 * h * (wa + wb)
        fa = _rotor_forcing(f_grav, jdofs, fb, fbr, s * h, unb_node, unb_me, unb_phase, ph, wa, wd)
        fbv = minv @ _rotor_forcing(f_grav, jdofs, fb, fbr, (s + 1) * h, unb_node, unb_me, unb_phase, phb, wb, wd)
        a0 = rotor_acceleration(minv, mk, minv_g, fa, q, v, wa, wd, mc)
        stiff, damp = rotor_operators(mk, minv_g, wb, wd, mc)
        v1 = v + 0.5 * h * a0 + 0.5 * h * (fbv - stiff @ (q + 0.5 * h * v))
        lhs = eye + 0.5 * h * damp + 0.25 * h * h * stiff
        if not (math.isfinite(v1.sum()) and lu_factor(lhs, piv)):
            return math.nan, ROTOR_NOT_FINITE
        lu_solve(lhs, piv, v1)
        q = q + 0.5 * h * (v + v1)
        v = v1
        ph = phb
    y_out[:n] = q
    y_out[n:] = v
    return ph, (ROTOR_OK if math.isfinite(y_out.sum()) and math.isfinite(ph) else ROTOR_NOT_FINITE)


#: rotor speed sources of :class:`RotorComponent` (and the rotor FMU's ``speed_source``)
SPEED_SOURCES = ("ramp", "input", "torque")


class RotorComponent:
    """The FE rotor for co-simulation; journals receive the linearized bearing forces of the coupling scheme.

    Parameters
    ----------
    system : Turbocharger
        Rotor, bearing nodes and gravity are taken from it.
    speed : callable t -> (Ω [rad/s], Ω̇ [rad/s²]), optional
        The prescribed speed of ``speed_source="ramp"`` (e.g. :func:`ramp_speed`).
    unbalance : sequence of Unbalance
        Rotating unbalances (:class:`frbmodel.nonlinear.runup.Unbalance`: disc name, m e [kg m], phase [rad]).
    substep : float
        Trapezoidal substep [s] (default 5e-6 s; a macro step is split into ceil(H / substep) substeps).
    speed_source : {"ramp", "input", "torque"}
        Where the rotor speed comes from. "ramp": ``speed(t)``. "input": the ``speed_in`` argument of every
        :meth:`step` [rad/s], held with the rate of the last two inputs (backward difference, zero at the first
        step or after a gap) as the angular acceleration over the step. "torque": the speed is a state, with
        J_p Ω̇ = T_drive + Σ T_J (:func:`frbmodel.physics.dynamics.spin_acceleration`) from the ``drive_torque`` and
        ``journal_torques`` arguments of every :meth:`step`, held over the step (first order in the step).
    initial_speed : float, optional
        Rotor speed at t = 0 [rad/s]: required for "torque"; for "input" the speed reported before the first step.
    polar_inertia : float, optional
        J_p [kg m²] of "torque" (default: :func:`frbmodel.physics.dynamics.rotor_polar_inertia` of the system's rotor).

    Attributes
    ----------
    rotor_speed : float
        Current rotor speed [rad/s] (output ``rotor_speed`` of the rotor FMU).
    phi : float
        Current rotor rotation angle [rad] (output ``rotor_angle``).

    Examples
    --------
    Without bearing forces the rotor falls freely: after one step of 10 µs the journals move down by g t²/2
    (the trapezoidal rule is exact for a constant acceleration):

    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> rc = RotorComponent(tc, speed=ramp_speed(50e3, 100e3, 1.0))
    >>> zeros = np.zeros((2, 2))
    >>> rc.step(1e-5, zeros, [zeros, zeros], [zeros, zeros])
    >>> x, y, vx, vy = rc.journal(0)
    >>> round(float(y) / (-tc.gravity * 1e-5**2 / 2), 9), round(float(vy) / (-tc.gravity * 1e-5), 9)
    (1.0, 1.0)
    """

    def __init__(self, system, speed=None, unbalance=(), substep=ROTOR_SUBSTEP, speed_source="ramp",
                 initial_speed=None, polar_inertia=None):
        if speed_source not in SPEED_SOURCES:
            raise ParameterError(f"speed_source = {speed_source!r} is unknown; valid: {', '.join(SPEED_SOURCES)}")
        if speed_source == "ramp" and not callable(speed):
            raise ParameterError("speed_source = 'ramp' needs a speed function t -> (omega [rad/s], omega_dot "
                                 f"[rad/s2]); got speed = {speed!r}")
        if speed_source == "torque" and initial_speed is None:
            raise ParameterError("speed_source = 'torque' needs initial_speed [rad/s] (the spin is a state)")
        rotor = system.rotor
        self.system = system
        self.speed = speed
        self.speed_source = speed_source
        self.n = rotor.n_dof
        self.eom = rotor.acceleration_matrices  # (M⁻¹, M⁻¹K, M⁻¹G)
        self.f_grav = rotor.gravity_load(system.gravity)
        self.jdofs = np.array([[4 * b.node, 4 * b.node + 1] for b in system.bearings], dtype=np.int64)
        self._jidx = [np.array([i, k, self.n + i, self.n + k]) for i, k in self.jdofs]
        self.unb_node, self.unb_me, self.unb_phase = unbalance_arrays(rotor, unbalance)
        self.substep = float(substep)
        self.polar_inertia = check_positive("rotor polar_inertia", rotor_polar_inertia(rotor) if polar_inertia is None
                                            else polar_inertia, "kg m^2")
        self.y = np.zeros(2 * self.n)
        self.phi = 0.0
        self.t = 0.0
        w0 = 0.0 if initial_speed is None else check_finite("initial_speed", initial_speed, "rad/s")
        self.omega = speed(0.0)[0] if speed_source == "ramp" else w0
        self.omega_dot = 0.0
        self._last_input = None  # (t, speed_in) of the previous step ("input")

    def journal(self, b):
        """(x, y, vx, vy) of bearing ``b``'s journal [m, m/s].

        Parameters
        ----------
        b : int
            Bearing index (order of ``system.bearings``).

        Returns
        -------
        ndarray (4,)
        """
        return self.y[self._jidx[b]]

    def node_xy(self, node):
        """Lateral displacement (x, y) [m] of rotor node ``node``.

        Parameters
        ----------
        node : int
            Rotor node index.

        Returns
        -------
        ndarray (2,)
            A copy.
        """
        return self.y[4 * node:4 * node + 2].copy()

    @property
    def rotor_speed(self):
        """Rotor speed [rad/s] at the current time."""
        return float(self.speed(self.t)[0]) if self.speed_source == "ramp" else float(self.omega)

    def current_speed(self):
        """Rotor speed and acceleration at the current time (the rate of the last step for "input"/"torque").

        Returns
        -------
        omega : float
            Ω [rad/s].
        omega_dot : float
            Ω̇ [rad/s²].
        """
        if self.speed_source == "ramp":
            w, wd = self.speed(self.t)
            return float(w), float(wd)
        return float(self.omega), float(self.omega_dot)

    def _spin(self, H, speed_in, drive_torque, journal_torques):
        """Speed at the start of the step and the angular acceleration held over it, ``(Ω0, Ω̇)``."""
        if self.speed_source == "ramp":
            return self.speed(self.t)
        if self.speed_source == "input":
            w0 = check_finite("speed_in", speed_in, "rad/s")
            last = self._last_input
            gap = None if last is None else self.t - last[0]
            wd = (w0 - last[1]) / gap if gap is not None and 0.0 < gap <= 4.0 * H else 0.0
            return w0, wd
        nb = self.jdofs.shape[0]
        tj = np.asarray(journal_torques if journal_torques is not None else [], dtype=float).reshape(-1)
        if tj.size != nb or not np.isfinite(tj).all():
            raise ParameterError(f"speed_source = 'torque' needs {nb} finite journal torques [N m]; got "
                                 f"{journal_torques!r}")
        drive = check_drive_torque_value("drive_torque", drive_torque, self.polar_inertia)
        return self.omega, spin_acceleration(drive, tj, self.polar_inertia)

    def step(self, H, forces, Ks, Cs, refs=None, path=None, speed_in=None, drive_torque=0.0, journal_torques=None):
        """Advance by ``H`` [s] with per-bearing F0 [N], K [N/m], C [N s/m], linearized about the journal states
        ``refs`` [(x, y, vx, vy)] at which F0 was evaluated (default: the current journal states).

        ``path = (F1, a)`` (staggered coupling, per bearing): the bearing has already stepped along the journal
        path x_p(τ) = x_ref + v_ref τ + a τ²/2 [m/s²] and F1 [N] is its force at the end of the step on that path.
        The force along the path is interpolated from F0 to F1 with the curvature the path itself causes,
        F_p(τ) = F0 + (F1 − F0) τ/H + K a τ (H − τ)/2, and corrected for the deviation from the path:
        F = F_p − K (x − x_p) − C (v − v_p) = F0 + [(F1 − F0)/H + K (v_ref + a H/2) + C a] τ − K (x − x_ref) −
        C (v − v_ref) — exact when the force is linear in the journal state. Without ``path``:
        F0 − K (x − x_ref) − C (v − v_ref).

        Speed inputs (see ``speed_source``): ``speed_in`` [rad/s] ("input"); ``drive_torque`` [N m] and
        ``journal_torques`` (per bearing, the film torques on the journals [N m]) ("torque"). Over the step the speed
        is Ω(τ) = Ω0 + Ω̇ τ.

        Parameters
        ----------
        H : float
            Macro step [s].
        forces : array_like (nb, 2)
            F0: bearing force on each journal [N].
        Ks : array_like (nb, 2, 2)
            K = −∂F/∂x of each bearing [N/m].
        Cs : array_like (nb, 2, 2)
            C = −∂F/∂v of each bearing [N s/m].
        refs : array_like (nb, 4), optional
            Journal states (x, y [m], vx, vy [m/s]) at which F0 was evaluated.
        path : tuple (F1, a), optional
            F1 (nb, 2) [N] and a (nb, 2) [m/s²] of the staggered coupling (see above).
        speed_in : float, optional
            Rotor speed [rad/s] ("input").
        drive_torque : float
            Net drive torque [N m] ("torque").
        journal_torques : array_like (nb,), optional
            Film torques on the journals [N m] ("torque").

        Raises
        ------
        ParameterError
            Missing or non-finite speed inputs.
        IntegrationError
            The rotor state became non-finite (a numerical blow-up: the macro step is too large for the coupling).
        """
        nb = self.jdofs.shape[0]
        coupling = np.empty((nb, len(COUPLING_COLUMNS)))
        coupling[:, 0:2] = np.asarray(forces, dtype=float).reshape(nb, 2)
        coupling[:, 2:6] = np.asarray(Ks, dtype=float).reshape(nb, 4)
        coupling[:, 6:10] = np.asarray(Cs, dtype=float).reshape(nb, 4)
        coupling[:, 10:14] = (self.y[np.array(self._jidx)] if refs is None else
                              np.asarray(refs, dtype=float).reshape(nb, 4))
        if path is None:
            coupling[:, 14:16] = coupling[:, 0:2]
            coupling[:, 16:18] = 0.0
        else:
            coupling[:, 14:16] = np.asarray(path[0], dtype=float).reshape(nb, 2)
            coupling[:, 16:18] = np.asarray(path[1], dtype=float).reshape(nb, 2)
        self.step_coupled(H, coupling, path is not None, speed_in, drive_torque, journal_torques)

    def step_coupled(self, H, coupling, use_path=True, speed_in=None, drive_torque=0.0, journal_torques=None):
        """:meth:`step` with the bearing inputs packed in one array: one compiled call per macro step
        (:func:`_rotor_macro_step`; the rotor FMU's path).

        Parameters
        ----------
        H : float
            Macro step [s].
        coupling : ndarray (nb, 18)
            Per bearing (order of ``system.bearings``) the columns :data:`COUPLING_COLUMNS`: F0 [N], K [N/m] and
            C [N s/m] row-major, the journal state (x, y [m], vx, vy [m/s]) they belong to, F1 [N] and a [m/s²] of
            the staggered coupling (used only with ``use_path``).
        use_path : bool
            Interpolate the force along the bearings' journal paths (``path`` of :meth:`step`).
        speed_in, drive_torque, journal_torques
            Speed inputs, as for :meth:`step`.

        Raises
        ------
        ParameterError
            Missing or non-finite speed inputs, non-finite bearing inputs (``coupling``; its last four columns only
            with ``use_path``).
        IntegrationError
            The rotor state became non-finite (the state is left at the start of the step).
        """
        w0, wd = self._spin(H, speed_in, drive_torque, journal_torques)
        n_sub = max(1, int(math.ceil(H / self.substep - 1e-9)))
        y = np.empty_like(self.y)
        phi, status = _rotor_macro_step(self.y, self.phi, H, n_sub, *self.eom, self.f_grav, self.jdofs, coupling,
                                        bool(use_path), w0, wd, self.unb_node, self.unb_me, self.unb_phase, y)
        if status == ROTOR_BAD_INPUT:
            cols = COUPLING_COLUMNS if use_path else COUPLING_COLUMNS[:14]
            bad = [f"{b.name}_bearing.{c} = {coupling[i, k]!r}" for i, b in enumerate(self.system.bearings)
                   for k, c in enumerate(cols) if not math.isfinite(coupling[i, k])]
            raise ParameterError(f"bearing inputs are not finite: {', '.join(bad)}")
        if status != ROTOR_OK:
            raise IntegrationError(f"rotor state became non-finite in the step t = {self.t:.6g} s + {H:.3g} s at "
                                   f"{rad_s_to_rpm(w0):.0f} rpm: the macro step is too large for the coupling (the "
                                   "state is left at the start of the step)")
        if self.speed_source == "input":
            self._last_input = (self.t, float(w0))
        self.y, self.phi = y, phi
        self.t += H
        self.omega, self.omega_dot = float(w0 + wd * H), float(wd)

    def state(self):
        """The component's state as plain data (for FMU get/set state): rotor DoFs, angle, time, speed.

        Returns
        -------
        dict
            ``y`` (q [m, rad], q̇ [m/s, rad/s]), ``phi`` [rad], ``t`` [s], ``omega`` [rad/s], ``omega_dot``
            [rad/s²] and ``last_input`` (time [s], speed [rad/s] of the last "input" step, or None); JSON-safe.
        """
        return {"y": self.y.tolist(), "phi": float(self.phi), "t": float(self.t),
                "omega": float(self.omega), "omega_dot": float(self.omega_dot),
                "last_input": None if self._last_input is None else list(self._last_input)}

    def set_state(self, st):
        """Restore a state from :meth:`state`.

        Parameters
        ----------
        st : dict
            A :meth:`state` (``omega``, ``omega_dot`` and ``last_input`` may be missing, as in older states).
        """
        self.y[:] = st["y"]
        self.phi, self.t = float(st["phi"]), float(st["t"])
        self.omega, self.omega_dot = float(st.get("omega", self.omega)), float(st.get("omega_dot", 0.0))
        last = st.get("last_input")
        self._last_input = None if last is None else (float(last[0]), float(last[1]))


def ramp_speed(start_rpm, end_rpm, ramp_time):
    """Speed function t -> (Ω, Ω̇) of a linear ramp (constant after ``ramp_time``) [rad/s, rad/s²].

    Parameters
    ----------
    start_rpm, end_rpm : float
        Rotor speed at t = 0 and at the end of the ramp [rpm].
    ramp_time : float
        Duration of the ramp [s]; <= 0 gives a constant ``end_rpm``.

    Returns
    -------
    callable
        ``speed(t)`` -> ``(Ω [rad/s], Ω̇ [rad/s²])`` for a time ``t`` [s].

    Examples
    --------
    >>> speed = ramp_speed(0.0, 60e3 / (2 * np.pi), 2.0)  # 0 -> 1000 rad/s in 2 s
    >>> [round(v, 9) for v in speed(1.0)], [round(v, 9) for v in speed(3.0)]
    ([500.0, 500.0], [1000.0, 0.0])
    """
    w0, w1 = rpm_to_rad_s(start_rpm), rpm_to_rad_s(end_rpm)
    a = (w1 - w0) / ramp_time if ramp_time > 0 else 0.0

    def speed(t):
        if t < ramp_time:
            return w0 + a * t, a
        return w1, 0.0

    return speed


def rotor_state_space(rotor_comp):
    """Local state space of the rotor component at its current time (:meth:`Rotor.state_matrix`).

    Parameters
    ----------
    rotor_comp : RotorComponent
        The rotor component (its current speed and acceleration set the gyroscopic terms).

    Returns
    -------
    dict
        ``A`` (2n, 2n), ``B`` (2n, 2 nb), ``C`` (4 nb, 2n), ``D`` (4 nb, 2 nb) for the state x = (q, q̇), the
        inputs u = bearing forces (Fx, Fy per bearing) [N] and the outputs y = journal (x, y, vx, vy per bearing)
        [m, m/s]. The bearing coupling terms are *not* included (they come from the bearings' own matrices when
        the system is assembled).

    Examples
    --------
    >>> import frbmodel as frb
    >>> ss = rotor_state_space(RotorComponent(frb.turbocharger(), speed=ramp_speed(50e3, 100e3, 1.0)))
    >>> {k: v.shape for k, v in ss.items()}
    {'A': (32, 32), 'B': (32, 4), 'C': (8, 32), 'D': (8, 4)}
    """
    n = rotor_comp.n
    w, wd = rotor_comp.current_speed()
    A = rotor_comp.system.rotor.state_matrix(w, wd)
    minv = rotor_comp.eom[0]
    nb = rotor_comp.jdofs.shape[0]
    B = np.zeros((2 * n, 2 * nb))
    C = np.zeros((4 * nb, 2 * n))
    for b in range(nb):
        for k in range(2):
            B[n:, 2 * b + k] = minv[:, rotor_comp.jdofs[b, k]]
            C[4 * b + k, rotor_comp.jdofs[b, k]] = 1.0
            C[4 * b + 2 + k, n + rotor_comp.jdofs[b, k]] = 1.0
    return {"A": A, "B": B, "C": C, "D": np.zeros((4 * nb, 2 * nb))}
