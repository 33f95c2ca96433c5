"""FMI 2.0 co-simulation slave: a minimal engine side for the turbocharger FMU (the repository's example, not a real
engine model).

It closes the turbocharger's torque balance: the exhaust turbine drives the shaft with a torque that falls with
speed and pulsates with the engine's firing, the compressor brakes it with a torque growing with the square of the
speed,

    T_turbine    = (T_0 − s ω) (1 + a sin(2π f_fire t))
    T_compressor = k ω²
    drive_torque = T_turbine − T_compressor        [N m], ω the rotor speed [rad/s] (the input)

with T_0 (``turbine_torque_0``), s (``turbine_torque_slope``), a (``pulsation``), f_fire (``firing_frequency``) and
k (``compressor_coefficient``) as parameters. The defaults (T_0 = 2 N m, s = 6.67e-5 N m s, k = 2.47e-9 N m s²,
a = 0.3, f_fire = 100 Hz: a four-cylinder four-stroke engine at 3000 rpm) balance at 18 000 rad/s (172 krpm) and
take the Table 2 rotor (J_p = 1.26e-4 kg m²) there from 20 krpm in about a second. With s = k = 0 the torque is a
function of time only (used to check the turbocharger FMU against frb.runup with SpeedProfile.torque).

The outputs are evaluated at the communication point from the input and the time (direct feedthrough of
``rotor_speed``); doStep only advances the time.
"""
import math

from _fmu_common import FrbSlaveMixin
from pythonfmu import DefaultExperiment, Fmi2Slave

#: the rotor speed bound of frbmodel (frbmodel.core.errors.MAX_SPEED_RPM = 1e6 rpm) [rad/s]
MAX_SPEED_RAD_S = 1e6 * math.pi / 30.0


class EngineTorque(FrbSlaveMixin, Fmi2Slave):
    """Exhaust-turbine torque minus compressor load torque for the turbocharger FMU (see the module description)."""

    author = "frbmodel"
    description = ("Example engine side of a turbocharger: exhaust-turbine torque falling with speed and pulsating "
                   "at the firing frequency, minus a compressor load torque k w^2.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-3)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._init_state()
        self._t = 0.0
        self._param("turbine_torque_0", 2.0, "turbine torque at zero speed, T_0 [N m]", unit="N.m", low=-1e3, high=1e3)
        self._param("turbine_torque_slope", 2.0 / 30000.0, "fall of the turbine torque with speed, s [N m s/rad]",
                    unit="N.m.s/rad", low=0.0, high=1.0)
        self._param("compressor_coefficient", 0.8 / 18000.0 ** 2, "compressor load torque / speed^2, k "
                    "[N m s2/rad2]", unit="N.m.s2/rad2", low=0.0, high=1e-3)
        self._param("pulsation", 0.3, "relative amplitude of the firing pulsation of the turbine torque, a [-]",
                    unit="1", low=0.0, high=1.0)
        self._param("firing_frequency", 100.0, "firing frequency of the engine, f_fire [Hz]", unit="Hz", low=0.0,
                    high=1e4)
        self._input("rotor_speed", "turbocharger rotor speed w [rad/s]", 2094.3951023931954, unit="rad/s", low=0.0,
                    high=MAX_SPEED_RAD_S)
        for k, (name, desc) in enumerate((("drive_torque", "net torque on the rotor, turbine minus compressor [N m]"),
                                          ("turbine_torque", "exhaust-turbine torque [N m]"),
                                          ("compressor_torque", "compressor load torque [N m]"))):
            self._output(name, desc, lambda k=k: self._torques()[k], unit="N.m", block=(self._torques, k),
                         depends=("rotor_speed",))

    def _torques(self):
        """(drive, turbine, compressor) torque [N m] at the current time and input."""
        v = self._values
        w = self._in("rotor_speed")
        pulse = 1.0 + v["pulsation"] * math.sin(2.0 * math.pi * v["firing_frequency"] * self._t)
        turbine = (v["turbine_torque_0"] - v["turbine_torque_slope"] * w) * pulse
        compressor = v["compressor_coefficient"] * w * w
        return [turbine - compressor, turbine, compressor]

    # ------------------------------------------------------------------ FMI (FrbSlaveMixin hooks)
    def _initialize(self):
        if not math.isfinite(self._in("rotor_speed")):
            raise ValueError(f"rotor_speed = {self._in('rotor_speed')!r} rad/s is invalid: it must be finite")
        self._comp = self  # the slave is its own component: the time is its only state

    def _advance(self, current_time, step_size):
        w = self._in("rotor_speed")
        if not (math.isfinite(w) and w >= 0.0):
            raise ValueError(f"rotor_speed = {w!r} rad/s is invalid: valid range [0, inf) rad/s")
        self._t = float(current_time) + float(step_size)

    def _component_state(self):
        return {"t": self._t}

    def _set_component_state(self, st):
        self._t = float(st["t"])
