"""Critical speeds: the 1X crossings of a Campbell diagram's damped branches (interpolated on its grid, optionally
refined by a root search on the speed), used by the Campbell figure and the unbalance response."""
from __future__ import annotations

import math

import numpy as np

from ..core.units import rpm_to_rad_s
from ..system.methods import get_method
from ..system.parameters import system_from_meta
from .assembly import linear_system
from .equilibrium import bearing_equilibrium
from .modal import state_matrix
from .thermal import OilSupply, at_operating_point

__all__ = ["CRITICAL_COLUMNS", "critical_speeds", "linear_at", "oil_supply_of", "system_of"]

#: columns of the critical-speed table
CRITICAL_COLUMNS = ("source", "speed [rpm]", "frequency [Hz]", "mode", "kind", "precession", "damping [-]",
                    "location", "amplitude [m]", "refined")


def linear_at(system, m, speed_rpm, kw, oil_supply=None):
    """The method's linear system at one speed (equilibria solved for the film methods); with an
    :class:`~frbmodel.linear.thermal.OilSupply`, of the system at that speed's thermal operating point."""
    system = at_operating_point(system, speed_rpm, oil_supply, m.letter)
    eqs = None
    if m.needs_films:
        omega = rpm_to_rad_s(speed_rpm)
        eqs = tuple(bearing_equilibrium(b, system.bearing_loads[k], omega, m.letter, system.film_model,
                                        system.gravity) for k, b in enumerate(system.bearings))
    return linear_system(system, m.letter, speed_rpm, equilibria=eqs, **kw)


def system_of(cd, system):
    """The system a Campbell result was computed for: ``system``, else rebuilt from ``cd.meta["system"]``."""
    if system is not None:
        return system
    if isinstance(cd.meta.get("system"), dict):
        return system_from_meta(cd.meta)
    return None


def oil_supply_of(result, oil_supply=None):
    """The oil supply a Campbell or unbalance result was computed with: ``oil_supply``, else rebuilt from
    ``result.meta["oil_supply"]`` (None for constant viscosities)."""
    if oil_supply is not None or not isinstance(result.meta.get("oil_supply"), dict):
        return oil_supply
    return OilSupply.from_dict(result.meta["oil_supply"])


def _eigenvalue_near(system, m, speed_rpm, guess, kw, oil_supply=None):
    """The eigenvalue (Im > 0) of the method's linear system at ``speed_rpm`` nearest to ``guess`` [1/s]."""

    ls = linear_at(system, m, speed_rpm, kw, oil_supply)
    lam = np.linalg.eigvals(state_matrix(ls.M, ls.C, ls.K))
    lam = lam[lam.imag > 0]
    return lam[np.argmin(np.abs(lam - guess))]


def _refine_crossing(system, m, cd, i, j, kw, oil_supply=None):
    """Root of Im λ_j(Ω)/2π − Ω/2π between grid speeds i and i+1 (Brent), λ_j followed as the eigenvalue
    nearest to the linear interpolation of the tracked one; None if the bracket does not hold, or if the root
    Brent returns is not one: the nearest eigenvalue can switch to another mode inside the interval (where two
    branches veer), a jump of the function across zero that Brent takes for a root, so the root is kept only
    where the function vanishes (|f − n/60| <= 1e-6 of n/60; Brent's own tolerance leaves ~1e-9)."""
    from scipy.optimize import brentq

    s = cd.speeds_rpm
    la, lb = cd.eigenvalues[i, j], cd.eigenvalues[i + 1, j]

    def lam(x):
        t = (x - s[i]) / (s[i + 1] - s[i])
        return _eigenvalue_near(system, m, x, la + t * (lb - la), kw, oil_supply)

    def g(x):
        return lam(x).imag / (2 * math.pi) - x / 60.0

    ga, gb = g(s[i]), g(s[i + 1])
    if ga == 0.0 or gb == 0.0:
        x = s[i] if ga == 0.0 else s[i + 1]
        return x, lam(x)
    if ga * gb > 0:
        return None
    x = brentq(g, s[i], s[i + 1], xtol=1e-9 * s[i + 1], rtol=1e-12)
    if abs(g(x)) > 1e-6 * x / 60.0:
        return None  # a jump between two modes, not a crossing (the grid's linear interpolation stands)
    return x, lam(x)


def critical_speeds(cd, system=None, refine=True, oil_supply=None, **kw):
    """Speeds where the 1X line f = n/60 crosses the damped Campbell branches of ``cd``.

    Crossings are found between grid speeds (sign change of f_mode − n/60, linear interpolation) and, with
    ``refine``, solved by a Brent root search on the eigenvalue of the tracked mode (to ~1e-9 relative).

    Parameters
    ----------
    cd : CampbellResult
    system : Turbocharger, optional
        The system ``cd`` was computed for (default: rebuilt from ``cd.meta["system"]``); needed to refine.
    refine : bool
        Root-solve each crossing (else: linear interpolation on the grid).
    oil_supply : OilSupply, optional
        The thermal model of ``cd`` (default: rebuilt from ``cd.meta["oil_supply"]``, None without one): the root
        search evaluates each trial speed at its own thermal operating point.
    **kw
        Spring stiffnesses of A, B, E [N/m] (default: ``cd.meta["method_options"]``).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CRITICAL_COLUMNS` with ``source`` "1X crossing": speed [rpm], frequency [Hz] (= speed/60),
        mode (Campbell column), kind, precession (at the nearer grid speed), damping [-] (at the crossing),
        ``refined``; sorted by speed.

    Examples
    --------
    >>> import frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "A", np.linspace(1e3, 40e3, 40), whirl=False)
    >>> cs = critical_speeds(cd)
    >>> cs[["speed [rpm]", "precession"]].round(0).values.tolist()
    [[6550.0, 'backward'], [7159.0, 'forward'], [18878.0, 'backward'], [19417.0, 'forward']]
    """
    import pandas as pd

    m = get_method(cd.method)
    opts = {**cd.meta.get("method_options", {}), **kw} if m.parameters else {}
    system = system_of(cd, system) if refine else None
    supply = oil_supply_of(cd, oil_supply)
    s, f = cd.speeds_rpm, cd.frequencies_hz
    g = f - s[:, None] / 60.0
    rows = []
    for j in range(cd.n_modes):
        with np.errstate(invalid="ignore"):
            idx = np.flatnonzero((g[:-1, j] * g[1:, j] < 0) | ((g[:-1, j] == 0) & np.isfinite(g[1:, j])))
        for i in idx:
            t = g[i, j] / (g[i, j] - g[i + 1, j])
            speed, lam = s[i] + t * (s[i + 1] - s[i]), cd.eigenvalues[i, j] + t * np.diff(cd.eigenvalues[i:i + 2, j])[0]
            root = _refine_crossing(system, m, cd, i, j, opts, supply) if system is not None else None
            if root is not None:
                speed, lam = root
            k = i if speed - s[i] <= s[i + 1] - speed else i + 1
            rows.append({"source": "1X crossing", "speed [rpm]": float(speed), "frequency [Hz]": float(speed) / 60.0,
                         "mode": int(j), "kind": cd.mode_kind[k, j], "precession": cd.precession[k, j],
                         "damping [-]": float(-lam.real / abs(lam)), "location": "", "amplitude [m]": math.nan,
                         "refined": root is not None})
    return pd.DataFrame(rows, columns=list(CRITICAL_COLUMNS)).sort_values("speed [rpm]", kind="stable") \
        .reset_index(drop=True)
