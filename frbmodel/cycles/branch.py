"""Following one branch of whirl limit cycles in rotor speed: Hopf points, the predictor-corrector, multiple shooting.

The numerics under :func:`frbmodel.cycles.continuation.continuation` (which assembles branches into a bifurcation
diagram) and the ``guess="hopf"`` of :func:`frbmodel.cycles.limitcycle.limit_cycle`: the Hopf points of the
equilibrium (:func:`hopf_points`), the branch born at one (:func:`hopf_guess`), the pseudo-arclength corrector and
multiple shooting at one speed (:func:`shoot_segments`). The equations are those described in
:mod:`frbmodel.cycles.continuation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ConvergenceError, ParameterError
from ..core.interrupt import deferred_signals
from ..linear.thermal import at_operating_point, check_oil_supply
from ..nonlinear.recorder import RunupSchema
from ..nonlinear.runup import SpeedProfile, atol_vector, build_problem, check_speed, initial_state
from .flow import FD_STEP, MULTIPLIER_TOL, SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS, ConstantSpeedFlow, orbit_result
from .shooting import ShootingSolution, monodromy, stable_multipliers

#: difference step of the speed derivative, relative
SPEED_FD = 1e-6


#: a turn of the branch in speed is a fold only if the speed moves back by more than this (relative) within three
#: points on both sides: on a vertical branch (the orbit grows at one speed, e.g. at the 2.0 krpm Hopf point of the
#: 36 µm system) the computed speeds jitter by ~4e-6 relative, the speed being ill-conditioned there
FOLD_MIN_REL = 2e-5


#: samples of each branch point's orbit over one period (radius and max eps; the sampled peak of a whirl is low by
#: at most (pi / 100)^2 / 2 = 0.05 %; the compiled solver's cost grows with the number of output times)
POINT_SAMPLES = 100


@dataclass
class BranchPoint:
    """One computed orbit of a branch: speed [rpm], period [s], multipliers, and the orbit's measures."""

    speed_rpm: float
    period: float
    multipliers: np.ndarray
    stable: bool
    turbine_radius_m: float
    max_eps: np.ndarray
    state: np.ndarray = field(repr=False, default=None)


#: most shooting segments per orbit (limit cycles, continuation, the CLI's --segments, bifurcation studies): four
#: serve the strongly unstable branches of the Table 2 system; each segment holds a state of the orbit, so 1e6
#: segments held a million states per orbit
MAX_SEGMENTS = 64


def check_segments(name, segments):
    """``int(segments)`` if it is a whole number 1 ... :data:`MAX_SEGMENTS`, else a :class:`ParameterError` naming
    ``name``, the value and the range.

    Examples
    --------
    >>> try:
    ...     check_segments("segments", 10**6)
    ... except ParameterError as exc:
    ...     print(exc)
    segments = 1000000 is invalid: valid range integer 1 ... 64 (shooting segments per orbit)
    """
    ok = isinstance(segments, (int, float, np.integer, np.floating)) and not isinstance(segments, bool)
    if not (ok and int(segments) == segments and 1 <= segments <= MAX_SEGMENTS):
        raise ParameterError(f"{name} = {segments!r} is invalid: valid range integer 1 ... {MAX_SEGMENTS} (shooting "
                             "segments per orbit)")
    return int(segments)


