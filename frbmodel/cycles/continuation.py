"""Pseudo-arclength continuation of whirl limit cycles in rotor speed, with bifurcation detection.

Unknowns X = (u0, τ, p): the scaled start state u0 = z0 / scale of a periodic orbit (:mod:`frbmodel.cycles.limitcycle`),
its period τ = T / T_ref and the rotor speed p = Ω / Ω_ref. Equations: the shooting residual (Φ_T(z0; Ω) − z0) /
scale, the phase condition (the start point on the hyperplane through the previous point normal to the flow there)
and the arclength condition t·(X − X_prev) = Δs along the unit tangent t of the branch. A predictor step along the
tangent is corrected by Newton iterations starting from the Jacobian of the last point (monodromy by forward
differences of the flow, ∂Φ/∂Ω by one more flow; after a failed step, and at a Hopf point, one computed at the
predicted point) and updated by Broyden's formula; the Jacobian and monodromy are then computed at the new point
(its multipliers, the next tangent, the next corrector). The step length adapts to the number of corrector
iterations. Folds (the speed turns: a multiplier through +1), period doublings (a real multiplier through −1) and
Neimark-Sacker points (a complex pair leaving the unit circle: a second whirl frequency, a torus) are detected from
the Floquet multipliers of consecutive points and located by linear interpolation between them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ConvergenceError, ParameterError

#: corrector: scaled residual tolerance, iterations at most; step control: the step grows after at most
#: GOOD_ITERATIONS corrector iterations, stays after at most SLOW_ITERATIONS, else shrinks. The corrector starts from
#: the previous point's Jacobian, a step behind the chord Jacobian at the predicted point used before, which took
#: one iteration less (3 / 5 then; the 101-point benchmark branch covers the same 14.2-139.8 krpm with 4 / 6 now,
#: with 3 / 5 only 15.5-135.5 krpm); on strongly unstable orbits (|mu| ~ 300) the iterations stay high at any step,
#: and shrinking there stalled the 58.5 krpm branch
TOL, MAX_CORRECTOR, GOOD_ITERATIONS, SLOW_ITERATIONS = 1e-6, 8, 4, 6
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


class _Branch:
    """Flows and residuals of the continuation problem at any speed (problems built per speed and cached)."""

    def __init__(self, system, model, rtol, atol_m, scale_m, workers, start_rpm, segments=1):
        from ..nonlinear.runup import atol_vector
        from .limitcycle import _Flow

        self.system, self.model = system, model
        self.rtol, self.atol_m, self.workers = rtol, atol_m, workers
        self._flows = {}
        self._last = None  # the last flow made for a new speed (it has chosen its integrator by the next one)
        self._flow_cls = _Flow
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
        from ..nonlinear.runup import SpeedProfile, build_problem

        key = float(speed_rpm)
        if key not in self._flows:
            if len(self._flows) > 8:
                self._flows.clear()
            problem = build_problem(self.system, SpeedProfile.constant(key, 1.0), self.model)
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
    from .limitcycle import FD_STEP
    from .shooting import monodromy

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
    from .limitcycle import FD_STEP, MULTIPLIER_TOL
    from .shooting import monodromy

    if _trivial_error(np.linalg.eigvals(m)) <= MULTIPLIER_TOL:
        return m
    mseg = br.segments
    z, T = x[:n] * br.scale(), x[n] * t_ref
    central = np.eye(br.n)
    try:
        for zk in z.reshape(mseg, br.n):
            central = monodromy(fl, zk, T / mseg, br.scale_vec, None, FD_STEP, br.workers, central=True) @ central
    except ConvergenceError:
        return m
    better = _trivial_error(np.linalg.eigvals(central)) < _trivial_error(np.linalg.eigvals(m))
    return central if better else m


def _trivial_error(mult):
    """Distance of the multiplier closest to 1 from 1 (0 for exact multipliers of a periodic orbit)."""
    return float(np.min(np.abs(np.asarray(mult) - 1.0)))


def _point(br, x, n, t_ref, w_ref, m, fl):
    """A BranchPoint (orbit measures sampled from the flow ``fl``) for the solution x with monodromy m."""
    from ..nonlinear.recorder import RunupSchema
    from .limitcycle import MULTIPLIER_TOL, _orbit_result
    from .shooting import stable_multipliers

    m = _checked_monodromy(br, x, n, t_ref, w_ref, m, fl)
    z, T, speed = x[:br.n] * br.start_scale, x[n] * t_ref, x[n + 1] * w_ref  # the orbit from segment 0's start
    t = np.linspace(0.0, T, POINT_SAMPLES + 1)
    orbit = _orbit_result(fl.problem, RunupSchema.from_system(br.system), t, fl.states(z, t))
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


def equilibrium_jacobian(system, speed_rpm, film_model=None):
    """Equilibrium state (method-J bearing equilibria: the full model's fixed point) and the full model's Jacobian
    there, without the rotation angle.

    Returns
    -------
    z_eq : ndarray (n,)
        Equilibrium state [SI].
    jac : ndarray (n, n)
        ∂(dz/dt)/∂z by central differences of the compiled RHS (steps 1e-6 of each state's typical size: truncation
        ~1e-12, round-off ~1e-10 relative, far below the forward differences' ~1e-8 that blurred Hopf speeds by
        ~0.3 % at 2 krpm where the critical damping changes slowly with speed).
    """
    from ..nonlinear.runup import SpeedProfile, atol_vector, build_problem, initial_state

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


def _unstable_pairs(system, speed_rpm, model):
    lam = np.linalg.eigvals(equilibrium_jacobian(system, speed_rpm, model)[1])
    return int(np.sum((lam.real > 0) & (lam.imag > 0)))


def _crossing_real(system, speed_rpm, model, near_hz):
    """Real part [1/s] of the eigenvalue whose frequency is closest to ``near_hz``."""
    lam = np.linalg.eigvals(equilibrium_jacobian(system, speed_rpm, model)[1])
    lam = lam[lam.imag > 0]
    return float(lam[np.argmin(np.abs(lam.imag / (2 * math.pi) - near_hz))].real)


def _refine_crossing(system, model, a, b, f_hz, count_a):
    """Speed [rpm] in (a, b) where the pair near ``f_hz`` crosses: Brent's method on its real part when it changes
    sign over the interval and the number of unstable pairs changes across the root found (the eigenvalue nearest
    in frequency can switch to another, heavily damped one within the interval: a jump of the real part that is no
    crossing — at 46 um one at 12.51 krpm, while the 85 Hz pair crosses at 12.77); otherwise bisection on the number
    of unstable pairs, to the same 1e-6 relative."""
    from scipy.optimize import brentq

    ra, rb = (_crossing_real(system, s, model, f_hz) for s in (a, b))
    if (ra <= 0.0 < rb) or (rb <= 0.0 < ra):
        s_h = brentq(lambda s: _crossing_real(system, s, model, f_hz), a, b, xtol=1e-6 * a)
        lo, hi = max(a, s_h * (1 - 2e-6)), min(b, s_h * (1 + 2e-6))
        if _unstable_pairs(system, lo, model) == count_a != _unstable_pairs(system, hi, model):
            return s_h
    while b - a > 1e-6 * a:
        mid = 0.5 * (a + b)
        if _unstable_pairs(system, mid, model) == count_a:
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


def hopf_points(system, speeds_rpm=(1e3, 250e3), film_model=None, n_grid=60, restabilizing=False):
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

    Returns
    -------
    list of HopfPoint
        In increasing speed.
    """
    model = film_model or system.film_model
    grid = np.geomspace(*sorted(speeds_rpm), n_grid)
    counts = [_unstable_pairs(system, s, model) for s in grid]
    out = []
    for a, b, ca, cb in zip(grid[:-1], grid[1:], counts[:-1], counts[1:]):
        if cb == ca or (cb < ca and not restabilizing):
            continue
        lam_a, lam_b = (np.linalg.eigvals(equilibrium_jacobian(system, s, model)[1]) for s in (a, b))
        f_hz = _crossing_pair(lam_a, lam_b, ca, cb).imag / (2 * math.pi)
        s_h = _refine_crossing(system, model, a, b, f_hz, ca)
        z_eq, jac = equilibrium_jacobian(system, s_h, model)
        lam, vec = np.linalg.eig(jac)
        k = int(np.argmin(np.where(lam.imag > 0, np.abs(lam.real), np.inf)))  # the pair on the imaginary axis there
        out.append(HopfPoint(float(s_h), float(lam[k].imag / (2 * math.pi)), vec[:, k], z_eq, cb < ca))
    return out


def _nontrivial(p):
    """Multipliers of a branch point without the trivial one (the one closest to 1)."""
    return np.delete(p.multipliers, int(np.argmin(np.abs(p.multipliers - 1.0))))


def _outside(p):
    """Non-trivial multipliers of a branch point outside the unit circle (by more than their accuracy)."""
    from .limitcycle import MULTIPLIER_TOL

    mu = _nontrivial(p)
    return mu[np.abs(mu) > 1.0 + MULTIPLIER_TOL]


def _classify(a, b):
    """Bifurcations between consecutive branch points a, b: [(type, fraction along a -> b)]. The number of
    multipliers outside the unit circle changes; the crossing one (outside on the unstable side, closest to the
    circle) decides the type by its angle: ~0 fold, ~π period doubling, otherwise Neimark-Sacker (a complex pair
    counts twice). Located where its modulus, interpolated (or extrapolated by up to one interval: the count uses
    :data:`frbmodel.cycles.limitcycle.MULTIPLIER_TOL`) linearly, is 1."""
    out_a, out_b = _outside(a), _outside(b)
    if out_a.size == out_b.size:
        return []
    side = out_b if out_b.size > out_a.size else out_a
    mu = side[np.argmin(np.abs(side))]
    angle = abs(float(np.angle(mu)))
    kind = "fold" if angle < 0.05 else "period doubling" if angle > math.pi - 0.05 else "Neimark-Sacker"
    other = b if side is out_a else a
    mo = _nontrivial(other)
    rest = mo[np.argsort(np.abs(mo - mu))][:1]
    r_in = float(np.abs(rest[0])) if rest.size else 1.0
    r_out = float(abs(mu))
    frac = (1.0 - r_in) / (r_out - r_in) if r_out != r_in else 0.5
    # detected beyond MULTIPLIER_TOL, located where the modulus is 1: possibly up to one interval before (after)
    frac = float(np.clip(frac if side is out_b else 1.0 - frac, -1.0, 2.0))
    return [(kind, frac)]


@dataclass
class BifurcationDiagram:
    """Branches of limit cycles vs rotor speed and their bifurcation points (:func:`continuation`).

    Attributes
    ----------
    points : list of BranchPoint
        The computed orbits, in branch order (arclength).
    bifurcations : list of dict
        Each: ``speed_rpm``, ``type`` (Hopf, fold, period doubling, Neimark-Sacker), ``criticality`` (of a Hopf
        point: super- or subcritical), ``frequency_hz``, ``turbine_radius_um``, ``mode`` (the Campbell mode of the
        branch's Hopf point), ``film`` (Hopf: the film moving most in the eigenvector; others: the film with the
        largest eccentricity ratio, :func:`hopf_record`), ``between`` (indices of the two points it lies between).
    meta : dict
        System, film model, tolerances, steps taken.
    """

    points: list
    bifurcations: list
    meta: dict = field(default_factory=dict)

    def to_dataframe(self):
        """The branch points as a table (units in the column names). ``trivial multiplier error`` is the distance from
        1 of the multiplier closest to it (1 exactly on a periodic orbit): the accuracy of the multipliers there."""
        import pandas as pd

        rows = [{"speed [rpm]": p.speed_rpm, "frequency [Hz]": 1 / p.period, "period [s]": p.period,
                 "turbine wheel orbit radius [um]": p.turbine_radius_m * 1e6, "stable": p.stable,
                 "max |multiplier| (nontrivial) [-]": float(np.max(np.abs(np.delete(
                     p.multipliers, int(np.argmin(np.abs(p.multipliers - 1.0))))))),
                 "trivial multiplier error [-]": _trivial_error(p.multipliers),
                 **{f"max eps {k} [-]": v for k, v in zip(("turbine inner", "turbine outer", "compressor inner",
                                                          "compressor outer"), p.max_eps)}} for p in self.points]
        return pd.DataFrame(rows)

    def bifurcation_table(self):
        """The bifurcation points as a table."""
        import pandas as pd

        return pd.DataFrame([{k: v for k, v in b.items() if k != "between"} for b in self.bifurcations],
                            columns=["speed_rpm", "type", "criticality", "frequency_hz", "turbine_radius_um", "mode",
                                     "film"])

    def to_xarray(self):
        """Branch points as an :class:`xarray.Dataset` along ``point`` (units in the attributes)."""
        import xarray as xr

        from ..core.results import netcdf_attrs, variable

        df = self.to_dataframe()
        ds = xr.Dataset({
            "speed": variable(("point",), df["speed [rpm]"].values, "rpm", "rotor speed"),
            "frequency": variable(("point",), df["frequency [Hz]"].values, "Hz", "orbit frequency 1/T"),
            "turbine_radius": variable(("point",), df["turbine wheel orbit radius [um]"].values * 1e-6, "m",
                                       "turbine wheel orbit radius"),
            "stable": variable(("point",), df["stable"].values.astype(int), "-", "1: stable orbit"),
            "max_eps": variable(("point", "film"), np.array([p.max_eps for p in self.points]), "-",
                                "largest eccentricity ratio over one period"),
            "multiplier_real": variable(("point", "multiplier"), np.array([p.multipliers.real for p in self.points]),
                                        "-", "Floquet multipliers, real part (largest modulus first)"),
            "multiplier_imag": variable(("point", "multiplier"), np.array([p.multipliers.imag for p in self.points]),
                                        "-", "Floquet multipliers, imaginary part"),
        })
        ds.attrs.update(netcdf_attrs({"bifurcations": self.bifurcations, **self.meta}))
        return ds

    @classmethod
    def load(cls, path):
        """Read a diagram written by :meth:`save` (``branch.nc``, or the folder holding it).

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        BifurcationDiagram
        """
        from pathlib import Path

        import xarray as xr

        from ..core.results import NETCDF_ENGINE, decode_attr

        path = Path(path)
        path = path / "branch.nc" if path.is_dir() else path
        with xr.open_dataset(path, engine=NETCDF_ENGINE) as ds:
            mult = ds["multiplier_real"].values + 1j * ds["multiplier_imag"].values
            pts = [BranchPoint(float(s), 1.0 / float(f), m, bool(st), float(r), e) for s, f, m, st, r, e in
                   zip(ds["speed"].values, ds["frequency"].values, mult, ds["stable"].values,
                       ds["turbine_radius"].values, ds["max_eps"].values)]
            meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        return cls(pts, meta.pop("bifurcations", []), meta)

    def save(self, out_dir, envelopes=(), spectrogram=None, campbell=None):
        """Write ``branch.csv``, ``bifurcations.csv``, ``branch.nc`` and the figures ``bifurcation.png`` and
        ``bifurcation.html`` (with the run envelopes, spectrogram and Campbell lines of :meth:`plot`) into
        ``out_dir``; returns the paths."""
        from pathlib import Path

        import matplotlib.pyplot as plt

        from ..core.results import NETCDF_ENGINE

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "branch.csv", out / "bifurcations.csv", out / "branch.nc", out / "bifurcation.png",
                 out / "bifurcation.html"]
        self.to_dataframe().to_csv(paths[0], index=False)
        self.bifurcation_table().to_csv(paths[1], index=False)
        self.to_xarray().to_netcdf(paths[2], engine=NETCDF_ENGINE)
        fig = self.plot(envelopes=envelopes, spectrogram=spectrogram, campbell=campbell)
        fig.savefig(paths[3], dpi=130)
        plt.close(fig)
        self.plot_html(paths[4], envelopes=envelopes, campbell=campbell)
        return paths

    def plot(self, title=None, envelopes=(), spectrogram=None, campbell=None):
        """Bifurcation diagram (matplotlib): turbine-wheel orbit radius [µm] and orbit frequency [Hz] vs speed;
        stable solid, unstable dashed, bifurcation points marked; behind them run envelopes (label, speeds [rpm],
        radius [µm]), a run's spectrogram and a Campbell diagram's unstable modes and film whirl lines
        (:func:`frbmodel.plots.bifurcation.diagram_figure`)."""
        from ..plots.bifurcation import diagram_figure

        return diagram_figure(self, title, envelopes, spectrogram, campbell)

    def plot_html(self, path, title=None, envelopes=(), campbell=None, include_plotlyjs="directory"):
        """The diagram as an interactive HTML file (:func:`frbmodel.plots.bifurcation.diagram_html`); returns
        its path."""
        from ..plots.bifurcation import diagram_html

        return diagram_html(self, path, title, envelopes, campbell, include_plotlyjs)


