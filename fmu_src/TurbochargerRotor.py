"""FMI 2.0 co-simulation slave: the turbocharger FE rotor (Euler-Bernoulli, gyroscopics, rigid wheels).

Thin adapter over :class:`frbmodel.nonlinear.components.RotorComponent`; the bearing forces arrive linearized at the
communication point (force, stiffness, damping per bearing) and are applied linear-implicitly over the step.

The rotor system is fixed when the FMU is built (:mod:`frbmodel.cosim.fmu_system`; ``frb build-fmus
--rotor-file FILE``, default: the paper's Table 2 system): its discs name the outputs ``<disc>.x/y`` and the
unbalance parameters, its bearings the inputs and outputs ``<bearing>_bearing.*``, and its node count sizes the
state and the linearization matrices.

The rotor speed follows ``speed_source`` (:data:`frbmodel.nonlinear.components.SPEED_SOURCES`): ``"ramp"`` the linear
ramp
of the parameters ``speed_start``, ``speed_end``, ``ramp_time``; ``"input"`` the input ``speed_in`` [rad/s] (its
rate from the last two inputs); ``"torque"`` the spin equation J_p dΩ/dt = ``drive_torque`` + Σ
``<bearing>_bearing.torque`` [N m] from ``speed_start`` (:func:`frbmodel.physics.dynamics.spin_acceleration`, the same
equation as the monolithic torque-driven run-up). The ``rotor_file`` parameter may select another system of the same
structure at run time; a system of another structure is refused at initialization with the differences named.
"""
import math

import numpy as np
from _fmu_common import FrbSlaveMixin
from pythonfmu import DefaultExperiment, Fmi2Slave

#: journal state quantities and their units, in the order of the outputs and of the journal_ref inputs
JOURNAL = (("x", "m"), ("y", "m"), ("vx", "m/s"), ("vy", "m/s"))