class ContinuationProblem:
    """Flows and residuals of the continuation problem at any speed (problems built per speed and cached). With an
    ``oil_supply`` the flow at each speed has the viscosities of that speed's thermal operating point
    (:func:`frbmodel.linear.thermal.at_operating_point`: quasi-static temperatures), so the speed column of the
    Jacobian, by differences of flows at two speeds, carries the viscosities' change with speed."""

    def __init__(self, system, model, rtol, atol_m, scale_m, workers, start_rpm, segments=1, oil_supply=None):

        self.system, self.model = system, model
        self.oil_supply = check_oil_supply(oil_supply, bearings=system.bearings)
        self.rtol, self.atol_m, self.workers = rtol, atol_m, workers
        self._flows = {}
        self._last = None  # the last flow made for a new speed (it has chosen its integrator by the next one)
        self._flow_cls = ConstantSpeedFlow
        #: one scaling of the states for the whole branch (that of the start speed): u = z / scale
        self.scale_vec = atol_vector(self.flow(start_rpm).problem, scale_m)[0][:-1]
        self.set_segments(segments)

    def set_segments(self, segments):
        """Shooting segments m (multiple shooting for m > 1); n is the state size of one segment start. The
        unknowns of a start are scaled by scale_vec √m, so that a step of the m starts together (arclength) means
        what one start's step means in single shooting; the defects are scaled by scale_vec."""
        self.segments, self.n = int(segments), self.scale_vec.size
        self.start_scale = self.scale_vec * math.sqrt(self.segments)
        self._scale_all = np.tile(self.start_scale, self.segments)
        self._defect_scale = np.tile(self.scale_vec, self.segments)

    def ends(self, z, T, speed_rpm, like=None):
        """The ends Φ_{T/m}(z_k) of all m segments (z: the m segment starts, concatenated) and the flow used."""
        fl = self.flow(speed_rpm, like)
        zs = z.reshape(self.segments, self.n)
        h = T / self.segments
        if self.segments == 1:
            return fl(zs[0], T), fl
        from concurrent.futures import ThreadPoolExecutor

        first = fl(zs[0], h)  # before the threads: a new flow chooses its integrator on segment 0, reproducibly
        with ThreadPoolExecutor(self.workers) as pool:
            return np.concatenate([first] + list(pool.map(lambda zk: fl(zk, h), zs[1:]))), fl

    def residual(self, z, end):
        """Segment defects Φ(z_k) − z_{k+1} (z_m = z_0), scaled."""
        nxt = np.roll(z.reshape(self.segments, self.n), -1, axis=0).ravel()
        return (end - nxt) / self._defect_scale

    def flow(self, speed_rpm, like=None):
        """The flow at a speed [rpm]; ``like``: a flow whose integrator it must use (differences between them)."""

        key = float(speed_rpm)
        if key not in self._flows:
            if len(self._flows) > 8:
                self._flows.clear()
            problem = build_problem(at_operating_point(self.system, key, self.oil_supply),
                                    SpeedProfile.constant(key, 1.0), self.model)
            if like is not None:
                self._flows[key] = self._flow_cls(problem, self.rtol, self.atol_m, like.method)
            else:  # a new speed of the branch: its integrator chosen with the last chosen one as hint
                self._flows[key] = self._last = self._flow_cls(problem, self.rtol, self.atol_m, hint=self._last)
        return self._flows[key]

    def scale(self, speed_rpm=None):
        """The scaling of all m segment starts [SI units per scaled unit]."""
        return self._scale_all


def _jacobian(br, z, T, speed, scale, t_ref, w_ref, f_ref, speed_column=True):
    """Residual (N+1) and its Jacobian (N+1, N+2) in the scaled unknowns (u_0 … u_{m−1}, τ, p) at (z, T, speed),
    N = m n, and the monodromy M = M_{m−1} ⋯ M_0 (each segment's by differences of its flow)."""

    m, n = br.segments, br.n
    N = m * n
    end, fl = br.ends(z, T, speed)
    zs, es, s1, su = z.reshape(m, n), end.reshape(m, n), br.scale_vec, br.start_scale
    blocks = [monodromy(fl, zs[k], T / m, s1, es[k], FD_STEP, br.workers) for k in range(m)]
    jac = np.zeros((N + 1, N + 2))
    if speed_column:  # (one more set of flows; left zero where the speed is fixed)
        ds = SPEED_FD * speed
        d_speed = (br.ends(z, T, speed + ds, like=fl)[0] - end) / ds
    for k in range(m):
        rows, nxt = slice(k * n, (k + 1) * n), ((k + 1) % m) * n
        jac[rows, rows] = blocks[k] * su[None, :] / s1[:, None]
        jac[rows, nxt:nxt + n] -= np.diag(su / s1)
        jac[rows, N] = fl.rhs(es[k]) / s1 * t_ref / m
        if speed_column:
            jac[rows, N + 1] = d_speed[rows] / s1 * w_ref
    jac[N, :N] = f_ref
    mono = blocks[0]
    for b in blocks[1:]:
        mono = b @ mono
    return np.append(br.residual(z, end), 0.0), jac, mono, fl


def _tangent(jac, previous):
    """Unit tangent of the branch: the null vector of the (n+1, n+2) Jacobian, oriented along ``previous``."""
    a = np.vstack([jac, previous])
    b = np.zeros(a.shape[0])
    b[-1] = 1.0
    t = np.linalg.solve(a, b)
    return t / np.linalg.norm(t)


#: the null vector of the Jacobian is taken as the next tangent unless it is more than 60° off the secant of the
#: last step (cosine below this): where the branch is vertical (a near-neutral radial multiplier) the Jacobian's near
#: null space is two-dimensional and its computed null vector turned the 2.0 krpm branch back onto the equilibrium
TANGENT_MIN_COS = 0.5