def continuation(system, speeds_rpm, start="hopf", film_model=None, ds=1.0, ds_max=8.0, max_points=100,
                 progress=False, on_point=None, segments=1):
    """Branches of limit cycles in rotor speed (pseudo-arclength), from the Hopf points or from a given orbit.

    Parameters
    ----------
    system : Turbocharger
        The system.
    speeds_rpm : (float, float)
        Speed range [rpm]; a branch is followed until it leaves it (or ``max_points`` are computed).
    start : "hopf", LimitCycle or float, or a list of them
        ``"hopf"``: one branch from each Hopf point of the full model in the range (:func:`hopf_points`), started
        along the Hopf eigenvector; a limit cycle or a speed [rpm] to compute one at: the branch through it, both
        directions; a list: each of them in turn (e.g. ``[25e3, 60e3]``: the branches of the whirls settled on at
        25 and 60 krpm).
    film_model : str, optional
        Default: the system's.
    ds, ds_max : float
        Initial and largest arclength step (scaled units: 1 ~ 1 % of the start speed or 1 µm of orbit).
    max_points : int
        Points per branch and direction at most.
    progress : bool
        Print a line per point on stderr.
    on_point : callable, optional
        Called with each new :class:`BranchPoint` as soon as it is computed (e.g. to stream it to a file).
    segments : int
        Shooting segments per orbit: 1 single shooting; m > 1 multiple shooting (m flows of T/m, the defects between
        them as equations; same cost per Newton step), for strongly unstable orbits: a flow over the whole period
        amplifies errors by the largest multiplier |mu|, a segment by about |mu|^(1/m).

    Returns
    -------
    BifurcationDiagram
    """
    from ..physics.film import check_model
    from .limitcycle import LimitCycle, limit_cycle

    lo, hi = sorted(float(s) for s in speeds_rpm)
    model = check_model(film_model or system.film_model)
    if int(segments) != segments or segments < 1:
        raise ParameterError(f"segments = {segments!r} is invalid: a whole number >= 1")
    starts = check_starts(start, (lo, hi))
    branches, origins = [], []  # origins: the Hopf point a branch starts at, None for a branch through an orbit
    for s0 in starts:
        if isinstance(s0, str):
            for hp in hopf_points(system, (lo, hi), model, restabilizing=True):
                branches.append(_hopf_branch(system, model, hp, lo, hi, ds_max, max_points, progress, on_point,
                                             segments))
                origins.append(hp)
        else:
            lc = s0 if isinstance(s0, LimitCycle) else limit_cycle(system, float(s0), film_model=model)
            branches.append(_branch_through(system, model, lc, lo, hi, ds, ds_max, max_points, progress, on_point,
                                            segments))
            origins.append(None)
    return _diagram(system, model, branches, origins, lo, hi)


