"""Bearing losses over speed: the journal torque and friction power of every bearing at the static equilibria of a
method (the kernels: :mod:`frbmodel.physics.losses`)."""
from __future__ import annotations

import numpy as np

from ..core.units import RPM
from ..physics.losses import bearing_loss
from .equilibrium import equilibrium

__all__ = ["bearing_losses", "equilibrium_loss", "with_ring_speed_ratio"]


def equilibrium_loss(bearing, eq, omega_rotor, film_model="short"):
    """Journal torque and friction powers of one bearing at its static equilibrium.

    Parameters
    ----------
    bearing : FloatingRingBearing
    eq : BearingEquilibrium
        Its equilibrium (:func:`frbmodel.linear.equilibrium.bearing_equilibrium`).
    omega_rotor : float
        Rotor speed ω_R [rad/s].
    film_model : {"short", "short_corrected"}

    Returns
    -------
    journal_torque, power_inner, power_outer : ndarray (0-d)
        [N m], [W], [W] (:func:`frbmodel.physics.losses.bearing_loss` with the members at rest).
    """
    journal = [eq.ring[0] + eq.r_inner[0], eq.ring[1] + eq.r_inner[1], 0.0, 0.0]
    return bearing_loss(bearing, journal, [eq.ring[0], eq.ring[1], 0.0, 0.0, eq.ring_speed], omega_rotor, film_model)


def bearing_losses(system, speed_rpm, method="J"):
    """Journal torque and power loss of every bearing at the static equilibrium of ``method``.

    Parameters
    ----------
    system : Turbocharger
        The system (e.g. :func:`frbmodel.turbocharger`).
    speed_rpm : float or sequence of float
        Rotor speed(s) [rpm], > 0.
    method : {"C", "D", "F", "G", "I", "J"}
        Equilibrium method (:func:`frbmodel.linear.equilibrium`); "J" balances the ring torque, so that the power loss
        equals −T_J ω_R.

    Returns
    -------
    pandas.DataFrame
        One row per speed and bearing: ``speed [rpm]``, ``bearing``, ``method``, ``journal torque [N m]``,
        ``power loss [W]``, ``power loss inner [W]``, ``power loss outer [W]``, ``ring speed [rad/s]``,
        ``eps inner [-]``, ``eps outer [-]``.

    Examples
    --------
    >>> import frbmodel as frb
    >>> df = bearing_losses(frb.turbocharger(36e-6), [50e3, 100e3])
    >>> len(df), bool((df["power loss [W]"] > 0).all() and (df["journal torque [N m]"] < 0).all())
    (4, True)
    """
    import pandas as pd

    rows = []
    for rpm in np.atleast_1d(np.asarray(speed_rpm, dtype=float)):
        eq = equilibrium(system, method, float(rpm))
        w = float(rpm) * RPM
        for b, e in zip(system.bearings, eq.bearings):
            t_j, p_i, p_o = equilibrium_loss(b, e, w, system.film_model)
            rows.append({"speed [rpm]": float(rpm), "bearing": b.name, "method": eq.method,
                         "journal torque [N m]": float(t_j),
                         "power loss [W]": float(p_i + p_o), "power loss inner [W]": float(p_i),
                         "power loss outer [W]": float(p_o), "ring speed [rad/s]": e.ring_speed,
                         "eps inner [-]": e.eps_inner, "eps outer [-]": e.eps_outer})
    return pd.DataFrame(rows)


def with_ring_speed_ratio(table):
    """A copy of a :func:`bearing_losses` table with the column ``RSR [-]`` = ring speed / rotor speed after
    ``bearing`` (the other columns unchanged).

    Examples
    --------
    >>> import frbmodel as frb
    >>> df = with_ring_speed_ratio(bearing_losses(frb.turbocharger(36e-6), [100e3], "F"))
    >>> [round(x, 5) for x in df["RSR [-]"]]                # method F: eq. (6)
    [0.19903, 0.19903]
    """
    table = table.copy()
    table.insert(2, "RSR [-]", table["ring speed [rad/s]"] / (table["speed [rpm]"] * RPM))
    return table
