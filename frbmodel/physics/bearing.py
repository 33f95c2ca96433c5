"""Floating ring: torques on the ring and ring-speed-ratio (RSR) models (docs/theory/rings.md#floating-ring).

The ring is the outer wall of the inner film and the inner wall of the outer film, so its torque is the
sum of :func:`frbmodel.physics.film.film_torques` of both films; the RSR formulas follow from setting that sum to 0.
"""
from __future__ import annotations

from numba import njit

from ..core.errors import ParameterError, check_real, check_real_array, renamed_keyword
from ..system.parameters import check_bearing
from .film import (
    check_model,
    film_force_kernel,
    film_torques,
    film_torques_kernel,
    offset_torque_coefficient,
    petroff_coefficient,
)


@njit(cache=True)
def ring_torque_kernel(inner_geom, outer_geom, ri_x, ri_y, fi_x, fi_y, ro_x, ro_y, fo_x, fo_y, omega_rotor,
                       omega_ring):
    """Total torque M^I + M^O on the ring (compiled, scalars; docs/theory/rings.md#torques-on-the-ring).

    Parameters
    ----------
    inner_geom, outer_geom : ndarray (4,)
        (radius [m], length [m], clearance [m], viscosity [Pa s]) of the inner and outer film.
    ri_x, ri_y : float
        Journal minus ring centre [m].
    fi_x, fi_y : float
        Inner-film force on the journal [N].
    ro_x, ro_y : float
        Ring minus housing centre [m].
    fo_x, fo_y : float
        Outer-film force on the ring [N].
    omega_rotor, omega_ring : float
        Journal and ring spin speeds [rad/s].

    Returns
    -------
    float
        Torque on the ring [N m], CCW about +z.
    """
    _, t_i = film_torques_kernel(inner_geom[0], inner_geom[1], inner_geom[2], inner_geom[3], ri_x, ri_y, fi_x, fi_y,
                                 omega_rotor, omega_ring)
    t_o, _ = film_torques_kernel(outer_geom[0], outer_geom[1], outer_geom[2], outer_geom[3], ro_x, ro_y, fo_x, fo_y,
                                 omega_ring, 0.0)
    return t_i + t_o


@njit(cache=True)
def ring_rhs_kernel(geom, polys, ring_m, ring_i, grav, jx, jy, jvx, jvy, ring, omega_rotor, eps_cap, dring,
                    housing_ax=0.0, housing_ay=0.0):
    """Ring equations of docs/theory/equations-of-motion.md#floating-rings for one bearing (compiled; the one
    implementation: the monolithic run-up and the bearing FMU both call it), written relative to the bearing housing: a
    housing that accelerates by (``housing_ax``, ``housing_ay``) loads the ring with −m (a_x, a_y)
    (docs/theory/housing.md; zero: bit for bit the fixed-housing equations).

    Parameters
    ----------
    geom : ndarray (2, 4)
        [R, L, c, μ] of the inner and outer film [m, m, m, Pa s].
    polys : ndarray (2, 2, 5)
        Correction polynomials (film, radial/tangential, coefficients).
    ring_m, ring_i, grav : float
        Ring mass [kg], polar inertia [kg m²], gravity [m/s²].
    jx, jy, jvx, jvy : float
        Journal position [m] and velocity [m/s].
    ring : ndarray (5,)
        Ring state (x, y, vx, vy, ω_FR) [m, m/s, rad/s].
    omega_rotor : float
        Rotor speed [rad/s].
    eps_cap : float
        Eccentricity cap of the film forces (see :func:`frbmodel.physics.film.film_force_kernel`).
    dring : ndarray (5,)
        Output: d(ring)/dt.
    housing_ax, housing_ay : float
        Translational acceleration of the housing [m/s²] (the ring's position and velocity are relative to it).

    Returns
    -------
    fx, fy : float
        Inner-film force on the journal [N].
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and outer film.
    """
    wfr = ring[4]
    rix = jx - ring[0]
    riy = jy - ring[1]
    g = geom[0]
    fix, fiy, ei = film_force_kernel(g[0], g[1], g[2], g[3], polys[0, 0], polys[0, 1], rix, riy, jvx - ring[2],
                                     jvy - ring[3], omega_rotor + wfr, eps_cap)
    g = geom[1]
    fox, foy, eo = film_force_kernel(g[0], g[1], g[2], g[3], polys[1, 0], polys[1, 1], ring[0], ring[1], ring[2],
                                     ring[3], wfr, eps_cap)
    dring[0] = ring[2]
    dring[1] = ring[3]
    dring[2] = (-fix + fox - ring_m * housing_ax) / ring_m
    dring[3] = (-fiy + foy - ring_m * (grav + housing_ay)) / ring_m
    # torques with positions capped like the forces (trial states of implicit integrators may pass the wall)
    si = min(1.0, eps_cap / ei) if ei > 0 else 1.0
    so = min(1.0, eps_cap / eo) if eo > 0 else 1.0
    dring[4] = ring_torque_kernel(geom[0], geom[1], rix * si, riy * si, fix, fiy, ring[0] * so, ring[1] * so, fox, foy,
                                  omega_rotor, wfr) / ring_i
    return fix, fiy, ei, eo