def check_starts(start, speeds_rpm, name="start", range_name="the speed range"):
    """The branch starts of :func:`continuation` as a list (``start``: "hopf", a LimitCycle, a speed [rpm] or a list
    of them), or a ParameterError naming the bad one and the valid values (used by the API, ``frb bifurcation`` and
    the ``bifurcation`` study before any computation).

    Examples
    --------
    >>> check_starts([25e3, "hopf"], (1e3, 40e3))
    [25000.0, 'hopf']
    >>> try:
    ...     check_starts(60e3, (1e3, 40e3))
    ... except ParameterError as exc:
    ...     print(exc)
    start = 60000 rpm is outside the speed range 1000:40000 rpm
    """
    from ..nonlinear.runup import check_speed
    from .limitcycle import LimitCycle

    lo, hi = sorted(float(s) for s in speeds_rpm)
    starts = [start] if isinstance(start, (str, LimitCycle)) or np.ndim(start) == 0 else list(start)
    out = []
    for s0 in starts:
        if isinstance(s0, str):
            if s0 != "hopf":
                raise ParameterError(f"{name} = {s0!r} is invalid: 'hopf', a LimitCycle or a speed [rpm] (or a "
                                     "list of them)")
            out.append(s0)
            continue
        speed = s0.speed_rpm if isinstance(s0, LimitCycle) else check_speed(name, s0)
        if not lo <= speed <= hi:
            raise ParameterError(f"{name} = {speed:.0f} rpm is outside {range_name} {lo:.0f}:{hi:.0f} rpm")
        out.append(s0 if isinstance(s0, LimitCycle) else speed)
    return out