def _next_tangent(jac, previous, secant):
    """Unit tangent at a new point: the Jacobian's null vector oriented along ``previous``, or the normalized
    secant of the last step where the two disagree (TANGENT_MIN_COS)."""
    t = _tangent(jac, previous)
    sec = secant / np.linalg.norm(secant)
    return t if float(t @ sec) >= TANGENT_MIN_COS else sec


def _correct(br, x_pred, tangent, x_prev, ds, n, t_ref, w_ref, f_ref, u_ref, jac=None):
    """Newton on [shooting residual; phase; arclength] from the predicted point; returns (x, iterations).

    The iteration starts from ``jac`` (the Jacobian at the previous branch point, its phase row replaced by
    ``f_ref``) or, if None, from one computed at the predicted point, and updates the shooting rows by Broyden's
    rank-one formula after every iteration. The update corrects the difference Jacobian (columns accurate to ~3e-4)
    along the directions the iteration takes: where the linearized problem is ill-conditioned (condition ~1e4 on
    the vertical branch of the 2.0 krpm Hopf point of the 36 µm system: amplitude neutral, speed fixed only by
    higher-order terms) the plain chord iteration oscillated in speed and stalled at residuals ~1e-5; with the update
    it converges there."""
    scale = br.scale()
    x = x_pred.copy()
    z, T, speed = x[:n] * scale, x[n] * t_ref, x[n + 1] * w_ref
    if jac is None:
        res, jac, _, fl = _jacobian(br, z, T, speed, scale, t_ref, w_ref, f_ref)
    else:
        end, fl = br.ends(z, T, speed)
        res = np.append(br.residual(z, end), 0.0)
    a = np.vstack([jac, tangent])  # rows n, n + 1 (phase, arclength) are linear: exact, never updated
    a[n] = 0.0
    a[n, :n] = f_ref
    for it in range(1, MAX_CORRECTOR + 1):
        phase = float(f_ref @ (x[:n] - u_ref))
        arc = float(tangent @ (x - x_prev)) - ds
        step = -np.linalg.solve(a, np.append(res[:n], [phase, arc]))
        x = x + step
        z, T, speed = x[:n] * scale, x[n] * t_ref, x[n + 1] * w_ref
        if not (T > 0 and speed > 0):
            break
        end, _ = br.ends(z, T, speed, like=fl)  # one integrator for the whole iteration
        new = np.append(br.residual(z, end), 0.0)
        if float(np.max(np.abs(new))) < TOL:
            return x, it
        if step @ step > 0.0:
            a[:n] += np.outer(new[:n] - res[:n] - a[:n] @ step, step) / (step @ step)
        res = new
    raise ConvergenceError("continuation: the corrector did not converge")


def _at_point(br, x, n, t_ref, w_ref):
    """Phase normal, Jacobian (phase row = that normal), monodromy and flow at a converged branch point x."""
    z, T, speed = x[:n] * br.scale(), x[n] * t_ref, x[n + 1] * w_ref
    f_ref = _phase_normal(br, z, speed)
    _, jac, m, fl = _jacobian(br, z, T, speed, br.scale(), t_ref, w_ref, f_ref)
    return f_ref, jac, m, fl


def _checked_monodromy(br, x, n, t_ref, w_ref, m, fl):
    """The monodromy ``m`` (forward differences) at the orbit x, or central differences of the segment flows if
    that is more accurate. A periodic orbit of an autonomous system has the multiplier 1 exactly (the flow direction:
    M f = f); where the computed one closest to 1 is off by more than MULTIPLIER_TOL, the forward differences'
    O(h) truncation error dominates (measured on the 2.0 krpm branch past its fold, 29 µm at 1857 rpm: the pair
    1.077 / 0.876 instead of 1.000 / 0.940, M f − f 1.9e-2 of f; central 2.9e-5, the pair 0.9997 / 0.9405 as with
    1e-11 tolerances). ``fl``: the flow (and so the integrator) ``m`` was computed with. If a central-difference
    flow fails, ``m`` is kept (the branch table's trivial-multiplier error shows its accuracy)."""

    if trivial_error(np.linalg.eigvals(m)) <= MULTIPLIER_TOL:
        return m
    mseg = br.segments
    z, T = x[:n] * br.scale(), x[n] * t_ref
    central = np.eye(br.n)
    try:
        for zk in z.reshape(mseg, br.n):
            central = monodromy(fl, zk, T / mseg, br.scale_vec, None, FD_STEP, br.workers, central=True) @ central
    except ConvergenceError:
        return m
    better = trivial_error(np.linalg.eigvals(central)) < trivial_error(np.linalg.eigvals(m))
    return central if better else m


