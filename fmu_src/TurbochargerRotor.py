"""FMI 2.0 co-simulation slave: the turbocharger FE rotor (Euler-Bernoulli, gyroscopics, rigid wheels).

Thin adapter over :class:`frbmodel.components.RotorComponent`; the bearing forces arrive linearized at the
communication point (force, stiffness, damping per bearing) and are applied linear-implicitly over the step.
"""
import numpy as np
from _fmu_common import FrbSlaveMixin, finite
from pythonfmu import Fmi2Slave

BEARINGS = ("turbine_bearing", "compressor_bearing")
WHEELS = ("turbine_wheel", "compressor_wheel")


class TurbochargerRotor(FrbSlaveMixin, Fmi2Slave):
    author = "frbmodel"
    description = "Turbocharger rotor, FE model (paper Table 2 by default), prescribed speed ramp."

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._init_state()
        self._param("rotor_file", "", "frbmodel system description (.toml/.json, see frb system) whose rotor, bearing "
                    "nodes and gravity are used; empty = the bundled paper Table 2 rotor", "str")
        # defaults: the paper's Table 2 system and the default run-up of frbmodel.presets
        from frbmodel.components import ROTOR_SUBSTEP
        from frbmodel.presets import RUNUP_DURATION, RUNUP_SPEED_RPM, turbocharger
        from frbmodel.units import rpm_to_rad_s

        tc = turbocharger()
        self._param("speed_start", rpm_to_rad_s(RUNUP_SPEED_RPM[0]), "rotor speed at t = 0 [rad/s]")
        self._param("speed_end", rpm_to_rad_s(RUNUP_SPEED_RPM[1]), "rotor speed after the ramp [rad/s]")
        self._param("ramp_time", RUNUP_DURATION, "duration of the linear speed ramp [s]")
        for w in WHEELS:
            self._param(f"{w}.unbalance", 0.0, f"{w} unbalance (mass x eccentricity) [kg m]")
            self._param(f"{w}.unbalance_phase", 0.0, f"{w} unbalance phase from +x [rad]")
        for b in BEARINGS:
            self._param(f"{b}.journal_x0", 0.0, f"initial journal centre x at the {b} [m]")
            self._param(f"{b}.journal_y0", 0.0, f"initial journal centre y at the {b} [m]")
        self._param("gravity", tc.gravity, "gravitational acceleration along -y [m/s2]")
        self._param("substep", ROTOR_SUBSTEP, "trapezoidal substep [s]")
        self._param("linearization", False, "publish the local state-space matrices A, B, C, D", "bool")
        self._param("force_interpolation", False, "interpolate the bearing force between force and force_end over the "
                    "step (staggered masters that step the bearings first); false for Jacobi masters", "bool")
        for b in BEARINGS:
            self._input(f"{b}.force.x", "bearing force on the journal, x [N]")
            self._input(f"{b}.force.y", "bearing force on the journal, y [N]")
            self._input(f"{b}.force_end.x", "bearing force at the end of the step, x [N] (force_interpolation)")
            self._input(f"{b}.force_end.y", "bearing force at the end of the step, y [N] (force_interpolation)")
            self._input(f"{b}.journal_accel.x", "journal acceleration of the bearing's extrapolated path, x [m/s2] "
                        "(force_interpolation)")
            self._input(f"{b}.journal_accel.y", "journal acceleration of the bearing's extrapolated path, y [m/s2] "
                        "(force_interpolation)")
            for q, u in (("x", "m"), ("y", "m"), ("vx", "m/s"), ("vy", "m/s")):
                self._input(f"{b}.journal_ref.{q}", f"journal {q} at which the bearing force was evaluated [{u}]")
            for i in range(2):
                for k in range(2):
                    self._input(f"{b}.stiffness[{i + 1},{k + 1}]", "bearing interface stiffness [N/m]")
                    self._input(f"{b}.damping[{i + 1},{k + 1}]", "bearing interface damping [N s/m]")
        self._output("rotor_speed", "rotor spin speed [rad/s]", lambda: self._comp.speed(self._comp.t)[0])
        for bi, b in enumerate(BEARINGS):
            for qi, (q, u) in enumerate((("x", "m"), ("y", "m"), ("vx", "m/s"), ("vy", "m/s"))):
                self._output(f"{b}.journal.{q}", f"journal {q} [{u}]", lambda bi=bi, qi=qi: self._comp.journal(bi)[qi])
        for w in WHEELS:
            for qi, q in enumerate("xy"):
                self._output(f"{w}.{q}", f"{w} centre {q} [m]",
                             lambda w=w, qi=qi: self._comp.node_xy(self._node[w])[qi])
        self._linearization_outputs(32, 4, 8, ("states: q, dq/dt", "inputs: bearing forces x, y per bearing",
                                                "outputs: journal x, y, vx, vy per bearing"))

    _KEYS = {b: ([f"{b}.force.x", f"{b}.force.y"],
                 [f"{b}.stiffness[{i},{k}]" for i in (1, 2) for k in (1, 2)],
                 [f"{b}.damping[{i},{k}]" for i in (1, 2) for k in (1, 2)],
                 [f"{b}.journal_ref.{q}" for q in ("x", "y", "vx", "vy")],
                 [f"{b}.force_end.x", f"{b}.force_end.y"],
                 [f"{b}.journal_accel.x", f"{b}.journal_accel.y"]) for b in BEARINGS}

    def _bearing_inputs(self):
        v = self._values
        F, K, C, self._refs, self._fend, self._acc = [], [], [], [], [], []
        for b in BEARINGS:
            kf, kk, kc, kr, ke, ka = self._KEYS[b]
            F.append(np.array([v[k] for k in kf]))
            K.append(np.array([v[k] for k in kk]).reshape(2, 2))
            C.append(np.array([v[k] for k in kc]).reshape(2, 2))
            self._refs.append(np.array([v[k] for k in kr]))
            self._fend.append(np.array([v[k] for k in ke]))
            self._acc.append(np.array([v[k] for k in ka]))
        return F, K, C

    def _linear(self):
        if not self._values["linearization"]:
            return {"A": np.zeros((32, 32)), "B": np.zeros((32, 4)), "C": np.zeros((8, 32)), "D": np.zeros((8, 4))}
        from frbmodel.components import rotor_state_space

        return rotor_state_space(self._comp)

    def exit_initialization_mode(self):
        self._require_version()
        import frbmodel as frb
        from frbmodel.components import RotorComponent, ramp_speed
        from frbmodel.units import rad_s_to_rpm

        v = self._values
        try:
            tc = frb.load_system(v["rotor_file"]) if v["rotor_file"] else frb.turbocharger()
            tc = tc.with_(gravity=finite("gravity", v["gravity"], 0.0, unit="m/s2"))
            w0 = finite("speed_start", v["speed_start"], 0.0, unit="rad/s")
            w1 = finite("speed_end", v["speed_end"], 0.0, unit="rad/s")
            ramp = finite("ramp_time", v["ramp_time"], 0.0, unit="s")
            unb = [frb.Unbalance(w, finite(f"{w}.unbalance", v[f"{w}.unbalance"], 0.0, unit="kg m"),
                             finite(f"{w}.unbalance_phase", v[f"{w}.unbalance_phase"])) for w in WHEELS
                   if v[f"{w}.unbalance"] > 0]
            self._comp = RotorComponent(tc, ramp_speed(rad_s_to_rpm(w0), rad_s_to_rpm(w1), ramp), unb,
                                        finite("substep", v["substep"], 1e-9, 1e-3, "s"))
            journals = [(finite(f"{b}.journal_x0", v[f"{b}.journal_x0"]),
                         finite(f"{b}.journal_y0", v[f"{b}.journal_y0"])) for b in BEARINGS]
            nodes = [b.node for b in tc.bearings]
            self._comp.y[:self._comp.n] = tc.rotor.static_deflection(nodes, journals, tc.gravity)
            self._node = {d.name: d.node for d in tc.rotor.discs}
        except Exception as exc:  # noqa: BLE001
            self._error(f"{self.instance_name}: invalid parameters: {exc}")
            raise
        self._ready = True

    def do_step(self, current_time, step_size):
        if not self._ready:
            return self._error(f"{self.instance_name}: doStep called before initialization (or after a failure)")
        try:
            F, K, C = self._bearing_inputs()
            if not np.isfinite(np.concatenate(F + [k.ravel() for k in K] + [c.ravel() for c in C] + self._refs)).all():
                raise ValueError(f"bearing inputs are not finite: force {F}, stiffness {K}, damping {C}, "
                                 f"journal_ref {self._refs}")
            path = None
            if self._values["force_interpolation"]:
                path = (self._fend, self._acc)
                if not np.isfinite(np.concatenate(self._fend + self._acc)).all():
                    raise ValueError(f"bearing force_end / journal_accel inputs are not finite: {self._fend!r}, "
                                     f"{self._acc!r}")
            self._comp.step(step_size, F, K, C, self._refs, path=path)
        except Exception as exc:  # noqa: BLE001
            self._ready = False
            return self._error(f"{self.instance_name} at t = {current_time:.6g} s: {exc}")
        return True

    def _component_state(self):
        return {"y": [float(x) for x in self._comp.y], "phi": self._comp.phi, "t": self._comp.t}

    def _set_component_state(self, st):
        self._comp.y[:] = st["y"]
        self._comp.phi, self._comp.t = st["phi"], st["t"]