def _hopf_branch(system, model, hp, lo, hi, ds_max, max_points, progress, on_point, segments):
    """The branch born at the Hopf point ``hp``, started along its eigenvector."""
    from .limitcycle import SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS

    br = _Branch(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, hp.speed_rpm, segments)
    n = br.segments * br.n
    t_ref, w_ref = 0.01 / hp.frequency_hz, 0.01 * hp.speed_rpm
    x0, tangent, f0 = _hopf_start(br, hp, n, t_ref, w_ref)
    return _follow(br, x0, n, t_ref, w_ref, tangent, lo, hi, 0.2, ds_max, max_points, progress, f0, on_point)


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
    pts = _hopf_branch(system, model, hp, lo, hi, 8.0, max_points, False, None, 1)
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


def _branch_through(system, model, lc, lo, hi, ds, ds_max, max_points, progress, on_point, segments):
    """The branch through the orbit ``lc``, followed in both directions (lower speeds first in the result)."""
    from .limitcycle import SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS

    br = _Branch(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, lc.speed_rpm, segments)
    n = br.segments * br.n
    t_ref, w_ref = 0.01 * lc.period, 0.01 * lc.speed_rpm
    starts = br.flow(lc.speed_rpm).states(lc.state, lc.period * np.arange(br.segments + 1) / br.segments)
    x0 = np.concatenate([starts[:-1, :-1].ravel() / br.scale(), [lc.period / t_ref, lc.speed_rpm / w_ref]])
    halves = []
    for direction in (+1, -1):
        tangent, first, jac0 = _start_tangent(br, x0, n, t_ref, w_ref, direction)
        halves.append([first] + _follow(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points, progress,
                                        on_point=on_point, jac0=jac0))
    return halves[1][::-1] + halves[0][1:]