def trivial_error(mult):
    """Distance of the multiplier closest to 1 from 1 (0 for exact multipliers of a periodic orbit)."""
    return float(np.min(np.abs(np.asarray(mult) - 1.0)))


def _point(br, x, n, t_ref, w_ref, m, fl):
    """A BranchPoint (orbit measures sampled from the flow ``fl``) for the solution x with monodromy m."""

    m = _checked_monodromy(br, x, n, t_ref, w_ref, m, fl)
    z, T, speed = x[:br.n] * br.start_scale, x[n] * t_ref, x[n + 1] * w_ref  # the orbit from segment 0's start
    t = np.linspace(0.0, T, POINT_SAMPLES + 1)
    orbit = orbit_result(fl.problem, RunupSchema.from_system(br.system), t, fl.states(z, t))
    xy = orbit.displacement[orbit.schema.discs[0]][:-1]
    radius = float(np.max(np.hypot(*(xy - xy.mean(axis=0)).T)))
    mult = np.linalg.eigvals(m)
    mult = mult[np.argsort(-np.abs(mult))]
    nontrivial = np.delete(mult, int(np.argmin(np.abs(mult - 1.0))))
    return BranchPoint(speed, T, mult, stable_multipliers(nontrivial, MULTIPLIER_TOL), radius,
                       orbit.eccentricity.max(axis=0), z)


@dataclass
class HopfPoint:
    """A Hopf point of the full model's equilibrium: a complex pair of eigenvalues of its Jacobian (rotor, rings and
    ring spin, without the rotation angle) crosses the imaginary axis.

    Attributes
    ----------
    speed_rpm : float
        Speed [rpm] of the crossing (to 1e-6 relative).
    frequency_hz : float
        Imaginary part / 2π of the crossing pair [Hz].
    eigenvector : ndarray (n,), complex
        Right eigenvector of the pair (state units).
    equilibrium : ndarray (n,)
        The equilibrium state there.
    restabilizing : bool
        True where the pair regains stability as the speed rises (unstable below the point), False where it loses
        it (unstable above).
    """

    speed_rpm: float
    frequency_hz: float
    eigenvector: np.ndarray = field(repr=False)
    equilibrium: np.ndarray = field(repr=False)
    restabilizing: bool = False


def hopf_dataframe(hopf):
    """The Hopf points ``hopf`` (:func:`hopf_points`) as a table: speed [rpm], frequency [Hz] and in orders of the
    rotor speed [X], and whether the pair loses or regains stability with rising speed."""
    import pandas as pd

    return pd.DataFrame({"speed [rpm]": [h.speed_rpm for h in hopf], "frequency [Hz]": [h.frequency_hz for h in hopf],
                         "frequency [X]": [h.frequency_hz * 60.0 / h.speed_rpm for h in hopf],
                         "with rising speed": ["regains" if h.restabilizing else "loses" for h in hopf]},
                        columns=["speed [rpm]", "frequency [Hz]", "frequency [X]", "with rising speed"])


def equilibrium_jacobian(system, speed_rpm, film_model=None, oil_supply=None):
    """Equilibrium state (method-J bearing equilibria: the full model's fixed point) and the full model's Jacobian
    there, without the rotation angle; with an :class:`~frbmodel.linear.thermal.OilSupply`, of the system at the
    thermal operating point of ``speed_rpm``.

    Returns
    -------
    z_eq : ndarray (n,)
        Equilibrium state [SI].
    jac : ndarray (n, n)
        ∂(dz/dt)/∂z by central differences of the compiled RHS (steps 1e-6 of each state's typical size: truncation
        ~1e-12, round-off ~1e-10 relative, far below the forward differences' ~1e-8 that blurred Hopf speeds by
        ~0.3 % at 2 krpm where the critical damping changes slowly with speed).
    """

    system = at_operating_point(system, speed_rpm, oil_supply)
    p = build_problem(system, SpeedProfile.constant(speed_rpm, 1.0), film_model or system.film_model)
    y = initial_state(p, "equilibrium", perturbation=0.0)
    n = p.n_states - 1
    typical = atol_vector(p, 1e-6)[0]
    jac = np.empty((n, n))
    buf = np.empty(p.n_states)
    for k in range(n):
        h = 1e-6 * max(abs(y[k]), typical[k])
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        fp = p.rhs(0.0, yp, buf)[:n].copy()
        jac[:, k] = (fp - p.rhs(0.0, ym, buf)[:n]) / (2 * h)
    return y[:-1].copy(), jac


