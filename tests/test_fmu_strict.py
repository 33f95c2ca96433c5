"""Strict FMI 2.0 behaviour of both FMUs (issue 11 item 5) and their declared units (item 4).

Each FMI call is made through fmpy's FMU2Slave with a logger that records the messages and their statuses. The
slaves never raise: they log every refusal with the status the call must return (fmi2Error for a call that is
not allowed, fmi2Discard for a step or an output that cannot be computed from the inputs). pythonfmu's own binary
can only return fmi2OK, fmi2Discard (do_step returned False) and fmi2Fatal (a Python exception); an FMU whose
binary returns the logged status (the frbmodel loader, marked by ``resources/frb_status_from_log``) must return
exactly the expected status. With pythonfmu's binary alone, the slave's side is checked in full and the test
ends as an expected failure naming the calls whose returned status differs (:func:`judge`).
"""
import math
from ctypes import byref, cdll, util
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import frbmodel as frb

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (  # noqa: E402
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
OK, DISCARD, ERROR, FATAL = 0, 2, 3, 4
#: the marker of an FMU binary that returns the statuses the slave logs (see fmu_src/_fmu_common.py)
STATUS_MARKER = "frb_status_from_log"
_LIBC = cdll.LoadLibrary(util.find_library("c"))
#: instance name -> Host: fmpy's logger proxy forwards to one Python logger per process (the last one given to
#: addLoggerProxy), so one module logger dispatches the messages by instance name
_HOSTS = {}


def _log(env, name, status, category, message):
    host = _HOSTS.get(name.decode())  # (another module's instance in this process reaches the proxy too)
    if host is not None:
        host.messages.append((int(status), message.decode("utf-8", "replace")))


_LOGGER = fmi2CallbackLoggerTYPE(_log)


class Host:
    """One FMU instance driven by fmpy's FMU2Slave; records every logged message with its status."""

    def __init__(self, fmu, name, tmp, logging_on=True):
        self.md = read_model_description(str(fmu))
        self.dir = extract(str(fmu), unzipdir=str(tmp / name))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.mapped = (Path(self.dir) / "resources" / STATUS_MARKER).is_file()
        self.messages, self.returned, self.mismatches = [], [], []
        cb = fmi2CallbackFunctions()
        cb.logger = _LOGGER
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_LIBC.calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(_LIBC.free)
        addLoggerProxy(byref(cb))  # formats the printf-style message before it reaches _log
        self._callbacks = cb  # kept alive: the FMU holds the pointer
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        _HOSTS[name] = self
        self.slave.instantiate(callbacks=cb, loggingOn=logging_on)

    def __call__(self, expected, function, *args):
        """``slave.<function>(*args)``; the slave must report ``expected`` (the worst status of the messages it
        logged during the call; pythonfmu's own fmi2Fatal message aside) and an FMU with the status marker must
        also return it. Returns (value or None, the messages of the call joined)."""
        self._callbacks.logger = _LOGGER  # fmpy's proxy forwards to the last logger given to it (another fmpy user,
        addLoggerProxy(byref(self._callbacks))  # e.g. simulate_fmu, may have given it its own): this module's again
        n = len(self.messages)
        try:
            value, returned = getattr(self.slave, function)(*args), OK
        except FMICallException as exc:
            value, returned = None, int(exc.status)
        new = self.messages[n:]
        logged = max((s for s, _ in new if s != FATAL), default=OK)
        text = " | ".join(m for _, m in new)
        assert logged == expected, f"{function}{args}: the slave reported {STATUS[logged]}, not {STATUS[expected]}: " \
                                   f"{text}"
        self.returned.append(returned)
        if returned != expected:
            assert not self.mapped, f"{function}{args} returned {STATUS[returned]}, not {STATUS[expected]}: {text}"
            self.mismatches.append(f"{function} returned {STATUS[returned]} for {STATUS[expected]}")
        return value, text

    def set(self, function, names, values, expected=OK):
        return self(expected, function, [self.vr[n] for n in names], list(values))

    def real(self, names):
        return np.array(self.slave.getReal([self.vr[n] for n in names]))

    def start(self, reals=None, strings=None):
        """setupExperiment, enterInitializationMode, parameters, exitInitializationMode (all must be OK)."""
        self(OK, "setupExperiment", None, 0.0, None)
        self(OK, "enterInitializationMode")
        if reals:
            self.set("setReal", reals.keys(), reals.values())
        if strings:
            self.set("setString", strings.keys(), strings.values())
        self(OK, "exitInitializationMode")


def judge(*hosts):
    """Free the instances (not one that pythonfmu's binary declared fatal: it has released its slave) and end
    the test as an expected failure if the FMU binary returned other statuses than the slave reported."""
    for h in hosts:
        if FATAL not in h.returned:
            h.slave.freeInstance()
    bad = [m for h in hosts for m in h.mismatches]
    if bad:
        pytest.xfail("the FMU binary is pythonfmu's own (no resources/frb_status_from_log), which can only return "
                     f"OK, Discard from doStep and Fatal; the slave reported the right statuses, but: {bad[:4]}")


def _bearing(built, name, tmp, logging_on=True):
    return Host(built / "fmus" / "FloatingRingBearing.fmu", name, tmp, logging_on)


def _rotor(built, name, tmp):
    return Host(built / "fmus" / "TurbochargerRotor.fmu", name, tmp)


JOURNAL = ("journal.x", "journal.y", "journal.vx", "journal.vy", "rotor_speed")


def _journal_inputs(k):
    """A journal orbit (3 µm around a point below the centre, 300 Hz) at 50 krpm, step k of 10 µs."""
    w = 2 * math.pi * 300 * k * 1e-5
    return [3e-6 * math.cos(w), -8e-6 + 3e-6 * math.sin(w), -3e-6 * 2 * math.pi * 300 * math.sin(w),
            3e-6 * 2 * math.pi * 300 * math.cos(w), 50e3 * math.pi / 30]


# ---------------------------------------------------------------------------------------------------- units
def test_units_module_algebra():
    from frbmodel.cosim.units import exponents, ratio

    # closed forms: N = kg m s^-2, Pa = N m^-2
    assert exponents("N") == {"kg": 1, "m": 1, "s": -2}
    assert exponents("N.s/m") == {"kg": 1, "s": -1}
    assert exponents("Pa.s") == {"kg": 1, "m": -1, "s": -1}
    assert exponents("kg.m2") == {"kg": 1, "m": 2}
    assert exponents("1") == {}
    # d(velocity)/d(position) per second = 1/s2; (m/s)/N/s = 1/kg; m/(N s) = s/kg
    assert ratio("m/s", "m", -1) == "1/s2" and ratio("m/s", "N", -1) == "1/kg" and ratio("m", "N", -1) == "s/kg"
    assert ratio("N", "m/s") == "N.s/m" and ratio("m", "rad", -2) == "m/(rad.s2)"
    with pytest.raises(ValueError, match="furlong"):
        exponents("furlong/s")


def test_every_real_variable_has_a_declared_unit(built_lin):
    """Both FMUs validate with units declared; fmpy reads a unit for every Real, each defined in the
    UnitDefinitions with the right SI exponents; spot checks by dimensional analysis of the quantities."""
    from frbmodel.cosim.units import exponents

    expected = {
        "FloatingRingBearing": {"force.x": "N", "stiffness.xy": "N/m", "damping.yx": "N.s/m",
                                "journal.vx": "m/s", "journal_accel.y": "m/s2", "rotor_speed": "rad/s",
                                "ring.inertia": "kg.m2", "ring.mass": "kg", "inner.viscosity": "Pa.s",
                                "outer.clearance": "m", "substep": "s", "contact_eps": "1", "eps_inner": "1",
                                "ring_speed_ratio": "1", "gravity": "m/s2",
                                # ring state (x, y, vx, vy), journal input, force output:
                                "A_1_3": "1", "A_3_1": "1/s2", "A_3_4": "1/s", "B_3_1": "1/s2",
                                "C_1_1": "N/m", "D_2_4": "N.s/m"},
        "TurbochargerRotor": {"turbine_wheel.unbalance": "kg.m", "turbine_wheel.unbalance_phase": "rad",
                              "ramp_time": "s", "speed_start": "rad/s", "compressor_wheel.x": "m",
                              "turbine_bearing.damping.xx": "N.s/m", "compressor_bearing.journal.vy": "m/s",
                              # state q = per node (x, y, θx, θy) of 4 nodes, then dq/dt; input: forces
                              "A_1_17": "1", "A_17_1": "1/s2", "A_17_3": "m/(rad.s2)", "A_19_1": "rad/(m.s2)",
                              "B_17_1": "1/kg", "B_1_1": "s/kg", "C_3_17": "1"},
    }
    for name, spot in expected.items():
        fmu = built_lin / "fmus" / f"{name}.fmu"
        assert validate_fmu(str(fmu)) == []
        md = read_model_description(str(fmu))
        defs = {u.name: u for u in md.unitDefinitions}
        reals = [v for v in md.modelVariables if v.type == "Real"]
        assert reals and all(v.unit in defs for v in reals), [v.name for v in reals if v.unit not in defs][:5]
        by_name = {v.name: v.unit for v in reals}
        for var, unit in spot.items():
            assert by_name[var] == unit, var
        for u in defs.values():  # each definition's BaseUnit carries the exponents its name means
            b = u.baseUnit
            got = {k: getattr(b, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad") if getattr(b, k)}
            assert got == exponents(u.name), u.name
    rpm = next(d for d in defs["rad/s"].displayUnits if d.name == "rpm")
    assert rpm.factor == pytest.approx(30 / math.pi, rel=1e-15)  # 1 rad/s = 30/π rpm


# ---------------------------------------------------------------------------------------------------- parameters
def test_all_parameters_are_fixed(built):
    """The declared variability is what the slaves enforce: every parameter is 'fixed' (settable up to
    fmi2ExitInitializationMode); none is 'tunable'."""
    for name in ("FloatingRingBearing", "TurbochargerRotor"):
        md = read_model_description(str(built / "fmus" / f"{name}.fmu"))
        params = [v for v in md.modelVariables if v.causality == "parameter"]
        assert params and {v.variability for v in params} == {"fixed"}


def test_parameter_set_in_initialization_mode_takes_effect(built, tmp_path):
    """inner.clearance 50 µm set in initialization mode: with the ring centred, eps_inner = |e| / c exactly."""
    h = _bearing(built, "clearance50", tmp_path)
    h.start({"inner.clearance": 50e-6})
    h.set("setReal", JOURNAL, [1e-5, 0.0, 0.0, 0.0, 5000.0])
    assert h.real(["eps_inner"])[0] == pytest.approx(1e-5 / 50e-6, rel=1e-12)  # round-off of |e|/c
    judge(h)


def test_fixed_parameter_set_after_initialization_is_refused(built, tmp_path):
    """inner.clearance 34 -> 50 µm after initialization: fmi2Error naming the variable; the value read back and
    the one the physics uses both stay 34 µm (eps_inner = |e| / 34 µm). The same for a String, a Boolean and a
    rotor parameter."""
    h = _bearing(built, "late", tmp_path)
    h.start()
    h.set("setReal", JOURNAL, [1e-5, 0.0, 0.0, 0.0, 5000.0])
    h(OK, "doStep", 0.0, 1e-5)
    before = h.real(["force.x", "force.y", "eps_inner", "ring.x"])
    _, msg = h.set("setReal", ["inner.clearance"], [50e-6], expected=ERROR)
    assert "inner.clearance" in msg and "fixed" in msg
    assert h.real(["inner.clearance"])[0] == 34e-6
    np.testing.assert_array_equal(h.real(["force.x", "force.y", "eps_inner", "ring.x"]), before)
    _, msg = h.set("setString", ["film_model"], ["short_corrected"], expected=ERROR)
    assert "film_model" in msg
    h(OK, "doStep", 1e-5, 1e-5)  # the instance works on with its parameters
    r = _rotor(built, "late_rotor", tmp_path)
    r.start()
    _, msg = r.set("setReal", ["gravity"], [0.0], expected=ERROR)
    assert "gravity" in msg and r.real(["gravity"])[0] == 9.81
    _, msg = r.set("setBoolean", ["force_interpolation"], [True], expected=ERROR)
    assert "force_interpolation" in msg
    judge(h, r)


@pytest.mark.parametrize("fmu, setter, name, value, words", [
    ("bearing", "setReal", "outer.clearance", -1e-6, ["-1e-06 m", "valid range (0, inf) m"]),
    ("bearing", "setReal", "ring.mass", math.nan, ["nan kg", "valid range (0, inf) kg"]),
    ("bearing", "setReal", "contact_eps", 2.0, ["2.0", "valid range [0.01, 0.9999]"]),
    ("bearing", "setReal", "substep", 0.0, ["0.0 s", "valid range [1e-09, 0.001] s"]),
    ("bearing", "setString", "film_model", "long", ["'long'", "valid values 'short', 'short_corrected'"]),
    ("bearing", "setReal", "inner.radius", 8e-3, ["0.008", "valid range < outer.radius = 0.008 m"]),  # ring bore
    ("rotor", "setReal", "speed_start", -1.0, ["-1.0 rad/s", "valid range [0, 104720] rad/s"]),
    # bounds the rotor FMU lacked (each started and stepped: 95 Mrpm after one step, 10 kg m, 1e9 m/s2) and the
    # bearing FMU's initial ring state outside its film
    ("rotor", "setReal", "speed_end", 1e12, ["1000000000000.0 rad/s", "valid range [0, 104720] rad/s"]),
    ("rotor", "setReal", "ramp_time", 1e12, ["valid range (0, 10000] s"]),
    ("rotor", "setReal", "turbine_wheel.unbalance", 10.0, ["10.0 kg.m", "valid range [0, 0.001] kg.m"]),
    ("rotor", "setReal", "turbine_wheel.unbalance_phase", 1e300, ["1e+300 rad", "valid range [-100, 100] rad"]),
    ("rotor", "setReal", "gravity", 1e9, ["1000000000.0 m/s2", "valid range [0, 1000] m/s2"]),
    ("rotor", "setReal", "turbine_bearing.journal_x0", 1.0, ["(1.0, 0.0) m", "< inner + outer clearance = 7e-05 m"]),
    ("bearing", "setReal", "ring.x0", 1.0, ["(1.0, 0.0) m", "< outer.clearance = 3.6e-05 m"]),
    ("bearing", "setReal", "ring.speed0", 1e12, ["valid range [-104720, 104720] rad/s"]),
    ("bearing", "setReal", "gravity", 1e9, ["valid range [0, 1000] m/s2"]),
    ("bearing", "setReal", "ring.y0", math.nan, ["ring.y0 = nan m is invalid: it must be a finite real number"]),
    ("rotor", "setReal", "turbine_wheel.unbalance", math.inf, ["inf kg.m", "valid range [0, 0.001] kg.m"]),
])
def test_invalid_parameters_are_an_error_naming_quantity_value_and_range(built, tmp_path, fmu, setter, name, value,
                                                                         words):
    """fmi2ExitInitializationMode with an invalid parameter: fmi2Error (not fmi2Fatal) with the quantity, the value
    and the valid range in the log; the instance refuses to step and to terminate, and can be freed."""
    h = (_bearing if fmu == "bearing" else _rotor)(built, "bad", tmp_path)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set(setter, [name], [value])
    _, msg = h(ERROR, "exitInitializationMode")
    assert name in msg and all(w in msg for w in words), msg
    if FATAL not in h.returned:
        _, msg = h(ERROR, "doStep", 0.0, 1e-5)
        assert "failed" in msg
        _, msg = h(ERROR, "terminate")  # (FMI 2.0: no fmi2Terminate in the error state)
        assert "fmi2Terminate called after the instance failed" in msg and name in msg
    judge(h)


def test_reasons_reach_a_host_that_instantiated_with_logging_off(built, tmp_path):
    """Most FMI hosts instantiate with loggingOn = fmi2False. The reason of a status above fmi2OK must still reach
    their logger (as the Modelica Reference FMUs log errors whatever loggingOn says; pythonfmu alone drops every
    message then), until the host switches all logging off with fmi2SetDebugLogging(fmi2False, 0, NULL): then the
    status is still returned, without a message."""
    h = _bearing(built, "quiet", tmp_path, logging_on=False)
    if not h.mapped:
        pytest.skip("the FMU binary is pythonfmu's own (no frbmodel loader: no C compiler at build time)")
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set("setReal", ["ring.mass"], [-1.0])
    _, msg = h(ERROR, "exitInitializationMode")  # (fails unless the Error's message arrived)
    assert "ring.mass" in msg and "valid range (0, inf) kg" in msg, msg
    judge(h)
    off = _bearing(built, "silenced", tmp_path, logging_on=False)
    off.slave.setDebugLogging(False, [])
    off(OK, "setupExperiment", None, 0.0, None)
    off(OK, "enterInitializationMode")
    off.set("setReal", ["ring.mass"], [-1.0])
    with pytest.raises(FMICallException) as ei:
        off.slave.exitInitializationMode()
    assert int(ei.value.status) == ERROR and off.messages == []
    off.slave.setDebugLogging(True, [])  # all on again: the refusal of the next call arrives
    with pytest.raises(FMICallException):
        off.slave.doStep(0.0, 1e-5)
    assert [s for s, _ in off.messages] == [ERROR] and "ring.mass" in off.messages[0][1]  # the failure repeated
    judge(off)
    # a category the host names follows its on/off, the others keep their reasons
    cat = _bearing(built, "categories", tmp_path, logging_on=False)
    cat.slave.setDebugLogging(False, ["logStatusError"])
    cat(OK, "setupExperiment", None, 0.0, None)
    cat(OK, "enterInitializationMode")
    cat.set("setReal", ["ring.mass"], [-1.0])
    with pytest.raises(FMICallException):
        cat.slave.exitInitializationMode()
    assert cat.messages == []
    cat.slave.setDebugLogging(True, ["logAll"])  # pythonfmu's "all categories"
    with pytest.raises(FMICallException):
        cat.slave.doStep(0.0, 1e-5)
    assert [s for s, _ in cat.messages] == [ERROR]
    judge(cat)


def test_rotor_file_of_another_structure_is_refused(built, tmp_path):
    """The rotor FMU built for Table 2 (4 nodes, discs turbine_wheel/compressor_wheel) refuses at initialization a
    rotor_file with another node count or other disc names, naming both; one of the same structure with other
    values is accepted (tests/test_fmi.py: heavier wheel)."""
    tc = frb.turbocharger()
    first, *rest = tc.rotor.shaft
    half = replace(first, length=first.length / 2)
    five = tc.with_(rotor=replace(tc.rotor, shaft=(half, half, *rest),
                                  discs=tuple(replace(d, node=d.node + (d.node > 0)) for d in tc.rotor.discs)),
                    bearings=tuple(replace(b, node=b.node + 1) for b in tc.bearings))
    renamed = tc.with_(rotor=replace(tc.rotor, discs=tuple(replace(d, name=d.name.replace("compressor", "fan"))
                                                            for d in tc.rotor.discs)))
    for i, (system, words) in enumerate(((five, ["node count 5", "built for 4"]),
                                         (renamed, ["disc names", "fan_wheel"]))):
        path = system.save(tmp_path / f"other{i}.toml")
        h = _rotor(built, f"other{i}", tmp_path)
        h(OK, "setupExperiment", None, 0.0, None)
        h(OK, "enterInitializationMode")
        h.set("setString", ["rotor_file"], [str(path)])
        _, msg = h(ERROR, "exitInitializationMode")
        assert "rotor_file" in msg and all(w in msg for w in words), msg
        judge(h)


# ---------------------------------------------------------------------------------------------------- doStep
def test_do_step_outside_step_mode_or_with_invalid_step_size_is_an_error(built, tmp_path):
    """doStep before initialization, with h = 0, h < 0, h = NaN, h = inf, or after fmi2Terminate: fmi2Error, and
    the refused calls change nothing (outputs identical bit for bit, the next valid step works)."""
    h = _bearing(built, "steps", tmp_path)
    _, msg = h(ERROR, "doStep", 0.0, 1e-5)
    assert "before initialization" in msg
    h.start()
    h.set("setReal", JOURNAL, _journal_inputs(0))
    h(OK, "doStep", 0.0, 1e-5)
    outs = ["force.x", "force.y", "force_end.x", "ring.x", "ring.y", "ring.speed"]
    before = h.real(outs)
    for step in (0.0, -1e-5, math.nan, math.inf):
        _, msg = h(ERROR, "doStep", 1e-5, step)
        assert "communicationStepSize" in msg and "valid range (0, inf) s" in msg
    np.testing.assert_array_equal(h.real(outs), before)
    h(OK, "doStep", 1e-5, 1e-5)
    h(OK, "terminate")
    _, msg = h(ERROR, "doStep", 2e-5, 1e-5)
    assert "after fmi2Terminate" in msg
    r = _rotor(built, "rotor_steps", tmp_path)
    r.start()
    r(ERROR, "doStep", 0.0, 0.0)
    r(OK, "doStep", 0.0, 1e-5)
    r(OK, "terminate")
    r(ERROR, "doStep", 1e-5, 1e-5)
    judge(h, r)


# ---------------------------------------------------------------------------------------------------- state machine
#: the four FMUs of frb build-fmus: every state-machine rule below holds for each (one FrbSlaveMixin)
ALL_FMUS = ("FloatingRingBearing", "TurbochargerRotor", "FloatingRingTurbocharger", "EngineTorque")
#: the words of the instantiated-state refusal of a getter
BEFORE_INIT = ("refused in the instantiated state", "before fmi2EnterInitializationMode", "after fmi2Reset")


def _probe_variables(h):
    """One Real output, Real parameter and Real input of the FMU, and its String parameters (names)."""
    def first(causality, typ="Real"):
        return [v.name for v in h.md.modelVariables if v.causality == causality and v.type == typ]

    return first("output")[0], first("parameter")[0], first("input")[0], first("parameter", "String")


def _refused_get(h, function, names):
    """``function`` (getReal, getString, ...) of ``names`` must be fmi2Error naming the first variable and the
    reason, with no value returned with fmi2OK."""
    value, msg = h(ERROR, function, [h.vr[n] for n in names])
    assert names[0] in msg and all(w in msg for w in BEFORE_INIT), msg
    if h.mapped:
        assert value is None  # fmpy raised: no value came back with fmi2OK
    return msg


@pytest.mark.parametrize("fmu", ALL_FMUS)
def test_getters_before_initialization_and_after_reset_are_an_error(built, tmp_path, fmu):
    """FMI 2.0 (section 4.2.4, the co-simulation state table) allows fmi2GetReal etc. from initialization mode on:
    in the instantiated state (a new instance, or one after fmi2Reset: pythonfmu makes a new slave) every getter is
    fmi2Error naming the variables and the reason. They returned fmi2OK with 0 for an output (and the start value
    for a parameter or an input). The model description's start values, which pythonfmu reads through the same
    getters at build time, are the values the instance reads in initialization mode."""
    h = Host(built / "fmus" / f"{fmu}.fmu", "early", tmp_path)
    out, par, inp, strings = _probe_variables(h)
    for names in ([out], [par], [inp], [out, par, inp]):
        _refused_get(h, "getReal", names)
    if strings:
        _refused_get(h, "getString", strings[:1])
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    starts = {v.name: float(v.start) for v in h.md.modelVariables if v.type == "Real" and v.start is not None}
    value, _ = h(OK, "getReal", [h.vr[n] for n in starts])
    np.testing.assert_allclose(value, list(starts.values()), rtol=1e-15, atol=0)  # (pythonfmu writes 16 digits)
    h(OK, "exitInitializationMode")
    h(OK, "doStep", 0.0, 1e-5)
    stepped, _ = h(OK, "getReal", [h.vr[out]])
    assert math.isfinite(stepped[0])
    h(OK, "reset")
    _refused_get(h, "getReal", [out])
    _refused_get(h, "getReal", [par, inp])
    h.start()  # the reset instance starts again and steps as a new one
    h(OK, "doStep", 0.0, 1e-5)
    assert h(OK, "getReal", [h.vr[out]])[0] == stepped
    judge(h)


@pytest.mark.parametrize("fmu", ALL_FMUS)
def test_terminate_outside_step_mode_is_an_error_and_changes_nothing(built, tmp_path, fmu):
    """fmi2Terminate is allowed after initialization only (FMI 2.0 section 4.2.4: stepComplete, stepFailed): before
    initialization, in initialization mode and a second time it is fmi2Error and the instance goes on as before
    (it returned fmi2OK and moved the instance to the terminated state: every later call was refused and its
    outputs read 0 with fmi2OK). After fmi2Terminate the outputs still read their last values (fmi2GetReal is
    allowed there); setReal of an input or a parameter and doStep are fmi2Error."""
    h = Host(built / "fmus" / f"{fmu}.fmu", "ends", tmp_path)
    out, par, inp, _ = _probe_variables(h)
    _, msg = h(ERROR, "terminate")
    assert "fmi2Terminate called before initialization" in msg
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    _, msg = h(ERROR, "terminate")
    assert "fmi2Terminate called in initialization mode" in msg
    h(OK, "exitInitializationMode")
    h(OK, "doStep", 0.0, 1e-5)
    before, _ = h(OK, "getReal", [h.vr[n] for n in (out, par, inp)])
    h(OK, "terminate")
    _, msg = h(ERROR, "terminate")
    assert "terminated already" in msg
    after, _ = h(OK, "getReal", [h.vr[n] for n in (out, par, inp)])
    assert after == before and all(math.isfinite(x) for x in after)
    _, msg = h.set("setReal", [inp], [before[2]], expected=ERROR)
    assert inp in msg and "terminated state" in msg
    _, msg = h.set("setReal", [par], [before[1]], expected=ERROR)
    assert par in msg and "fixed" in msg
    _, msg = h(ERROR, "doStep", 1e-5, 1e-5)
    assert "after fmi2Terminate" in msg
    judge(h)


@pytest.mark.parametrize("fmu", ALL_FMUS)
def test_parameters_are_fixed_and_refused_after_initialization(built, tmp_path, fmu):
    """Every parameter of every FMU is declared 'fixed' (none is 'tunable', FMI 2.0 section 4.2.4 table, footnote
    of fmi2SetReal in stepComplete): setting one after fmi2ExitInitializationMode is fmi2Error naming it, the value
    read back stays, and doStep before fmi2ExitInitializationMode is fmi2Error."""
    h = Host(built / "fmus" / f"{fmu}.fmu", "fixed", tmp_path)
    params = [v for v in h.md.modelVariables if v.causality == "parameter"]
    assert params and {v.variability for v in params} == {"fixed"}
    _, par, _, _ = _probe_variables(h)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    _, msg = h(ERROR, "doStep", 0.0, 1e-5)
    assert "initialization mode" in msg
    h(OK, "exitInitializationMode")
    start, _ = h(OK, "getReal", [h.vr[par]])
    _, msg = h.set("setReal", [par], [2.0 * start[0] + 1.0], expected=ERROR)
    assert par in msg and "fixed" in msg and "step mode" in msg
    assert h(OK, "getReal", [h.vr[par]])[0] == start
    h(OK, "doStep", 0.0, 1e-5)
    judge(h)


@pytest.mark.parametrize("fmu", ALL_FMUS)
def test_a_state_taken_before_initialization_brings_the_instance_back_there(built, tmp_path, fmu):
    """fmi2GetFMUstate is allowed in the instantiated state (FMI 2.0 section 4.2.4) and returns fmi2OK; the state
    serializes, and restoring it into an initialized instance brings that back to the instantiated state: its
    getters are fmi2Error (they read 0 with fmi2OK) and it initializes and steps again."""
    h = Host(built / "fmus" / f"{fmu}.fmu", "early_state", tmp_path)
    out, _, _, _ = _probe_variables(h)
    state, _ = h(OK, "getFMUstate")
    data, _ = h(OK, "serializeFMUstate", state)
    copy, _ = h(OK, "deSerializeFMUstate", data)
    h.start()
    h(OK, "doStep", 0.0, 1e-5)
    stepped, _ = h(OK, "getReal", [h.vr[out]])
    for s in (state, copy):
        h(OK, "setFMUstate", s)
        _refused_get(h, "getReal", [out])
        _, msg = h(ERROR, "doStep", 0.0, 1e-5)
        assert "before initialization" in msg
        h.start()
        h(OK, "doStep", 0.0, 1e-5)
        assert h(OK, "getReal", [h.vr[out]])[0] == stepped
    h(OK, "freeFMUstate", state)
    h(OK, "freeFMUstate", copy)
    judge(h)


# ---------------------------------------------------------------------------------------------------- inputs
def _run_bearing(h, k0, n):
    rows = []
    for k in range(k0, k0 + n):
        h.set("setReal", JOURNAL, _journal_inputs(k))
        rows.append(h.real(["force.x", "force.y", "force_end.x", "ring.x", "ring.y", "ring.speed"]))
        h(OK, "doStep", k * 1e-5, 1e-5)
    return np.array(rows)


def test_non_finite_bearing_inputs_discard_the_step_and_the_bearing_recovers(built, tmp_path):
    """A NaN or infinite input: doStep is fmi2Discard and keeps nothing of the step; an output that depends on the
    input is fmi2Discard, never a NaN with fmi2OK; with valid inputs again, the instance steps on exactly as a twin
    that never saw the bad input (bit for bit)."""
    eq = frb.equilibrium(frb.turbocharger(36e-6), "J", 50e3).bearings[0]
    ring = {"ring.x0": eq.ring[0], "ring.y0": eq.ring[1], "ring.speed0": eq.ring_speed}
    a, b = _bearing(built, "a", tmp_path), _bearing(built, "b", tmp_path)
    a.start(ring)
    b.start(ring)
    np.testing.assert_array_equal(_run_bearing(a, 0, 3), _run_bearing(b, 0, 3))
    for bad, name in ((math.nan, "journal.x"), (math.inf, "rotor_speed"), (-math.inf, "journal.vy")):
        a.set("setReal", [name], [bad])
        _, msg = a(DISCARD, "doStep", 3e-5, 1e-5)
        assert "discarded" in msg and "finite" in msg
        value, msg = a(DISCARD, "getReal", [a.vr["force.x"]])
        assert "force.x" in msg and (value is None or math.isnan(value[0]))
        for v in (x for x in a.md.modelVariables if x.causality == "output" and x.type == "Real"):
            n = len(a.messages)
            try:
                value = a.slave.getReal([v.valueReference])[0]
            except FMICallException:  # Discard: allowed
                continue
            # returned OK: then the slave either reported nothing and the value is finite, or (pythonfmu's
            # binary alone) it reported Discard for a NaN
            assert math.isfinite(value) or max((s for s, _ in a.messages[n:]), default=OK) == DISCARD, v.name
    np.testing.assert_array_equal(_run_bearing(a, 3, 5), _run_bearing(b, 3, 5))
    judge(a, b)


def test_non_finite_rotor_inputs_discard_the_step_and_the_rotor_recovers(built, tmp_path):
    """The rotor: a NaN bearing force or an infinite stiffness discards the step and keeps nothing; the journal
    outputs (states) stay finite with fmi2OK; valid inputs afterwards -> the same trajectory as a twin."""
    inputs = {f"{b}_bearing.{q}": v for b in ("turbine", "compressor")
              for q, v in (("stiffness.xx", 2e6), ("stiffness.yy", 2e6), ("damping.xx", 200.0),
                           ("damping.yy", 200.0), ("force.x", 0.5), ("force.y", 3.0))}
    outs = [f"{b}_bearing.journal.{q}" for b in ("turbine", "compressor") for q in ("x", "y", "vx", "vy")]
    a, b = _rotor(built, "ra", tmp_path), _rotor(built, "rb", tmp_path)

    def run(h, k0, n):
        rows = []
        for k in range(k0, k0 + n):
            h.set("setReal", inputs.keys(), inputs.values())
            h(OK, "doStep", k * 1e-5, 1e-5)
            rows.append(h.real(outs))
        return np.array(rows)

    a.start()
    b.start()
    np.testing.assert_array_equal(run(a, 0, 3), run(b, 0, 3))
    for name, bad in (("turbine_bearing.force.x", math.nan), ("compressor_bearing.stiffness.xx", math.inf)):
        a.set("setReal", [name], [bad])
        _, msg = a(DISCARD, "doStep", 3e-5, 1e-5)
        assert f"input {name} = {bad!r}" in msg and "it must be finite" in msg, msg
        value, _ = a(OK, "getReal", [a.vr[n] for n in outs])
        assert np.isfinite(value).all()
    np.testing.assert_array_equal(run(a, 3, 5), run(b, 3, 5))
    judge(a, b)


# ---------------------------------------------------------------------------------------------------- FMU state
def test_a_state_restored_after_reset_steps_on_from_that_state(built, tmp_path):
    """fmi2SetFMUstate after fmi2Reset (pythonfmu makes a new slave, without its component): the state's component
    is rebuilt from its parameters and the instance steps on exactly as before the reset (it read 0 with fmi2OK and
    the next doStep was fmi2Fatal: 'NoneType' object has no attribute 'state')."""
    h = _bearing(built, "reset_state", tmp_path)
    h.start({"outer.clearance": 40e-6})
    outs = ["force.x", "force.y", "ring.x", "ring.y", "ring.speed"]
    h.set("setReal", JOURNAL, _journal_inputs(0))
    h(OK, "doStep", 0.0, 1e-5)
    state, _ = h(OK, "getFMUstate")
    h.set("setReal", JOURNAL, _journal_inputs(1))
    h(OK, "doStep", 1e-5, 1e-5)
    after = h.real(outs)
    h(OK, "reset")
    h(OK, "setFMUstate", state)
    h.set("setReal", JOURNAL, _journal_inputs(1))
    h(OK, "doStep", 1e-5, 1e-5)
    np.testing.assert_array_equal(h.real(outs), after)
    h(OK, "freeFMUstate", state)
    judge(h)


@pytest.mark.parametrize("speed", [-5000.0, 1e9])
def test_an_input_outside_its_declared_range_discards_the_step_and_its_outputs(built, tmp_path, speed):
    """The bearing's rotor_speed below its declared min 0 (a rotor running backwards) or above 1e6 rpm: the outputs
    that depend on it and the doStep are fmi2Discard naming the input, its value and its range (they were fmi2OK:
    the films computed at -47746 rpm, or 9.8e11 W of friction power at 9.5e9 rpm); valid again, the bearing steps
    on as a twin that never saw it. The example engine's rotor_speed likewise."""
    a, b = _bearing(built, "range_a", tmp_path), _bearing(built, "range_b", tmp_path)
    a.start()
    b.start()
    np.testing.assert_array_equal(_run_bearing(a, 0, 2), _run_bearing(b, 0, 2))
    a.set("setReal", ["rotor_speed"], [speed])
    _, msg = a(DISCARD, "getReal", [a.vr["force.x"], a.vr["power_loss"]])
    assert f"input rotor_speed = {speed!r} rad/s is invalid: valid range [0, 104720] rad/s" in msg
    _, msg = a(DISCARD, "doStep", 2e-5, 1e-5)
    assert "discarded" in msg and f"rotor_speed = {speed!r} rad/s is invalid" in msg
    a(OK, "getReal", [a.vr["ring.x"]])  # a state: it does not depend on the input
    np.testing.assert_array_equal(_run_bearing(a, 2, 2), _run_bearing(b, 2, 2))
    e = Host(built / "fmus" / "EngineTorque.fmu", "range_engine", tmp_path)
    e.start()
    e.set("setReal", ["rotor_speed"], [speed])
    _, msg = e(DISCARD, "getReal", [e.vr["drive_torque"]])
    assert f"input rotor_speed = {speed!r} rad/s is invalid" in msg
    judge(a, b, e)


def test_an_unwritable_record_folder_is_named(built, tmp_path):
    """The turbocharger FMU's record_folder where nothing can be written: fmi2Error naming the parameter (the message
    was "[Errno 2] No such file or directory: '/proc/x'" alone)."""
    h = Host(built / "fmus" / "FloatingRingTurbocharger.fmu", "record", tmp_path)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set("setString", ["record_folder"], ["/proc/x"])
    _, msg = h(ERROR, "exitInitializationMode")
    assert "record_folder = '/proc/x' cannot be written: No such file or directory" in msg, msg
    judge(h)


def test_a_record_left_open_by_the_host_ends_as_interrupted(built, tmp_path):
    """A turbocharger FMU freed after steps without fmi2Terminate (a host that crashed or forgot it): its
    record_folder's runup.json says interrupted with the time it ends at, not "running" for ever; with
    fmi2Terminate, finished."""
    import gc
    import json

    for name, terminate in (("abandoned", False), ("terminated", True)):
        h = Host(built / "fmus" / "FloatingRingTurbocharger.fmu", name, tmp_path)
        h.start(strings={"record_folder": str(tmp_path / f"rec_{name}")})
        for k in range(3):
            h(OK, "doStep", k * 1e-5, 1e-5)
        if terminate:
            h(OK, "terminate")
        judge(h)
        del h
        gc.collect()  # (the slave's getters hold it in reference cycles: collected, not freed at once)
        meta = json.loads((tmp_path / f"rec_{name}" / "runup.json").read_text())
        if terminate:
            assert meta["status"] == "finished", meta["status"]
        else:
            assert meta["status"] == "interrupted" and "ended without fmi2Terminate" in meta["message"], meta


def test_unused_inputs_round_off_passes_nan_is_named(built, tmp_path):
    """Without the parameter oil the supply inputs are unused and must stay at their start values, but to a relative
    1e-9: the FMU Compliance Checker's interpolation of a constant 363.15 K gives 363.1499999999999 K, which was
    discarded. A clearly other supply is still refused, and a NaN fed into an input the settings leave unused (the
    drive torque of a ramp-driven rotor) discards the step naming it (it was stepped with fmi2OK)."""
    h = Host(built / "fmus" / "FloatingRingTurbocharger.fmu", "unused_in", tmp_path)
    h.start()
    h.set("setReal", ["oil_supply_temperature"], [363.1499999999999])
    h(OK, "doStep", 0.0, 1e-5)
    h.set("setReal", ["oil_supply_temperature"], [363.16])
    _, msg = h(DISCARD, "doStep", 1e-5, 1e-5)
    assert "oil_supply_temperature = 363.16 needs the thermal model" in msg, msg
    h.set("setReal", ["oil_supply_temperature", "drive_torque"], [363.15, math.nan])
    _, msg = h(DISCARD, "doStep", 1e-5, 1e-5)
    assert "input drive_torque = nan N.m is invalid: it must be finite" in msg, msg
    h.set("setReal", ["drive_torque"], [0.0])
    h(OK, "doStep", 1e-5, 1e-5)
    b = _bearing(built, "unused_in_b", tmp_path)
    b.start()
    b.set("setReal", ["oil_supply_temperature"], [363.1499999999999])
    b(OK, "doStep", 0.0, 1e-5)
    judge(h, b)


def test_a_skipped_step_is_discarded_naming_the_time_the_state_is_at(built, tmp_path):
    """doStep from t = 5 s of a turbocharger FMU at t = 0: Discard, and the message says the state stays at 0 s (it
    said 'stays at t = 5 s', where it never was)."""
    h = Host(built / "fmus" / "FloatingRingTurbocharger.fmu", "skip", tmp_path)
    h.start()
    _, msg = h(DISCARD, "doStep", 5.0, 1e-5)
    assert "doStep from t = 5 s by 1e-05 s discarded, the state stays at t = 0 s" in msg, msg
    h(OK, "doStep", 0.0, 1e-5)
    judge(h)


def test_supply_inputs_declare_the_thermal_models_range(built, tmp_path):
    """The oil supply inputs' max is the thermal model's (473.15 K, 2e6 Pa; it was none, so 1e4 K was declared
    valid), and a value beyond it discards the step naming that range."""
    h = _bearing(built, "supply", tmp_path)
    v = {x.name: x for x in h.md.modelVariables}
    assert (v["oil_supply_temperature"].min, v["oil_supply_temperature"].max) == ("243.15", "473.15")
    assert float(v["oil_supply_pressure"].max) == 2e6
    h.start(strings={"oil": "SAE 5W-30"})
    h.set("setReal", JOURNAL, _journal_inputs(0))
    h.set("setReal", ["oil_supply_temperature"], [1e4])
    _, msg = h(DISCARD, "doStep", 0.0, 1e-5)
    assert "input oil_supply_temperature = 10000.0 K is invalid: valid range [243.15, 473.15] K" in msg, msg
    judge(h)


@pytest.mark.parametrize("name, value, words", [
    ("thermal.speed_max", 1e12, "thermal.speed_max = 1000000000000.0 rad/s is invalid: valid range (0, 104720] rad/s"),
    ("static_load", 1e9, "the thermal table for oil = 'SAE 5W-30', static_load = 1000000000.0 N, "
                         "thermal.speed_min ... speed_max = 1047.2 ... 26179.9 rad/s cannot be made: "),
])
def test_thermal_parameters_a_table_cannot_be_made_for_are_named(built, tmp_path, name, value, words):
    """trust5: the bearing FMU's thermal table refused 1e12 rad/s as 'speed_rpm = np.float64(1.99e11) rpm', and a
    static load it finds no equilibrium for by the ring-speed root search alone, naming neither parameter."""
    h = _bearing(built, "thermal_params", tmp_path)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set("setString", ["oil"], ["SAE 5W-30"])
    h.set("setReal", [name], [value])
    _, msg = h(ERROR, "exitInitializationMode")
    assert words in msg, msg
    judge(h)