def ring_torque(bearing, r_inner, force_inner, r_outer, force_outer, omega_rotor, omega_ring):
    """Total torque on the ring, M^I + M^O of docs/theory/rings.md#torques-on-the-ring /
    equations-of-motion.md#floating-rings.

    Parameters
    ----------
    bearing : FloatingRingBearing
    r_inner : array_like (..., 2)
        Journal minus ring centre [m].
    force_inner : array_like (..., 2)
        Inner-film force on the journal [N].
    r_outer : array_like (..., 2)
        Ring centre minus housing centre [m].
    force_outer : array_like (..., 2)
        Outer-film force on the ring [N].
    omega_rotor, omega_ring : float or array_like
        Journal and ring spin speeds [rad/s].

    Returns
    -------
    float or ndarray (...)
        Torque on the ring [N m], CCW about +z.

    Raises
    ------
    ParameterError
        An input is not finite, not real or not of shape (..., 2) (the message names it).

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> z = [0.0, 0.0]
    >>> t = frb.ring_torque(b, z, z, z, z, 1000.0, 1000.0 * frb.ring_speed_ratio(b))
    >>> abs(t) < 1e-15    # centred films at the eq. (6) ring speed: the Petroff torques balance
    True
    """
    for name, v, unit in (("r_inner", r_inner, "m"), ("force_inner", force_inner, "N"), ("r_outer", r_outer, "m"),
                          ("force_outer", force_outer, "N")):
        check_real_array(name, v, unit, last_axis=2)
    for name, v in (("omega_rotor", omega_rotor), ("omega_ring", omega_ring)):
        check_real_array(name, v, "rad/s")
    check_bearing(bearing)
    _, t_ring_from_inner = film_torques(bearing.inner, r_inner, force_inner, omega_rotor, omega_ring)
    t_ring_from_outer, _ = film_torques(bearing.outer, r_outer, force_outer, omega_ring, 0.0)
    return t_ring_from_inner + t_ring_from_outer


