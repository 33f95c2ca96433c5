"""Oil films: short-bearing (IS) π-film forces, finite-length correction, coefficients, static inverse, torques.

Conventions (physics.md §1): a film sits between an *inner member* and an *outer member*;
``e = centre_inner - centre_outer`` [m], ``e_dot`` its time derivative [m/s]; ``omega_sum`` [rad/s] is the
sum of the two surfaces' angular speeds (journal + ring for the inner film, ring for the outer film).
Every force returned is the film force **on the inner member** [N]; the outer member receives its negative.

Two film models exist (``model=``):

``"short"``
    Infinitely short bearing with half-Sommerfeld cavitation (π-film, moving cavitation boundary),
    closed form for arbitrary dynamic states (physics.md §2).
``"short_corrected"``
    The short-bearing forces multiplied by finite-length correction factors ``f_r(ε, L/D)``,
    ``f_t(ε, L/D)`` in the line-of-centres frame (physics.md §5), calibrated against a finite-difference
    solution of the finite-length Reynolds equation (:mod:`frbmodel.finite_length`).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from .errors import FilmContactError, ParameterError, check_positive

FILM_MODELS = ("short", "short_corrected")
PI = math.pi


@dataclass(frozen=True)
class Film:
    """Geometry and lubricant of one oil film.

    Parameters
    ----------
    radius : float
        Film radius R [m] (journal radius for the inner film, ring outer radius for the outer film).
    length : float
        Axial film length L [m].
    clearance : float
        Radial clearance c [m].
    viscosity : float
        Dynamic viscosity μ [Pa s].

    Examples
    --------
    >>> f = Film(radius=5.5e-3, length=6.5e-3, clearance=34e-6, viscosity=4.9e-3)
    >>> round(f.length_to_diameter, 4)
    0.5909
    """

    radius: float
    length: float
    clearance: float
    viscosity: float

    def __post_init__(self):
        for name, unit in (("radius", "m"), ("length", "m"), ("clearance", "m"), ("viscosity", "Pa s")):
            object.__setattr__(self, name, check_positive(f"film {name}", getattr(self, name), unit))
        if self.clearance >= 0.1 * self.radius:
            raise ParameterError(
                f"film clearance = {self.clearance:g} m is invalid for radius {self.radius:g} m: the thin-film "
                f"(Reynolds) theory needs clearance < 0.1 * radius = {0.1 * self.radius:g} m")

    @property
    def length_to_diameter(self) -> float:
        """L/D [-]."""
        return self.length / (2.0 * self.radius)

    def to_dict(self) -> dict:
        return asdict(self)


def check_model(model: str) -> str:
    if model not in FILM_MODELS:
        raise ParameterError(f"film model = {model!r} is unknown; valid models are {', '.join(FILM_MODELS)}")
    return model


# --------------------------------------------------------------------------------------------------
# Short-bearing π-film: the force kernel (physics.md §2.4). This is the one implementation of the dynamic
# film force; the vectorised public API, the equilibria, the run-up and the FMUs all call it.
# --------------------------------------------------------------------------------------------------
#: correction polynomial of the plain short film: f = 1
NO_CORRECTION = np.array([1.0])


@njit(cache=True)
def _polyval(p, x):
    acc = 0.0
    for cf in p:
        acc = acc * x + cf
    return acc


@njit(cache=True)
def film_force_kernel(radius, length, clearance, viscosity, poly_r, poly_t, rx, ry, vx, vy, omega_sum, eps_cap):
    """Film force on the inner member ``(fx, fy, eps)`` for one relative state (scalars, SI units).

    ``poly_r``, ``poly_t``: correction polynomials in ε (``NO_CORRECTION`` for the short film).
    ``eps_cap``: if ε exceeds it, the force is evaluated at ε = eps_cap along the same direction (a numerical
    guard for trial states of an implicit integrator); pass ``inf`` for none — then ε >= 1 gives NaN.
    """
    ecc = math.sqrt(rx * rx + ry * ry)
    if ecc > 0.0:
        cphi, sphi = rx / ecc, ry / ecc
    else:
        cphi, sphi = 1.0, 0.0  # direction is arbitrary at e = 0; the force is continuous there
    eps = ecc / clearance
    eps_true = eps
    if eps > eps_cap:
        eps = eps_cap
    if not eps < 1.0:
        return math.nan, math.nan, eps_true
    v_r = vx * cphi + vy * sphi  # radial relative velocity = c ε̇
    v_t = -vx * sphi + vy * cphi  # tangential relative velocity = e φ̇
    a = eps * omega_sum - 2.0 * v_t / clearance  # ε (ω_s − 2 φ̇)
    b = 2.0 * v_r / clearance  # 2 ε̇
    alpha = math.atan2(b, a)
    s2 = 1.0 - eps * eps
    s = math.sqrt(s2)
    ca, sa = math.cos(alpha), math.sin(alpha)
    dp = 1.0 - eps * ca
    dm = 1.0 + eps * ca
    idp2, idm2 = 1.0 / (dp * dp), 1.0 / (dm * dm)
    dphi = (2.0 / s) * (0.5 * PI + math.atan(eps * sa / s))
    j_sc = -0.5 * ca * ca * (idp2 - idm2)
    j_ss = (sa * (eps - ca) * idp2 + sa * (eps + ca) * idm2) / (2.0 * s2) + dphi / (2.0 * s2)
    j_cc = (sa * ca / (2.0 * s2)) * (idp2 - idm2) + (3.0 * eps * sa / (2.0 * s2 * s2)) * (1.0 / dp + 1.0 / dm) \
        + (1.0 + 2.0 * eps * eps) * dphi / (2.0 * s2 * s2)
    kf = viscosity * radius * length ** 3 / (2.0 * clearance * clearance)
    f_r = kf * (a * j_sc - b * j_cc) * _polyval(poly_r, eps)
    f_t = kf * (a * j_ss - b * j_sc) * _polyval(poly_t, eps)
    return f_r * cphi - f_t * sphi, f_r * sphi + f_t * cphi, eps_true


@njit(cache=True)
def _film_force_loop(radius, length, clearance, viscosity, poly_r, poly_t, rx, ry, vx, vy, ws, out):
    for k in range(rx.size):
        fx, fy, _ = film_force_kernel(radius, length, clearance, viscosity, poly_r, poly_t, rx[k], ry[k], vx[k],
                                      vy[k], ws[k], math.inf)
        out[k, 0] = fx
        out[k, 1] = fy


def correction_polys(film: "Film", model: str):
    """``(poly_r, poly_t)`` of the film model for this film (``NO_CORRECTION`` for the short film)."""
    if model == "short_corrected":
        from .finite_length import correction_polynomials

        return correction_polynomials(film.length_to_diameter)
    return NO_CORRECTION, NO_CORRECTION


def eccentricity_ratio(film: Film, e):
    """ε = |e| / c [-] for relative position(s) ``e`` [m] (..., 2)."""
    e = np.asarray(e, dtype=float)
    return np.hypot(e[..., 0], e[..., 1]) / film.clearance


def _check_contact(eps, where=""):
    eps = np.asarray(eps)
    if np.any(~(eps < 1.0)):
        bad = float(np.max(np.where(np.isfinite(eps), eps, np.inf)))
        raise FilmContactError(
            f"eccentricity ratio eps = {bad:.6g}{where} is invalid: the film needs 0 <= eps < 1 "
            "(the member touches its wall)")


def film_force(film: Film, e, e_dot, omega_sum, model: str = "short"):
    """Dynamic film force on the inner member [N].

    Parameters
    ----------
    film : Film
    e : array_like (..., 2)
        Relative position inner minus outer centre [m].
    e_dot : array_like (..., 2)
        Relative velocity [m/s].
    omega_sum : float or array_like (...)
        Sum of the two surfaces' angular speeds [rad/s].
    model : {"short", "short_corrected"}

    Returns
    -------
    ndarray (..., 2)
        Force on the inner member [N] (x, y).

    Raises
    ------
    FilmContactError
        If the eccentricity ratio is >= 1.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> F = film_force(f, [9.4691e-6, -3.7916e-6], [0.0, 0.0], 3000.0)
    >>> round(float(F[1]), 2)   # physics.md §4.3: W = 5.6157 N carried upward
    5.62
    """
    model = check_model(model)
    e, e_dot, ws = np.broadcast_arrays(np.asarray(e, dtype=float), np.asarray(e_dot, dtype=float),
                                       np.asarray(omega_sum, dtype=float)[..., None])
    shape = e.shape[:-1]
    n = int(np.prod(shape))
    out = np.empty((n, 2))
    pr, pt = correction_polys(film, model)
    flat = [np.array(a, dtype=float).reshape(n) for a in (e[..., 0], e[..., 1], e_dot[..., 0], e_dot[..., 1],
                                                         ws[..., 0])]
    _film_force_loop(film.radius, film.length, film.clearance, film.viscosity, pr, pt, *flat, out)
    if not np.all(np.isfinite(out)):
        _check_contact(eccentricity_ratio(film, e))
        raise ParameterError("film force is not finite: check the inputs for NaN or inf "
                             f"(e = {e!r} m, e_dot = {e_dot!r} m/s, omega_sum = {omega_sum!r} rad/s)")
    return out.reshape(shape + (2,))


# --------------------------------------------------------------------------------------------------
# Static (quasi-static) relations (physics.md §2.6, §3, §4.2)
# --------------------------------------------------------------------------------------------------
def static_force_rt(eps: float, model: str = "short", lam: float | None = None):
    """Static (F_r, F_t) in units of μ ω_s R L³ / c² for eccentricity ratio ``eps`` (scalar)."""
    s2 = 1.0 - eps * eps
    f_r = -eps * eps / (s2 * s2)
    f_t = PI * eps / (4.0 * s2 * math.sqrt(s2))
    if model == "short_corrected":
        from .finite_length import correction_factors_scalar

        fr, ft, _, _ = correction_factors_scalar(eps, lam)
        f_r, f_t = fr * f_r, ft * f_t
    return f_r, f_t


def static_load(eps: float, model: str = "short", lam: float | None = None) -> float:
    """Dimensionless static load W̄ = W c² / (μ ω_s R L³) at eccentricity ratio ``eps``."""
    f_r, f_t = static_force_rt(eps, model, lam)
    return math.hypot(f_r, f_t)


def _eps_from_load_short(wbar: float):
    """Exact inverse of W̄(ε) for the short π-film via the quartic in X = ε² (physics.md §3).

    Safeguarded Newton on g(X) = 16 W̄² (1-X)^4 - (16-π²) X² - π² X, which falls monotonically on [0, 1].
    Returns (ε, iterations).
    """
    if wbar <= 0.0:
        return 0.0, 0
    k = 16.0 * wbar * wbar
    c2 = 16.0 - PI * PI
    p2 = PI * PI
    lo, hi = 0.0, 1.0
    # initial guess: light-load asymptote ε ≈ 4 W̄ / π, heavy-load asymptote 1 - X ≈ (16/k)^(1/4)... clipped
    x = min((4.0 * wbar / PI) ** 2, 0.5)
    if x >= 0.5:
        x = max(1.0 - (16.0 / k) ** 0.25, 0.5)
    for it in range(1, 100):
        om = 1.0 - x
        g = k * om ** 4 - c2 * x * x - p2 * x
        if g > 0.0:
            lo = x
        else:
            hi = x
        dg = -4.0 * k * om ** 3 - 2.0 * c2 * x - p2
        xn = x - g / dg
        if not (lo < xn < hi):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= 1e-16 + 1e-15 * x:
            return math.sqrt(xn), it
        x = xn
    return math.sqrt(x), it


def _eps_from_load_corrected(wbar: float, lam: float):
    from scipy.optimize import brentq

    if wbar <= 0.0:
        return 0.0, 0
    eps0, _ = _eps_from_load_short(wbar)  # the corrected load is lower: the root lies at larger ε
    lo = eps0
    hi = 1.0 - 1e-14
    eps, res = brentq(lambda x: static_load(x, "short_corrected", lam) - wbar, lo, hi, xtol=1e-15,
                      rtol=1e-15, full_output=True)
    return eps, res.iterations


def static_eccentricity(film: Film, load: float, omega_sum: float, model: str = "short"):
    """Eccentricity ratio ε of a film carrying static ``load`` [N] at ``omega_sum`` [rad/s].

    Returns ``(eps, iterations)``.  Closed form (quartic) for the short film, a 1-D root for the
    corrected film (physics.md §3, §5).
    """
    model = check_model(model)
    if not omega_sum > 0.0:
        raise ParameterError(
            f"film speed omega_sum = {omega_sum!r} rad/s is invalid for a static film solution: it must be > 0 "
            "(a film carries a static load only when its surfaces move)")
    wbar = abs(load) * film.clearance ** 2 / (film.viscosity * omega_sum * film.radius * film.length ** 3)
    if model == "short":
        return _eps_from_load_short(wbar)
    return _eps_from_load_corrected(wbar, film.length_to_diameter)


def attitude_angle(eps: float, model: str = "short", lam: float | None = None) -> float:
    """Attitude angle β [rad] between load line and line of centres (physics.md §3)."""
    if eps <= 0.0:
        return 0.5 * PI
    f_r, f_t = static_force_rt(eps, model, lam)
    return math.atan2(f_t, -f_r)


def static_position(film: Film, force, omega_sum: float, model: str = "short"):
    """Relative position ``e`` [m] at which the film exerts ``force`` [N] on its inner member.

    Closed-form inverse of the static film law (physics.md §3): ε from the load, the attitude angle β,
    and φ = ψ_F + β − π with ψ_F the direction of the required force.

    Returns
    -------
    e : ndarray (2,)
        Relative position inner minus outer [m].
    eps : float
        Eccentricity ratio.
    iterations : int
        Newton (short) or Brent (corrected) iterations of the 1-D inverse.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> e, eps, _ = static_position(f, (0.0, 5.61568), 3000.0)
    >>> round(eps, 4)
    0.3
    """
    fx, fy = float(force[0]), float(force[1])
    w = math.hypot(fx, fy)
    eps, it = static_eccentricity(film, w, omega_sum, model)
    if eps >= 1.0:
        raise FilmContactError(f"static load {w:g} N drives eps to {eps:g}; valid range 0 <= eps < 1")
    if eps == 0.0:
        return np.zeros(2), 0.0, it
    beta = attitude_angle(eps, model, film.length_to_diameter)
    phi = math.atan2(fy, fx) + beta - PI
    r = eps * film.clearance
    return np.array([r * math.cos(phi), r * math.sin(phi)]), eps, it


def rt_coefficients(eps: float, model: str = "short", lam: float | None = None):
    """Dimensionless stiffness and damping in the (r, t) frame (physics.md §4.2, §5).

    K in units of μ ω_s R L³ / c³ and C in units of μ R L³ / c³; valid down to ε = 0.
    """
    e2 = eps * eps
    s2 = 1.0 - e2
    s = math.sqrt(s2)
    s3, s5 = s2 * s, s2 * s2 * s
    k_rr = 2.0 * eps * (1.0 + e2) / (s2 * s2 * s2)
    k_rt = PI / (4.0 * s3)
    k_tr = -PI * (1.0 + 2.0 * e2) / (4.0 * s5)
    k_tt = eps / (s2 * s2)
    c_rr = PI * (1.0 + 2.0 * e2) / (2.0 * s5)
    c_rt = -2.0 * eps / (s2 * s2)
    c_tt = PI / (2.0 * s3)
    K = np.array([[k_rr, k_rt], [k_tr, k_tt]])
    C = np.array([[c_rr, c_rt], [c_rt, c_tt]])
    if model == "short_corrected":
        from .finite_length import correction_factors_scalar

        fr, ft, dfr, dft = correction_factors_scalar(eps, lam)
        f_r, f_t = static_force_rt(eps, "short")
        # K_rr = f_r K_rr − F_r f_r'/c  (here in units per c: dimensionless derivative w.r.t. ε)
        K = np.array([[fr * k_rr - f_r * dfr, ft * k_rt],
                      [ft * k_tr - f_t * dft, fr * k_tt]])
        C = np.array([[fr * c_rr, fr * c_rt], [ft * c_rt, ft * c_tt]])
    return K, C


def film_coefficients(film: Film, e, omega_sum: float, model: str = "short"):
    """Linearized stiffness and damping of a film at a static point.

    ``K = -dF/de`` [N/m] and ``C = -dF/de_dot`` [N s/m] (2x2, x-y frame), F the force on the inner member,
    evaluated at relative position ``e`` [m] with zero relative velocity and ``omega_sum`` [rad/s] held
    fixed. Uses the (r, t) form, so it stays finite as ε → 0.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> K, C = film_coefficients(f, [9.4691e-6, -3.7916e-6], 3000.0)
    >>> round(float(K[0, 0]) / 1e5, 2), round(float(C[1, 1]), 0)       # physics.md §4.3
    (3.98, 449.0)
    """
    model = check_model(model)
    e = np.asarray(e, dtype=float)
    ecc = math.hypot(e[0], e[1])
    c = film.clearance
    eps = ecc / c
    _check_contact(eps)
    Kd, Cd = rt_coefficients(eps, model, film.length_to_diameter)
    if ecc > 0.0:
        cp, sp = e[0] / ecc, e[1] / ecc
    else:
        cp, sp = 1.0, 0.0
    T = np.array([[cp, -sp], [sp, cp]])
    base = film.viscosity * film.radius * film.length ** 3 / c ** 3
    K = base * omega_sum * (T @ Kd @ T.T)
    C = base * (T @ Cd @ T.T)
    return K, C


# --------------------------------------------------------------------------------------------------
# Wall torques (physics.md §6)
# --------------------------------------------------------------------------------------------------
@njit(cache=True)
def petroff_kernel(radius, length, clearance, viscosity, eps):
    """A = 2π μ R³ L / (c sqrt(1-ε²)) [N m s] (scalar or array ε)."""
    return 2.0 * PI * viscosity * radius ** 3 * length / (clearance * np.sqrt(1.0 - eps * eps))


@njit(cache=True)
def film_torques_kernel(radius, length, clearance, viscosity, rx, ry, fx, fy, omega_inner, omega_outer):
    """Wall torques ``(T_inner_wall, T_outer_wall)`` [N m] of one film (scalars or equal-shape arrays).

    ``T_inner = +M_P(ω_outer − ω_inner) − (e × F)/2``, ``T_outer = −M_P(ω_outer − ω_inner) − (e × F)/2``
    (physics.md §6.1), e = (rx, ry) inner minus outer centre, F = (fx, fy) the force on the inner member.
    """
    eps = np.sqrt(rx * rx + ry * ry) / clearance
    mp = petroff_kernel(radius, length, clearance, viscosity, eps) * (omega_outer - omega_inner)
    half_cross = 0.5 * (rx * fy - ry * fx)
    return mp - half_cross, -mp - half_cross


def petroff_coefficient(film: Film, eps):
    """A = 2π μ R³ L / (c sqrt(1-ε²)) [N m s]: Petroff torque per unit speed difference."""
    eps = np.asarray(eps, dtype=float) if np.ndim(eps) else float(eps)
    return petroff_kernel(film.radius, film.length, film.clearance, film.viscosity, eps)


def film_torques(film: Film, e, force, omega_inner, omega_outer):
    """Torques [N m] (CCW about +z) the film exerts on its inner and outer wall, each about its own centre.

    ``T_inner = +M_P(ω_outer − ω_inner) − (e × F)/2`` and ``T_outer = −M_P(ω_outer − ω_inner) − (e × F)/2``,
    with ``e × F = e_x F_y − e_y F_x`` and F the film force on the inner member (physics.md §6.1).
    Works on arrays (..., 2).
    """
    e, force = np.asarray(e, dtype=float), np.asarray(force, dtype=float)
    args = np.broadcast_arrays(e[..., 0], e[..., 1], force[..., 0], force[..., 1],
                               np.asarray(omega_inner, dtype=float), np.asarray(omega_outer, dtype=float))
    if args[0].ndim == 0:
        return film_torques_kernel(film.radius, film.length, film.clearance, film.viscosity, *map(float, args))
    args = [np.array(a) for a in args]
    return film_torques_kernel(film.radius, film.length, film.clearance, film.viscosity, *args)


def offset_torque_coefficient(film: Film, eps: float, model: str = "short") -> float:
    """k with (e/2) F_t = k ω_s at a static point [N m s] (physics.md §6.2, §6.3)."""
    _, f_t = static_force_rt(eps, model, film.length_to_diameter)
    return 0.5 * eps * film.clearance * f_t * film.viscosity * film.radius * film.length ** 3 / film.clearance ** 2