def _event(kind, a, c, frac, between, films=(), mode=""):
    """A bifurcation record between branch points a and c at fraction ``frac`` (linear interpolation); ``film`` is
    the film with the largest eccentricity ratio there (of ``films``, the names), ``mode`` the branch's Hopf mode."""
    eps = a.max_eps + frac * (np.asarray(c.max_eps) - a.max_eps)
    return {"speed_rpm": a.speed_rpm + frac * (c.speed_rpm - a.speed_rpm), "type": kind, "criticality": "",
            "frequency_hz": 1 / a.period + frac * (1 / c.period - 1 / a.period),
            "turbine_radius_um": max(0.0, 1e6 * (a.turbine_radius_m
                                                 + frac * (c.turbine_radius_m - a.turbine_radius_m))),
            "mode": mode, "film": f"{films[int(np.argmax(eps))]} (eps {np.max(eps):.2f})" if len(films) else "",
            "between": between}


def hopf_record(system, hp, branch=(), film_model=None):
    """The bifurcation-table record of a Hopf point.

    ``type``: "Hopf", or "Hopf (restabilizing)" where the pair regains stability with rising speed
    (:attr:`HopfPoint.restabilizing`). ``criticality``: "supercritical" if its branch grows towards the side where
    the crossing pair is unstable (higher speeds; lower ones at a restabilizing point), "subcritical" if it grows
    towards the other side — the side of the first branch point more than :data:`FOLD_MIN_REL` from the Hopf speed
    —, "" without a branch or when all its points stay within that of the Hopf speed (a vertical branch).
    ``mode``: precession and kind of the method-J Campbell mode nearest in frequency at that speed (the linear
    onsets agree to 0.03 %). ``film``: the film whose relative motion in the crossing eigenvector, over its
    clearance, is largest (inner: journal minus ring, outer: ring), with that share of the four.

    Parameters
    ----------
    system : Turbocharger
    hp : HopfPoint
    branch : sequence of BranchPoint
        The branch started there (may be empty).
    film_model : str, optional

    Returns
    -------
    dict
    """
    from ..linear.campbell import campbell
    from ..linear.whirl import film_names
    from ..nonlinear.runup import SpeedProfile, build_problem

    cd = campbell(system, "J", [hp.speed_rpm], whirl=False)
    j = int(np.nanargmin(np.abs(cd.frequencies_hz[0] - hp.frequency_hz)))
    p = build_problem(system, SpeedProfile.constant(hp.speed_rpm, 1.0), film_model or system.film_model)
    v, rel = hp.eigenvector, []
    for i, b in enumerate(system.bearings):
        ring = v[p.ring_index(i):p.ring_index(i) + 2]
        rel += [np.linalg.norm(v[4 * b.node:4 * b.node + 2] - ring) / b.inner.clearance,
                np.linalg.norm(ring) / b.outer.clearance]
    rel = np.array(rel) / np.sum(rel)
    k = int(np.argmax(rel))
    # the side of the branch's first speed excursion beyond the jitter of a vertical branch (the first points may
    # all lie within it: small first steps, or a degenerate Hopf point whose branch bends only at finite amplitude)
    ahead = next((d for d in (q.speed_rpm - hp.speed_rpm for q in branch) if abs(d) > FOLD_MIN_REL * hp.speed_rpm),
                 0.0)
    unstable_side = -1.0 if hp.restabilizing else 1.0
    crit = "" if ahead == 0.0 else "supercritical" if ahead * unstable_side > 0 else "subcritical"  # "": vertical
    return {"speed_rpm": hp.speed_rpm, "type": "Hopf (restabilizing)" if hp.restabilizing else "Hopf",
            "criticality": crit, "frequency_hz": hp.frequency_hz,
            "turbine_radius_um": 0.0, "mode": f"{cd.precession[0, j]} {cd.mode_kind[0, j]}",
            "film": f"{film_names(system)[k]} ({100 * rel[k]:.0f} %)", "between": []}