class TurbochargerRotor(FrbSlaveMixin, Fmi2Slave):
    """FMI 2.0 co-simulation slave of the FE rotor built into the FMU (see the module description).

    Parameters (all ``fixed``): ``rotor_file``, ``speed_source``, speed ramp, unbalance per disc, initial journal
    positions per bearing, gravity, substep, ``force_interpolation``. Inputs: ``speed_in``
    [rad/s], ``drive_torque`` [N m]; per bearing force, end-of-step force and path acceleration, reference journal
    state, interface Jacobian, film torque on the journal ``torque`` [N m]. Outputs: ``rotor_speed`` [rad/s],
    ``rotor_angle`` [rad], journal states per bearing, disc centres per disc, optional linearization. FMI
    behaviour and statuses: :class:`_fmu_common.FrbSlaveMixin`.
    """

    author = "frbmodel"
    description = ("Turbocharger rotor, FE model of the system built into the FMU (paper Table 2 by default), "
                   "speed from a ramp, an input or a drive torque (speed_source).")
    #: the macro step validated against the monolithic run-up (frbmodel.cosim.master.VALIDATED_STEP_S)
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-5)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._init_state()
        self._out_gen = None  # self._gen at which the output array of the state was computed
        from frbmodel.cosim.fmu_system import rotor_system

        self._built_for = rotor_system(self.resources)  # the system the variables are made for
        self._bearings = [f"{b.name}_bearing" for b in self._built_for.bearings]
        self._discs = [d.name for d in self._built_for.rotor.discs]
        self._parameters()
        self._inputs()
        self._outputs()

    # ------------------------------------------------------------------ variables
    def _parameters(self):
        """Parameters (all ``fixed``) with units and valid ranges; defaults: the built-in system and the default
        run-up of frbmodel.system.presets."""
        from frbmodel.core.errors import MAX_SPEED_RPM
        from frbmodel.core.units import rpm_to_rad_s
        from frbmodel.nonlinear.components import ROTOR_SUBSTEP, SPEED_SOURCES
        from frbmodel.system.presets import RUNUP_DURATION, RUNUP_SPEED_RPM

        self._param("rotor_file", "", "frbmodel system description (.toml/.json, see frb system) whose rotor, bearing "
                    "nodes and gravity are used; it must have the structure this FMU was built for (node count, disc "
                    "names, bearing names); empty = the system built into the FMU", "str")
        self._param("speed_source", "ramp", "where the rotor speed comes from: ramp (speed_start -> speed_end in "
                    "ramp_time) | input (the input speed_in) | torque (the spin is a state driven by the inputs "
                    "drive_torque and <bearing>_bearing.torque, from speed_start)", "str", choices=SPEED_SOURCES)
        top = rpm_to_rad_s(MAX_SPEED_RPM)  # the bounds of the turbocharger FMU's parameters of the same name
        self._param("speed_start", rpm_to_rad_s(RUNUP_SPEED_RPM[0]), "rotor speed at t = 0 [rad/s] (ramp and torque "
                    "modes)", unit="rad/s", low=0.0, high=top)
        self._param("speed_end", rpm_to_rad_s(RUNUP_SPEED_RPM[1]), "rotor speed after the ramp [rad/s]",
                    unit="rad/s", low=0.0, high=top)
        self._param("ramp_time", RUNUP_DURATION, "duration of the linear speed ramp [s]", unit="s", low=0.0,
                    high=1e4, low_open=True)
        for w in self._discs:
            self._param(f"{w}.unbalance", 0.0, f"{w} unbalance (mass x eccentricity) [kg m]", unit="kg.m", low=0.0,
                        high=1e-3)
            self._param(f"{w}.unbalance_phase", 0.0, f"{w} unbalance phase from +x [rad]", unit="rad", low=-100.0,
                        high=100.0)
        for b in self._bearings:
            self._param(f"{b}.journal_x0", 0.0, f"initial journal centre x at the {b} [m]", unit="m")
            self._param(f"{b}.journal_y0", 0.0, f"initial journal centre y at the {b} [m]", unit="m")
        self._param("gravity", self._built_for.gravity, "gravitational acceleration along -y [m/s2]", unit="m/s2",
                    low=0.0, high=1e3)
        self._param("substep", ROTOR_SUBSTEP, "trapezoidal substep [s]", unit="s", low=1e-9, high=1e-3)
        self._param("force_interpolation", False, "interpolate the bearing force between force and force_end over the "
                    "step (staggered masters that step the bearings first); false for Jacobi masters", "bool")

    def _inputs(self):
        """Speed and drive torque; per bearing: force, end-of-step force and path acceleration, reference journal
        state, Jacobian, film torque."""
        from frbmodel.core.errors import MAX_SPEED_RPM
        from frbmodel.core.units import rpm_to_rad_s
        from frbmodel.system.presets import RUNUP_SPEED_RPM

        self._input("speed_in", "rotor speed [rad/s] (speed_source = input; its value at the end of initialization "
                    "is the speed before the first step)", rpm_to_rad_s(RUNUP_SPEED_RPM[0]), unit="rad/s",
                    low=0.0, high=rpm_to_rad_s(MAX_SPEED_RPM))
        self._input("drive_torque", "net external torque on the rotor about +z [N m], e.g. turbine minus compressor "
                    "(speed_source = torque)", unit="N.m")
        for b in self._bearings:
            self._input(f"{b}.force.x", "bearing force on the journal, x [N]", unit="N")
            self._input(f"{b}.force.y", "bearing force on the journal, y [N]", unit="N")
            self._input(f"{b}.force_end.x", "bearing force at the end of the step, x [N] (force_interpolation)",
                        unit="N")
            self._input(f"{b}.force_end.y", "bearing force at the end of the step, y [N] (force_interpolation)",
                        unit="N")
            self._input(f"{b}.journal_accel.x", "journal acceleration of the bearing's extrapolated path, x [m/s2] "
                        "(force_interpolation)", unit="m/s2")
            self._input(f"{b}.journal_accel.y", "journal acceleration of the bearing's extrapolated path, y [m/s2] "
                        "(force_interpolation)", unit="m/s2")
            for q, u in JOURNAL:
                self._input(f"{b}.journal_ref.{q}", f"journal {q} at which the bearing force was evaluated [{u}]",
                            unit=u)
            for i in "xy":
                for k in "xy":
                    self._input(f"{b}.stiffness.{i}{k}", f"bearing interface stiffness -dF_{i}/d{k} [N/m]",
                                unit="N/m")
                    self._input(f"{b}.damping.{i}{k}", f"bearing interface damping -dF_{i}/dv{k} [N s/m]",
                                unit="N.s/m")
            self._input(f"{b}.torque", "film torque on the journal about +z [N m] (the bearing's journal_torque; "
                        "brakes the rotor when speed_source = torque)", unit="N.m")
        from frbmodel.nonlinear.components import COUPLING_COLUMNS

        pos = self._input_pos
        # positions in self._input_values of the rotor component's packed coupling array (bearings x COUPLING_COLUMNS)
        self._coupling_idx = np.array([[pos[f"{b}.{c}"] for c in COUPLING_COLUMNS] for b in self._bearings])
        self._torque_idx = np.array([pos[f"{b}.torque"] for b in self._bearings])
        self._speed_in, self._drive = pos["speed_in"], pos["drive_torque"]

    def _outputs(self):
        """Speed, journal states per bearing, disc centres per disc, linearization sized by the node count. All but
        the linearization are one array of the state (:meth:`_state_out`)."""
        k = iter(range(10 ** 6))

        def state(name, desc, unit):
            i = next(k)
            self._output(name, desc, lambda: self._state_out()[i], unit=unit, block=(self._state_out, i),
                         depends=(), init_depends=("speed_in",))

        state("rotor_speed", "rotor spin speed [rad/s]", "rad/s")
        state("rotor_angle", "rotor rotation angle about +z since t = 0 [rad]", "rad")
        for b in self._bearings:
            for q, u in JOURNAL:
                state(f"{b}.journal.{q}", f"journal {q} [{u}]", u)
        for w in self._discs:
            for q in "xy":
                state(f"{w}.{q}", f"{w} centre {q} [m]", "m")
        n_nodes, nb = self._built_for.rotor.n_nodes, len(self._bearings)
        x_units = ["m", "m", "rad", "rad"] * n_nodes + ["m/s", "m/s", "rad/s", "rad/s"] * n_nodes
        self._linearization_outputs(x_units, ["N", "N"] * nb, [u for _ in range(nb) for _, u in JOURNAL],
                                    ("states: q, dq/dt (per node x, y, rotation about x, about y)",
                                     "inputs: bearing forces x, y per bearing",
                                     "outputs: journal x, y, vx, vy per bearing"), depends=())

    # ------------------------------------------------------------------ helpers
    def _state_out(self):
        """rotor speed [rad/s], angle [rad], journal x, y, vx, vy per bearing [m, m/s], disc centre x, y per disc
        [m]; computed once per change of the state."""
        if self._out_gen != self._gen:
            c = self._comp
            out = np.empty(2 + self._y_idx.size)
            out[0], out[1] = c.rotor_speed, c.phi
            out[2:] = c.y[self._y_idx]
            self._out_cache, self._out_gen = out, self._gen
        return self._out_cache

    def _linear(self):
        from frbmodel.nonlinear.components import rotor_state_space

        return rotor_state_space(self._comp)

    # ------------------------------------------------------------------ FMI (FrbSlaveMixin hooks)
    def _initialize(self):
        """Build the component from the (range-checked) parameters and the system of ``rotor_file`` (the built-in
        one when empty); raises when that system's structure differs from the one the FMU was built for."""
        import frbmodel as frb
        from frbmodel.core.units import rad_s_to_rpm
        from frbmodel.cosim.fmu_system import structure_differences
        from frbmodel.nonlinear.components import RotorComponent, ramp_speed

        v = self._values
        tc = frb.load_system(v["rotor_file"]) if v["rotor_file"] else self._built_for
        diff = structure_differences(self._built_for, tc)
        if diff:
            raise ValueError(f"rotor_file = {v['rotor_file']!r} does not fit this FMU's variables: "
                             f"{'; '.join(diff)}. Build an FMU for that system: frb build-fmus --rotor-file FILE")
        tc = tc.with_(gravity=float(v["gravity"]))
        unb = [frb.Unbalance(w, float(v[f"{w}.unbalance"]), float(v[f"{w}.unbalance_phase"])) for w in self._discs
               if v[f"{w}.unbalance"] > 0]
        speed = ramp_speed(rad_s_to_rpm(float(v["speed_start"])), rad_s_to_rpm(float(v["speed_end"])),
                           float(v["ramp_time"]))
        source = v["speed_source"]
        w0 = float(self._in("speed_in") if source == "input" else v["speed_start"])
        if not math.isfinite(w0):
            raise ValueError(f"speed_in = {w0!r} rad/s is invalid at the end of initialization with speed_source = "
                             "'input' (it is the rotor speed before the first step): it must be finite")
        comp = RotorComponent(tc, speed, unb, float(v["substep"]), speed_source=source, initial_speed=w0)
        journals = [(float(v[f"{b}.journal_x0"]), float(v[f"{b}.journal_y0"])) for b in self._bearings]
        for name, (x0, y0), b in zip(self._bearings, journals, tc.bearings):
            room = b.inner.clearance + b.outer.clearance
            if not math.hypot(x0, y0) < room:
                raise ValueError(f"{name}.journal_x0, journal_y0 = ({x0!r}, {y0!r}) m is invalid: valid range "
                                 f"sqrt(x0^2 + y0^2) < inner + outer clearance = {room:g} m (the journal inside its "
                                 "bearing)")
        comp.y[:comp.n] = tc.rotor.static_deflection([b.node for b in tc.bearings], journals, tc.gravity)
        n = comp.n
        journals = [[i, k, n + i, n + k] for i, k in comp.jdofs]  # x, y, vx, vy of each journal in the state y
        node = {d.name: d.node for d in tc.rotor.discs}
        discs = [[4 * node[w], 4 * node[w] + 1] for w in self._discs]
        self._y_idx = np.array([i for idx in journals + discs for i in idx], dtype=np.intp)
        self._out_gen = None
        self._comp = comp
        self._changed()
        self._warm_up(w0)

    def _warm_up(self, w0):
        """Load (or compile) the rotor step's compiled kernel now, in initialization, not in the first doStep: one
        1 ns step of a copy without bearing forces (nothing is kept)."""
        import copy

        from frbmodel.nonlinear.components import COUPLING_COLUMNS

        nb = len(self._bearings)
        try:
            copy.deepcopy(self._comp).step_coupled(1e-9, np.zeros((nb, len(COUPLING_COLUMNS))), False, speed_in=w0,
                                                   drive_torque=0.0, journal_torques=np.zeros(nb))
        except Exception:  # noqa: BLE001
            pass

    def _advance(self, current_time, step_size):
        """One step of the component with the bearing inputs gathered into its packed coupling array (it refuses
        non-finite ones, naming them: F0, K, C, journal_ref always, force_end and journal_accel with
        ``force_interpolation``)."""
        x = self._input_values
        self._comp.step_coupled(step_size, x[self._coupling_idx], self._values["force_interpolation"],
                                speed_in=float(x[self._speed_in]), drive_torque=float(x[self._drive]),
                                journal_torques=x[self._torque_idx])

    def _step_context(self):
        from frbmodel.core.units import rad_s_to_rpm

        w = self._comp.rotor_speed
        return f"rotor speed {rad_s_to_rpm(w):.0f} rpm: " if math.isfinite(w) else ""

    def _component_state(self):
        """Rotor DoFs, angle, time and spin state (speed, rate, last speed input): RotorComponent.state()."""
        return self._comp.state()

    def _set_component_state(self, st):
        self._comp.set_state(st)
