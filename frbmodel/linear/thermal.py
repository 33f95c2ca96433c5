"""Thermo-hydrodynamic operating point of the floating-ring bearings over speed (docs/theory/thermal.md).

Per bearing and speed, the fixed point film temperatures → viscosities μ(T) of the oil → method-J equilibrium
(ring speed, eccentricities) → friction powers (:func:`frbmodel.linear.losses.equilibrium_loss`) and oil flows
(:func:`frbmodel.physics.thermal.bearing_flows`) → temperatures (:func:`frbmodel.physics.thermal.film_temperatures`)
is solved for the two film temperatures with a Newton-type root (MINPACK hybr). :func:`thermal_system` returns the
Turbocharger with its film viscosities at those temperatures; :class:`OilSupply` (oil, supply temperature and
pressure, coefficients) is the one option by which the Campbell diagram and the film whirl onsets take the thermal
model (``oil_supply=``), each speed at its own operating point (stage 2 of issue #25).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..core.errors import ConvergenceError, ParameterError, check_real, check_real_array, check_speed, check_system
from ..core.units import RPM
from ..physics.thermal import (
    ThermalModel,
    bearing_flows,
    check_feed_holes,
    film_temperatures,
    films_at_ring_temperature,
    heat_flows,
)
from ..system.methods import get_method
from ..system.oil import T_MIN_K, Oil, check_temperature
from ..system.rotor import GRAVITY
from .equilibrium import bearing_equilibrium
from .losses import bearing_losses, equilibrium_loss, with_ring_speed_ratio

__all__ = ["MAX_SUPPLY_PRESSURE_PA", "OilSupply", "at_operating_point", "bearing_operating_point", "thermal_bearing",
           "thermal_losses", "thermal_system"]

#: the highest oil supply pressure accepted [Pa] (gauge): 20 bar; turbocharger oil circuits run at 1 ... 6 bar
MAX_SUPPLY_PRESSURE_PA = 2e6
#: default supply pressure [Pa] (gauge): 3 bar, a typical engine oil-gallery pressure at speed
SUPPLY_PRESSURE_PA = 3e5


def check_supply_pressure(name, pressure_Pa):
    """``float(pressure_Pa)`` if 0 <= p <= :data:`MAX_SUPPLY_PRESSURE_PA`, else a :class:`ParameterError`."""
    p = check_real(name, pressure_Pa, "Pa")
    if not 0.0 <= p <= MAX_SUPPLY_PRESSURE_PA:
        raise ParameterError(f"{name} = {pressure_Pa!r} Pa is invalid: valid range 0 ... {MAX_SUPPLY_PRESSURE_PA:g} "
                             "Pa (gauge; 1 bar = 1e5 Pa)")
    return p


@dataclass(frozen=True)
class OilSupply:
    """The oil and its supply state: what an analysis needs to put every film at its thermal operating point
    (:func:`thermal_losses`) at each rotor speed.

    Parameters
    ----------
    oil : Oil
        The lubricant (:data:`frbmodel.OILS` or an :class:`~frbmodel.system.oil.Oil` of datasheet values).
    supply_temperature_K : float
        Oil supply (inlet) temperature [K], 243.15 ... the oil's upper limit. Default 363.15 (90 °C).
    supply_pressure_Pa : float
        Supply pressure above ambient [Pa], 0 ... 2e6. Default 3e5.
    model : ThermalModel, optional
        Coefficients of the balance; default :class:`ThermalModel()`.

    Examples
    --------
    >>> import frbmodel as frb
    >>> OilSupply(frb.OILS["SAE 5W-30"], 333.15).supply_pressure_Pa
    300000.0
    >>> try:
    ...     OilSupply(frb.OILS["SAE 5W-30"], 90.0)
    ... except ParameterError as exc:
    ...     print(exc)
    supply_temperature_K = 90.0 K is invalid: valid range 243.15 ... 473.15 K (-30 ... 200 °C); temperatures are in K
    """

    oil: Oil
    supply_temperature_K: float = 363.15
    supply_pressure_Pa: float = SUPPLY_PRESSURE_PA
    model: ThermalModel = None

    def __post_init__(self):
        if not isinstance(self.oil, Oil):
            raise ParameterError(f"oil = {self.oil!r:.60} is a {type(self.oil).__name__}; expected an Oil "
                                 "(frbmodel.OILS[name])")
        model = ThermalModel() if self.model is None else self.model
        if not isinstance(model, ThermalModel):
            raise ParameterError(f"model = {model!r:.60} is a {type(model).__name__}; expected a ThermalModel")
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "supply_temperature_K", check_temperature(
            "supply_temperature_K", self.supply_temperature_K, T_MIN_K, self.oil.max_temperature_K))
        object.__setattr__(self, "supply_pressure_Pa", check_supply_pressure("supply_pressure_Pa",
                                                                             self.supply_pressure_Pa))

    def to_dict(self) -> dict:
        """Plain data for a result's metadata: the oil, the supply temperature [K] and pressure [Pa], the model."""
        return {"oil": self.oil.to_dict(), "supply_temperature_K": self.supply_temperature_K,
                "supply_pressure_Pa": self.supply_pressure_Pa, "model": self.model.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> "OilSupply":
        """Inverse of :meth:`to_dict` (a result's ``meta["oil_supply"]``): the oil, supply temperature [K] and
        pressure [Pa], the model's coefficients."""
        keys = ("oil", "supply_temperature_K", "supply_pressure_Pa", "model")
        if not isinstance(d, dict) or set(d) != set(keys) or not isinstance(d["model"], dict):
            raise ParameterError(f"oil_supply = {d!r:.80} is invalid: expected a table with the keys "
                                 f"{', '.join(keys)} (OilSupply.to_dict; model a table of ThermalModel fields)")
        unknown = [k for k in d["model"] if k not in ThermalModel.__dataclass_fields__]
        if unknown:
            raise ParameterError(f"oil_supply model: unknown key {unknown[0]!r}; valid keys: "
                                 f"{', '.join(ThermalModel.__dataclass_fields__)}")
        return cls(Oil.from_dict(d["oil"], "oil_supply oil"), d["supply_temperature_K"], d["supply_pressure_Pa"],
                   ThermalModel(**d["model"]))


def check_oil_supply(oil_supply, method="J", bearings=()):
    """``oil_supply`` if it is None or an :class:`OilSupply` used with a film method (C, D, F, G, I, J: the
    thermal operating point is solved with that method's own equilibrium) whose thermal model's feed holes fit the
    rings of ``bearings`` (:func:`frbmodel.physics.thermal.check_feed_holes`; every analysis passes its system's
    bearings, so the check runs before any work), else a :class:`ParameterError` (the spring methods A, B, E have no
    films)."""
    if oil_supply is None:
        return None
    if not isinstance(oil_supply, OilSupply):
        raise ParameterError(f"oil_supply = {oil_supply!r:.60} is a {type(oil_supply).__name__}; expected an "
                             "OilSupply(oil, supply_temperature_K, supply_pressure_Pa) or None")
    if not get_method(method).needs_films:
        raise ParameterError(f"method = {method!r} cannot be combined with an oil supply: its bearings are linear "
                             "springs without oil films; use a film method (C, D, F, G, I, J)")
    for b in bearings:
        check_feed_holes(b, oil_supply.model)
    return oil_supply


def _with_viscosities(bearing, mu_inner, mu_outer):
    return replace(bearing, inner=replace(bearing.inner, viscosity=mu_inner),
                   outer=replace(bearing.outer, viscosity=mu_outer))


def _state(bearing, load, omega, oil, t_s, p_s, model, film_model, gravity, temps, t_ring=None, method="J"):
    """Everything at film temperatures ``temps`` (clipped into the oil's range while the solver searches); with
    ``t_ring`` [K] the ring is held there (its temperature a state) and ``ring_heat`` [W] is the heat into it."""
    t_i, t_o = (min(max(float(t), T_MIN_K), oil.max_temperature_K) for t in temps)
    b = _with_viscosities(bearing, oil.dynamic_viscosity(t_i), oil.dynamic_viscosity(t_o))
    eq = bearing_equilibrium(b, load, omega, method, film_model, gravity)
    t_j, p_i, p_o = (float(v) for v in equilibrium_loss(b, eq, omega, film_model))
    flows = bearing_flows(b, eq.eps_inner, eq.eps_outer, omega, eq.ring_speed, p_s, oil.density(t_s),
                          oil.dynamic_viscosity(t_s), model)
    q_i, q_o = flows["side_inner"] + flows["feed_inner"], flows["side_outer"] + flows["supply_outer"]
    cap_i = oil.density(t_i) * oil.specific_heat_J_kgK * q_i
    cap_o = oil.density(t_o) * oil.specific_heat_J_kgK * q_o
    ring_heat = 0.0
    if t_ring is None:
        new = film_temperatures(b, model, p_i, p_o, cap_i, cap_o, t_s)
    else:
        *films, ring_heat = films_at_ring_temperature(b, model, p_i, p_o, cap_i, cap_o, t_s, t_ring)
        new = (*films, float(t_ring))
    return {"bearing": b, "eq": eq, "torque": t_j, "powers": (p_i, p_o), "flows": flows, "q": (q_i, q_o),
            "capacities": (cap_i, cap_o), "temperatures": new, "ring_heat": ring_heat, "method": method}


def _operating_point(bearing, load, omega, oil, t_s, p_s, model, film_model, gravity, t_ring=None, method="J"):
    """Converged state of one bearing (see :func:`thermal_losses`), with iterations and residual; with ``t_ring``
    the films' balance with the ring held at that temperature [K]."""
    from scipy.optimize import root

    count = {"n": 0}

    def residual(x):
        count["n"] += 1
        s = _state(bearing, load, omega, oil, t_s, p_s, model, film_model, gravity, x, t_ring, method)
        return np.array(s["temperatures"][:2]) - x

    sol = root(residual, np.array([t_s, t_s]), method="hybr",
               options={"xtol": 1e-13, "maxfev": model.max_evaluations})
    res = float(np.max(np.abs(sol.fun)))
    rpm = omega / RPM
    if not res <= model.tolerance_K:
        raise ConvergenceError(f"thermal operating point of the {bearing.name} bearing at {rpm:.0f} rpm, supply "
                               f"{t_s:g} K did not converge: film-temperature residual {res:.3g} K > tolerance "
                               f"{model.tolerance_K:g} K after {count['n']} evaluations ({sol.message})")
    for name, t in zip(("inner", "outer"), sol.x):
        try:
            check_temperature(f"{bearing.name} {name} film temperature at {rpm:.0f} rpm (supply {t_s:g} K)", t,
                              T_MIN_K, oil.max_temperature_K)
        except ParameterError as exc:
            raise ParameterError(f"{exc}: beyond the oil's viscosity law, the oil flow cannot carry the film's "
                                 f"friction power (supply pressure {p_s:g} Pa; raise it, or the feed holes of the "
                                 "ThermalModel)") from None
    s = _state(bearing, load, omega, oil, t_s, p_s, model, film_model, gravity, sol.x, t_ring, method)
    s.update(iterations=count["n"], residual_K=res)
    return s


def _row(rpm, t_s, p_s, oil, model, s):
    """One table row (units in every column) of a converged state ``s``."""
    b, eq, (p_i, p_o), f, (q_i, q_o) = s["bearing"], s["eq"], s["powers"], s["flows"], s["q"]
    t_i, t_o, t_r = s["temperatures"]
    h = heat_flows(b, model, s["temperatures"], *s["capacities"], t_s)
    closure = p_i + p_o - (h["oil_inner"] + h["oil_outer"] + h["shaft"] + h["housing"])
    return {"speed [rpm]": rpm, "bearing": b.name, "supply temperature [K]": t_s, "supply pressure [Pa]": p_s,
            "oil": oil.name, "inner film temperature [K]": t_i, "outer film temperature [K]": t_o,
            "ring temperature [K]": t_r,
            "inner outlet temperature [K]": t_s + (t_i - t_s) / model.mixing,
            "outer outlet temperature [K]": t_s + (t_o - t_s) / model.mixing,
            "inner viscosity [Pa s]": b.inner.viscosity, "outer viscosity [Pa s]": b.outer.viscosity,
            "ring speed [rad/s]": eq.ring_speed, "RSR [-]": eq.ring_speed_ratio,
            "eps inner [-]": eq.eps_inner, "eps outer [-]": eq.eps_outer, "journal torque [N m]": s["torque"],
            "power loss [W]": p_i + p_o, "power loss inner [W]": p_i, "power loss outer [W]": p_o,
            "inner side flow [m^3/s]": f["side_inner"], "inner feed flow [m^3/s]": f["feed_inner"],
            "outer side flow [m^3/s]": f["side_outer"], "outer supply flow [m^3/s]": f["supply_outer"],
            "inner flow [m^3/s]": q_i, "outer flow [m^3/s]": q_o, "feed pressure [Pa]": f["feed_pressure"],
            "heat to oil inner [W]": h["oil_inner"], "heat to oil outer [W]": h["oil_outer"],
            "heat inner film to ring [W]": h["inner_to_ring"], "heat ring to outer film [W]": h["ring_to_outer"],
            "heat to shaft [W]": h["shaft"], "heat to housing [W]": h["housing"],
            "energy-balance residual [W]": closure,
            "ring balance residual [W]": h["inner_to_ring"] - h["ring_to_outer"],
            "temperature residual [K]": s["residual_K"], "iterations [-]": s["iterations"], "method": s["method"]}


def _isothermal(system, speeds, method="J"):
    """Constant viscosities (no oil): :func:`bearing_losses` of ``method`` with the RSR, no temperatures."""
    return with_ring_speed_ratio(bearing_losses(system, speeds, method))


def thermal_losses(system, speed_rpm, oil=None, supply_temperature_K=None, supply_pressure_Pa=None, model=None,
                   method="J"):
    """Film and ring temperatures, viscosities, ring speed, power losses and oil flows of every bearing at the
    thermo-hydrodynamic operating point (the equilibrium of ``method`` at the films' temperatures).

    Parameters
    ----------
    system : Turbocharger
    speed_rpm : float or sequence of float
        Rotor speed(s) [rpm], 0 < speed <= 1e6.
    oil : Oil, optional
        The lubricant; None: the system's ``oil``; if that is None too, the films keep their constant viscosities
        and the result is :func:`frbmodel.linear.losses.bearing_losses` (method J) with an ``RSR [-]`` column.
    supply_temperature_K : float or sequence of float, optional
        Oil supply (inlet) temperature(s) [K], 243.15 ... the oil's upper limit (<= 473.15). Default 363.15.
    supply_pressure_Pa : float, optional
        Supply pressure above ambient [Pa], 0 ... 2e6. Default 3e5.
    model : ThermalModel, optional
        Coefficients; default :class:`ThermalModel()`. The supply and the model need an oil: without one they are
        refused (they would have no effect).
    method : {"C", "D", "F", "G", "I", "J"}
        The equilibrium (ring speed, eccentricities) the films' friction powers and flows are evaluated at: J
        balances the ring torque (default; its RSR falls with speed as the inner film heats), F/G/C/D take the RSR
        of eq. (6), which depends on the films' viscosity ratio, I that of eq. (7).

    Returns
    -------
    pandas.DataFrame
        One row per supply temperature, speed and bearing; the columns (units in every name) are those of
        ``_row``: speed, bearing, supply temperature and pressure, film, ring and outlet temperatures [K], film
        viscosities [Pa s], ring speed [rad/s], RSR [-], ε, journal torque [N m], power losses [W], flows [m³/s],
        heat flows [W], the energy-balance residual [W], the temperature residual [K] and the iterations.

    Raises
    ------
    ParameterError
        A bad speed, temperature, pressure or oil (named, with its valid range), or a film temperature beyond the
        oil's viscosity law.
    ConvergenceError
        The fixed point did not converge (the message names bearing, speed, residual and evaluations).

    Examples
    --------
    >>> import frbmodel as frb
    >>> df = thermal_losses(frb.turbocharger(), [100e3], frb.OILS["SAE 5W-30"], 363.15)
    >>> bool((df["inner film temperature [K]"] > 363.15).all())
    True
    >>> bool(abs(df["energy-balance residual [W]"]).max() < 1e-9)   # friction power = heat to oil + walls
    True
    """
    import pandas as pd

    check_system(system)
    method = get_method(method).letter
    speeds = [check_speed("speed_rpm", s) for s in _values("speed_rpm", speed_rpm, "rpm")]
    oil = system.oil if oil is None else oil
    if oil is None:
        given = [n for n, v in (("supply_temperature_K", supply_temperature_K),
                                ("supply_pressure_Pa", supply_pressure_Pa), ("model", model)) if v is not None]
        if given:  # (they were ignored: the result was the constant-viscosity one)
            raise ParameterError(f"{given[0]} needs an oil: give oil=frbmodel.OILS[name] or a system with an oil "
                                 "(without one the films keep their constant viscosities)")
        return _isothermal(system, speeds, method)
    model, temps, p_s = _thermal_inputs(system, oil, supply_temperature_K, supply_pressure_Pa, model, method)
    rows = []
    for t_s in temps:
        for rpm in speeds:
            for b, load in zip(system.bearings, system.bearing_loads):
                s = _operating_point(b, float(load), rpm * RPM, oil, t_s, p_s, model, system.film_model,
                                     system.gravity, method=method)
                rows.append(_row(rpm, t_s, p_s, oil, model, s))
    return pd.DataFrame(rows)


def _thermal_inputs(system, oil, supply_temperature_K, supply_pressure_Pa, model, method):
    """The thermal model (default :class:`ThermalModel()`), supply temperatures [K] and pressure [Pa] of
    :func:`thermal_losses` with an ``oil``, each checked before any balance — the feed holes against the system's
    rings too (they were refused inside the first balance)."""
    if not isinstance(oil, Oil):
        raise ParameterError(f"oil = {oil!r:.60} is a {type(oil).__name__}; expected an Oil (frbmodel.OILS[name])")
    if not get_method(method).needs_films:
        raise ParameterError(f"method = {method!r} has no oil films: the thermal operating point needs one of C, D, F, "
                             "G, I, J")
    model = ThermalModel() if model is None else model
    if not isinstance(model, ThermalModel):
        raise ParameterError(f"model = {model!r:.60} is a {type(model).__name__}; expected a ThermalModel")
    for b in system.bearings:
        check_feed_holes(b, model)
    p_s = check_supply_pressure("supply_pressure_Pa", SUPPLY_PRESSURE_PA if supply_pressure_Pa is None
                                else supply_pressure_Pa)
    temps = [check_temperature("supply_temperature_K", t, T_MIN_K, oil.max_temperature_K)
             for t in _values("supply_temperature_K", 363.15 if supply_temperature_K is None else
                              supply_temperature_K, "K")]
    return model, temps, p_s


def _values(name, value, unit):
    """A number or a sequence of numbers as a non-empty 1-D float array (strings refused, not converted)."""
    arr = np.atleast_1d(check_real_array(name, value, unit))
    if arr.ndim != 1 or arr.size == 0:
        raise ParameterError(f"{name} = {value!r:.60} is invalid: give one value [{unit}] or a non-empty sequence "
                             "of them")
    return arr


def thermal_bearing(bearing, load_N, speed_rpm, oil_supply, film_model="short", gravity=GRAVITY, method="J"):
    """One bearing with its films' viscosities [Pa s] at their temperatures of the thermal operating point at
    ``speed_rpm`` (the per-bearing step of :func:`thermal_system`, for searches over speed such as the film whirl
    onsets).

    Parameters
    ----------
    bearing : FloatingRingBearing
    load_N : float
        Static load of the bearing [N].
    speed_rpm : float
        Rotor speed [rpm], > 0.
    oil_supply : OilSupply
    film_model : str
    gravity : float
        The system's gravitational acceleration [m/s²].
    method : str
        The film method whose equilibrium the operating point uses (default J).

    Returns
    -------
    FloatingRingBearing
    """
    sup = check_oil_supply(oil_supply, method, (bearing,))
    s = _operating_point(bearing, float(load_N), check_speed("speed_rpm", speed_rpm) * RPM, sup.oil,
                         sup.supply_temperature_K, sup.supply_pressure_Pa, sup.model, film_model,
                         gravity, method=method)
    return s["bearing"]


def bearing_operating_point(bearing, load_N, speed_rpm, oil_supply, film_model="short", gravity=GRAVITY):
    """The thermal operating point of one bearing at one speed as one :func:`thermal_losses` row (the same
    computation: temperatures [K], viscosities [Pa s], flows [m³/s], powers [W], …), for a component that knows
    only its bearing and its static load (the split bearing FMU).

    Parameters
    ----------
    bearing : FloatingRingBearing
    load_N : float
        Static load of the bearing [N].
    speed_rpm : float
        Rotor speed [rpm], > 0.
    oil_supply : OilSupply
    film_model : str
    gravity : float
        Gravitational acceleration [m/s²].

    Returns
    -------
    dict
        The columns of :func:`thermal_losses` (units in every key).
    """
    sup = check_oil_supply(oil_supply, bearings=(bearing,))
    rpm = check_speed("speed_rpm", speed_rpm)
    s = _operating_point(bearing, float(load_N), rpm * RPM, sup.oil, sup.supply_temperature_K, sup.supply_pressure_Pa,
                         sup.model, film_model, gravity)
    return _row(rpm, sup.supply_temperature_K, sup.supply_pressure_Pa, sup.oil, sup.model, s)


def ring_lag(system, time_s, speed_rpm, oil_supply, rtol=1e-8):
    """Film and ring temperatures along a prescribed speed history with each ring's temperature as a state:
    m_R c_R dT_R/dt = G_RI (T_I − T_R) + G_RO (T_O − T_R), the films in balance with the ring at every instant
    (their oil is renewed within milliseconds) and the method-J equilibrium at the films' viscosities, as in
    :func:`thermal_losses`; the ring starts at its steady temperature of the first speed.

    Parameters
    ----------
    system : Turbocharger
    time_s, speed_rpm : array_like
        The speed history: times [s] (increasing) and rotor speeds [rpm] (> 0), linear between them.
    oil_supply : OilSupply
        Its ``model.ring_heat_capacity_J_K`` is m_R c_R [J/K] (required here).
    rtol : float
        Relative tolerance of the ring-temperature integration (scipy's LSODA: stiff when m_R c_R is small),
        1e-13 ... 1e-3.

    Returns
    -------
    time : ndarray (nt,)
        ``time_s`` [s].
    ring_K, inner_K, outer_K : ndarray (nb, nt)
        Ring, inner-film and outer-film temperatures [K] per bearing.
    viscosities : ndarray (2 nb, nt)
        Inner and outer film viscosities [Pa s] per bearing (turbine inner, outer, compressor inner, outer).
    ring_heat_W : ndarray (nb, nt)
        Net heat into each ring [W] (m_R c_R dT_R/dt).
    """
    from scipy.integrate import solve_ivp

    check_system(system)
    supply = check_oil_supply(oil_supply, bearings=system.bearings)
    if supply is None or supply.model.ring_heat_capacity_J_K is None:
        raise ParameterError("ring_lag needs an OilSupply whose model has ring_heat_capacity_J_K [J/K]")
    rtol = check_real("rtol", rtol, "", minimum=0.0)
    if not 1e-13 <= rtol <= 1e-3:  # (LSODA took 0 and -1 with a warning, and 10 changed the temperatures)
        raise ParameterError(f"rtol = {rtol!r} is invalid: valid range 1e-13 ... 1e-3")
    t = _values("time_s", time_s, "s")
    w = np.array([check_speed("speed_rpm", v) for v in _values("speed_rpm", speed_rpm, "rpm")]) * RPM
    if t.shape != w.shape or t.size < 2 or not np.all(np.diff(t) > 0):
        raise ParameterError(f"time_s ({t.size} values) must increase and match speed_rpm ({w.size} values)")
    m, cap = supply.model, supply.model.ring_heat_capacity_J_K
    pairs = list(zip(system.bearings, system.bearing_loads))

    def at(k, omega, t_ring):
        b, load = pairs[k]
        return _operating_point(b, float(load), omega, supply.oil, supply.supply_temperature_K,
                                supply.supply_pressure_Pa, m, system.film_model, system.gravity, t_ring)

    def rhs(tt, t_r):
        omega = float(np.interp(tt, t, w))
        return [at(k, omega, t_r[k])["ring_heat"] / cap for k in range(len(pairs))]

    t0 = [at(k, w[0], None)["temperatures"][2] for k in range(len(pairs))]
    sol = solve_ivp(rhs, (t[0], t[-1]), t0, method="LSODA", t_eval=t, rtol=rtol, atol=1e-6)
    states = [[at(k, wi, sol.y[k, i]) for i, wi in enumerate(w)] for k in range(len(pairs))]
    temps = np.array([[s["temperatures"] for s in row] for row in states])  # (nb, nt, 3)
    mu = np.array([[(s["bearing"].inner.viscosity, s["bearing"].outer.viscosity) for s in row] for row in states])
    heat = np.array([[s["ring_heat"] for s in row] for row in states])
    return (t, temps[:, :, 2], temps[:, :, 0], temps[:, :, 1], mu.transpose(0, 2, 1).reshape(2 * len(pairs), t.size),
            heat)


def at_operating_point(system, speed_rpm, oil_supply, method="J"):
    """``system`` itself without an oil supply (the films' constant viscosities, bit for bit), else
    :func:`thermal_system` at ``speed_rpm`` with ``oil_supply`` and the equilibria of ``method``."""
    if oil_supply is None:
        return system
    return thermal_system(system, speed_rpm, oil_supply.oil, oil_supply.supply_temperature_K,
                          oil_supply.supply_pressure_Pa, oil_supply.model, method)


def thermal_system(system, speed_rpm, oil=None, supply_temperature_K=None, supply_pressure_Pa=None, model=None,
                   method="J"):
    """The Turbocharger with every film's viscosity at its temperature of the thermal operating point at one speed
    (:func:`thermal_losses`): what a Campbell diagram, a run-up or an FMU at that oil state uses.

    Parameters
    ----------
    system, oil, supply_temperature_K, supply_pressure_Pa, model, method
        As :func:`thermal_losses` (one supply temperature [K]; default 363.15 K, 3e5 Pa; without an oil the supply
        and the model are refused).
    speed_rpm : float
        Rotor speed [rpm].

    Returns
    -------
    Turbocharger
        ``system`` with the inner and outer viscosities [Pa s] of each bearing replaced (unchanged without an oil).

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = thermal_system(frb.turbocharger(), 150e3, frb.OILS["SAE 5W-30"], 363.15)
    >>> bool(tc.bearings[0].inner.viscosity < tc.bearings[0].outer.viscosity)   # the inner film runs hotter
    True
    """
    t_s = None if supply_temperature_K is None else check_real("supply_temperature_K", supply_temperature_K, "K")
    table = thermal_losses(system, check_speed("speed_rpm", speed_rpm), oil, t_s, supply_pressure_Pa, model, method)
    if "inner viscosity [Pa s]" not in table:
        return system
    bearings = tuple(_with_viscosities(b, float(r["inner viscosity [Pa s]"]), float(r["outer viscosity [Pa s]"]))
                     for b, (_, r) in zip(system.bearings, table.iterrows()))
    return replace(system, bearings=bearings)