def _unstable_pairs(system, speed_rpm, model, oil_supply=None):
    lam = np.linalg.eigvals(equilibrium_jacobian(system, speed_rpm, model, oil_supply)[1])
    return int(np.sum((lam.real > 0) & (lam.imag > 0)))


def _crossing_real(system, speed_rpm, model, near_hz, oil_supply=None):
    """Real part [1/s] of the eigenvalue whose frequency is closest to ``near_hz``."""
    lam = np.linalg.eigvals(equilibrium_jacobian(system, speed_rpm, model, oil_supply)[1])
    lam = lam[lam.imag > 0]
    return float(lam[np.argmin(np.abs(lam.imag / (2 * math.pi) - near_hz))].real)


def _refine_crossing(system, model, a, b, f_hz, count_a, oil_supply=None):
    """Speed [rpm] in (a, b) where the pair near ``f_hz`` crosses: Brent's method on its real part when it changes
    sign over the interval and the number of unstable pairs changes across the root found (the eigenvalue nearest
    in frequency can switch to another, heavily damped one within the interval: a jump of the real part that is no
    crossing — at 46 um one at 12.51 krpm, while the 85 Hz pair crosses at 12.77); otherwise bisection on the number
    of unstable pairs, to the same 1e-6 relative."""
    from scipy.optimize import brentq

    ra, rb = (_crossing_real(system, s, model, f_hz, oil_supply) for s in (a, b))
    if (ra <= 0.0 < rb) or (rb <= 0.0 < ra):
        s_h = brentq(lambda s: _crossing_real(system, s, model, f_hz, oil_supply), a, b, xtol=1e-6 * a)
        lo, hi = max(a, s_h * (1 - 2e-6)), min(b, s_h * (1 + 2e-6))
        if _unstable_pairs(system, lo, model, oil_supply) == count_a != _unstable_pairs(system, hi, model, oil_supply):
            return s_h
    while b - a > 1e-6 * a:
        mid = 0.5 * (a + b)
        if _unstable_pairs(system, mid, model, oil_supply) == count_a:
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)


def _crossing_pair(lam_a, lam_b, count_a, count_b):
    """The eigenvalue (upper half plane) at the end of a grid interval that is unstable on the interval's unstable
    side and whose nearest partner on the other side is stable: the pair that crossed."""
    if count_b < count_a:  # regains stability: unstable at a, its partner stable at b
        lam_a, lam_b = lam_b, lam_a
    new = [x for x in lam_b if x.real > 0 and x.imag > 0]
    return min(new, key=lambda x: np.min(np.abs(lam_a[(lam_a.real <= 0) & (lam_a.imag > 0)] - x)))


def check_speed_range(speeds_rpm, name="speeds_rpm"):
    """``(lo, hi)`` [rpm] of a speed range given as (START, END) in either order: two speeds in the model's range that
    differ, else a :class:`ParameterError` (a range of one speed gave an unpacking error or an empty result)."""
    pair = np.atleast_1d(np.asarray(speeds_rpm, dtype=object))
    if pair.shape != (2,):
        raise ParameterError(f"{name} = {speeds_rpm!r:.60} is invalid: give the speed range (START, END) in rpm")
    lo, hi = sorted(check_speed(f"{name} {k}", v) for k, v in zip(("START", "END"), pair))
    if not lo < hi:
        raise ParameterError(f"{name} = {speeds_rpm!r} is invalid: START and END must differ (a range)")
    return lo, hi


