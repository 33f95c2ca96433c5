"""Oil films: short-bearing (IS) π-film forces, finite-length correction, coefficients, static inverse, torques.

Conventions (docs/theory/conventions.md#conventions): a film sits between an *inner member* and an *outer member*;
``e = centre_inner - centre_outer`` [m], ``e_dot`` its time derivative [m/s]; ``omega_sum`` [rad/s] is the
sum of the two surfaces' angular speeds (journal + ring for the inner film, ring for the outer film).
Every force returned is the film force **on the inner member** [N]; the outer member receives its negative.

Two film models exist (``film_model=``):

``"short"``
    Infinitely short bearing with half-Sommerfeld cavitation (π-film, moving cavitation boundary),
    closed form for arbitrary dynamic states (docs/theory/films.md#short-bearing-film-model).
``"short_corrected"``
    The short-bearing forces multiplied by finite-length correction factors ``f_r(ε, L/D)``, ``f_t(ε, L/D)`` in the
    line-of-centres frame (docs/theory/films.md#finite-length-correction), calibrated against a finite-difference
    solution of the finite-length Reynolds equation (:mod:`frbmodel.physics.finite_length`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.errors import FilmContactError, ParameterError, check_real, check_real_array, renamed_keyword
from ..system.films import FILM_MODELS, Film, check_film, check_model  # noqa: F401  (FILM_MODELS: re-exported)
from .finite_length import correction_factors_scalar, correction_polynomials, short_static_force_rt

PI = math.pi


# --------------------------------------------------------------------------------------------------
# Short-bearing π-film: the force kernel (docs/theory/films.md#forces). This is the one implementation of the dynamic
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
    """Film force on the inner member for one relative state (compiled, scalars, SI units; docs/theory/films.md#forces).

    Parameters
    ----------
    radius, length, clearance, viscosity : float
        Film geometry [m] and viscosity [Pa s].
    poly_r, poly_t : ndarray
        Correction polynomials in ε (``NO_CORRECTION`` for the short film, :func:`correction_polys`).
    rx, ry, vx, vy : float
        Relative position [m] and velocity [m/s], inner minus outer.
    omega_sum : float
        Sum of the surfaces' angular speeds [rad/s].
    eps_cap : float
        If ε exceeds it, the force is evaluated at ε = eps_cap along the same direction (a numerical guard for
        trial states of an implicit integrator); ``inf`` for none — then ε >= 1 gives NaN.

    Returns
    -------
    fx, fy : float
        Force on the inner member [N] (NaN for ε >= 1 without a cap; no input checks: see :func:`film_force`).
    eps : float
        The true eccentricity ratio (before capping).

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> fx, fy, eps = film_force_kernel(f.radius, f.length, f.clearance, f.viscosity, NO_CORRECTION, NO_CORRECTION,
    ...                                 9.4691e-6, -3.7916e-6, 0.0, 0.0, 3000.0, math.inf)
    >>> bool(np.allclose([fx, fy], film_force(f, [9.4691e-6, -3.7916e-6], [0.0, 0.0], 3000.0), rtol=1e-15))
    True
    """
    ecc = math.sqrt(rx * rx + ry * ry)
    if ecc > 0.0:
        ie = 1.0 / ecc
        cphi, sphi = rx * ie, ry * ie
    else:
        cphi, sphi = 1.0, 0.0  # direction is arbitrary at e = 0; the force is continuous there
    ic = 1.0 / clearance
    eps = ecc * ic
    eps_true = eps
    if eps > eps_cap:
        eps = eps_cap
    if not eps < 1.0:
        return math.nan, math.nan, eps_true
    v_r = vx * cphi + vy * sphi  # radial relative velocity = c ε̇
    v_t = -vx * sphi + vy * cphi  # tangential relative velocity = e φ̇
    a = eps * omega_sum - 2.0 * v_t * ic  # ε (ω_s − 2 φ̇)
    b = 2.0 * v_r * ic  # 2 ε̇
    # cos α, sin α of α = atan2(b, a) as a / |(a, b)|, b / |(a, b)| (and α = 0 at a = b = 0), one reciprocal per
    # repeated divisor: 50 ns instead of 75 ns per call, the same forces to 1e-12 (measured)
    hyp = math.sqrt(a * a + b * b)
    if hyp > 0.0:
        ih = 1.0 / hyp
        ca, sa = a * ih, b * ih
    else:
        ca, sa = 1.0, 0.0
    s2 = 1.0 - eps * eps
    s = math.sqrt(s2)
    i_s = 1.0 / s
    h2 = 0.5 / s2
    idp, idm = 1.0 / (1.0 - eps * ca), 1.0 / (1.0 + eps * ca)
    idp2, idm2 = idp * idp, idm * idm
    dphi = 2.0 * i_s * (0.5 * PI + math.atan(eps * sa * i_s))
    diff = idp2 - idm2
    j_sc = -0.5 * ca * ca * diff
    j_ss = (sa * (eps - ca) * idp2 + sa * (eps + ca) * idm2 + dphi) * h2
    j_cc = sa * ca * h2 * diff + h2 / s2 * (3.0 * eps * sa * (idp + idm) + (1.0 + 2.0 * eps * eps) * dphi)
    kf = viscosity * radius * length * length * length * 0.5 * ic * ic
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


def correction_polys(film: "Film", film_model: str):
    """Correction polynomials of a film model for this film.

    Parameters
    ----------
    film : Film
    film_model : {"short", "short_corrected"}

    Returns
    -------
    poly_r, poly_t : ndarray
        Coefficients in ε (highest power first) of the radial and tangential correction factors;
        ``NO_CORRECTION`` (= 1) for the short film.

    Examples
    --------
    >>> correction_polys(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3), "short")
    (array([1.]), array([1.]))
    """
    if film_model == "short_corrected":
        return correction_polynomials(film.length_to_diameter)
    return NO_CORRECTION, NO_CORRECTION


def eccentricity_ratio(film: Film, e):
    """Eccentricity ratio ε = |e| / c of relative position(s) ``e``.

    Parameters
    ----------
    film : Film
    e : array_like (..., 2)
        Relative position inner minus outer centre [m].

    Returns
    -------
    ndarray (...)
        ε [-].

    Examples
    --------
    >>> float(eccentricity_ratio(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3), [0.0, -17e-6]))
    0.5
    """
    e = np.asarray(e, dtype=float)
    return np.hypot(e[..., 0], e[..., 1]) / film.clearance


def _check_contact(eps, where=""):
    eps = np.asarray(eps)
    if np.any(~(eps < 1.0)):
        bad = float(np.max(np.where(np.isfinite(eps), eps, np.inf)))
        raise FilmContactError(
            f"eccentricity ratio eps = {bad:.6g}{where} is invalid: the film needs 0 <= eps < 1 "
            "(the member touches its wall)")


@renamed_keyword("model", "film_model")
def film_force(film: Film, e, e_dot, omega_sum, film_model: str = "short"):
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
    film_model : {"short", "short_corrected"}
        (``model=`` is the deprecated old name.)

    Returns
    -------
    ndarray (..., 2)
        Force on the inner member [N] (x, y).

    Raises
    ------
    ParameterError
        An input is not finite, not real or of the wrong shape (the message names it and its value).
    FilmContactError
        If the eccentricity ratio is >= 1.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> F = film_force(f, [9.4691e-6, -3.7916e-6], [0.0, 0.0], 3000.0)
    >>> round(float(F[1]), 2)   # docs/theory/films.md#worked-numbers: W = 5.6157 N carried upward
    5.62
    """
    film_model = check_model(film_model)
    check_film(film)
    e, e_dot, ws = _broadcast_inputs(e, e_dot, omega_sum)
    shape = e.shape[:-1]
    n = int(np.prod(shape))
    out = np.empty((n, 2))
    pr, pt = correction_polys(film, film_model)
    flat = [np.array(a, dtype=float).reshape(n) for a in (e[..., 0], e[..., 1], e_dot[..., 0], e_dot[..., 1],
                                                         ws[..., 0])]
    _film_force_loop(film.radius, film.length, film.clearance, film.viscosity, pr, pt, *flat, out)
    if not np.all(np.isfinite(out)):
        _check_contact(eccentricity_ratio(film, e))
        raise ParameterError("film force is not finite at finite inputs (an overflow): "
                             f"e = {e!r} m, e_dot = {e_dot!r} m/s, omega_sum = {omega_sum!r} rad/s")
    return out.reshape(shape + (2,))


