"""Unit conversions at the user interface (SI inside; rotor speeds are given in rpm by users).

>>> round(rpm_to_rad_s(30.0), 12) == round(3.141592653589793, 12)
True
>>> rad_s_to_rpm(rpm_to_rad_s(150e3))
150000.0
"""
from __future__ import annotations

import math

#: rad/s per rpm (2π / 60)
RPM = 2.0 * math.pi / 60.0


def rpm_to_rad_s(speed_rpm):
    """Rotor speed [rpm] → [rad/s] (scalars or numpy arrays).

    Parameters
    ----------
    speed_rpm : float or numpy.ndarray
        Speed [rpm].

    Returns
    -------
    float or numpy.ndarray
        Speed [rad/s].
    """
    return speed_rpm * RPM


def rad_s_to_rpm(omega_rad_s):
    """Rotor speed [rad/s] → [rpm] (scalars or numpy arrays).

    Parameters
    ----------
    omega_rad_s : float or numpy.ndarray
        Speed [rad/s].

    Returns
    -------
    float or numpy.ndarray
        Speed [rpm].
    """
    return omega_rad_s / RPM
