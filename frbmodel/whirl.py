"""Film whirl frequencies and their stability onset (physics.md §8).

Each of the four films (turbine/compressor × inner/outer) is treated as the only flexible element under a
rigid mass (Lund's closed form of the Routh–Hurwitz threshold). Whirl frequency Ω_w = γ(ε) ω_s; the film is
unstable when c ω_s² / g > K̄_eq(ε) / γ²(ε) (the W = m g form of the criterion, physics.md §8 step 4).
"""
from __future__ import annotations

import math

import numpy as np

from .equilibrium import bearing_equilibrium
from .film import rt_coefficients, static_load
from .rotor import GRAVITY
from .units import rpm_to_rad_s

FILM_NAMES = ("turbine inner", "turbine outer", "compressor inner", "compressor outer")


def lund_threshold(K, C):
    """Lund's K_eq and γ² from 2x2 stiffness K and damping C (any consistent units, frame-invariant).

    ``K_eq = (K_xx C_yy + K_yy C_xx − K_xy C_yx − K_yx C_xy) / (C_xx + C_yy)`` and
    ``γ² ω_s² = ((K_eq − K_xx)(K_eq − K_yy) − K_xy K_yx) / (C_xx C_yy − C_xy C_yx)`` — with K in units of
    ω_s·(C units) the second value is γ² itself.
    """
    _, a3, _, a1, _ = characteristic_polynomial(1.0, K, C)
    k_eq = a1 / a3
    g2 = ((k_eq - K[0, 0]) * (k_eq - K[1, 1]) - K[0, 1] * K[1, 0]) / (C[0, 0] * C[1, 1] - C[0, 1] * C[1, 0])
    return k_eq, g2


def characteristic_polynomial(m, K, C):
    """Coefficients ``(a4, a3, a2, a1, a0)`` of det(m s² I + C s + K) for a rigid mass ``m`` [kg] on a 2x2
    film ``K`` [N/m], ``C`` [N s/m] (physics.md §8)."""
    a4 = m * m
    a3 = m * (C[0, 0] + C[1, 1])
    a2 = m * (K[0, 0] + K[1, 1]) + C[0, 0] * C[1, 1] - C[0, 1] * C[1, 0]
    a1 = K[0, 0] * C[1, 1] + K[1, 1] * C[0, 0] - K[0, 1] * C[1, 0] - K[1, 0] * C[0, 1]
    a0 = K[0, 0] * K[1, 1] - K[0, 1] * K[1, 0]
    return a4, a3, a2, a1, a0


def routh_hurwitz_stable(m, K, C) -> bool:
    """Routh–Hurwitz stability of a rigid mass ``m`` [kg] on a 2x2 film ``K`` [N/m], ``C`` [N s/m]."""
    a4, a3, a2, a1, a0 = characteristic_polynomial(m, K, C)
    return bool(min(a4, a3, a2, a1, a0) > 0 and a3 * a2 > a4 * a1 and a1 * a2 * a3 - a0 * a3 ** 2 - a4 * a1 ** 2 > 0)


def film_whirl_ratio(eps: float, model: str = "short", lam: float | None = None):
    """``(γ, K̄_eq/γ²)`` of a film at eccentricity ratio ``eps`` (dimensionless, frame-invariant).

    γ is the whirl frequency ratio Ω/ω_s; K̄_eq/γ² is the mass threshold m c ω_s²/W (γ² ≤ 0: stable for
    any mass, returned as +inf).
    """
    e = max(eps, 1e-9)  # the ratios are continuous at ε → 0 (limits γ = 1/2, K̄_eq/γ² = 24/π)
    K, C = rt_coefficients(e, model, lam)
    k_eq, g2 = lund_threshold(K, C)
    if g2 <= 0.0:
        return 0.0, math.inf
    kbar = k_eq / static_load(e, model, lam)
    return math.sqrt(g2), kbar / g2


def bearing_whirl(bearing, eq, model="short", gravity=GRAVITY):
    """Whirl frequencies [rad/s] and instability margins of the inner and outer film of one bearing.

    Parameters
    ----------
    bearing : FloatingRingBearing
    eq : BearingEquilibrium
        Static state (ε and film speeds) of the bearing.
    model : {"short", "short_corrected"}
    gravity : float
        [m/s²]

    Returns
    -------
    tuple of float
        ``(omega_w_inner, omega_w_outer, margin_inner, margin_outer)``; a margin > 0 means the film is past
        its onset (c ω_s²/g − K̄_eq/γ²).
    """
    out = []
    for film, eps, ws in ((bearing.inner, eq.eps_inner, eq.omega_inner), (bearing.outer, eq.eps_outer, eq.omega_outer)):
        gamma, thr = film_whirl_ratio(eps, model, film.length_to_diameter)
        margin = film.clearance * ws * ws / gravity - thr
        out.append((gamma * ws, margin))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def film_onset_speeds(system, method="J", speed_range_rpm=(500.0, 400e3)):
    """Rotor speeds [rpm] at which each of the four films passes its whirl threshold (NaN if none in range).

    Order: turbine inner, turbine outer, compressor inner, compressor outer.

    Examples
    --------
    >>> import frbmodel as frb
    >>> on = frb.film_onset_speeds(frb.turbocharger(36e-6))
    >>> [round(float(x) / 1e3, 1) for x in on]        # krpm, physics.md §11
    [11.1, 68.1, 11.8, 69.2]
    """
    from scipy.optimize import brentq

    loads = system.bearing_loads
    res = []
    for i, b in enumerate(system.bearings):
        def margins(rpm, i=i, b=b):
            eq = bearing_equilibrium(b, loads[i], rpm_to_rad_s(rpm), method, system.film_model, system.gravity)
            return bearing_whirl(b, eq, system.film_model, system.gravity)[2:]

        grid = np.geomspace(speed_range_rpm[0], speed_range_rpm[1], 40)
        vals = np.array([margins(s) for s in grid])
        for k in range(2):
            idx = np.flatnonzero((vals[:-1, k] <= 0) & (vals[1:, k] > 0))
            if idx.size == 0:
                res.append(math.nan)
                continue
            j = idx[0]
            res.append(brentq(lambda s, k=k: margins(s)[k], grid[j], grid[j + 1], xtol=1e-6))
    return np.array(res)