def _end_hopf(system, model, b, at_start, offset, films):
    """The record of the Hopf point at which the branch ``b`` (through a given orbit) collapses onto the equilibrium:
    the full model's Hopf point (either direction of crossing) within :data:`END_HOPF_REL` of the end's speed and
    frequency, recorded as from :func:`hopf_record` with the branch read from that end; without one, the end point
    itself (type "Hopf", no criticality or mode)."""
    end = b[0] if at_start else b[-1]
    s, f = end.speed_rpm, 1.0 / end.period
    near = [hp for hp in hopf_points(system, ((1 - END_HOPF_REL) * s, (1 + END_HOPF_REL) * s), model, n_grid=8,
                                     restabilizing=True) if abs(hp.frequency_hz / f - 1) < END_HOPF_REL]
    if not near:
        return _event("Hopf", end, end, 0.0, [offset + b.index(end)], films)
    hp = min(near, key=lambda h: abs(h.speed_rpm - s))
    rec = hopf_record(system, hp, b if at_start else b[::-1], model)
    rec["between"] = [offset + b.index(end)]
    return rec


def _branch_events(b, off, films=(), mode=""):
    """Bifurcations along one branch: folds where the speed turns (the branch point of extreme speed; a multiplier
    passes +1 there, which the multipliers near the turn, with the trivial one beside it, cannot tell reliably), and
    the period doublings and Neimark-Sacker points of :func:`_classify` away from the folds (2 points or more)."""
    s = np.array([p.speed_rpm for p in b])
    turns = [i for i in range(1, len(b) - 1) if (s[i] - s[i - 1]) * (s[i + 1] - s[i]) < 0
             and min(np.max(np.abs(s[max(i - 3, 0):i] - s[i])), np.max(np.abs(s[i + 1:i + 4] - s[i])))
             > FOLD_MIN_REL * s[i]]
    events = [_event("fold", b[i], b[i], 0.0, [off + i], films, mode) for i in turns]
    for i in range(len(b) - 1):
        if any(abs(i - j) <= 2 or abs(i + 1 - j) <= 2 for j in turns):
            continue
        # a real multiplier through +1 without a turn in speed is not generic without a symmetry (none here, with
        # gravity): it is the radial multiplier of a nearly vertical branch drifting about 1 + MULTIPLIER_TOL
        events += [_event(kind, b[i], b[i + 1], frac, [off + i, off + i + 1], films, mode)
                   for kind, frac in _classify(b[i], b[i + 1]) if kind != "fold"]
    return events


