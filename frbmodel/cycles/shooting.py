"""Periodic orbits of autonomous (or periodically forced) ODEs by single shooting, with Floquet multipliers.

A periodic orbit z(t + T) = z(t) of dz/dt = f(z) is a zero of the shooting residual
R(z0, T) = [Φ_T(z0) − z0, f(z_ref)·(z0 − z_ref)], where Φ_T is the flow over the time T and the second row is the
phase condition (the start point stays on the hyperplane through the reference point normal to the flow there,
which removes the time-shift freedom of an autonomous orbit). Newton's method solves it with the Jacobian
[[M − I, f(Φ_T(z0))], [f(z_ref)ᵀ, 0]], the monodromy matrix M = ∂Φ_T/∂z0 by forward differences of the flow (one
integration per state). For a forced system the period is fixed and the phase condition dropped. The Floquet
multipliers are the eigenvalues of M at the solution; an autonomous orbit has the trivial multiplier 1, and it is
stable when all others lie inside the unit circle.

Everything is done in scaled variables u = z / scale, so that states of very different magnitude (film positions
of micrometres, ring speeds of 10⁴ rad/s) weigh alike in the residual and in the difference steps.

>>> import numpy as np
>>> from scipy.integrate import solve_ivp
>>> def f(z):  # Hopf normal form, mu = 0.25, omega = 2: the limit cycle r = 0.5, T = pi
...     r2 = z[0] ** 2 + z[1] ** 2
...     return np.array([0.25 * z[0] - 2 * z[1] - r2 * z[0], 2 * z[0] + 0.25 * z[1] - r2 * z[1]])
>>> def flow(z0, T):
...     return solve_ivp(lambda t, z: f(z), (0, T), z0, rtol=1e-12, atol=1e-12).y[:, -1]
>>> orb = shoot(flow, f, np.array([0.6, 0.0]), 3.0)
>>> round(orb.period, 8), round(float(np.hypot(*orb.z0)), 8)
(3.14159265, 0.5)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConvergenceError

#: largest Floquet multiplier modulus above which a failed single shooting names multiple shooting as the remedy
#: (the 36 um branches of the 58.5 / 95.9 krpm Hopf points: 335 / 149; single shooting stalled at ~1e-4 there)
STRONGLY_UNSTABLE = 50.0


@dataclass
class ShootingSolution:
    """A periodic orbit found by :func:`shoot`.

    Attributes
    ----------
    z0 : ndarray (n,)
        A point of the orbit (the start of the period), in the system's units.
    period : float
        Period T [s] (the time unit of the flow).
    monodromy : ndarray (n, n)
        ∂Φ_T/∂z0 at the solution, in the system's units.
    multipliers : ndarray (n,)
        Floquet multipliers (eigenvalues of the monodromy), largest modulus first.
    iterations : int
        Newton iterations taken.
    residual : float
        Final scaled residual max |Φ_T(z0) − z0| / scale.
    autonomous : bool
        True if the period was an unknown (phase condition used).
    """

    z0: np.ndarray
    period: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    iterations: int
    residual: float
    autonomous: bool = True

    @property
    def nontrivial_multipliers(self):
        """The multipliers without the trivial one (the one closest to 1) of an autonomous orbit."""
        if not self.autonomous:
            return self.multipliers
        k = int(np.argmin(np.abs(self.multipliers - 1.0)))
        return np.delete(self.multipliers, k)

    @property
    def stable(self):
        """True if every non-trivial Floquet multiplier has modulus < 1 (:func:`stable_multipliers`, tol = 0)."""
        return stable_multipliers(self.nontrivial_multipliers)


def stable_multipliers(nontrivial, tol=0.0):
    """True if no multiplier lies outside the unit circle by more than ``tol``.

    Parameters
    ----------
    nontrivial : array_like of complex
        Floquet multipliers without the trivial one.
    tol : float
        Accuracy of the multipliers' moduli [-] (a multiplier within it of the circle is taken as on it).

    Returns
    -------
    bool

    Examples
    --------
    >>> stable_multipliers([0.5, 1.0005], tol=2e-3), stable_multipliers([0.5, 1.0005])
    (True, False)
    """
    return bool(np.all(np.abs(np.asarray(nontrivial)) <= 1.0 + tol))


def monodromy(flow, z0, period, scale, end=None, fd_step=1e-6, workers=1, central=False):
    """Monodromy matrix ∂Φ_T/∂z0 by forward differences of the flow, one integration per state (central: two).

    Parameters
    ----------
    flow : callable
        ``flow(z0, T) -> z(T)``.
    z0 : ndarray (n,)
        Start point.
    period : float
        Integration time T.
    scale : ndarray (n,)
        Typical magnitude of each state; the difference step of state k is ``fd_step * scale[k]``.
    end : ndarray (n,), optional
        Φ_T(z0) if already known.
    fd_step : float
        Difference step in scaled units (the flow must be accurate to much better than this: its error enters the
        columns divided by the step).
    workers : int
        Threads integrating columns side by side (worth it when ``flow`` runs compiled code without the GIL).
    central : bool
        Central differences (Φ(z0 + h) − Φ(z0 − h)) / 2h: truncation error O(h²) instead of O(h), twice the flows
        (``end`` is then not used in the columns).

    Returns
    -------
    ndarray (n, n)
        M, in the system's units.
    """
    end = flow(z0, period) if end is None else end  # first, on z0: a flow that chooses its integrator does it here

    def column(k):
        z = z0.copy()
        h = fd_step * scale[k]
        z[k] += h
        if not central:
            return (flow(z, period) - end) / h
        zm = z0.copy()
        zm[k] -= h
        return (flow(z, period) - flow(zm, period)) / (2 * h)

    if workers > 1:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(workers) as pool:
            return np.column_stack(list(pool.map(column, range(z0.size))))
    return np.column_stack([column(k) for k in range(z0.size)])


def _newton_step(m, end, z0, rhs_end, f_ref, scale, autonomous):
    """Scaled Newton correction (dz, dT) of the shooting system."""
    n = z0.size
    ms = m * scale[None, :] / scale[:, None]  # monodromy in scaled variables
    res = (end - z0) / scale
    if not autonomous:
        du = np.linalg.solve(ms - np.eye(n), -res)
        return du * scale, 0.0
    a = np.zeros((n + 1, n + 1))
    a[:n, :n] = ms - np.eye(n)
    a[:n, n] = rhs_end / scale
    a[n, :n] = f_ref * scale
    b = np.append(-res, 0.0)
    sol = np.linalg.solve(a, b)
    return sol[:n] * scale, float(sol[n])


def shoot(flow, rhs, z0, period, scale=None, autonomous=True, tol=1e-8, max_iter=25, fd_step=1e-6,
          max_period_change=0.3, workers=1, monodromy0=None):
    """Periodic orbit through Newton's method on the shooting residual (see the module docstring).

    The monodromy matrix (n integrations) is computed at the first iterate and reused (chord iterations, one
    integration each) as long as the residual falls at least fourfold per iteration; otherwise, and at the solution
    when the iterate has moved since (for the Floquet multipliers), it is recomputed.

    Parameters
    ----------
    flow : callable
        ``flow(z0, T) -> z(T)``: the state after the time T from z0 (accurate to well below ``fd_step * scale``).
    rhs : callable
        ``rhs(z) -> dz/dt`` (autonomous part; used for the phase condition and the period column).
    z0 : ndarray (n,)
        Initial guess of a point on the orbit (also the phase condition's reference point).
    period : float
        Initial guess of the period (the fixed period if ``autonomous`` is False).
    scale : ndarray (n,), optional
        Typical magnitude of each state (default: |z0|, at least 1e-3 of its largest component).
    autonomous : bool
        True: the period is an unknown (phase condition); False: a forced system of known period.
    tol : float
        Convergence: scaled residual max |Φ_T(z0) − z0| / scale below this.
    max_iter : int
        Newton iterations at most.
    fd_step : float
        Scaled difference step of the monodromy (:func:`monodromy`).
    max_period_change : float
        Largest relative period change per iteration (damping; a larger step is scaled down).
    workers : int
        Threads for the monodromy's columns (:func:`monodromy`).
    monodromy0 : ndarray (n, n), optional
        A monodromy matrix near the guess (e.g. of the orbit at a neighbouring speed) for the first chord
        iterations; it is recomputed at the solution for the multipliers.

    Returns
    -------
    ShootingSolution

    Raises
    ------
    ConvergenceError
        If Newton does not converge, naming the iterations and the last residual.
    """
    z = np.asarray(z0, dtype=float).copy()
    if scale is None:
        scale = np.maximum(np.abs(z), max(1e-3 * float(np.max(np.abs(z))), 1e-300))
    scale = np.asarray(scale, dtype=float)
    f_ref = rhs(z) / scale  # phase condition's normal, in scaled variables (u − u_ref)·f_ref = 0
    f_ref = f_ref / np.linalg.norm(f_ref)
    T = float(period)
    history, z_m = [], None
    m = None if monodromy0 is None else np.asarray(monodromy0, dtype=float)
    for it in range(1, max_iter + 1):
        end = flow(z, T)
        if not np.all(np.isfinite(end)):
            raise ConvergenceError(f"shooting: the flow over T = {T:.6g} s gave non-finite states at iteration {it}")
        res = float(np.max(np.abs(end - z) / scale))
        stalled = len(history) > 0 and res > 0.25 * history[-1]
        history.append(res)
        if res < tol:
            if m is None or z_m is None or np.max(np.abs(z - z_m) / scale) > 1e-3:
                m = monodromy(flow, z, T, scale, end, fd_step, workers)
            mult = np.linalg.eigvals(m)
            return ShootingSolution(z, T, m, mult[np.argsort(-np.abs(mult))], it, res, autonomous)
        if m is None or stalled:
            m, z_m = monodromy(flow, z, T, scale, end, fd_step, workers), z.copy()
        dz, dT = _newton_step(m, end, z, rhs(end), f_ref, scale, autonomous)
        damp = min(1.0, max_period_change * T / abs(dT)) if dT else 1.0
        z = z + damp * dz
        T = T + damp * dT
        if not T > 0:
            raise ConvergenceError(f"shooting: the period became {T:.6g} s at iteration {it} (no orbit near the guess)")
    mu = float(np.max(np.abs(np.linalg.eigvals(m)))) if m is not None and np.all(np.isfinite(m)) else math.nan
    unstable = (f"; the largest Floquet multiplier of the last monodromy computed is {mu:.3g}: a flow over the period "
                "amplifies errors by that much, multiple shooting (frbmodel.limit_cycle segments > 1) splits it"
                if mu > STRONGLY_UNSTABLE else "")
    raise ConvergenceError(f"shooting did not converge in {max_iter} Newton iterations: scaled residuals "
                           f"{', '.join(f'{r:.2g}' for r in history[-5:])} (tolerance {tol:g}); a better guess "
                           "(longer settling) or a quasi-periodic response (two whirl frequencies) are likely causes"
                           + unstable)


__all__ = ["ShootingSolution", "monodromy", "shoot"]
