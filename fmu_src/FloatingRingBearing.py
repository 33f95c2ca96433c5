"""FMI 2.0 co-simulation slave: one floating-ring bearing (nonlinear films + ring lateral and spin DoFs).

Thin adapter over :class:`frbmodel.nonlinear.components.BearingComponent`; all physics is in frbmodel.
"""
import math

import numpy as np
from _fmu_common import FrbSlaveMixin
from pythonfmu import DefaultExperiment, Fmi2Slave

#: the journal inputs (x, y, vx, vy) and the rotor speed: every output of the communication point depends on them
JOURNAL_IN = ("journal.x", "journal.y", "journal.vx", "journal.vy")
#: the oil supply inputs (thermal model, parameter oil): (name, unit, description, start, low, high) (the bounds:
#: frbmodel.system.oil.T_MIN_K, T_MAX_K, frbmodel.linear.thermal.MAX_SUPPLY_PRESSURE_PA)
SUPPLY_IN = (("oil_supply_temperature", "K", "oil supply temperature (thermal model: parameter oil; a change "
              "recomputes the thermal table, ~0.2 s)", 363.15, 243.15, 473.15),
             ("oil_supply_pressure", "Pa", "oil supply pressure above ambient (thermal model: parameter oil)", 3e5,
              0.0, 2e6))
#: speeds of the thermal table over thermal.speed_min ... thermal.speed_max (as the turbocharger FMU's)
THERMAL_TABLE_SPEEDS = 49


