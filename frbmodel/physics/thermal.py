"""Lumped thermal balance of one floating-ring bearing: oil flows through the two films and the steady film and ring
temperatures (docs/theory/thermal.md).

A lumped model of the kind of San Andrés & Kerth (2004, "Thermal effects on the performance of floating ring
bearings for turbochargers", Proc. IMechE Part J 218): each film has one effective temperature, heated by
its friction power (:func:`frbmodel.physics.losses.bearing_loss`) and cooled by the oil flowing through it and by the
heat it exchanges with the ring (and, optionally, with the shaft or the housing). The equations here are written for
this project from the energy balance; they are not a transcription of the paper's, whose coefficients are not
reproduced. Simplifications (each stated in the theory page): the ring is one temperature (its wall conducts much
better than the films), the oil enters both films at the supply temperature, the side flow of the π-film and the
supply-pressure flow are superposed, and the viscosity of each film is uniform at its effective temperature.

The operating point over speed (the fixed point temperatures → viscosities → equilibrium → powers → temperatures) is
:func:`frbmodel.linear.thermal.thermal_losses`.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..core.errors import ParameterError, check_real

__all__ = ["ThermalModel", "bearing_flows", "check_feed_holes", "film_temperatures", "heat_flows", "pressure_flow",
           "ring_wall_m", "side_flow"]


#: the loosest accepted convergence of the film temperatures [K] (ThermalModel.tolerance_K)
MAX_TOLERANCE_K = 1e-3


@dataclass(frozen=True)
class ThermalModel:
    """Coefficients of the lumped thermal balance (docs/theory/thermal.md#coefficients-and-defaults).

    Parameters
    ----------
    mixing : float
        κ [-], 0 < κ <= 1: the effective film temperature T_f = T_in + κ (T_out − T_in). Default 0.5: the mean of
        inlet and outlet, the usual engineering choice of an effective film temperature; κ = 1 is a fully mixed film
        (the film at its outlet temperature).
    oil_conductivity_W_mK : float
        Thermal conductivity of the oil k [W/(m K)]. Default 0.13, typical of mineral and synthetic oils
        (0.12 ... 0.14 at 40 ... 150 °C).
    film_nusselt : float
        Nu [-] of the film-to-ring heat transfer, h = Nu k / c (c the film's clearance). Default 2: conduction across
        half the gap, from the film's mid-plane at T_f to the wall (laminar Couette flow, no convection across the
        gap). 0 switches the exchange through the ring off.
    shaft_heat_transfer_W_m2K, housing_heat_transfer_W_m2K : float
        h [W/(m² K)] from the inner film to the journal and from the outer film to the housing, over the film areas.
        Default 0 (off): the walls are adiabatic, because the shaft's and the housing's temperatures are not known for
        the Table 2 turbocharger (a hot turbine-side shaft heats the inner film; give both coefficient and temperature
        to model it).
    shaft_temperature_K, housing_temperature_K : float or None
        Wall temperatures [K] of those paths; None = the supply temperature (given, they need their path's
        coefficient > 0).
    feed_holes : int
        Number of radial feed holes through the ring that feed the inner film. Default 4 (a typical count for
        automotive rings; not given in Table 2).
    feed_hole_diameter_m : float
        Their diameter [m]. Default 1.5e-3 (a typical size; not given in Table 2).
    centrifugal_feed : bool
        Subtract the centrifugal pressure ρ ω_FR² (R_O² − R_I²)/2 the spinning ring's holes build up against the
        inward flow. Default True.
    tolerance_K : float
        Convergence of the film temperatures of the fixed point [K], 0 < tolerance_K <= 1e-3. Default 1e-9.
    max_evaluations : int
        Most evaluations (equilibrium + balance) of the fixed point per bearing and speed. Default 200.
    ring_heat_capacity_J_K : float or None
        m_R c_R [J/K] of each ring, for run-ups with the ring temperature as a state (the films' oil is renewed in
        milliseconds and stays quasi-static; docs/theory/thermal.md#run-ups). Default None: the ring quasi-static
        too. Steady analyses (equilibria, Campbell, Hopf points, limit cycles) are the long-time limit and do not
        depend on it.

    Examples
    --------
    >>> ThermalModel().mixing
    0.5
    >>> try:
    ...     ThermalModel(mixing=0.0)
    ... except ParameterError as exc:
    ...     print(exc)
    thermal model mixing = 0.0 is invalid: valid range 0 < mixing <= 1
    """

    mixing: float = 0.5
    oil_conductivity_W_mK: float = 0.13
    film_nusselt: float = 2.0
    shaft_heat_transfer_W_m2K: float = 0.0
    housing_heat_transfer_W_m2K: float = 0.0
    shaft_temperature_K: float = None
    housing_temperature_K: float = None
    feed_holes: int = 4
    feed_hole_diameter_m: float = 1.5e-3
    centrifugal_feed: bool = True
    tolerance_K: float = 1e-9
    max_evaluations: int = 200
    ring_heat_capacity_J_K: float = None

    def __post_init__(self):
        m = check_real("thermal model mixing", self.mixing, "")
        if not 0.0 < m <= 1.0:
            raise ParameterError(f"thermal model mixing = {self.mixing!r} is invalid: valid range 0 < mixing <= 1")
        for name, unit, strict in (("oil_conductivity_W_mK", "W/(m K)", True), ("film_nusselt", "", False),
                                   ("shaft_heat_transfer_W_m2K", "W/(m^2 K)", False),
                                   ("housing_heat_transfer_W_m2K", "W/(m^2 K)", False),
                                   ("feed_hole_diameter_m", "m", True), ("tolerance_K", "K", True)):
            object.__setattr__(self, name, check_real(f"thermal model {name}", getattr(self, name), unit,
                                                      minimum=0.0, inclusive=not strict))
        if self.ring_heat_capacity_J_K is not None:
            object.__setattr__(self, "ring_heat_capacity_J_K", check_real(
                "thermal model ring_heat_capacity_J_K", self.ring_heat_capacity_J_K, "J/K", minimum=0.0,
                inclusive=False))
        for name, h in (("shaft_temperature_K", "shaft_heat_transfer_W_m2K"),
                        ("housing_temperature_K", "housing_heat_transfer_W_m2K")):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_real(f"thermal model {name}", getattr(self, name), "K",
                                                          minimum=0.0))
                if getattr(self, h) == 0.0:  # (it was ignored: the path is off)
                    raise ParameterError(f"thermal model {name} = {getattr(self, name)!r} K has no effect with {h} "
                                         "= 0 (the path is off): give both, or leave the temperature out")
        if self.tolerance_K > MAX_TOLERANCE_K:
            raise ParameterError(f"thermal model tolerance_K = {self.tolerance_K!r} K is invalid: valid range "
                                 f"0 < tolerance_K <= {MAX_TOLERANCE_K:g} K (a looser one accepts an operating point "
                                 "whose film temperatures are not converged)")
        if not isinstance(self.centrifugal_feed, (bool, np.bool_)):
            raise ParameterError(f"thermal model centrifugal_feed = {self.centrifugal_feed!r} is a "
                                 f"{type(self.centrifugal_feed).__name__}; expected True or False")
        for name, lo in (("feed_holes", 0), ("max_evaluations", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise ParameterError(f"thermal model {name} = {v!r} is invalid: valid range integer >= {lo}")
        object.__setattr__(self, "mixing", m)

    def to_dict(self) -> dict:
        """The coefficients as plain data (SI, the field names)."""
        return asdict(self)


def side_flow(film, eps, omega_sum):
    """Side (axial) flow of the static short π-film out of both ends, Q_s = ε ω_s R c L [m³/s]
    (docs/theory/thermal.md#side-flow-of-the-short-film).

    Parameters
    ----------
    film : Film
        Radius R, length L, clearance c [m].
    eps : float
        Eccentricity ratio [-].
    omega_sum : float
        Sum of the wall speeds ω_s [rad/s] (inner film ω_R + ω_FR, outer film ω_FR).

    Examples
    --------
    >>> from frbmodel.system.films import Film
    >>> round(side_flow(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3), 0.1, 1e4) * 1e6, 6)   # [cm³/s]
    1.2155
    """
    return abs(eps * omega_sum) * film.radius * film.clearance * film.length


def pressure_flow(film, eps, pressure_Pa):
    """Axial Poiseuille flow of a film fed at mid-length (a circumferential groove) at ``pressure_Pa`` above the
    ambient pressure at both ends, Q_p = 2π R c³ (1 + 1.5 ε²) p / (3 μ L) [m³/s], μ the film's viscosity.

    Examples
    --------
    >>> from frbmodel.system.films import Film
    >>> round(pressure_flow(Film(8e-3, 9e-3, 36e-6, 4.9e-3), 0.0, 3e5) * 1e6, 4)   # [cm³/s]
    5.3179
    """
    return (2.0 * math.pi * film.radius * film.clearance ** 3 * (1.0 + 1.5 * eps * eps) * pressure_Pa
            / (3.0 * film.viscosity * film.length))


def ring_wall_m(bearing):
    """Wall thickness of the ring [m], R_O − R_I − c_I: the length of its feed holes."""
    return bearing.outer.radius - bearing.inner.radius - bearing.inner.clearance


def check_feed_holes(bearing, model):
    """Refuse feed holes of the thermal ``model`` that do not fit the ring of ``bearing``: a diameter not below its
    wall thickness (:func:`ring_wall_m`; the holes' Poiseuille resistance assumes a tube longer than wide) or more
    holes than fit side by side around the inner film (a 1 m hole was taken: the inner film flooded at the supply
    temperature). Called where an oil supply meets the system, before any work
    (:func:`frbmodel.linear.thermal.check_oil_supply`), not inside the balance (:func:`bearing_flows`).

    Examples
    --------
    >>> from frbmodel.system.presets import turbocharger
    >>> try:
    ...     check_feed_holes(turbocharger().bearings[0], ThermalModel(feed_hole_diameter_m=1.0))
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    thermal model feed_hole_diameter_m = 1 m is invalid for the turbine bearing's ring: valid range < its wall ...
    """
    d, n, wall_m = model.feed_hole_diameter_m, model.feed_holes, ring_wall_m(bearing)
    if n > 0 and not d < wall_m:
        raise ParameterError(f"thermal model feed_hole_diameter_m = {d:g} m is invalid for the {bearing.name} "
                             f"bearing's ring: valid range < its wall thickness {wall_m:g} m (the holes' length)")
    if n > 0 and n * d >= 2.0 * math.pi * bearing.inner.radius:
        raise ParameterError(f"thermal model feed_holes = {n} of {d:g} m do not fit around the {bearing.name} "
                             f"bearing's ring: valid range feed_holes x feed_hole_diameter_m < 2 pi R_I = "
                             f"{2.0 * math.pi * bearing.inner.radius:g} m")


def bearing_flows(bearing, eps_inner, eps_outer, rotor_speed, ring_speed, supply_pressure_Pa, density_kg_m3,
                  hole_viscosity_Pa_s, model):
    """Oil flows through the two films of one bearing at a static state.

    The outer film is fed from the housing's groove at the supply pressure; the inner film through the ring's
    feed holes (laminar Poiseuille resistance 128 μ ℓ / (π n d⁴), ℓ the ring's wall thickness) in series with the
    inner film's own axial resistance, against the holes' centrifugal pressure if ``model.centrifugal_feed``. Each
    film's total flow adds its side flow (:func:`side_flow`).

    Parameters
    ----------
    bearing : FloatingRingBearing
        With the films' viscosities at their temperatures.
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and the outer film at the static state [-].
    rotor_speed, ring_speed : float
        ω_R and ω_FR [rad/s].
    supply_pressure_Pa : float
        Oil supply pressure above ambient [Pa].
    density_kg_m3 : float
        Oil density in the feed holes [kg/m³] (for the centrifugal pressure).
    hole_viscosity_Pa_s : float
        Oil viscosity in the feed holes [Pa s].
    model : ThermalModel

    Returns
    -------
    dict
        ``side_inner``, ``feed_inner``, ``side_outer``, ``supply_outer`` [m³/s] and ``feed_pressure`` [Pa] (the
        pressure driving the inner feed; <= 0: the holes deliver nothing beyond the side flow).
    """
    inner, outer = bearing.inner, bearing.outer
    wall = ring_wall_m(bearing)  # (the holes fit the ring: check_feed_holes ran when the inputs were validated)
    p_feed = supply_pressure_Pa
    if model.centrifugal_feed:
        p_feed -= 0.5 * density_kg_m3 * ring_speed ** 2 * (outer.radius ** 2 - inner.radius ** 2)
    feed = 0.0
    if p_feed > 0.0 and model.feed_holes > 0 and model.feed_hole_diameter_m > 0.0:
        r_holes = 128.0 * hole_viscosity_Pa_s * wall / (math.pi * model.feed_holes * model.feed_hole_diameter_m ** 4)
        r_film = p_feed / pressure_flow(inner, eps_inner, p_feed)
        feed = p_feed / (r_holes + r_film)
    return {"side_inner": side_flow(inner, eps_inner, rotor_speed + ring_speed), "feed_inner": feed,
            "side_outer": side_flow(outer, eps_outer, ring_speed),
            "supply_outer": pressure_flow(outer, eps_outer, supply_pressure_Pa), "feed_pressure": p_feed}


def _conductances(bearing, model, capacity_inner, capacity_outer):
    """Thermal conductances [W/K]: oil (ρ c_p Q / κ), film–ring, film–shaft, film–housing of both films."""
    a_i = 2.0 * math.pi * bearing.inner.radius * bearing.inner.length
    a_o = 2.0 * math.pi * bearing.outer.radius * bearing.outer.length
    k_nu = model.film_nusselt * model.oil_conductivity_W_mK
    return {"oil_inner": capacity_inner / model.mixing, "oil_outer": capacity_outer / model.mixing,
            "ring_inner": k_nu / bearing.inner.clearance * a_i, "ring_outer": k_nu / bearing.outer.clearance * a_o,
            "shaft": model.shaft_heat_transfer_W_m2K * a_i, "housing": model.housing_heat_transfer_W_m2K * a_o}


def film_temperatures(bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K, capacity_outer_W_K,
                      supply_temperature_K):
    """Steady effective temperatures of the inner film, the outer film and the ring for given powers and flows
    (a linear 3 × 3 balance, docs/theory/thermal.md#energy-balance).

    Parameters
    ----------
    bearing : FloatingRingBearing
        Geometry (film areas and clearances).
    model : ThermalModel
    power_inner_W, power_outer_W : float
        Friction power of the films [W].
    capacity_inner_W_K, capacity_outer_W_K : float
        Heat capacity flow ρ c_p Q of the oil through each film [W/K].
    supply_temperature_K : float
        Oil inlet temperature of both films [K].

    Returns
    -------
    T_inner, T_outer, T_ring : float
        [K]; T_ring is NaN when the ring exchanges no heat (``model.film_nusselt = 0``).

    Raises
    ------
    ParameterError
        A film with power but no heat sink (no flow, no exchange): its temperature has no steady value.

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> [round(t, 9) for t in film_temperatures(b, ThermalModel(), 0.0, 0.0, 2.0, 3.0, 363.15)]   # no power
    [363.15, 363.15, 363.15]
    """
    g, d_i, d_o, b_i, b_o = _film_balances(bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K,
                                           capacity_outer_W_K, supply_temperature_K)
    g_r = g["ring_inner"] + g["ring_outer"]
    if g_r == 0.0:  # the ring is uncoupled: two independent films
        if d_i == 0.0 or d_o == 0.0:
            raise ParameterError(f"{bearing.name} bearing: a film has no heat sink (no oil flow, no exchange)")
        return b_i / d_i, b_o / d_o, math.nan
    # eliminate the ring: T_R = (G_I T_I + G_O T_O) / (G_I + G_O)
    a = np.array([[d_i - g["ring_inner"] ** 2 / g_r, -g["ring_inner"] * g["ring_outer"] / g_r],
                  [-g["ring_inner"] * g["ring_outer"] / g_r, d_o - g["ring_outer"] ** 2 / g_r]])
    if abs(np.linalg.det(a)) <= 1e-300:
        raise ParameterError(f"{bearing.name} bearing: the films have no heat sink (no oil flow, no wall path)")
    t_i, t_o = np.linalg.solve(a, [b_i, b_o])
    return float(t_i), float(t_o), float((g["ring_inner"] * t_i + g["ring_outer"] * t_o) / g_r)


def _film_balances(bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K, capacity_outer_W_K,
                   supply_temperature_K):
    """The conductances and each film's balance d T_f = b + G_Rf T_R without the ring term: (g, d_i, d_o, b_i, b_o)."""
    g = _conductances(bearing, model, capacity_inner_W_K, capacity_outer_W_K)
    t_s = supply_temperature_K
    t_j = t_s if model.shaft_temperature_K is None else model.shaft_temperature_K
    t_h = t_s if model.housing_temperature_K is None else model.housing_temperature_K
    d_i = g["oil_inner"] + g["ring_inner"] + g["shaft"]
    d_o = g["oil_outer"] + g["ring_outer"] + g["housing"]
    b_i = power_inner_W + g["oil_inner"] * t_s + g["shaft"] * t_j
    b_o = power_outer_W + g["oil_outer"] * t_s + g["housing"] * t_h
    return g, d_i, d_o, b_i, b_o


def films_at_ring_temperature(bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K, capacity_outer_W_K,
                              supply_temperature_K, ring_temperature_K):
    """Film temperatures in steady balance with the ring at a given temperature, and the net heat into the ring:
    the fast part of the balance when the ring's temperature is a state (m_R c_R dT_R/dt = that heat).

    Parameters
    ----------
    bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K, capacity_outer_W_K, supply_temperature_K
        As :func:`film_temperatures`.
    ring_temperature_K : float
        T_R [K].

    Returns
    -------
    T_inner, T_outer : float
        [K].
    ring_heat_W : float
        G_RI (T_I − T_R) + G_RO (T_O − T_R) [W]; zero at the steady ring temperature of :func:`film_temperatures`.

    Examples
    --------
    >>> import frbmodel as frb
    >>> b = frb.turbocharger().bearings[0]
    >>> t = film_temperatures(b, ThermalModel(), 20.0, 10.0, 2.0, 3.0, 363.15)
    >>> t_i, t_o, q = films_at_ring_temperature(b, ThermalModel(), 20.0, 10.0, 2.0, 3.0, 363.15, t[2])
    >>> bool(abs(t_i - t[0]) < 1e-9 and abs(q) < 1e-9)
    True
    """
    g, d_i, d_o, b_i, b_o = _film_balances(bearing, model, power_inner_W, power_outer_W, capacity_inner_W_K,
                                           capacity_outer_W_K, supply_temperature_K)
    if d_i == 0.0 or d_o == 0.0:
        raise ParameterError(f"{bearing.name} bearing: a film has no heat sink (no oil flow, no exchange)")
    t_r = float(ring_temperature_K)
    t_i = (b_i + g["ring_inner"] * t_r) / d_i
    t_o = (b_o + g["ring_outer"] * t_r) / d_o
    return float(t_i), float(t_o), float(g["ring_inner"] * (t_i - t_r) + g["ring_outer"] * (t_o - t_r))


def heat_flows(bearing, model, temperatures_K, capacity_inner_W_K, capacity_outer_W_K, supply_temperature_K):
    """Heat flows [W] at given temperatures, for the energy balance and the tables.

    Returns
    -------
    dict
        ``oil_inner``, ``oil_outer`` (heat carried away by the oil, ρ c_p Q (T_out − T_in)), ``inner_to_ring``,
        ``ring_to_outer``, ``shaft`` (inner film → journal), ``housing`` (outer film → housing).
    """
    t_i, t_o, t_r = temperatures_K
    g = _conductances(bearing, model, capacity_inner_W_K, capacity_outer_W_K)
    t_s = supply_temperature_K
    t_j = t_s if model.shaft_temperature_K is None else model.shaft_temperature_K
    t_h = t_s if model.housing_temperature_K is None else model.housing_temperature_K
    coupled = not math.isnan(t_r)
    return {"oil_inner": g["oil_inner"] * (t_i - t_s), "oil_outer": g["oil_outer"] * (t_o - t_s),
            "inner_to_ring": g["ring_inner"] * (t_i - t_r) if coupled else 0.0,
            "ring_to_outer": g["ring_outer"] * (t_r - t_o) if coupled else 0.0,
            "shaft": g["shaft"] * (t_i - t_j), "housing": g["housing"] * (t_o - t_h)}
