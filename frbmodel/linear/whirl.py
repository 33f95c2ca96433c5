"""Film whirl frequencies and their stability onset (docs/theory/whirl.md#film-whirl).

Each of the four films (turbine/compressor × inner/outer) is treated as the only flexible element under a
rigid mass (Lund's closed form of the Routh–Hurwitz threshold). Whirl frequency Ω_w = γ(ε) ω_s; the film is
unstable when c ω_s² / g > K̄_eq(ε) / γ²(ε) (the W = m g form of the criterion, docs/theory/whirl.md#film-whirl step 4).
"""
from __future__ import annotations

import math

import numpy as np

from ..core.errors import ParameterError, check_real, check_system
from ..core.units import rpm_to_rad_s
from ..physics.film import check_model, rt_coefficients, static_load
from ..system.films import FILM_NAMES  # noqa: F401  (the default order of the whirl columns, see film_names)
from ..system.methods import get_method
from ..system.rotor import GRAVITY
from .equilibrium import bearing_equilibrium
from .thermal import check_oil_supply, thermal_bearing

#: default search range [rpm] of :func:`film_onset_speeds`
ONSET_SEARCH_RPM = (500.0, 400e3)


def film_names(system):
    """Names of the films of a system, ``"<bearing> inner"``, ``"<bearing> outer"`` per bearing in its order.

    Parameters
    ----------
    system : Turbocharger

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> import frbmodel as frb
    >>> film_names(frb.turbocharger()) == FILM_NAMES
    True
    """
    return tuple(f"{b.name} {side}" for b in system.bearings for side in ("inner", "outer"))


def lund_threshold(K, C):
    """Lund's equivalent stiffness K_eq and whirl ratio γ² from a 2x2 film stiffness and damping.

    ``K_eq = (K_xx C_yy + K_yy C_xx − K_xy C_yx − K_yx C_xy) / (C_xx + C_yy)`` and
    ``γ² ω_s² = ((K_eq − K_xx)(K_eq − K_yy) − K_xy K_yx) / (C_xx C_yy − C_xy C_yx)`` — with K in units of
    ω_s·(C units) the second value is γ² itself (any consistent units; frame-invariant).

    Parameters
    ----------
    K, C : ndarray (2, 2)
        Stiffness and damping.

    Returns
    -------
    k_eq : float
        Equivalent stiffness (units of K).
    g2 : float
        γ² ω_s² in units of K / C (γ² when K is given per ω_s).

    Examples
    --------
    >>> from frbmodel.physics.film import rt_coefficients
    >>> k_eq, g2 = lund_threshold(*rt_coefficients(1e-9))   # centred film: γ = 1/2
    >>> round(float(g2), 6)
    0.25
    """
    _, a3, _, a1, _ = characteristic_polynomial(1.0, K, C)
    k_eq = a1 / a3
    g2 = ((k_eq - K[0, 0]) * (k_eq - K[1, 1]) - K[0, 1] * K[1, 0]) / (C[0, 0] * C[1, 1] - C[0, 1] * C[1, 0])
    return k_eq, g2


def characteristic_polynomial(m, K, C):
    """Coefficients of det(m s² I + C s + K) for a rigid mass on a 2x2 film (docs/theory/whirl.md#film-whirl).

    Parameters
    ----------
    m : float
        Mass [kg].
    K, C : ndarray (2, 2)
        Film stiffness [N/m] and damping [N s/m].

    Returns
    -------
    tuple of float
        ``(a4, a3, a2, a1, a0)``, highest power of s first.

    Examples
    --------
    >>> [float(a) for a in characteristic_polynomial(2.0, np.eye(2), np.zeros((2, 2)))]   # (2 s² + 1)²
    [4.0, 0.0, 4.0, 0.0, 1.0]
    """
    a4 = m * m
    a3 = m * (C[0, 0] + C[1, 1])
    a2 = m * (K[0, 0] + K[1, 1]) + C[0, 0] * C[1, 1] - C[0, 1] * C[1, 0]
    a1 = K[0, 0] * C[1, 1] + K[1, 1] * C[0, 0] - K[0, 1] * C[1, 0] - K[1, 0] * C[0, 1]
    a0 = K[0, 0] * K[1, 1] - K[0, 1] * K[1, 0]
    return a4, a3, a2, a1, a0