def _broadcast_inputs(e, e_dot, omega_sum):
    """Checked, broadcast film-force inputs: e, e_dot (..., 2) and omega_sum (..., 1)."""
    e = check_real_array("e", e, "m", last_axis=2)
    e_dot = check_real_array("e_dot", e_dot, "m/s", last_axis=2)
    ws = check_real_array("omega_sum", omega_sum, "rad/s")
    try:
        return np.broadcast_arrays(e, e_dot, ws[..., None])
    except ValueError:
        raise ParameterError(f"e (shape {e.shape}), e_dot (shape {e_dot.shape}) and omega_sum (shape {ws.shape}) "
                             "do not broadcast: give e and e_dot as (..., 2) and omega_sum as (...) with the same "
                             "leading shape (or scalars)") from None


# --------------------------------------------------------------------------------------------------
# Static (quasi-static) relations (docs/theory/films.md#static-and-quasi-static-case,
# films.md#static-equilibrium-of-one-film, films.md#line-of-centres-frame)
# --------------------------------------------------------------------------------------------------
def static_force_rt(eps: float, film_model: str = "short", lam: float | None = None):
    """Static film force in the line-of-centres frame, dimensionless (docs/theory/films.md#static-and-quasi-static-case,
    films.md#finite-length-correction).

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 <= ε < 1.
    film_model : {"short", "short_corrected"}
    lam : float, optional
        L/D of the film (needed for ``"short_corrected"``).

    Returns
    -------
    f_r, f_t : float
        Radial and tangential force in units of μ ω_s R L³ / c².

    Examples
    --------
    >>> [round(x, 6) for x in static_force_rt(0.3)]    # -ε²/(1-ε²)², π ε / (4 (1-ε²)^1.5)
    [-0.108683, 0.271425]
    """
    f_r, f_t = short_static_force_rt(eps)
    if film_model == "short_corrected":
        fr, ft, _, _ = correction_factors_scalar(eps, lam)
        f_r, f_t = fr * f_r, ft * f_t
    return f_r, f_t


