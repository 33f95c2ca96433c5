"""Independent reference implementations used by the tests (not imported by frbmodel)."""
import math

import numpy as np


def short_pressure_theta(film, r, rdot, omega_s, theta):
    """∫ p dz [N/m] of the short-bearing π-film at angles ``theta``, built directly from the inertial-frame
    gap h = c − r_x cos θ − r_y sin θ and the short Reynolds equation ∂z(h³ ∂z p) = 6μω_s ∂θh + 12μ ∂t h,
    clipped to p >= 0 (half-Sommerfeld). Also returns h(θ)."""
    c, mu, L = film.clearance, film.viscosity, film.length
    th = np.asarray(theta)
    h = c - r[0] * np.cos(th) - r[1] * np.sin(th)
    h_th = r[0] * np.sin(th) - r[1] * np.cos(th)
    h_t = -rdot[0] * np.cos(th) - rdot[1] * np.sin(th)
    prof = (6 * mu * omega_s * h_th + 12 * mu * h_t) / (2 * h ** 3)  # p = prof (z² − L²/4)
    return np.maximum(-prof * L ** 3 / 6.0, 0.0), h