def hopf_points(system, speeds_rpm=(1e3, 250e3), film_model=None, n_grid=60, restabilizing=False, oil_supply=None):
    """Hopf points of the full model's equilibrium in a speed range: where the number of unstable complex pairs of
    its Jacobian rises (and, with ``restabilizing``, falls), refined by Brent's method on the real part of the
    crossing pair.

    Parameters
    ----------
    system : Turbocharger
        The system.
    speeds_rpm : (float, float)
        Search range [rpm] (geometric grid of ``n_grid`` speeds, then refined).
    film_model : str, optional
        Default: the system's.
    n_grid : int
        Grid speeds.
    restabilizing : bool
        Also list where a pair regains stability (:attr:`HopfPoint.restabilizing`); by default only the crossings
        to instability (the linear onsets). A grid interval where one pair gains and another loses stability keeps
        the count and shows neither: refine ``n_grid`` to separate them.
    oil_supply : OilSupply, optional
        The thermal model: every speed of the grid and of the refinement at its own thermal operating point
        (:func:`frbmodel.linear.thermal.thermal_system` at that speed), so a Hopf point is a speed whose own
        temperatures put a pair on the imaginary axis (where the thermal Campbell diagram loses stability); its
        equilibrium state and eigenvector are those of that operating point. Default None: constant viscosities.

    Returns
    -------
    list of HopfPoint
        In increasing speed.
    """
    supply = check_oil_supply(oil_supply, bearings=system.bearings)
    model = film_model or system.film_model
    lo, hi = check_speed_range(speeds_rpm)
    if isinstance(n_grid, bool) or not isinstance(n_grid, (int, np.integer)) or n_grid < 2:
        raise ParameterError(f"n_grid = {n_grid!r} is invalid: valid range integer >= 2 (one speed finds no crossing)")
    if not isinstance(restabilizing, (bool, np.bool_)):
        raise ParameterError(f"restabilizing = {restabilizing!r} is a {type(restabilizing).__name__}; expected True "
                             "or False")
    grid = np.geomspace(lo, hi, n_grid)
    counts = [_unstable_pairs(system, s, model, supply) for s in grid]
    out = []
    for a, b, ca, cb in zip(grid[:-1], grid[1:], counts[:-1], counts[1:]):
        if cb == ca or (cb < ca and not restabilizing):
            continue
        lam_a, lam_b = (np.linalg.eigvals(equilibrium_jacobian(system, s, model, supply)[1]) for s in (a, b))
        f_hz = _crossing_pair(lam_a, lam_b, ca, cb).imag / (2 * math.pi)
        s_h = _refine_crossing(system, model, a, b, f_hz, ca, supply)
        z_eq, jac = equilibrium_jacobian(system, s_h, model, supply)
        lam, vec = np.linalg.eig(jac)
        k = int(np.argmin(np.where(lam.imag > 0, np.abs(lam.real), np.inf)))  # the pair on the imaginary axis there
        out.append(HopfPoint(float(s_h), float(lam[k].imag / (2 * math.pi)), vec[:, k], z_eq, cb < ca))
    return out


def hopf_branch(system, model, hp, lo, hi, ds_max, max_points, progress, on_point, segments, oil_supply=None):
    """The branch born at the Hopf point ``hp`` (of :func:`hopf_points` with the same ``oil_supply``), started along
    its eigenvector."""

    br = ContinuationProblem(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, hp.speed_rpm, segments,
                             oil_supply)
    n = br.segments * br.n
    t_ref, w_ref = 0.01 / hp.frequency_hz, 0.01 * hp.speed_rpm
    x0, tangent, f0 = _hopf_start(br, hp, n, t_ref, w_ref)
    return follow_branch(br, x0, n, t_ref, w_ref, tangent, lo, hi, 0.2, ds_max, max_points, progress, f0, on_point)


def hopf_guess(system, speed_rpm, film_model=None, search=0.25, max_points=40):
    """A guess of the orbit at ``speed_rpm`` born at the nearest Hopf point (:func:`hopf_points`, either crossing
    direction, within ``search`` of the speed): its branch followed from the Hopf eigenvector (continuation) until
    it passes the speed; the branch point nearest to it.

    Parameters
    ----------
    system : Turbocharger
    speed_rpm : float
    film_model : str, optional
    search : float
        Relative speed range searched for Hopf points, speed / (1 + search) ... speed (1 + search).
    max_points : int
        Branch points at most.

    Returns
    -------
    state : ndarray
        State without the rotation angle [SI] of that branch point.
    period : float
        Its period [s].
    info : dict
        ``hopf_rpm``, ``hopf_hz``, ``branch_points`` computed, ``from_point_rpm``.

    Raises
    ------
    ConvergenceError
        No Hopf point within ``search``, or its branch does not reach the speed within ``max_points`` (it grows
        towards the other side, or turns back).
    """
    model = film_model or system.film_model
    hps = hopf_points(system, (speed_rpm / (1 + search), speed_rpm * (1 + search)), model, n_grid=12,
                      restabilizing=True)
    if not hps:
        raise ConvergenceError(f"limit cycle guess 'hopf': the full model has no Hopf point within {search:.0%} of "
                               f"{speed_rpm:.0f} rpm")
    hp = min(hps, key=lambda h: abs(h.speed_rpm - speed_rpm))
    margin = 0.05 * abs(speed_rpm - hp.speed_rpm) + 10 * FOLD_MIN_REL * hp.speed_rpm  # vertical start's jitter
    lo, hi = min(hp.speed_rpm, speed_rpm) - margin, max(hp.speed_rpm, speed_rpm) + margin
    pts = hopf_branch(system, model, hp, lo, hi, 8.0, max_points, False, None, 1)
    side = np.sign(speed_rpm - hp.speed_rpm)
    passed = [p for p in pts if side * (p.speed_rpm - speed_rpm) >= 0]
    if side != 0 and not passed:
        reach = max((side * (p.speed_rpm - hp.speed_rpm) for p in pts), default=0.0)
        raise ConvergenceError(f"limit cycle guess 'hopf': the branch of the Hopf point at {hp.speed_rpm:.0f} rpm "
                               f"({hp.frequency_hz:.2f} Hz) does not reach {speed_rpm:.0f} rpm in {len(pts)} points "
                               f"(at most {reach:.0f} rpm towards it: it grows the other way or turns back); "
                               "use another guess")
    best = min(pts, key=lambda p: abs(p.speed_rpm - speed_rpm))
    return best.state.copy(), best.period, {"hopf_rpm": hp.speed_rpm, "hopf_hz": hp.frequency_hz,
                                            "branch_points": len(pts), "from_point_rpm": best.speed_rpm}