#: largest relative distance in speed and frequency between the end of a branch that collapses onto the equilibrium
#: and the Hopf point it is attributed to (the end is one step short of the point: 0.1 % measured at 30.7 krpm)
END_HOPF_REL = 0.03


def _diagram(system, model, branches, origins, lo, hi):
    """The BifurcationDiagram of computed branches (``origins``: per branch the Hopf point it starts at, or None):
    Hopf points, folds and multiplier crossings."""
    from ..linear.whirl import film_names
    from .limitcycle import SHOOT_RTOL

    films = film_names(system)
    points, bifs = [], []
    for b, hp in zip(branches, origins):
        ends = [hopf_record(system, hp, b, model)] if hp is not None else []
        for end in ((b[0], b[-1]) if hp is None and len(b) > 1 else ()):
            if end.turbine_radius_m < COLLAPSE * max(p.turbine_radius_m for p in b):  # the branch ends at a Hopf point
                ends.append(_end_hopf(system, model, b, end is b[0], len(points), films))
        mode = next((e["mode"] for e in ends if e["mode"]), "")  # the branch's points inherit its Hopf point's mode
        bifs += ends + _branch_events(b, len(points), films, mode)
        points.extend(b)
    meta = {"system": system.to_dict(), "film_model": model, "speed_range_rpm": [lo, hi], "rtol": SHOOT_RTOL,
            "branches": [len(b) for b in branches]}
    return BifurcationDiagram(points, sorted(_unique_hopf(bifs), key=lambda e: e["speed_rpm"]), meta)


