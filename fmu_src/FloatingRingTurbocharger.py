"""FMI 2.0 co-simulation slave: the whole turbocharger in one FMU, for system-simulation tools.

Thin adapter over :class:`frbmodel.nonlinear.turbocharger_component.TurbochargerComponent`: the FE rotor and both
floating-ring bearings (ring lateral and spin DoFs) integrated inside by the compiled monolithic integrator of
``frb.runup`` with its own error control. ``doStep(t, h)`` reaches exactly t + h for any h; the inputs are held over
the step; no output depends directly on an input (ModelStructure), so the FMU closes no algebraic loop.

The rotor system is fixed when the FMU is built (``frb build-fmus --rotor-file FILE``, default: the paper's Table 2
system), as for the rotor FMU: its discs name the outputs ``<disc>.x/y`` and the unbalance parameters, its
bearings the per-bearing parameters and outputs ``<bearing>_bearing.*``. ``system_file`` may select another system
of the same structure at run time (rotor and bearing nodes); the films and rings are the parameters
``<bearing>_bearing.inner.*``, ``.outer.*``, ``.ring.*`` (defaults: the system the FMU was built for).
"""
import math
import weakref

import numpy as np
from _fmu_common import FrbSlaveMixin
from pythonfmu import DefaultExperiment, Fmi2Slave

#: film parameters per bearing: (name, unit, description)
FILM = (("radius", "m", "film radius"), ("length", "m", "film length"), ("clearance", "m", "radial clearance"),
        ("viscosity", "Pa.s", "dynamic viscosity"))
#: inputs: (name, unit, description, low); the speed input's start value is set from the default start speed
INPUTS = (("speed_in", "rad/s", "rotor speed held over the step (speed_source = input)", 0.0),
          ("drive_torque", "N.m", "net external torque on the rotor about +z held over the step, e.g. turbine "
           "minus compressor (speed_source = torque)", -math.inf),
          ("housing_acceleration.x", "m/s2", "translational acceleration of the rigid bearing housing, x (base "
           "excitation; positions are relative to the housing)", -math.inf),
          ("housing_acceleration.y", "m/s2", "translational acceleration of the rigid bearing housing, y", -math.inf),
          ("oil_supply_temperature", "K", "oil supply temperature held over the step (thermal model: parameter oil; "
           "a change recomputes the thermal table, ~0.45 s)", 243.15),
          ("oil_supply_pressure", "Pa", "oil supply pressure above ambient held over the step (thermal model: "
           "parameter oil)", 0.0))
#: start values of the inputs that do not start at 0 (speed_in: the default start speed, set in __init__)
INPUT_STARTS = {"oil_supply_temperature": 363.15, "oil_supply_pressure": 3e5}
#: upper bounds of the supply inputs (frbmodel.system.oil.T_MAX_K, frbmodel.linear.thermal.MAX_SUPPLY_PRESSURE_PA)
INPUT_HIGHS = {"oil_supply_temperature": 473.15, "oil_supply_pressure": 2e6}


def _close_abandoned_record(comp):
    """Close a record the host left open (fmi2FreeInstance, fmi2Reset or the end of its process without an accepted
    fmi2Terminate) as interrupted, so that its runup.json does not say "running" for ever; nothing when fmi2Terminate
    closed it (a finalizer of the slave: it runs once, when the slave is collected or at the process's exit)."""
    try:
        comp.close_record("interrupted", f"the FMU instance ended without fmi2Terminate; the record ends at t = "
                                         f"{comp.t:.9g} s")
    except Exception:  # noqa: BLE001  (a finalizer must not raise, e.g. at the interpreter's exit)
        pass


