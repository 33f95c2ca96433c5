"""Finite-length correction of the short-bearing forces ("IScor", docs/theory/films.md#finite-length-correction).

The correction factors ``f_r(ε, λ)`` and ``f_t(ε, λ)`` (λ = L/D) are the ratios of the static force
components of the finite-length π-film to those of the infinitely short film, in the line-of-centres frame.
They are *calibrated here*, for any λ, by solving the finite-length Reynolds equation with finite
differences (full-Sommerfeld solution with negative pressures clipped, the π-film analogue of the
half-Sommerfeld short film), then fitted by quartic polynomials in ε as in
docs/theory/films.md#finite-length-correction.
The calibration runs once per λ (about 0.2 s) and is cached for the process.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..core.errors import ParameterError


def short_static_force_rt(eps):
    """Static force of the short π-film in the line-of-centres frame, dimensionless (in units of μ ω_s R L³ / c²):
    f_r = −ε²/(1−ε²)², f_t = π ε / (4 (1−ε²)^1.5) (docs/theory/films.md#static-and-quasi-static-case); the
    reference the finite-length ratios are taken against, and the factor :func:`frbmodel.physics.film.static_force_rt`
    corrects.

    >>> [round(x, 6) for x in short_static_force_rt(0.3)]
    [-0.108683, 0.271425]
    """
    s2 = 1.0 - eps * eps
    return -eps * eps / (s2 * s2), math.pi * eps / (4.0 * s2 * math.sqrt(s2))

#: ε values at which the ratios are computed for the fit (docs/theory/films.md#finite-length-correction uses 0.02 ...
# 0.9)
CALIBRATION_EPS = np.array([0.02, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9])


def reynolds_force_ratio(eps: float, lam: float, n_theta: int = 360, n_z: int = 60):
    """Finite-length / short-bearing static force ratios ``(f_r, f_t)`` at ``eps`` and L/D = ``lam``.

    Integrates the clipped finite-volume pressure field of :func:`reynolds_pressure` over the film; converged to
    about 1e-3 at 360 × 60 cells.

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 < ε < 1.
    lam : float
        L/D > 0.
    n_theta, n_z : int
        Cells around and along the film.

    Returns
    -------
    f_r, f_t : float
        Radial and tangential force of the finite film divided by those of the short film [-].

    Examples
    --------
    >>> f_r, f_t = reynolds_force_ratio(0.3, 0.05)     # a very short film: the short-bearing theory holds
    >>> bool(abs(f_r - 1.0) < 0.01 and abs(f_t - 1.0) < 0.01)
    True
    """
    th, P = reynolds_pressure(eps, lam, n_theta, n_z)
    dth = 2.0 * math.pi / n_theta
    dz = 1.0 / n_z
    # forces on the inner member per μ ω_s R³ L / c²: F = −∫∫ P (cos θ, sin θ) dθ dζ
    integ = P.sum(axis=1) * dz
    f_r = -np.sum(integ * np.cos(th)) * dth
    f_t = -np.sum(integ * np.sin(th)) * dth
    # short-bearing static forces per μ ω_s R L³/c² (docs/theory/films.md#static-and-quasi-static-case); convert units:
    # R³ L = R L³ / (4 λ²)
    fr_is, ft_is = short_static_force_rt(eps)
    scale = 1.0 / (4.0 * lam * lam)  # R³L / (R L³)
    return f_r * scale / fr_is, f_t * scale / ft_is


def reynolds_pressure(eps: float, lam: float, n_theta: int = 360, n_z: int = 60):
    """Dimensionless static pressure field of the finite-length π-film by finite volumes.

    Solves ∂θ(H³ ∂θ P) + (R/L)² ∂ζ(H³ ∂ζ P) = 6 ∂H/∂θ on θ ∈ [0, 2π) (periodic), ζ = z/L ∈ [−½, ½] with
    P = 0 at the film ends, H = 1 − ε cos θ, p = μ ω_s R²/c² · P; then clips P < 0 (Gümbel). Second-order finite
    volumes, ``n_theta`` × ``n_z`` cells.

    Parameters
    ----------
    eps : float
        Eccentricity ratio, 0 < ε < 1.
    lam : float
        L/D > 0.
    n_theta, n_z : int
        Cells around and along the film.

    Returns
    -------
    theta : ndarray (n_theta,)
        Cell centres θ [rad] (θ = ϑ: measured from the line of centres, minimum film at θ = 0).
    P : ndarray (n_theta, n_z)
        Pressure p c² / (μ ω_s R²) [-] at the cell centres ζ_j = −½ + (j + ½)/n_z, negative values clipped to 0.

    Examples
    --------
    >>> th, P = reynolds_pressure(0.3, 0.5, 36, 8)
    >>> P.shape, bool(P.min() == 0.0 and P.max() > 0.0)
    ((36, 8), True)
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    if not (0.0 < eps < 1.0):
        raise ParameterError(f"eps = {eps!r} is invalid for the Reynolds solver; valid range 0 < eps < 1")
    if not lam > 0.0:
        raise ParameterError(f"L/D = {lam!r} is invalid; valid range > 0")
    n_t, n_zz = n_theta, n_z
    dth = 2.0 * math.pi / n_t
    dz = 1.0 / n_zz
    th = (np.arange(n_t) + 0.5) * dth  # cell centres
    ratio2 = (1.0 / (2.0 * lam)) ** 2  # (R/L)^2 with R = D/2 = L/(2λ)
    h3_face = (1.0 - eps * np.cos(th + 0.5 * dth)) ** 3  # east faces θ_i + ½
    h3_c = (1.0 - eps * np.cos(th)) ** 3
    n = n_t * n_zz
    idx = np.arange(n).reshape(n_t, n_zz)
    rows, cols, vals = [], [], []
    diag = np.zeros((n_t, n_zz))
    # circumferential (periodic) fluxes
    aw = np.roll(h3_face, 1) / dth ** 2
    ae = h3_face / dth ** 2
    for a, shift in ((ae, -1), (aw, 1)):
        A = np.repeat(a[:, None], n_zz, axis=1)
        rows.append(idx.ravel())
        cols.append(np.roll(idx, shift, axis=0).ravel())
        vals.append(A.ravel())
        diag -= A
    # axial fluxes with Dirichlet P = 0 at ζ = ±½ (half cell to the boundary)
    az = ratio2 * h3_c[:, None] / dz ** 2 * np.ones((1, n_zz))
    # north and south neighbours
    for r_, c_, a_ in ((idx[:, :-1], idx[:, 1:], az[:, :-1]), (idx[:, 1:], idx[:, :-1], az[:, 1:])):
        rows.append(r_.ravel())
        cols.append(c_.ravel())
        vals.append(a_.ravel())
    diag[:, :-1] -= az[:, :-1]
    diag[:, 1:] -= az[:, 1:]
    diag[:, 0] -= 2.0 * az[:, 0]  # boundary half cell
    diag[:, -1] -= 2.0 * az[:, -1]
    rows.append(idx.ravel())
    cols.append(idx.ravel())
    vals.append(diag.ravel())
    A = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsc()
    # right side: 6 dH/dθ integrated over the cell = 6 (H_e − H_w)/dθ
    h_e = 1.0 - eps * np.cos(th + 0.5 * dth)
    h_w = 1.0 - eps * np.cos(th - 0.5 * dth)
    rhs = np.repeat((6.0 * (h_e - h_w) / dth)[:, None], n_zz, axis=1).ravel()
    P = spsolve(A, rhs).reshape(n_t, n_zz)
    P = np.clip(P, 0.0, None)
    return th, P


@lru_cache(maxsize=64)
def _calibration(lam_key: float):
    ratios = np.array([reynolds_force_ratio(e, lam_key) for e in CALIBRATION_EPS])
    pr = np.polyfit(CALIBRATION_EPS, ratios[:, 0], 4)
    pt = np.polyfit(CALIBRATION_EPS, ratios[:, 1], 4)
    return pr, pt, np.polyder(pr), np.polyder(pt)


def correction_polynomials(lam: float):
    """Quartic fits of the correction factors for L/D = ``lam`` (calibrated once per L/D and cached).

    Parameters
    ----------
    lam : float
        L/D, 0 < L/D <= 2.

    Returns
    -------
    poly_r, poly_t : ndarray (5,)
        Coefficients in ε (highest power first) of ``f_r`` and ``f_t``.

    Examples
    --------
    >>> pr, pt = correction_polynomials(0.5909)
    >>> pr.shape, bool(np.polyval(pr, 0.3) < 1.0)        # the finite film carries less than the short film
    ((5,), True)
    """
    if lam is None or not (0.0 < lam <= 2.0):
        raise ParameterError(f"film L/D = {lam!r} is outside the calibrated range 0 < L/D <= 2")
    pr, pt, _, _ = _calibration(round(float(lam), 4))
    return pr.copy(), pt.copy()


def correction_factors(eps, lam: float):
    """Correction factors and their ε-derivatives.

    Parameters
    ----------
    eps : float or ndarray
        Eccentricity ratio(s).
    lam : float
        L/D, 0 < L/D <= 2.

    Returns
    -------
    f_r, f_t, df_r, df_t : float or ndarray
        Factors [-] and derivatives d/dε [-].

    Examples
    --------
    >>> f_r, f_t, _, _ = correction_factors(np.array([0.3]), 0.5909)
    >>> f_r.shape
    (1,)
    """
    if lam is None or not (0.0 < lam <= 2.0):
        raise ParameterError(f"film L/D = {lam!r} is outside the calibrated range 0 < L/D <= 2")
    pr, pt, dpr, dpt = _calibration(round(float(lam), 4))
    return np.polyval(pr, eps), np.polyval(pt, eps), np.polyval(dpr, eps), np.polyval(dpt, eps)


def correction_factors_scalar(eps: float, lam: float):
    """Scalar fast path of :func:`correction_factors`.

    Parameters
    ----------
    eps : float
        Eccentricity ratio.
    lam : float
        L/D (must already be in the calibrated range).

    Returns
    -------
    f_r, f_t, df_r, df_t : float

    Examples
    --------
    >>> a = correction_factors_scalar(0.3, 0.5909)
    >>> b = correction_factors(0.3, 0.5909)
    >>> bool(np.allclose(a, b, rtol=1e-14))
    True
    """
    pr, pt, dpr, dpt = _calibration(round(float(lam), 4))

    def hv(p, x):
        acc = 0.0
        for cf in p:
            acc = acc * x + cf
        return acc

    return hv(pr, eps), hv(pt, eps), hv(dpr, eps), hv(dpt, eps)