def _unique_hopf(bifs):
    """The records with each Hopf point once (a branch from it and a branch through an orbit that ends there both
    record it; the one with a criticality is kept)."""
    out = []
    for b in bifs:
        same = next((i for i, o in enumerate(out) if b["type"].startswith("Hopf") and o["type"] == b["type"]
                     and abs(o["speed_rpm"] - b["speed_rpm"]) <= 1e-5 * b["speed_rpm"]), None)
        if same is None:
            out.append(b)
        elif b["criticality"] and not out[same]["criticality"]:
            out[same] = b
    return out


def _follow(br, x0, n, t_ref, w_ref, tangent, lo, hi, ds, ds_max, max_points, progress, f_first=None,
            on_point=None, jac0=None):
    """Branch points from x0 along ``tangent`` (x0 itself not included; ``f_first``: the phase normal at x0 if the
    flow vanishes there, at a Hopf point; ``jac0``: the Jacobian at x0, if known and regular). Ctrl-C / SIGTERM are
    raised between points."""
    from ..core.interrupt import deferred_signals

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


def _start_tangent(br, x0, n, t_ref, w_ref, direction):
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
    method on the segment defects and the phase condition (the equations of :func:`continuation` without the speed
    unknown and the arclength row), from a guess (z0 [SI], period [s]).

    Returns
    -------
    frbmodel.cycles.shooting.ShootingSolution
        The start of segment 0, the period, the monodromy (product of the segments') and its multipliers.

    Raises
    ------
    ConvergenceError
        Newton did not converge within ``max_iter`` iterations.
    """
    from .limitcycle import SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS
    from .shooting import ShootingSolution

    br = _Branch(system, model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, speed_rpm, segments)
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


__all__ = ["BifurcationDiagram", "BranchPoint", "HopfPoint", "continuation", "equilibrium_jacobian", "hopf_guess",
           "hopf_points", "hopf_record", "check_starts", "shoot_segments"]