class FloatingRingBearing(FrbSlaveMixin, Fmi2Slave):
    """FMI 2.0 co-simulation slave of one floating-ring bearing (one instance per bearing).

    Parameters (all ``fixed``): films, ring mass and inertia, initial ring state, gravity, substep,
    ``contact_eps``, ``film_model``, ``ring_speed_model``, and the thermal model's ``oil`` (empty: constant
    viscosities), ``static_load`` [N], ``thermal.speed_min``/``thermal.speed_max`` [rad/s]. Inputs: journal state,
    rotor speed, ``oil_supply_temperature`` [K] and ``oil_supply_pressure`` [Pa] (used with an oil; without one
    they must keep their start values). Thermal outputs: ``inner_film_temperature``, ``outer_film_temperature`` [K],
    ``oil_flow`` [m3/s] (0 without an oil).
    Outputs: force on the journal and its interface Jacobian, staggered-coupling values, the film torque on the
    journal ``journal_torque`` [N m] and the friction power of both films ``power_loss`` [W] (direct feedthrough,
    evaluated with the force at the same journal and ring state), ring state, eccentricities; the linearization
    outputs in a build with them (``frb build-fmus --linearization``). FMI behaviour and statuses:
    :class:`_fmu_common.FrbSlaveMixin` (a ring integrator that does not converge or blows up in a step is an
    fmi2Discard with the state restored, like a film reaching its wall).
    """

    author = "frbmodel"
    description = ("Floating-ring bearing: inner film, free-spinning ring, outer film (short-bearing pi-film, "
                   "half-Sommerfeld). Outputs the force on the journal and its interface Jacobian, the film torque "
                   "on the journal and the power loss.")
    #: the macro step validated against the monolithic run-up (frbmodel.cosim.master.VALIDATED_STEP_S)
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-5)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._init_state()
        from frbmodel.nonlinear.components import EXCHANGE_OUTPUTS

        self._cache = np.empty(len(EXCHANGE_OUTPUTS) + 4)  # BearingComponent.exchange, then journal_ref x, y, vx, vy
        self._cache_gen = None  # self._gen at which _cache was computed
        self._lin = None
        self._lin_gen = None
        self._parameters()
        for q, u, d in (("x", "m", "journal centre x"), ("y", "m", "journal centre y"),
                        ("vx", "m/s", "journal velocity x"), ("vy", "m/s", "journal velocity y")):
            self._input(f"journal.{q}", f"{d} [{u}]", unit=u)
        from frbmodel.core.errors import MAX_SPEED_RPM
        from frbmodel.core.units import rpm_to_rad_s

        self._input("rotor_speed", "rotor spin speed [rad/s]", 1000.0, unit="rad/s", low=0.0,
                    high=rpm_to_rad_s(MAX_SPEED_RPM))
        for name, unit, desc, start, low, high in SUPPLY_IN:
            self._input(name, f"{desc} [{unit}]", start, unit=unit, low=low, high=high)
        self._journal_idx = np.array([self._input_pos[f"journal.{q}"] for q in ("x", "y", "vx", "vy")])
        self._speed_idx = self._input_pos["rotor_speed"]
        self._outputs()
        self._linearization_outputs(["m", "m", "m/s", "m/s"], ["m", "m", "m/s", "m/s"], ["N", "N"],
                                    ("states: ring x, y, vx, vy", "inputs: journal x, y, vx, vy",
                                     "outputs: force x, y on the journal"), depends=JOURNAL_IN + ("rotor_speed",))

    def _parameters(self):
        """Parameters (all ``fixed``) with units and valid ranges; defaults: the turbine bearing of the paper's
        Table 2 system (frbmodel.system.presets) and the component's own."""
        from frbmodel.nonlinear.components import BEARING_SUBSTEP, CONTACT_EPS
        from frbmodel.physics.film import FILM_MODELS
        from frbmodel.system.presets import turbocharger

        tc = turbocharger()
        bearing = tc.bearings[0]
        positive = dict(low=0.0, low_open=True)
        for name, film in (("inner", bearing.inner), ("outer", bearing.outer)):
            self._param(f"{name}.radius", film.radius, f"{name} film radius [m]", unit="m", **positive)
            self._param(f"{name}.length", film.length, f"{name} film length [m]", unit="m", **positive)
            self._param(f"{name}.clearance", film.clearance, f"{name} film radial clearance [m]", unit="m", **positive)
            self._param(f"{name}.viscosity", film.viscosity, f"{name} film dynamic viscosity [Pa s]", unit="Pa.s",
                        **positive)
        self._param("ring.mass", bearing.ring_mass, "ring mass [kg]", unit="kg", **positive)
        self._param("ring.inertia", bearing.ring_inertia, "ring polar moment of inertia [kg m2]", unit="kg.m2",
                    **positive)
        self._param("ring.x0", 0.0, "initial ring centre x [m]", unit="m")
        self._param("ring.y0", 0.0, "initial ring centre y [m]", unit="m")
        top = 1e6 * math.pi / 30.0  # 1e6 rpm, frbmodel's speed bound (frbmodel.core.errors.MAX_SPEED_RPM)
        self._param("ring.speed0", 0.0, "initial ring speed [rad/s]", unit="rad/s", low=-top, high=top)
        self._param("gravity", tc.gravity, "gravitational acceleration along -y [m/s2]", unit="m/s2", low=0.0,
                    high=1e3)
        self._param("substep", BEARING_SUBSTEP, "ring integration substep [s] (2-stage SDIRK, second order)",
                    unit="s", low=1e-9, high=1e-3)
        self._param("contact_eps", CONTACT_EPS, "eccentricity ratio treated as wall contact (Discard above) [-]",
                    unit="1", low=0.01, high=0.9999)
        self._param("film_model", tc.film_model, "film model: short | short_corrected", "str", choices=FILM_MODELS)
        self._param("ring_speed_model", "free", "ring speed: free (spin DoF) | rsr_eq6 | rsr_eq7", "str",
                    choices=("free", "rsr_eq6", "rsr_eq7"))
        from frbmodel.core.units import rpm_to_rad_s
        from frbmodel.system.oil import OILS

        self._param("oil", "", "thermal model: the oil (" + ", ".join(OILS) + "); the films' viscosities follow the "
                    "rotor speed at the inputs' supply temperature and pressure (docs/theory/thermal.md#bearing-fmu); "
                    "empty = the films' constant viscosity parameters", "str", choices=("", *OILS))
        self._param("static_load", float(tc.bearing_loads[0]), "static load of the bearing [N] (downward; the thermal "
                    "operating points are the method-J equilibria under it; thermal model only)", unit="N", low=0.0)
        self._param("thermal.speed_min", rpm_to_rad_s(10e3), "lowest rotor speed of the thermal table [rad/s] (held "
                    "below)", unit="rad/s", high=top, **positive)
        self._param("thermal.speed_max", rpm_to_rad_s(250e3), "highest rotor speed of the thermal table [rad/s] "
                    "(held above)", unit="rad/s", high=top, **positive)

    def _outputs(self):
        """Force, interface Jacobian, staggered-coupling values, ring state, eccentricities (all with units). Those
        of the communication point (force, Jacobian, journal_ref, losses, ε) are one array computed by one
        compiled call (:meth:`_out`), the others one array of the state (:meth:`_state_out`)."""
        from frbmodel.nonlinear.components import EXCHANGE_OUTPUTS

        where = {n: k for k, n in enumerate(EXCHANGE_OUTPUTS)}

        feed = JOURNAL_IN + ("rotor_speed",)
        every = feed  # initialization mode: the ring starts from its parameters; force_end from the inputs

        def point(name, desc, unit, k=None, depends=feed, **kw):
            k = where[name] if k is None else k
            self._output(name, desc, lambda: self._out()[k], unit=unit, block=(self._out, k), depends=depends,
                         init_depends=every, **kw)

        def state(name, desc, unit, k, depends=(), **kw):
            self._output(name, desc, lambda: self._state_out()[k], unit=unit, block=(self._state_out, k),
                         depends=depends, init_depends=every, **kw)

        point("force.x", "film force on the journal, x [N]", "N")
        point("force.y", "film force on the journal, y [N]", "N")
        for i in "xy":
            for k in "xy":
                point(f"stiffness.{i}{k}", f"interface Jacobian -dF_{i}/d{k}_journal [N/m]", "N/m")
                point(f"damping.{i}{k}", f"interface Jacobian -dF_{i}/dv{k}_journal [N s/m]", "N.s/m")
        for qi, (q, u) in enumerate((("x", "m"), ("y", "m"), ("vx", "m/s"), ("vy", "m/s"))):
            point(f"journal_ref.{q}", f"journal {q} at which force and Jacobian were evaluated [{u}]", u,
                  len(EXCHANGE_OUTPUTS) + qi, depends=(f"journal.{q}",))
        state("force_end.x", "force on the journal at the end of the last step along the extrapolated journal "
              "path, x [N] (staggered coupling)", "N", 0)
        state("force_end.y", "force on the journal at the end of the last step, y [N]", "N", 1)
        state("journal_accel.x", "journal acceleration of the quadratic path the ring was integrated on in the "
              "last step, x [m/s2] (staggered coupling)", "m/s2", 2)
        state("journal_accel.y", "journal acceleration of that path, y [m/s2]", "m/s2", 3)
        point("journal_torque", "inner-film torque on the journal about +z [N m] (negative: it brakes the "
              "rotor; input <bearing>_bearing.torque of the rotor)", "N.m")
        point("power_loss", "friction power of the inner and outer film [W]", "W")
        state("ring.x", "ring centre x [m]", "m", 4)
        state("ring.y", "ring centre y [m]", "m", 5)
        state("ring.speed", "ring spin speed [rad/s] (ring_speed_model rsr_eq6/7: from the rotor speed)", "rad/s", 6,
              depends=("rotor_speed",))
        point("eps_inner", "inner film eccentricity ratio [-]", "1", depends=("journal.x", "journal.y"), low=0.0,
              high=1.0)
        point("eps_outer", "outer film eccentricity ratio [-]", "1", depends=(), low=0.0, high=1.0)
        state("ring_speed_ratio", "ring speed / rotor speed [-]", "1", 7, depends=("rotor_speed",))
        supply = ("rotor_speed", "oil_supply_temperature", "oil_supply_pressure")
        for k, (name, unit, desc) in enumerate((
                ("inner_film_temperature", "K", "inner-film temperature of the thermal operating point at the rotor "
                 "speed"),
                ("outer_film_temperature", "K", "outer-film temperature of the thermal operating point"),
                ("oil_flow", "m3/s", "oil flow through both films at the thermal operating point"))):
            self._output(name, f"{desc}; 0 without an oil [{unit}]", lambda k=k: self._thermal_out()[k], unit=unit,
                         block=(self._thermal_out, k), depends=supply, init_depends=supply, low=0.0)

    # ------------------------------------------------------------------ helpers
    def _journal(self):
        return self._input_values[self._journal_idx]

    def _supply_inputs(self):
        return tuple(float(self._in(name)) for name, *_ in SUPPLY_IN)

    def _sync_supply(self):
        """Thermal model: recompute the component's table when the supply inputs differ from its supply."""
        from frbmodel.linear.thermal import OilSupply
        from frbmodel.system.oil import OILS

        sup, (t_s, p_s) = self._comp.supply, self._supply_inputs()
        if (t_s, p_s) != (sup.supply_temperature_K, sup.supply_pressure_Pa):
            self._comp.set_supply(OilSupply(OILS[self._values["oil"]], t_s, p_s))

    def _thermal_out(self):
        """Inner, outer film temperature [K] and oil flow [m3/s] at the rotor speed (zeros without an oil)."""
        if not self._values["oil"]:
            return np.zeros(3)
        self._sync_supply()
        return np.array(self._comp.thermal_outputs(float(self._input_values[self._speed_idx])))

    def _out(self):
        """The outputs of the communication point: :meth:`BearingComponent.exchange` at the current inputs and ring
        state (layout EXCHANGE_OUTPUTS), then the journal state they belong to; computed once per change."""
        if self._values["oil"]:
            self._sync_supply()
        if self._cache_gen != self._gen:
            j = self._journal()
            self._cache_gen = None
            self._comp.exchange(j, float(self._input_values[self._speed_idx]), out=self._cache[:-4])
            self._cache[-4:] = j
            self._cache_gen = self._gen
        return self._cache

    def _state_out(self):
        """force_end x, y [N], journal_accel x, y [m/s2], ring x, y [m], ring speed [rad/s], ring speed ratio [-]."""
        c = self._comp
        w = float(self._input_values[self._speed_idx])
        speed = c.ring_speed(w)
        return np.array([c.force_end[0], c.force_end[1], c.path_accel[0], c.path_accel[1], c.ring[0], c.ring[1],
                         speed, speed / w if w else 0.0])

    def _linear(self):
        if self._lin is None or self._lin_gen != self._gen:
            A, B, C, D = self._comp.linearization(self._journal(), self._in("rotor_speed"))
            self._lin = {"A": A, "B": B, "C": C, "D": D}
            self._lin_gen = self._gen
        return self._lin

    # ------------------------------------------------------------------ FMI (FrbSlaveMixin hooks)
    def _initialize(self):
        """Build the component from the (range-checked) parameters; raises on an invalid combination."""
        from frbmodel.nonlinear.components import BearingComponent
        from frbmodel.physics.film import Film
        from frbmodel.system.parameters import FloatingRingBearing as FRB

        v = self._values
        self._check_geometry()
        films = [Film(v[f"{f}.radius"], v[f"{f}.length"], v[f"{f}.clearance"], v[f"{f}.viscosity"])
                 for f in ("inner", "outer")]
        b = FRB(0, films[0], films[1], v["ring.mass"], v["ring.inertia"], self.instance_name)
        comp = BearingComponent(b, v["film_model"], v["ring_speed_model"], float(v["gravity"]), float(v["substep"]),
                                float(v["contact_eps"]))
        comp.ring[:] = [v["ring.x0"], v["ring.y0"], 0.0, 0.0, v["ring.speed0"]]
        if v["oil"]:
            self._use_oil(comp)
        j, w = self._journal(), self._in("rotor_speed")
        if math.isfinite(j.sum()) and w > 0 and abs(j[0]) + abs(j[1]) > 0:
            comp.force_end[:] = comp.outputs(j, w)[0]
        self._comp = comp
        self._changed()
        self._warm_up(j, w)

    def _use_oil(self, comp):
        """Switch the component's thermal model on (parameter oil) at the supply inputs' start state."""
        from frbmodel.linear.thermal import OilSupply
        from frbmodel.system.oil import OILS

        v = self._values
        lo, hi = float(v["thermal.speed_min"]), float(v["thermal.speed_max"])
        if not lo < hi:
            raise ValueError(f"thermal.speed_min = {lo!r} rad/s is invalid: valid range < thermal.speed_max = {hi!r} "
                             "rad/s")
        try:
            comp.use_oil(OilSupply(OILS[v["oil"]], *self._supply_inputs()), float(v["static_load"]),
                         np.linspace(lo, hi, THERMAL_TABLE_SPEEDS))
        except Exception as exc:  # noqa: BLE001  (the library's message named none of these parameters)
            raise ValueError(f"the thermal table for oil = {v['oil']!r}, static_load = {v['static_load']!r} N, "
                             f"thermal.speed_min ... speed_max = {lo:g} ... {hi:g} rad/s cannot be made: "
                             f"{exc}") from None

    def _warm_up(self, j, w):
        """Load (or compile) the compiled kernels of the exchange and the ring step now, in initialization, not in
        the first doStep: one evaluation and one 1 ns step of a copy (nothing is kept; a failure here is left to
        the real call to report)."""
        import copy

        try:
            self._out()
            copy.deepcopy(self._comp).step(j, w, 0.0, 1e-9)
        except Exception:  # noqa: BLE001
            pass

    def _check_geometry(self):
        """ValueError naming the FMU parameters of a film geometry the model does not cover."""
        v = self._values
        for f in ("inner", "outer"):
            c, r = v[f"{f}.clearance"], v[f"{f}.radius"]
            if c >= 0.1 * r:
                raise ValueError(f"{f}.clearance = {c!r} m is invalid for {f}.radius = {r!r} m: valid range "
                                 f"(0, {0.1 * r:g}) m (the thin-film theory needs clearance < 0.1 radius)")
        x0, y0, c = v["ring.x0"], v["ring.y0"], v["outer.clearance"]
        if not math.hypot(x0, y0) < c:
            raise ValueError(f"ring.x0, ring.y0 = ({x0!r}, {y0!r}) m is invalid: valid range sqrt(x0^2 + y0^2) < "
                             f"outer.clearance = {c!r} m (the ring inside its outer film)")
        bore = v["inner.radius"] + v["inner.clearance"]
        if bore >= v["outer.radius"]:
            raise ValueError(f"inner.radius + inner.clearance = {bore:g} m (the ring's bore) is invalid: valid range "
                             f"< outer.radius = {v['outer.radius']!r} m")

    def _advance(self, current_time, step_size):
        if not self._values["oil"]:
            self._check_unused_inputs((name, value, start) for (name, _, _, start, *_), value
                                      in zip(SUPPLY_IN, self._supply_inputs()))
        out = self._out()  # outputs at the current inputs (cached since the exchange): validates them, updates eps
        self._comp.step(out[-4:].copy(), float(self._input_values[self._speed_idx]), 0.0, step_size, t=current_time)

    def _step_context(self):
        from frbmodel.core.units import rad_s_to_rpm

        w = self._in("rotor_speed")
        return f"rotor speed {rad_s_to_rpm(w):.0f} rpm: " if math.isfinite(w) else ""

    def _component_state(self):
        """Ring state, journal history, last ε, end-of-step force and path acceleration (copies)."""
        c = self._comp
        st = {"ring": c.ring.copy(), "history": c.history.state(), "eps": tuple(c.eps),
              "force_end": c.force_end.copy(), "path_accel": c.path_accel.copy()}
        if c.supply is not None:
            st["supply"] = c.supply.to_dict()
        return st

    def _set_component_state(self, st):
        c = self._comp
        c.ring[:] = st["ring"]
        c.history.set_state(st["history"])
        c.eps = tuple(st["eps"])
        c.force_end = np.array(st["force_end"], dtype=float)
        c.path_accel = np.array(st["path_accel"], dtype=float)
        if "supply" in st and st["supply"] != c.supply.to_dict():
            from frbmodel.linear.thermal import OilSupply

            c.set_supply(OilSupply.from_dict(st["supply"]))