def follow_branch(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points, progress, f_first=None,
            on_point=None, jac0=None):
    """Branch points from x0 along ``tangent`` (x0 itself not included; ``f_first``: the phase normal at x0 if the
    flow vanishes there, at a Hopf point; ``jac0``: the Jacobian at x0, if known and regular). Ctrl-C / SIGTERM are
    raised between points."""

    with deferred_signals() as signals:
        return _follow_loop(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points, progress, f_first,
                            on_point, signals, jac0)


def _follow_loop(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points, progress, f_first, on_point,
                 signals, jac0):
    """The points: predictor along the tangent, corrector from the last point's Jacobian (from a fresh one at the
    predicted point after a failure, or at a Hopf point, where the period column vanishes), then the Jacobian and
    monodromy at the new point — its multipliers are those of the computed orbit, and it starts the next corrector."""
    import sys

    points = []
    x, jac = x0, jac0
    f_ref = f_first if f_first is not None else _phase_normal(br, x0[:n] * br.scale(), x0[n + 1] * w_ref)
    while len(points) < max_points:
        signals.check()
        try:
            x_new, iters = _correct(br, x + ds * tangent, tangent, x, ds, n, t_ref, w_ref, f_ref, x[:n], jac)
            f_new, jac_new, m, fl = _at_point(br, x_new, n, t_ref, w_ref)
        except (ConvergenceError, np.linalg.LinAlgError):
            ds, jac = 0.5 * ds, None
            if ds < 1e-3:
                break
            continue
        tangent = _next_tangent(jac_new, tangent, x_new - x)
        x, jac, f_ref = x_new, jac_new, f_new
        points.append(_point(br, x, n, t_ref, w_ref, m, fl))
        if on_point is not None:
            on_point(points[-1])
        if progress:
            p = points[-1]
            sys.stderr.write(f"continuation: {p.speed_rpm:9.0f} rpm, {1 / p.period:8.2f} Hz, radius "
                             f"{p.turbine_radius_m * 1e6:6.2f} um, {'stable' if p.stable else 'unstable'}\n")
        if not lo <= points[-1].speed_rpm <= hi or _collapsed(points):
            break
        ds = min(ds_max, ds * (1.5 if iters <= GOOD_ITERATIONS else 1.0 if iters <= SLOW_ITERATIONS else 0.6))
    return points


#: a branch has reached the equilibrium (a Hopf point) when its orbit shrinks below this share of its largest orbit
COLLAPSE = 0.02


def _collapsed(points):
    """True if the branch came back down onto the equilibrium: its last orbit is below COLLAPSE of the largest one
    and shrinking (continuing would pass through the Hopf point and retrace the branch half a period shifted)."""
    r = [p.turbine_radius_m for p in points]
    return len(r) >= 2 and r[-1] < COLLAPSE * max(r) and r[-1] < r[-2]


def start_tangent(br, x0, n, t_ref, w_ref, direction):
    """Unit tangent at a computed orbit x0, its speed component of sign ``direction``, the orbit as a point, and
    the Jacobian there."""
    _, jac, m, fl = _at_point(br, x0, n, t_ref, w_ref)
    guide = np.zeros(n + 2)
    guide[n + 1] = direction
    return _tangent(jac, guide), _point(br, x0, n, t_ref, w_ref, m, fl), jac