class FloatingRingTurbocharger(FrbSlaveMixin, Fmi2Slave):
    """FMI 2.0 co-simulation slave of the whole turbocharger (see the module description).

    Parameters (all ``fixed``): ``system_file``, films and rings per bearing, ``film_model``, unbalance per disc,
    gravity, ``speed_source`` with its ramp, ``rtol``, ``atol``, ``speed_scale``, ``contact_eps``, the initial
    state (``initial``, ``perturbation``), ``check_rate``, ``record_folder`` and ``oil`` (the thermal model: a named
    oil, or empty for the films' constant viscosities). Inputs: ``speed_in`` [rad/s], ``drive_torque`` [N m],
    ``housing_acceleration.x/y`` [m/s2], ``oil_supply_temperature`` [K] and ``oil_supply_pressure`` [Pa] (used with
    an oil; without one they must keep their start values). Outputs:
    :func:`frbmodel.nonlinear.turbocharger_component.output_names`, then
    :func:`~frbmodel.nonlinear.turbocharger_component.thermal_output_names` (film temperatures [K] and oil flow
    [m3/s] per bearing; 0 without an oil). FMI behaviour and statuses:
    :class:`_fmu_common.FrbSlaveMixin`; a film reaching ``contact_eps`` inside a step discards it.
    """

    author = "frbmodel"
    description = ("Turbocharger rotor on two floating-ring bearings (FE rotor, nonlinear films, ring lateral and spin "
                   "DoFs) integrated inside with error control: any communication step, the monolithic answer.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-3)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._init_state()
        from frbmodel.cosim.fmu_system import rotor_system

        self._built_for = rotor_system(self.resources)
        self._bearings = [b.name for b in self._built_for.bearings]
        self._discs = [d.name for d in self._built_for.rotor.discs]
        self._parameters()
        from frbmodel.core.errors import MAX_SPEED_RPM
        from frbmodel.core.units import rpm_to_rad_s

        for name, unit, desc, low in INPUTS:
            start = rpm_to_rad_s(20e3) if name == "speed_in" else INPUT_STARTS.get(name, 0.0)
            self._input(name, f"{desc} [{unit}]", start, unit=unit, low=low,
                        high=INPUT_HIGHS.get(name, math.inf) if name != "speed_in" else rpm_to_rad_s(MAX_SPEED_RPM))
        self._in_idx = np.array([self._input_pos[n] for n, *_ in INPUTS])
        self._outputs()

    # ------------------------------------------------------------------ variables
    def _parameters(self):
        """Parameters with units and valid ranges; defaults: the built-in system and frb.runup's defaults."""
        from frbmodel.core.units import rpm_to_rad_s
        from frbmodel.nonlinear.runup import DEFAULT_ATOL_M, DEFAULT_RTOL, RTOL_RANGE
        from frbmodel.nonlinear.turbocharger_component import CHECK_RATE_HZ, CONTACT_EPS, SPEED_SOURCES
        from frbmodel.physics.film import FILM_MODELS
        from frbmodel.system.presets import RUNUP_DURATION, RUNUP_SPEED_RPM

        tc = self._built_for
        positive = dict(low=0.0, low_open=True)
        self._param("system_file", "", "frbmodel system description (.toml/.json, see frb system) whose rotor and "
                    "bearing nodes are used; it must have the structure this FMU was built for; empty = the system "
                    "built into the FMU", "str")
        for b in tc.bearings:
            for film_name, film in (("inner", b.inner), ("outer", b.outer)):
                for q, unit, desc in FILM:
                    self._param(f"{b.name}_bearing.{film_name}.{q}", getattr(film, q), f"{b.name} bearing, "
                                f"{film_name} film: {desc} [{unit}]", unit=unit, **positive)
            self._param(f"{b.name}_bearing.ring.mass", b.ring_mass, f"{b.name} bearing: ring mass [kg]", unit="kg",
                        **positive)
            self._param(f"{b.name}_bearing.ring.inertia", b.ring_inertia, f"{b.name} bearing: ring polar moment of "
                        "inertia [kg m2]", unit="kg.m2", **positive)
        self._param("film_model", tc.film_model, "film model: short | short_corrected", "str", choices=FILM_MODELS)
        for w in self._discs:
            self._param(f"{w}.unbalance", 0.0, f"{w} unbalance (mass x eccentricity) [kg m]", unit="kg.m", low=0.0,
                        high=1e-3)
            self._param(f"{w}.unbalance_phase", 0.0, f"{w} unbalance phase from +x at rotor angle 0 [rad]",
                        unit="rad", low=-100.0, high=100.0)
        self._param("gravity", tc.gravity, "gravitational acceleration along -y [m/s2]", unit="m/s2", low=0.0,
                    high=1e3)
        self._param("speed_source", "ramp", "where the rotor speed comes from: ramp (speed_start -> speed_end in "
                    "ramp_time, then constant) | input (speed_in) | torque (the spin is a state driven by "
                    "drive_torque and the film torques, from speed_start)", "str", choices=SPEED_SOURCES)
        top = rpm_to_rad_s(1e6)
        self._param("speed_start", rpm_to_rad_s(RUNUP_SPEED_RPM[0]), "rotor speed at t = 0 [rad/s] (ramp, torque)",
                    unit="rad/s", low=0.0, high=top, low_open=True)
        self._param("speed_end", rpm_to_rad_s(RUNUP_SPEED_RPM[1]), "rotor speed at the end of the ramp [rad/s]",
                    unit="rad/s", low=0.0, high=top, low_open=True)
        self._param("ramp_time", RUNUP_DURATION, "duration of the linear speed ramp [s]", unit="s", low=0.0,
                    high=1e4, low_open=True)
        self._param("speed_scale", 0.0, "largest rotor speed expected [rad/s]: scales the absolute tolerances of "
                    "velocities and spin speeds as in frb.runup; 0 = the larger of speed_start and speed_end",
                    unit="rad/s", low=0.0, high=top)
        self._param("rtol", DEFAULT_RTOL, "relative tolerance of the internal integrator [-] (frb.runup's)",
                    unit="1", low=RTOL_RANGE[0], high=RTOL_RANGE[1])
        self._param("atol", DEFAULT_ATOL_M, "absolute tolerance on displacements [m] (frb.runup's; velocities and "
                    "speeds scaled from it; at most 1e-3 of the smallest film clearance)", unit="m", low=1e-16,
                    high=1e-7)
        self._param("contact_eps", CONTACT_EPS, "eccentricity ratio treated as wall contact: a step that reaches it "
                    "is discarded [-]", unit="1", low=0.01, high=0.9999)
        self._param("initial", "equilibrium", "initial state: equilibrium (method-J static equilibrium at the start "
                    "speed) | centred", "str", choices=("equilibrium", "centred"))
        self._param("perturbation", 0.05, "initial offset of journals and rings in +x as a fraction of their "
                    "clearance [-] (frb.runup's)", unit="1", low=0.0, high=0.5)
        self._param("check_rate", CHECK_RATE_HZ, "rate of the in-step grid [Hz]: contact check, smallest film "
                    "thickness over the step, record_folder rows", unit="Hz", low=100.0, high=1e7)
        self._param("record_folder", "", "folder for frb.runup's result files (runup.csv, runup.json) written at "
                    "check_rate while the FMU steps; empty = no record", "str")
        from frbmodel.system.oil import OILS

        self._param("oil", "", "thermal model: the oil (" + ", ".join(OILS) + "); the films' viscosities follow "
                    "the rotor speed at the inputs' supply temperature and pressure (docs/theory/thermal.md); empty = "
                    "the films' constant viscosity parameters", "str", choices=("", *OILS))

    def _outputs(self):
        """All outputs are one array of the component (:meth:`_out`), computed once per step; none depends directly
        on an input (in initialization mode on speed_in, the start speed of speed_source = input)."""
        from frbmodel.nonlinear.turbocharger_component import output_names

        ranges = {"1": (0.0, 1.0), "m": (-math.inf, math.inf)}
        for k, (name, unit, desc) in enumerate(output_names(self._built_for)):
            low, high = (0.0, math.inf) if ".h_min" in name else ranges.get(unit, (-math.inf, math.inf))
            if name.endswith("ring_speed_ratio"):
                low, high = -math.inf, math.inf
            self._output(name, f"{desc} [{unit}]", lambda k=k: self._out()[k], unit=unit, block=(self._out, k),
                         depends=(), init_depends=("speed_in",), low=low, high=high)
        from frbmodel.nonlinear.turbocharger_component import thermal_output_names

        for k, (name, unit, desc) in enumerate(thermal_output_names(self._built_for)):
            self._output(name, f"{desc}; 0 without an oil [{unit}]", lambda k=k: self._thermal_out()[k], unit=unit,
                         block=(self._thermal_out, k), depends=(),
                         init_depends=("speed_in", "oil_supply_temperature", "oil_supply_pressure"), low=0.0)

    def _out(self):
        return self._comp.outputs()

    def _thermal_out(self):
        if self._values["oil"]:
            return self._comp.thermal_outputs()
        return np.zeros(3 * len(self._bearings))

    # ------------------------------------------------------------------ FMI (FrbSlaveMixin hooks)
    def _system(self):
        """The system of the parameters: rotor of system_file (or the built-in one), films and rings per bearing."""
        from dataclasses import replace

        import frbmodel as frb
        from frbmodel.cosim.fmu_system import structure_differences
        from frbmodel.physics.film import Film

        v = self._values
        tc = frb.load_system(v["system_file"]) if v["system_file"] else self._built_for
        diff = structure_differences(self._built_for, tc)
        if diff:
            raise ValueError(f"system_file = {v['system_file']!r} does not fit this FMU's variables: "
                             f"{'; '.join(diff)}. Build an FMU for that system: frb build-fmus --rotor-file FILE")
        bearings = []
        for b in tc.bearings:
            p = f"{b.name}_bearing"
            films = [Film(*(float(v[f"{p}.{f}.{q}"]) for q, _, _ in FILM)) for f in ("inner", "outer")]
            bearings.append(replace(b, inner=films[0], outer=films[1], ring_mass=float(v[f"{p}.ring.mass"]),
                                    ring_inertia=float(v[f"{p}.ring.inertia"])))
        return tc.with_(bearings=tuple(bearings), gravity=float(v["gravity"]), film_model=v["film_model"])

    def _initialize(self):
        """Build the component from the (range-checked) parameters; its compiled kernels are loaded (or compiled)
        here, not in the first doStep."""
        import frbmodel as frb
        from frbmodel.nonlinear.turbocharger_component import TurbochargerComponent

        v = self._values
        tc = self._system()
        unb = [frb.Unbalance(w, float(v[f"{w}.unbalance"]), float(v[f"{w}.unbalance_phase"])) for w in self._discs
               if v[f"{w}.unbalance"] > 0]
        comp = TurbochargerComponent(
            tc, v["speed_source"], float(v["speed_start"]), float(v["speed_end"]), float(v["ramp_time"]),
            unbalance=unb, rtol=float(v["rtol"]), atol=float(v["atol"]),
            speed_scale=float(v["speed_scale"]) or None, contact_eps=float(v["contact_eps"]),
            perturbation=float(v["perturbation"]), initial=v["initial"], initial_speed=self._in("speed_in"),
            check_rate_hz=float(v["check_rate"]), oil=frb.OILS[v["oil"]] if v["oil"] else None,
            supply_temperature_K=self._in("oil_supply_temperature"), supply_pressure_Pa=self._in("oil_supply_pressure"))
        comp.warm_up()
        if v["record_folder"]:
            try:
                comp.record(v["record_folder"], {"fmu_instance": self.instance_name})
            except OSError as exc:  # (the message was "[Errno 2] No such file or directory: '/proc/x'" alone)
                raise ValueError(f"record_folder = {v['record_folder']!r} cannot be written: "
                                 f"{exc.strerror or exc}") from None
            weakref.finalize(self, _close_abandoned_record, comp)
        self._comp = comp
        self._changed()

    def _advance(self, current_time, step_size):
        w, tq, ax, ay, t_s, p_s = self._input_values[self._in_idx]
        supply = {}
        if self._values["oil"]:
            supply = {"supply_temperature_K": float(t_s), "supply_pressure_Pa": float(p_s)}
        else:
            self._check_unused_inputs((name, value, INPUT_STARTS[name]) for name, value
                                      in (("oil_supply_temperature", t_s), ("oil_supply_pressure", p_s)))
        self._comp.step(step_size, speed_in=float(w), drive_torque=float(tq), housing_acc=(float(ax), float(ay)),
                        t=current_time, **supply)

    def _step_context(self):
        from frbmodel.core.units import rad_s_to_rpm

        w = float(self._comp.outputs()[0])
        return f"rotor speed {rad_s_to_rpm(w):.0f} rpm: " if math.isfinite(w) else ""

    def _component_state(self):
        return self._comp.state()

    def _set_component_state(self, st):
        self._comp.set_state(st)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        super().setup_experiment(start_time, stop_time, tolerance)
        if tolerance is not None:
            self.log(f"{self.instance_name}: the tolerance {tolerance!r} of fmi2SetupExperiment is not used: the "
                     "internal integrator's tolerances are the parameters rtol and atol")

    def terminate(self):
        """Terminate; the record (``record_folder``) is closed as finished, or as stopped with the reason when the
        last doStep was discarded (a host that carries on after a Discard: the record ends there). A refused
        fmi2Terminate (outside step mode) leaves the record open; an instance that ends without an accepted one closes
        it as interrupted (:func:`_close_abandoned_record`)."""
        if super().terminate() and self._comp is not None:
            if self._last_discard:
                self._comp.close_record("stopped", self._last_discard)
            else:
                self._comp.close_record("finished", f"terminated at t = {self._comp.t:.9g} s")