def static_load(eps: float, film_model: str = "short", lam: float | None = None) -> float:
    """Dimensionless static load W̄ = W c² / (μ ω_s R L³) at eccentricity ratio ``eps``.

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 <= ε < 1.
    film_model : {"short", "short_corrected"}
    lam : float, optional
        L/D of the film (needed for ``"short_corrected"``).

    Returns
    -------
    float
        W̄ [-].

    Examples
    --------
    >>> round(static_load(0.3), 6)     # docs/theory/films.md#static-equilibrium-of-one-film table
    0.292375
    """
    f_r, f_t = static_force_rt(eps, film_model, lam)
    return math.hypot(f_r, f_t)


def _eps_from_load_short(wbar: float):
    """Exact inverse of W̄(ε) for the short π-film via the quartic in X = ε²
    (docs/theory/films.md#static-equilibrium-of-one-film).

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


@renamed_keyword("model", "film_model")
def static_eccentricity(film: Film, load: float, omega_sum: float, film_model: str = "short"):
    """Eccentricity ratio ε of a film carrying a static load (docs/theory/films.md#static-equilibrium-of-one-film,
    films.md#finite-length-correction).

    Closed form (quartic) for the short film, a 1-D root for the corrected film.

    Parameters
    ----------
    film : Film
    load : float
        Static load [N] (its magnitude is used).
    omega_sum : float
        Sum of the two surfaces' angular speeds [rad/s], > 0.
    film_model : {"short", "short_corrected"}
        (``model=`` is the deprecated old name.)

    Returns
    -------
    eps : float
        Eccentricity ratio [-].
    iterations : int
        Newton (short) or Brent (corrected) iterations.

    Raises
    ------
    ParameterError
        ``load`` or ``omega_sum`` not a finite real number, or ``omega_sum`` <= 0.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> eps, _ = static_eccentricity(f, 5.61568, 3000.0)
    >>> round(eps, 4)                     # docs/theory/films.md#worked-numbers
    0.3
    """
    film_model = check_model(film_model)
    check_film(film)
    load = check_real("load", load, "N")
    omega_sum = check_real("omega_sum", omega_sum, "rad/s", minimum=0.0)
    wbar = abs(load) * film.clearance ** 2 / (film.viscosity * omega_sum * film.radius * film.length ** 3)
    if film_model == "short":
        return _eps_from_load_short(wbar)
    return _eps_from_load_corrected(wbar, film.length_to_diameter)


def attitude_angle(eps: float, film_model: str = "short", lam: float | None = None) -> float:
    """Attitude angle β between load line and line of centres (docs/theory/films.md#static-equilibrium-of-one-film).

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 <= ε < 1.
    film_model : {"short", "short_corrected"}
    lam : float, optional
        L/D of the film (needed for ``"short_corrected"``).

    Returns
    -------
    float
        β [rad] (π/2 at ε = 0).

    Examples
    --------
    >>> round(math.degrees(attitude_angle(0.3)), 3)     # docs/theory/films.md#static-equilibrium-of-one-film table
    68.178
    """
    if eps <= 0.0:
        return 0.5 * PI
    f_r, f_t = static_force_rt(eps, film_model, lam)
    return math.atan2(f_t, -f_r)


@renamed_keyword("model", "film_model")
def static_position(film: Film, force, omega_sum: float, film_model: str = "short"):
    """Relative position ``e`` [m] at which the film exerts ``force`` [N] on its inner member.

    Closed-form inverse of the static film law (docs/theory/films.md#static-equilibrium-of-one-film): ε from the load,
    the attitude angle β, and φ = ψ_F + β − π with ψ_F the direction of the required force.

    Parameters
    ----------
    film : Film
    force : array_like (2,)
        Required force on the inner member [N] (x, y).
    omega_sum : float
        Sum of the two surfaces' angular speeds [rad/s], > 0.
    film_model : {"short", "short_corrected"}
        (``model=`` is the deprecated old name.)

    Returns
    -------
    e : ndarray (2,)
        Relative position inner minus outer [m].
    eps : float
        Eccentricity ratio.
    iterations : int
        Newton (short) or Brent (corrected) iterations of the 1-D inverse.

    Raises
    ------
    ParameterError
        ``force`` is not two finite real numbers, or ``omega_sum`` is not a finite number > 0.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> e, eps, _ = static_position(f, (0.0, 5.61568), 3000.0)
    >>> round(eps, 4)
    0.3
    """
    force = check_real_array("force", force, "N", last_axis=2)
    if force.shape != (2,):
        raise ParameterError(f"force = {force!r} has shape {force.shape}; expected one force (2,) [N]")
    check_film(film)
    omega_sum = check_real("omega_sum", omega_sum, "rad/s", minimum=0.0)
    return static_position_kernel(film, float(force[0]), float(force[1]), omega_sum, check_model(film_model))


def static_position_kernel(film: Film, fx: float, fy: float, omega_sum: float, film_model: str):
    """:func:`static_position` without input checks, for the equilibrium solvers (their inputs are checked once).

    Parameters
    ----------
    film : Film
    fx, fy : float
        Required force on the inner member [N] (finite).
    omega_sum : float
        Sum of the surfaces' angular speeds [rad/s], > 0.
    film_model : {"short", "short_corrected"}

    Returns
    -------
    e : ndarray (2,)
        Relative position inner minus outer [m].
    eps : float
        Eccentricity ratio.
    iterations : int

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> e, eps, _ = static_position_kernel(f, 0.0, 5.61568, 3000.0, "short")
    >>> bool(np.array_equal(e, static_position(f, (0.0, 5.61568), 3000.0)[0]))
    True
    """
    w = math.hypot(fx, fy)
    wbar = w * film.clearance ** 2 / (film.viscosity * omega_sum * film.radius * film.length ** 3)
    eps, it = _eps_from_load_short(wbar) if film_model == "short" else \
        _eps_from_load_corrected(wbar, film.length_to_diameter)
    if eps >= 1.0:
        raise FilmContactError(f"static load {w:g} N drives eps to {eps:g}; valid range 0 <= eps < 1")
    if eps == 0.0:
        return np.zeros(2), 0.0, it
    beta = attitude_angle(eps, film_model, film.length_to_diameter)
    phi = math.atan2(fy, fx) + beta - PI
    r = eps * film.clearance
    return np.array([r * math.cos(phi), r * math.sin(phi)]), eps, it


def rt_coefficients(eps: float, film_model: str = "short", lam: float | None = None):
    """Dimensionless stiffness and damping in the (r, t) frame (docs/theory/films.md#line-of-centres-frame,
    films.md#finite-length-correction); valid
    down to ε = 0.

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 <= ε < 1.
    film_model : {"short", "short_corrected"}
    lam : float, optional
        L/D of the film (needed for ``"short_corrected"``).

    Returns
    -------
    K : ndarray (2, 2)
        Stiffness in units of μ ω_s R L³ / c³.
    C : ndarray (2, 2)
        Damping in units of μ R L³ / c³.

    Examples
    --------
    >>> K, C = rt_coefficients(0.0)          # centred film: pure cross-coupling, isotropic damping
    >>> K.round(4).tolist(), C.round(4).tolist()
    ([[0.0, 0.7854], [-0.7854, 0.0]], [[1.5708, -0.0], [-0.0, 1.5708]])
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
    if film_model == "short_corrected":
        fr, ft, dfr, dft = correction_factors_scalar(eps, lam)
        f_r, f_t = static_force_rt(eps, "short")
        # K_rr = f_r K_rr − F_r f_r'/c  (here in units per c: dimensionless derivative w.r.t. ε)
        K = np.array([[fr * k_rr - f_r * dfr, ft * k_rt],
                      [ft * k_tr - f_t * dft, fr * k_tt]])
        C = np.array([[fr * c_rr, fr * c_rt], [ft * c_rt, ft * c_tt]])
    return K, C


@renamed_keyword("model", "film_model")
def film_coefficients(film: Film, e, omega_sum: float, film_model: str = "short"):
    """Linearized stiffness and damping of a film at a static point.

    ``K = -dF/de`` and ``C = -dF/de_dot`` (x-y frame), F the force on the inner member, at zero relative velocity
    with ``omega_sum`` held fixed. Uses the (r, t) form, so it stays finite as ε → 0.

    Parameters
    ----------
    film : Film
    e : array_like (2,)
        Relative position inner minus outer centre [m], |e| < clearance.
    omega_sum : float
        Sum of the two surfaces' angular speeds [rad/s].
    film_model : {"short", "short_corrected"}
        (``model=`` is the deprecated old name.)

    Returns
    -------
    K : ndarray (2, 2)
        Stiffness [N/m].
    C : ndarray (2, 2)
        Damping [N s/m].

    Raises
    ------
    ParameterError
        ``e`` is not two finite real numbers or ``omega_sum`` not a finite real number.
    FilmContactError
        |e| >= clearance.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> K, C = film_coefficients(f, [9.4691e-6, -3.7916e-6], 3000.0)
    >>> round(float(K[0, 0]) / 1e5, 2), round(float(C[1, 1]), 0)       # docs/theory/films.md#worked-numbers
    (3.98, 449.0)
    """
    film_model = check_model(film_model)
    check_film(film)
    e = check_real_array("e", e, "m", last_axis=2)
    if e.shape != (2,):
        raise ParameterError(f"e = {e!r} has shape {e.shape}; expected one relative position (2,) [m]")
    omega_sum = check_real("omega_sum", omega_sum, "rad/s")
    ecc = math.hypot(e[0], e[1])
    c = film.clearance
    eps = ecc / c
    _check_contact(eps)
    Kd, Cd = rt_coefficients(eps, film_model, film.length_to_diameter)
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
# Wall torques (docs/theory/rings.md#floating-ring)
# --------------------------------------------------------------------------------------------------
@njit(cache=True)
def petroff_kernel(radius, length, clearance, viscosity, eps):
    """Petroff coefficient A = 2π μ R³ L / (c sqrt(1-ε²)) [N m s] (compiled; scalar or array ``eps``).

    Parameters
    ----------
    radius, length, clearance, viscosity : float
        Film geometry [m] and viscosity [Pa s].
    eps : float or ndarray
        Eccentricity ratio(s).

    Returns
    -------
    float or ndarray
        A [N m s].
    """
    return 2.0 * PI * viscosity * radius ** 3 * length / (clearance * np.sqrt(1.0 - eps * eps))


@njit(cache=True)
def film_torques_kernel(radius, length, clearance, viscosity, rx, ry, fx, fy, omega_inner, omega_outer):
    """Wall torques of one film (compiled; scalars or equal-shape arrays),
    docs/theory/rings.md#wall-torques-of-one-film.

    ``T_inner = +M_P(ω_outer − ω_inner) − (e × F)/2``, ``T_outer = −M_P(ω_outer − ω_inner) − (e × F)/2``.

    Parameters
    ----------
    radius, length, clearance, viscosity : float
        Film geometry [m] and viscosity [Pa s].
    rx, ry : float or ndarray
        e = inner minus outer centre [m].
    fx, fy : float or ndarray
        Film force on the inner member [N].
    omega_inner, omega_outer : float or ndarray
        Spin speeds of the inner and outer wall [rad/s].

    Returns
    -------
    T_inner_wall, T_outer_wall : float or ndarray
        [N m], CCW about +z.
    """
    eps = np.sqrt(rx * rx + ry * ry) / clearance
    mp = petroff_kernel(radius, length, clearance, viscosity, eps) * (omega_outer - omega_inner)
    half_cross = 0.5 * (rx * fy - ry * fx)
    return mp - half_cross, -mp - half_cross


def petroff_coefficient(film: Film, eps):
    """Petroff torque per unit speed difference, A = 2π μ R³ L / (c sqrt(1-ε²)).

    Parameters
    ----------
    film : Film
    eps : float or array_like
        Eccentricity ratio(s), 0 <= ε < 1.

    Returns
    -------
    float or ndarray
        A [N m s].

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> round(petroff_coefficient(f, 0.0) * 1e6, 4)      # 2π μ R³ L / c [µN m s]
    0.9793
    """
    eps = np.asarray(eps, dtype=float) if np.ndim(eps) else float(eps)
    return petroff_kernel(film.radius, film.length, film.clearance, film.viscosity, eps)


def film_torques(film: Film, e, force, omega_inner, omega_outer):
    """Torques the film exerts on its inner and outer wall, each about its own centre
    (docs/theory/rings.md#wall-torques-of-one-film).

    ``T_inner = +M_P(ω_outer − ω_inner) − (e × F)/2`` and ``T_outer = −M_P(ω_outer − ω_inner) − (e × F)/2``,
    with ``e × F = e_x F_y − e_y F_x``.

    Parameters
    ----------
    film : Film
    e : array_like (..., 2)
        Relative position inner minus outer centre [m].
    force : array_like (..., 2)
        Film force on the inner member [N] (e.g. from :func:`film_force`).
    omega_inner, omega_outer : float or array_like (...)
        Spin speeds of the inner and outer wall [rad/s].

    Returns
    -------
    T_inner_wall, T_outer_wall : float or ndarray (...)
        [N m], CCW about +z.

    Raises
    ------
    ParameterError
        An input is not finite, not real or of the wrong shape.

    Examples
    --------
    >>> f = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)
    >>> ti, to = film_torques(f, [0.0, 0.0], [0.0, 0.0], 1000.0, 0.0)   # centred: Petroff torques only
    >>> round(ti * 1e3, 4), round(to * 1e3, 4)                          # [mN m]
    (-0.9793, 0.9793)
    """
    check_film(film)
    e = check_real_array("e", e, "m", last_axis=2)
    force = check_real_array("force", force, "N", last_axis=2)
    w_i = check_real_array("omega_inner", omega_inner, "rad/s")
    w_o = check_real_array("omega_outer", omega_outer, "rad/s")
    try:
        args = np.broadcast_arrays(e[..., 0], e[..., 1], force[..., 0], force[..., 1], w_i, w_o)
    except ValueError:
        raise ParameterError(f"e (shape {e.shape}), force (shape {force.shape}), omega_inner (shape {w_i.shape}) "
                             f"and omega_outer (shape {w_o.shape}) do not broadcast") from None
    if args[0].ndim == 0:
        return film_torques_kernel(film.radius, film.length, film.clearance, film.viscosity, *map(float, args))
    args = [np.array(a) for a in args]
    return film_torques_kernel(film.radius, film.length, film.clearance, film.viscosity, *args)


def offset_torque_coefficient(film: Film, eps: float, film_model: str = "short") -> float:
    """Pressure-offset torque coefficient k with (e/2) F_t = k ω_s at a static point
    (docs/theory/rings.md#torques-on-the-ring, rings.md#ring-speed-ratio).

    Parameters
    ----------
    film : Film
    eps : float
        Eccentricity ratio, 0 <= ε < 1.
    film_model : {"short", "short_corrected"}

    Returns
    -------
    float
        k [N m s].

    Examples
    --------
    >>> offset_torque_coefficient(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3), 0.0)   # centred film: no offset torque
    0.0
    """
    _, f_t = static_force_rt(eps, film_model, film.length_to_diameter)
    return 0.5 * eps * film.clearance * f_t * film.viscosity * film.radius * film.length ** 3 / film.clearance ** 2
