"""Bearing friction: film torque on the journal and friction power of both films
(docs/theory/rings.md#friction-torque-and-power-loss).

The journal torque and the power loss of a floating-ring bearing come from the same film kernels as the ring's torque
balance (:func:`frbmodel.physics.film.film_force_kernel`, :func:`frbmodel.physics.film.film_torques_kernel`; the ring
torque of :func:`frbmodel.physics.bearing.ring_torque_kernel` is the sum of the same two film torques), so the journal
torque that brakes a torque-driven rotor (:func:`frbmodel.physics.dynamics.spin_acceleration`) is the reaction of the
film torque that drives the ring.

Sign conventions (docs/theory/conventions.md#conventions, rings.md#floating-ring): torques are CCW about +z; the journal
torque T_J is the inner film's torque on the journal about its centre, negative when it brakes the rotor. The friction
power of a film is the mechanical power its two walls put into it, P = −Σ_walls (T_wall ω_wall + F_wall · v_wall), with
F_wall the film force on the wall and v_wall the velocity of the wall's centre. For the inner film (journal, ring) and
the outer film (ring, fixed housing)::

    P_I = −[T_J ω_R + M^I ω_FR + F^I · (v_J − v_FR)]
    P_O = −[M^O ω_FR + F^O · v_FR]

With the short-film torques and forces this is P = A Δω² + (c K_F / 2) ∫ G² / D³ dϑ over the pressure zone
(Δω the speed difference of the walls, A the Petroff coefficient, G and D of
docs/theory/films.md#reynolds-equation-and-pressure–2.4): never negative,
and A_I (ω_R − ω_FR)² + A_O ω_FR² with centred members (Petroff). In a steady state with the ring torque balanced
(method J) the total is −T_J ω_R.

The losses at the equilibria over speed are :func:`frbmodel.linear.losses.bearing_losses` (an analysis, one layer
up); their figure is :func:`frbmodel.plots.losses.plot_bearing_losses`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.errors import ParameterError
from ..system.parameters import check_bearing
from .film import check_model, correction_polys, film_force_kernel, film_torques_kernel

__all__ = ["bearing_loss", "bearing_loss_kernel", "film_arrays", "journal_torque_kernel"]


def film_arrays(bearing, film_model="short"):
    """The film data of one bearing as the compiled kernels take them.

    Parameters
    ----------
    bearing : FloatingRingBearing
        The bearing.
    film_model : {"short", "short_corrected"}
        Film model; "short" gives zero correction polynomials.

    Returns
    -------
    geom : ndarray (2, 4)
        [R, L, c, μ] of the inner and the outer film [m, m, m, Pa s].
    polys : ndarray (2, 2, 5)
        Correction polynomials (film, radial/tangential, coefficients highest power first).

    Raises
    ------
    ParameterError
        For an unknown film model.

    Examples
    --------
    >>> import frbmodel as frb
    >>> geom, polys = film_arrays(frb.turbocharger().bearings[0])
    >>> geom.shape, polys.shape
    ((2, 4), (2, 2, 5))
    """
    model = check_model(film_model)
    films = (bearing.inner, bearing.outer)
    geom = np.array([[f.radius, f.length, f.clearance, f.viscosity] for f in films])
    polys = np.zeros((2, 2, 5))
    for k, film in enumerate(films):
        for m_, p in enumerate(correction_polys(film, model)):
            polys[k, m_, 5 - p.size:] = p
    return geom, polys


@njit(cache=True)
def journal_torque_kernel(inner_geom, rx, ry, fx, fy, omega_rotor, omega_ring, eps_cap):
    """Torque T_J [N m] of the inner film on the journal about +z (negative: it brakes the rotor).

    Parameters
    ----------
    inner_geom : ndarray (4,)
        [R, L, c, μ] of the inner film.
    rx, ry : float
        Journal centre minus ring centre [m]; beyond ``eps_cap`` taken at ε = eps_cap along the same direction,
        as the force (:func:`frbmodel.physics.bearing.ring_rhs_kernel` caps the ring torque the same way).
    fx, fy : float
        Inner-film force on the journal [N].
    omega_rotor, omega_ring : float
        Journal and ring spin speeds [rad/s].
    eps_cap : float
        Eccentricity ratio [-] at which positions are capped; ``inf`` for no cap.

    Returns
    -------
    float
        T_J = −A_I (ω_R − ω_FR) − (e_I × F^I)/2 (docs/theory/rings.md#friction-torque-and-power-loss), the inner wall
        torque of
        :func:`frbmodel.physics.film.film_torques_kernel`.
    """
    eps = math.sqrt(rx * rx + ry * ry) / inner_geom[2]
    s = min(1.0, eps_cap / eps) if eps > 0 else 1.0
    t_journal, _ = film_torques_kernel(inner_geom[0], inner_geom[1], inner_geom[2], inner_geom[3], rx * s, ry * s,
                                       fx, fy, omega_rotor, omega_ring)
    return t_journal


@njit(cache=True)
def bearing_loss_kernel(geom, polys, jx, jy, jvx, jvy, ring, omega_rotor, eps_cap):
    """Journal torque and friction power of one floating-ring bearing in one state (the one implementation).

    Parameters
    ----------
    geom : ndarray (2, 4)
        [R, L, c, μ] of the inner and outer film (:func:`film_arrays`).
    polys : ndarray (2, 2, 5)
        Correction polynomials (:func:`film_arrays`).
    jx, jy, jvx, jvy : float
        Journal centre [m] and velocity [m/s] relative to the housing.
    ring : ndarray (5,)
        Ring centre x, y [m], velocity vx, vy [m/s], spin speed ω_FR [rad/s].
    omega_rotor : float
        Rotor (journal) spin speed ω_R [rad/s].
    eps_cap : float
        Positions beyond this ε are evaluated at it (as in the run-up's right-hand side); ``inf`` for none (then
        a film at ε >= 1 gives NaN).

    Returns
    -------
    t_journal : float
        Inner-film torque on the journal about +z [N m].
    p_inner, p_outer : float
        Friction power of the inner and the outer film [W] (see the module docstring).
    """
    wfr = ring[4]
    rix, riy = jx - ring[0], jy - ring[1]
    vix, viy = jvx - ring[2], jvy - ring[3]
    g = geom[0]
    fix, fiy, ei = film_force_kernel(g[0], g[1], g[2], g[3], polys[0, 0], polys[0, 1], rix, riy, vix, viy,
                                     omega_rotor + wfr, eps_cap)
    g = geom[1]
    fox, foy, eo = film_force_kernel(g[0], g[1], g[2], g[3], polys[1, 0], polys[1, 1], ring[0], ring[1], ring[2],
                                     ring[3], wfr, eps_cap)
    if math.isnan(fix) or math.isnan(fox):  # a member at or beyond its wall (no cap): no film
        return math.nan, math.nan, math.nan
    si = min(1.0, eps_cap / ei) if ei > 0 else 1.0  # positions capped like the forces (as ring_rhs_kernel)
    so = min(1.0, eps_cap / eo) if eo > 0 else 1.0
    t_journal, t_ring_inner = film_torques_kernel(geom[0, 0], geom[0, 1], geom[0, 2], geom[0, 3], rix * si,
                                                  riy * si, fix, fiy, omega_rotor, wfr)
    t_ring_outer, _ = film_torques_kernel(g[0], g[1], g[2], g[3], ring[0] * so, ring[1] * so, fox, foy, wfr, 0.0)
    p_inner = -(t_journal * omega_rotor + t_ring_inner * wfr + fix * vix + fiy * viy)
    p_outer = -(t_ring_outer * wfr + fox * ring[2] + foy * ring[3])
    return t_journal, p_inner, p_outer


@njit(cache=True)
def _loss_loop(geom, polys, journal, ring, omega_rotor, eps_cap, out):
    for k in range(journal.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = bearing_loss_kernel(geom, polys, journal[k, 0], journal[k, 1],
                                                              journal[k, 2], journal[k, 3], ring[k], omega_rotor[k],
                                                              eps_cap)


def bearing_loss(bearing, journal, ring, omega_rotor, film_model="short"):
    """Journal torque and friction power of a floating-ring bearing for given states (vectorised).

    Parameters
    ----------
    bearing : FloatingRingBearing
        The bearing.
    journal : array_like (..., 4)
        Journal x, y [m] and vx, vy [m/s] relative to the housing.
    ring : array_like (..., 5)
        Ring x, y [m], vx, vy [m/s] and spin speed ω_FR [rad/s].
    omega_rotor : float or array_like (...)
        Rotor speed ω_R [rad/s].
    film_model : {"short", "short_corrected"}
        Film model.

    Returns
    -------
    journal_torque : ndarray (...)
        Inner-film torque on the journal about +z [N m] (negative: braking).
    power_inner, power_outer : ndarray (...)
        Friction power of the inner and outer film [W]; their sum is the bearing's power loss.

    Raises
    ------
    ParameterError
        Non-finite input or a member at or beyond its wall (ε >= 1).

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> t, p_i, p_o = bearing_loss(b, [0, 0, 0, 0], [0, 0, 0, 0, 2000.0], 10000.0)
    >>> bool(t < 0 and p_i > 0 and p_o > 0)
    True
    """
    check_bearing(bearing)
    journal = np.asarray(journal, dtype=float)
    ring = np.asarray(ring, dtype=float)
    if journal.shape[-1:] != (4,) or ring.shape[-1:] != (5,):
        raise ParameterError(f"journal must have shape (..., 4) and ring (..., 5); got {journal.shape} and "
                             f"{ring.shape}")
    shape = np.broadcast_shapes(journal.shape[:-1], ring.shape[:-1], np.shape(omega_rotor))
    j = np.ascontiguousarray(np.broadcast_to(journal, shape + (4,)).reshape(-1, 4))
    r = np.ascontiguousarray(np.broadcast_to(ring, shape + (5,)).reshape(-1, 5))
    w = np.ascontiguousarray(np.broadcast_to(np.asarray(omega_rotor, dtype=float), shape).reshape(-1))
    if not (np.isfinite(j).all() and np.isfinite(r).all() and np.isfinite(w).all()):
        raise ParameterError("bearing_loss: journal, ring and rotor speed must be finite")
    geom, polys = film_arrays(bearing, film_model)
    out = np.empty((j.shape[0], 3))
    _loss_loop(geom, polys, j, r, w, math.inf, out)
    if not np.isfinite(out).all():
        raise ParameterError(f"{bearing.name} bearing: a film eccentricity ratio is >= 1 (a member at its wall); "
                             "valid range 0 <= eps < 1")
    return tuple(out[:, k].reshape(shape) for k in range(3))