def routh_hurwitz_stable(m, K, C) -> bool:
    """Routh–Hurwitz stability of a rigid mass on a 2x2 film.

    Parameters
    ----------
    m : float
        Mass [kg].
    K, C : ndarray (2, 2)
        Film stiffness [N/m] and damping [N s/m].

    Returns
    -------
    bool
        True if every root of :func:`characteristic_polynomial` has a negative real part.

    Examples
    --------
    >>> routh_hurwitz_stable(1.0, np.eye(2), 0.1 * np.eye(2)), routh_hurwitz_stable(1.0, np.eye(2), -0.1 * np.eye(2))
    (True, False)
    """
    a4, a3, a2, a1, a0 = characteristic_polynomial(m, K, C)
    return bool(min(a4, a3, a2, a1, a0) > 0 and a3 * a2 > a4 * a1 and a1 * a2 * a3 - a0 * a3 ** 2 - a4 * a1 ** 2 > 0)


def film_whirl_ratio(eps: float, film_model: str = "short", lam: float | None = None):
    """Whirl frequency ratio and mass threshold of a film at eccentricity ratio ``eps``
    (docs/theory/whirl.md#film-whirl).

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 <= ε < 1 (the ratios are continuous at ε → 0: γ = 1/2, K̄_eq/γ² = 24/π).
    film_model : {"short", "short_corrected"}
    lam : float, optional
        L/D of the film (needed for ``"short_corrected"``).

    Returns
    -------
    gamma : float
        Whirl frequency ratio Ω / ω_s [-] (0 where the film is stable for any mass).
    threshold : float
        K̄_eq/γ² = the mass threshold m c ω_s² / W [-] (+inf where γ² <= 0: stable for any mass).

    Examples
    --------
    >>> [round(x, 5) for x in film_whirl_ratio(0.3)]        # docs/theory/whirl.md#film-whirl table: 0.51942, 6.790
    [0.51942, 6.79012]
    """
    e = max(eps, 1e-9)  # the ratios are continuous at ε → 0 (limits γ = 1/2, K̄_eq/γ² = 24/π)
    K, C = rt_coefficients(e, film_model, lam)
    k_eq, g2 = lund_threshold(K, C)
    if g2 <= 0.0:
        return 0.0, math.inf
    kbar = k_eq / static_load(e, film_model, lam)
    return math.sqrt(g2), float(kbar / g2)


def bearing_whirl(bearing, eq, film_model="short", gravity=GRAVITY):
    """Whirl frequencies and instability margins of the inner and outer film of one bearing.

    Parameters
    ----------
    bearing : FloatingRingBearing
    eq : BearingEquilibrium
        Static state (ε and film speeds) of the bearing.
    film_model : {"short", "short_corrected"}
    gravity : float
        [m/s²]

    Returns
    -------
    tuple of float
        ``(omega_w_inner, omega_w_outer, margin_inner, margin_outer)``: whirl frequencies [rad/s] and margins
        c ω_s²/g − K̄_eq/γ² [-]; a margin > 0 means the film is past its onset.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> eq = frb.equilibrium(tc, "J", 30e3).bearings[0]
    >>> w_i, w_o, m_i, m_o = bearing_whirl(tc.bearings[0], eq)
    >>> # onsets 11.1, 68.1 krpm: docs/theory/parameters.md#reference-numbers
    >>> round(w_i / (2 * np.pi), 1), bool(m_i > 0), bool(m_o > 0)
    (306.0, True, False)
    """
    out = []
    for film, eps, ws in ((bearing.inner, eq.eps_inner, eq.omega_inner), (bearing.outer, eq.eps_outer, eq.omega_outer)):
        gamma, thr = film_whirl_ratio(eps, film_model, film.length_to_diameter)
        margin = film.clearance * ws * ws / gravity - thr
        out.append((gamma * ws, margin))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def _check_search_range(speed_range_rpm):
    try:
        lo, hi = speed_range_rpm
    except (TypeError, ValueError):
        raise ParameterError(f"speed_range_rpm = {speed_range_rpm!r} is invalid: expected (low, high) [rpm] with "
                             "0 < low < high") from None
    lo = check_real("speed_range_rpm[0]", lo, "rpm", minimum=0.0)
    hi = check_real("speed_range_rpm[1]", hi, "rpm", minimum=lo)
    return lo, hi