@renamed_keyword("model", "film_model")
def ring_speed_ratio(bearing, eps_inner: float = 0.0, eps_outer: float = 0.0, torque: str = "petroff",
                     film_model: str = "short") -> float:
    """Ring-speed ratio ω_FR / ω_R of the steady torque balance at given film eccentricity ratios.

    ``torque="petroff"``: Petroff torques only — the paper's eq. (7); with ``eps_inner = eps_outer = 0``
    this is eq. (6), ``1 / (1 + (μ_O/μ_I)(L_O/L_I)(c_I/c_O)(D_O/D_I)³)``.
    ``torque="full"``: Petroff plus the pressure-offset torques (docs/theory/rings.md#ring-speed-ratio),
    ``(A_I − k_I) / (A_I + A_O + k_I + k_O)``.

    Parameters
    ----------
    bearing : FloatingRingBearing
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and outer film, 0 <= ε < 1.
    torque : {"petroff", "full"}
    film_model : {"short", "short_corrected"}
        (``model=`` is the deprecated old name.)

    Returns
    -------
    float
        ω_FR / ω_R [-].

    Raises
    ------
    ParameterError
        An ε outside [0, 1) or not a real number, an unknown ``torque`` or film model.

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger(outer_clearance=36e-6).bearings[0]
    >>> round(frb.ring_speed_ratio(b), 5)
    0.19903
    """
    check_bearing(bearing)
    for name, eps in (("eps_inner", eps_inner), ("eps_outer", eps_outer)):
        if not (0.0 <= check_real(name, eps) < 1.0):
            raise ParameterError(f"{name} = {eps!r} is invalid: valid range 0 <= eps < 1")
    if torque not in ("petroff", "full"):
        raise ParameterError(f"torque = {torque!r} is unknown; valid values are 'petroff', 'full'")
    film_model = check_model(film_model)
    a_i, a_o, k_i, k_o = static_torque_coefficients(bearing, eps_inner, eps_outer, film_model, torque == "full")
    if torque == "petroff":
        return float(a_i / (a_i + a_o))
    return float((a_i - k_i) / (a_i + a_o + k_i + k_o))


def static_torque_coefficients(bearing, eps_inner: float, eps_outer: float, film_model: str = "short",
                               offset: bool = True):
    """Coefficients of the steady ring torque (docs/theory/rings.md#torques-on-the-ring, rings.md#ring-speed-ratio).

    Parameters
    ----------
    bearing : FloatingRingBearing
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and outer film.
    film_model : {"short", "short_corrected"}
    offset : bool
        Also compute the pressure-offset coefficients (else they are returned as 0).

    Returns
    -------
    a_i, a_o, k_i, k_o : float
        Petroff coefficients A = 2π μ R³ L / (c sqrt(1 − ε²)) and offset coefficients k with (e/2) F_t = k ω_s
        [N m s], so that the torque on the ring is a_i (ω_R − ω_FR) − k_i (ω_R + ω_FR) − a_o ω_FR − k_o ω_FR.

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> a_i, a_o, k_i, k_o = static_torque_coefficients(b, 0.0, 0.0)
    >>> round(float(a_i / (a_i + a_o)), 5), k_i, k_o     # eq. (6); centred films have no offset torque
    (0.19903, 0.0, 0.0)
    """
    a_i = petroff_coefficient(bearing.inner, eps_inner)
    a_o = petroff_coefficient(bearing.outer, eps_outer)
    if not offset:
        return a_i, a_o, 0.0, 0.0
    k_i = offset_torque_coefficient(bearing.inner, eps_inner, film_model)
    k_o = offset_torque_coefficient(bearing.outer, eps_outer, film_model)
    return a_i, a_o, k_i, k_o


def static_ring_torque(bearing, eps_inner: float, eps_outer: float, omega_rotor: float, omega_ring: float,
                       film_model: str = "short") -> float:
    """Steady torque on the ring at static film states (the eq. (32) residual with full torques).

    Parameters
    ----------
    bearing : FloatingRingBearing
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and outer film.
    omega_rotor, omega_ring : float
        Rotor and ring speed [rad/s].
    film_model : {"short", "short_corrected"}

    Returns
    -------
    float
        Torque on the ring [N m] (:func:`static_torque_coefficients`).

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> abs(static_ring_torque(b, 0.0, 0.0, 1000.0, 1000.0 * frb.ring_speed_ratio(b))) < 1e-15
    True
    """
    a_i, a_o, k_i, k_o = static_torque_coefficients(bearing, eps_inner, eps_outer, film_model)
    return float(a_i * (omega_rotor - omega_ring) - k_i * (omega_rotor + omega_ring) - a_o * omega_ring
                 - k_o * omega_ring)

