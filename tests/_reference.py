"""Independent reference implementations used by the tests (not imported by frbmodel).

Everything here is written from the formulas of docs/theory/ directly (closed forms, brute-force quadrature, hand
statics); none
of it calls the code it is used to check.
"""
import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq


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


def quadrature_film_force(film, r, rdot, omega_s):
    """Film force on the inner member [N] by brute force: :func:`short_pressure_theta` integrated over θ with
    adaptive quadrature, split at the cavitation boundaries (sign changes of the unclipped pressure, located by
    Brent) so that every interval is smooth. Accurate to ~1e-12 relative."""
    R = film.radius

    def numerator(th):  # 6 ω_s ∂θh + 12 ∂t h (per μ): the unclipped pressure changes sign with it
        return 6 * omega_s * (r[0] * math.sin(th) - r[1] * math.cos(th)) \
            + 12 * (-rdot[0] * math.cos(th) - rdot[1] * math.sin(th))

    grid = np.linspace(0.0, 2 * math.pi, 721)
    vals = np.array([numerator(t) for t in grid])
    pts = [0.0] + [brentq(numerator, grid[k], grid[k + 1], xtol=1e-15) for k in range(720)
                   if vals[k] * vals[k + 1] < 0] + [2 * math.pi]

    def p(th):
        return float(short_pressure_theta(film, r, rdot, omega_s, th)[0])

    f = np.zeros(2)
    for a, b in zip(pts[:-1], pts[1:]):
        f[0] -= quad(lambda th: p(th) * math.cos(th), a, b, limit=200, epsabs=0, epsrel=1e-12)[0] * R
        f[1] -= quad(lambda th: p(th) * math.sin(th), a, b, limit=200, epsabs=0, epsrel=1e-12)[0] * R
    return f


def static_film_force(film, r, omega_s, poly_r=(1.0,), poly_t=(1.0,)):
    """Static film force on the inner member [N] at relative position ``r`` [m] (ṙ = 0): the closed form of
    docs/theory/films.md#static-and-quasi-static-case, F_r = −(μRL³/c²) ε² ω_s/(1−ε²)², F_t = (μRL³/c²) π ε ω_s/(4
    (1−ε²)^{3/2}), multiplied by
    the finite-length factors f_r(ε), f_t(ε) given as polynomial coefficients (highest power first;
    films.md#finite-length-correction)."""
    c = film.clearance
    e = math.hypot(r[0], r[1])
    eps = e / c
    k = film.viscosity * film.radius * film.length ** 3 / c ** 2
    s2 = 1.0 - eps * eps
    f_r = -k * eps * eps * omega_s / s2 ** 2 * np.polyval(poly_r, eps)
    f_t = k * math.pi * eps * omega_s / (4.0 * s2 ** 1.5) * np.polyval(poly_t, eps)
    cp, sp = r[0] / e, r[1] / e
    return np.array([f_r * cp - f_t * sp, f_r * sp + f_t * cp])


def petroff(film, eps):
    """Petroff torque coefficient A = 2π μ R³ L / (c sqrt(1 − ε²)) [N m s]
    (docs/theory/rings.md#wall-torques-of-one-film)."""
    return 2 * math.pi * film.viscosity * film.radius ** 3 * film.length / (film.clearance * math.sqrt(1 - eps * eps))


def table2_bearing_loads(gravity=9.81):
    """Static reactions [N] (turbine, compressor bearing; upward positive) of the paper's Table 2 rotor by hand
    statics (docs/theory/parameters.md#table-2-in-si-units): wheels at z = 0 and 105 mm, a solid 11 mm steel shaft in
    three pieces of 33, 39
    and 33 mm, supports at z = 33 and 72 mm."""
    rho_a = 7860 * math.pi / 4 * 0.011 ** 2  # shaft mass per length [kg/m]
    pieces = [(0.326, 0.0), (0.118, 0.105), (rho_a * 0.033, 0.0165), (rho_a * 0.039, 0.0525), (rho_a * 0.033, 0.0885)]
    total = sum(m for m, _ in pieces) * gravity
    moment = sum(m * gravity * (z - 0.033) for m, z in pieces)  # weight moment about the turbine bearing
    w2 = moment / 0.039  # compressor reaction from the moment balance
    return np.array([total - w2, w2])


def with_viscosities_by_hand(system, table):
    """``system`` with each bearing's inner and outer film viscosity [Pa s] copied by hand from the rows of a
    thermal_losses ``table`` (one row per bearing, in order): the "frozen" system a thermal analysis at that
    speed must equal."""
    from dataclasses import replace

    bearings = tuple(replace(b, inner=replace(b.inner, viscosity=float(r["inner viscosity [Pa s]"])),
                             outer=replace(b.outer, viscosity=float(r["outer viscosity [Pa s]"])))
                     for b, (_, r) in zip(system.bearings, table.iterrows()))
    return replace(system, bearings=bearings)