def film_onset_speeds(system, method="J", speed_range_rpm=ONSET_SEARCH_RPM, oil_supply=None):
    """Rotor speeds at which each film passes its whirl threshold, to 1e-6 rpm (docs/theory/whirl.md#film-whirl).

    The margins of :func:`bearing_whirl` at the ``method`` equilibria are sampled at 40 geometrically spaced
    speeds; the first sign change from stable (<= 0) to unstable (> 0) of each film is refined by Brent's method.

    Parameters
    ----------
    system : Turbocharger
    method : {"C", "D", "F", "G", "I", "J"}
        Method of the static equilibria (default J: full torque balance).
    speed_range_rpm : (float, float)
        Search range [rpm], 0 < low < high.
    oil_supply : OilSupply, optional
        With the thermal model: at every speed of the search each bearing's films have their viscosities at the
        thermal operating point of that speed (:func:`frbmodel.linear.thermal.thermal_bearing`), so an onset is at
        the film temperatures of the onset speed (the operating point solved with ``method``'s equilibrium). None:
        the constant viscosities (bit for bit as without the option).

    Returns
    -------
    ndarray (2 · n_bearings,)
        Onset speeds [rpm] in the order of :func:`film_names` (turbine inner, outer, compressor inner, outer for
        Table 2). NaN if the film does not pass from stable to unstable inside the range (it may already be past
        its onset at the range start, or never reach it).

    Raises
    ------
    ParameterError
        ``system`` is not a system, ``method`` has no film equilibrium, the range is invalid, or an oil supply with
        a method other than J.

    Examples
    --------
    >>> import frbmodel as frb
    >>> on = frb.film_onset_speeds(frb.turbocharger(36e-6))
    >>> [round(float(x) / 1e3, 1) for x in on]        # krpm, docs/theory/parameters.md#reference-numbers
    [11.1, 68.1, 11.8, 69.2]
    """
    from scipy.optimize import brentq

    check_system(system)
    m = get_method(method)
    if m.equilibrium is None:
        raise ParameterError(f"method = {method!r} has no film equilibrium; film onsets need one of C, D, F, G, I, J")
    supply = check_oil_supply(oil_supply, m.letter, system.bearings)
    lo, hi = _check_search_range(speed_range_rpm)
    film_model = check_model(system.film_model)
    loads = system.bearing_loads
    res = []
    for i, b0 in enumerate(system.bearings):
        def margins(rpm, i=i, b0=b0):
            b = b0 if supply is None else thermal_bearing(b0, loads[i], rpm, supply, film_model, system.gravity,
                                                          m.letter)
            eq = bearing_equilibrium(b, loads[i], rpm_to_rad_s(rpm), m.letter, film_model, system.gravity)
            return bearing_whirl(b, eq, film_model, system.gravity)[2:]

        grid = np.geomspace(lo, hi, 40)
        vals = np.array([margins(s) for s in grid])
        for k in range(2):
            idx = np.flatnonzero((vals[:-1, k] <= 0) & (vals[1:, k] > 0))
            if idx.size == 0:
                res.append(math.nan)
                continue
            j = idx[0]
            res.append(brentq(lambda s, k=k: margins(s)[k], grid[j], grid[j + 1], xtol=1e-6))
    return np.array(res)