def _hopf_start(br, hp, n, t_ref, w_ref):
    """Start point (the equilibrium at the Hopf point, period 2π/ω), tangent (the linear orbit Re(v e^{iωt}) at the
    segment starts t_k = kT/m) and phase normal (its derivative at t = 0) of the periodic branch born at a Hopf
    point, in scaled unknowns."""
    m = br.segments
    v = hp.eigenvector / br.start_scale
    v = v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))
    x0 = np.concatenate([np.tile(hp.equilibrium / br.start_scale, m), [1.0 / hp.frequency_hz / t_ref,
                                                                       hp.speed_rpm / w_ref]])
    orbit = np.concatenate([(v * np.exp(2j * math.pi * k / m)).real for k in range(m)])
    tangent = np.concatenate([orbit / np.linalg.norm(orbit), [0.0, 0.0]])
    return x0, tangent, _padded(br, v.imag / np.linalg.norm(v.imag))


def shoot_segments(system, model, speed_rpm, z0, period, segments, tol=1e-6, max_iter=25):
    """A periodic orbit at a constant speed by multiple shooting: the m segment starts and the period by Newton's
    method on the segment defects and the phase condition (the equations of
    :func:`frbmodel.cycles.continuation.continuation` without the speed unknown and the arclength row), from a guess
    (z0 [SI], period [s]).

    Returns
    -------
    frbmodel.cycles.shooting.ShootingSolution
        The start of segment 0, the period, the monodromy (product of the segments') and its multipliers.

    Raises
    ------
    ConvergenceError
        Newton did not converge within ``max_iter`` iterations.
    """

    br = ContinuationProblem(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, speed_rpm, segments)
    n_all, t_ref = br.segments * br.n, 0.01 * period
    starts = br.flow(speed_rpm).states(np.asarray(z0, float), period * np.arange(br.segments + 1) / br.segments)
    x = np.append(starts[:-1, :-1].ravel() / br.scale(), period / t_ref)
    f_ref, u_ref = _phase_normal(br, starts[0, :-1], speed_rpm), x[:n_all].copy()
    for it in range(max_iter + 1):
        z, T = x[:n_all] * br.scale(), x[n_all] * t_ref
        res, jac, mono, _ = _jacobian(br, z, T, speed_rpm, br.scale(), t_ref, 1.0, f_ref, speed_column=False)
        res[n_all] = f_ref @ (x[:n_all] - u_ref)
        err = float(np.max(np.abs(res)))
        if err < tol:
            mult = np.linalg.eigvals(mono)
            return ShootingSolution(z[:br.n].copy(), T, mono, mult[np.argsort(-np.abs(mult))], it, err, True)
        x = x + np.linalg.solve(jac[:, :n_all + 1], -res)
        if not x[n_all] > 0:
            break
    raise ConvergenceError(f"multiple shooting ({br.segments} segments) at {speed_rpm:.0f} rpm did not converge: "
                           f"residual {err:.3g} (tolerance {tol:g}) after {it} Newton iterations")


def _padded(br, f):
    """A phase normal on segment 0 as a vector over all segment starts."""
    out = np.zeros(br.segments * br.n)
    out[:br.n] = f
    return out


def _phase_normal(br, z, speed):
    """Unit normal of the phase condition: the flow at segment 0's start, scaled (zero on the other segments)."""
    f = br.flow(speed).rhs(z[:br.n]) / br.start_scale  # d(u)/dt = f / scale
    return _padded(br, f / np.linalg.norm(f))


#: corrector: scaled residual tolerance, iterations at most; step control: the step grows after at most
#: GOOD_ITERATIONS corrector iterations, stays after at most SLOW_ITERATIONS, else shrinks. The corrector starts from
#: the previous point's Jacobian, a step behind the chord Jacobian at the predicted point used before, which took
#: one iteration less (3 / 5 then; the 101-point benchmark branch covers the same 14.2-139.8 krpm with 4 / 6 now,
#: with 3 / 5 only 15.5-135.5 krpm); on strongly unstable orbits (|mu| ~ 300) the iterations stay high at any step,
#: and shrinking there stalled the 58.5 krpm branch
TOL, MAX_CORRECTOR, GOOD_ITERATIONS, SLOW_ITERATIONS = 1e-6, 8, 4, 6


__all__ = ["BranchPoint", "ContinuationProblem", "HopfPoint", "equilibrium_jacobian", "follow_branch", "hopf_branch",
           "hopf_dataframe", "hopf_guess", "hopf_points", "shoot_segments", "start_tangent", "trivial_error"]
