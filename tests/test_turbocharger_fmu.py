"""The whole turbocharger as one FMU (FloatingRingTurbocharger): the monolithic answer at any macro step in any
master, its interface, its state, its errors; the example engine SSP in libcosim and frb cosim.

Expected values come from frb.runup (the monolithic reference; the FMU must reproduce it, not itself), from
SpeedProfile.torque of the same torque law, and from a second master (libcosim, the C host)."""
import json
import math
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.core.units import RPM
from frbmodel.nonlinear.runup import SpeedProfile, runup

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from _fmu import Slave  # noqa: E402
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

C_O = 36e-6  # [m] outer clearance of the main job (the FMU's default is the Table 2 system's, 36 µm too)
T_CHECK = 0.1  # [s] the acceptance window: the first 0.1 s of the main job (20 -> 250 krpm in 1 s)
JOURNAL = ["turbine_bearing.journal.x", "turbine_bearing.journal.y"]


@pytest.fixture(scope="module")
def reference():
    """frb.runup of the main job's first 0.1 s at its default tolerances, 20 kHz."""
    run = runup(frb.turbocharger(C_O), profile=SpeedProfile.ramp(20e3, 250e3, 1.0), duration=T_CHECK,
                output_rate_hz=20e3)
    df = run.to_dataframe()
    return df["time [s]"].to_numpy(), df[["journal turbine x [m]", "journal turbine y [m]"]].to_numpy()


def _fmu(built):
    return built / "fmus" / "FloatingRingTurbocharger.fmu"


@pytest.mark.parametrize("h", [1e-5, 1e-4, 1e-3, 1e-2])
def test_any_macro_step_gives_the_monolithic_run_up(built, tmp_path, reference, h):
    """fmpy FMU2Slave loop at 10 µs ... 10 ms: the turbine journal equals frb.runup of the same system and
    tolerances within 0.1 % of c_o over the first 0.1 s (the acceptance bound; measured 3e-6 ... 7e-5 c_o: the
    integrator's own error, as it meets the communication points with other internal steps)."""
    t_ref, x_ref = reference
    s = Slave(_fmu(built), f"h{h:g}", tmp_path)
    ts, xs = s.run(h, T_CHECK, JOURNAL, every=max(h, 5e-5))
    s.close()
    idx = np.round(ts * 20e3).astype(int)
    assert np.allclose(t_ref[idx], ts, rtol=0, atol=1e-12)
    assert np.abs(xs - x_ref[idx]).max() < 1e-3 * C_O


def test_a_step_of_one_solver_call_is_the_run_up_bit_for_bit():
    """One physics: stepped by the run-up's own solver-call length (100 samples at 20 kHz = 5 ms) from the
    run-up's sample times, the component takes the run-up's integrator steps exactly: the same state, bit for bit."""
    from frbmodel.nonlinear.turbocharger_component import TurbochargerComponent

    tc = frb.turbocharger(C_O)
    run = runup(tc, profile=SpeedProfile.ramp(20e3, 250e3, 1.0), duration=0.02, output_rate_hz=20e3)
    t_out = np.arange(401) / 20e3
    comp = TurbochargerComponent(tc, "ramp", 20e3 * RPM, 250e3 * RPM, 1.0)
    for k in range(0, 400, 100):
        h = t_out[k + 100] - t_out[k]
        assert t_out[k] + h == t_out[k + 100]  # (so that the component's end is the run-up's chunk end)
        comp.step(h, t=t_out[k])
    np.testing.assert_array_equal(comp.y, run.final_state)


def test_interface_of_the_turbocharger_fmu(built):
    """Validation, a system-model DefaultExperiment, no direct feedthrough (no algebraic loop in any host), units and
    min/max, serializable state, and the system's names (per bearing, per disc)."""
    fmu = _fmu(built)
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    de, cs = md.defaultExperiment, md.coSimulation
    assert (de.startTime, de.stopTime, de.stepSize) == ("0.0", "1.0", "0.001") or \
        (float(de.startTime), float(de.stopTime), float(de.stepSize)) == (0.0, 1.0, 1e-3)
    assert not cs.needsExecutionTool and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert cs.canHandleVariableCommunicationStepSize
    v = {x.name: x for x in md.modelVariables}
    for name in ("speed_in", "drive_torque", "housing_acceleration.x", "housing_acceleration.y"):
        assert v[name].causality == "input"
    tc = frb.turbocharger()
    for b in tc.bearings:
        for q, unit in (("journal_torque", "N.m"), ("power_loss", "W"), ("housing_force.x", "N"), ("eps_outer", "1"),
                        ("h_min_inner", "m"), ("ring_speed", "rad/s"), ("ring_speed_ratio", "1"),
                        ("journal.y", "m")):
            assert v[f"{b.name}_bearing.{q}"].causality == "output" and v[f"{b.name}_bearing.{q}"].unit == unit
    assert all(v[f"{d.name}.{q}"].unit == "m" for d in tc.rotor.discs for q in "xy")
    assert all(u.dependencies == [] for u in md.outputs)  # state only: rotor ↔ engine loops cannot close
    assert float(v["rtol"].min) == 1e-13 and float(v["rtol"].max) == 1e-4  # frb.runup's RTOL_RANGE
    assert float(v["turbine_bearing.outer.clearance"].min) == 0.0 and v["contact_eps"].max is not None


#: parameters whose valid range does not depend on other parameters, per FMU: each must declare it (min/max)
RANGED = {"FloatingRingBearing": ("inner.clearance", "outer.viscosity", "ring.mass", "gravity", "substep",
                                  "contact_eps"),
          "TurbochargerRotor": ("speed_start", "ramp_time", "gravity", "substep", "turbine_wheel.unbalance"),
          "FloatingRingTurbocharger": ("turbine_bearing.inner.clearance", "compressor_bearing.ring.inertia", "rtol",
                                       "atol", "contact_eps", "speed_end", "perturbation", "check_rate",
                                       "compressor_wheel.unbalance"),
          "EngineTorque": ("pulsation", "firing_frequency", "compressor_coefficient")}


def test_every_fmu_declares_a_model_description_a_host_can_trust(built, built_lin):
    """For all FMUs: DefaultExperiment, no commas in names (CSV writers), min/max on every parameter with a valid
    range, binaries only for linux64 (what the loader can start), real dependencies (the bearing force depends on
    the journal inputs; rotor and turbocharger outputs on no input; no algebraic loop rotor ↔ bearing), the
    linearization outputs only in a --linearization build, nx/nu/ny constants with the sizes."""
    steps = {"FloatingRingBearing": 1e-5, "TurbochargerRotor": 1e-5, "FloatingRingTurbocharger": 1e-3,
             "EngineTorque": 1e-3}
    for name, step in steps.items():
        fmu = built / "fmus" / f"{name}.fmu"
        assert validate_fmu(str(fmu)) == [], name
        md = read_model_description(str(fmu))
        assert float(md.defaultExperiment.stepSize) == step and float(md.defaultExperiment.stopTime) == 1.0
        assert not any("," in x.name for x in md.modelVariables), name
        assert not any(x.name in ("nx", "A_1_1") for x in md.modelVariables), name
        assert all(u.dependencies is not None for u in md.outputs), name  # none "on everything" by omission
        with zipfile.ZipFile(fmu) as z:
            plats = {n.split("/")[1] for n in z.namelist() if n.startswith("binaries/") and n.count("/") > 1}
        assert plats == {"linux64"}, (name, plats)
        v = {x.name: x for x in md.modelVariables}
        for p in RANGED[name]:  # quantities with a valid range of their own (positions depend on the clearances)
            assert v[p].min is not None, (name, p)
    deps = {u.variable.name: [d.name for d in u.dependencies] for u in
            read_model_description(str(built / "fmus" / "FloatingRingBearing.fmu")).outputs}
    assert set(deps["force.x"]) == {"journal.x", "journal.y", "journal.vx", "journal.vy", "rotor_speed"}
    assert deps["ring.x"] == [] and deps["eps_outer"] == [] and deps["journal_ref.vy"] == ["journal.vy"]
    rotor = read_model_description(str(built / "fmus" / "TurbochargerRotor.fmu"))
    assert all(u.dependencies == [] for u in rotor.outputs)  # so bearing -> rotor -> bearing is no algebraic loop
    lin = read_model_description(str(built_lin / "fmus" / "TurbochargerRotor.fmu"))
    sizes = {x.name: (x.variability, x.start) for x in lin.modelVariables if x.name in ("nx", "nu", "ny")}
    n = 2 * frb.turbocharger().rotor.n_dof
    assert sizes == {"nx": ("constant", str(n)), "nu": ("constant", "4"), "ny": ("constant", "8")}


def test_state_rollback_and_serialization_reproduce_the_steps(built, tmp_path):
    """fmi2GetFMUstate/SetFMUstate and fmi2SerializeFMUstate/DeSerialize: replaying the same steps from a restored
    (or serialized and restored) state gives the same outputs, bit for bit (the same integrator calls)."""
    s = Slave(_fmu(built), "state", tmp_path, {"speed_start": 30e3 * RPM, "speed_end": 30e3 * RPM})
    names = JOURNAL + ["turbine_bearing.power_loss", "rotor_angle"]
    s.run(1e-3, 2e-3, names)
    state = s.s.getFMUstate()
    blob = s.s.serializeFMUstate(state)
    first = [s.s.doStep(2e-3 + k * 1e-3, 1e-3) or s.get(names) for k in range(3)]
    s.s.setFMUstate(state)
    again = [s.s.doStep(2e-3 + k * 1e-3, 1e-3) or s.get(names) for k in range(3)]
    s.s.setFMUstate(s.s.deSerializeFMUstate(blob))
    third = [s.s.doStep(2e-3 + k * 1e-3, 1e-3) or s.get(names) for k in range(3)]
    s.s.freeFMUstate(state)
    s.close()
    np.testing.assert_array_equal(np.array(first), np.array(again))
    np.testing.assert_array_equal(np.array(first), np.array(third))


def test_two_turbocharger_fmus_in_one_process_equal_one_alone(built, tmp_path):
    """Instances share nothing: two interleaved instances (different clearances) give each what it gives alone."""
    p36, p46 = {}, {f"{b}_bearing.outer.clearance": 46e-6 for b in ("turbine", "compressor")}
    alone = []
    for i, p in enumerate((p36, p46)):
        s = Slave(_fmu(built), f"alone{i}", tmp_path, p)
        alone.append(s.run(1e-3, 5e-3, JOURNAL)[1])
        s.close()
    a, b = Slave(_fmu(built), "a", tmp_path, p36), Slave(_fmu(built), "b", tmp_path, p46)
    both = [[], []]
    for k in range(5):
        for i, s in enumerate((a, b)):
            s.s.doStep(k * 1e-3, 1e-3)
            both[i].append(s.get(JOURNAL))
    a.close()
    b.close()
    for i in range(2):
        np.testing.assert_array_equal(np.array(both[i]), alone[i])
    assert np.abs(alone[0] - alone[1]).max() > 1e-7  # and the two clearances differ


def test_bad_input_gives_fmi_errors_and_discards_never_nan(built, tmp_path):
    """A parameter out of range: fmi2Error at exitInitializationMode naming it; a non-finite input: Discard for that
    step, the state kept, and the next step with a finite input goes on; a step into the wall: Discard naming the
    film and contact_eps."""
    fmu = _fmu(built)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), unzipdir=str(tmp_path / "bad")),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.setReal([vr["rtol"]], [5.0])
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    s.freeInstance()
    g = Slave(fmu, "nan", tmp_path, {"speed_source": "torque"})
    g.s.setReal([vr["drive_torque"]], [math.nan])
    with pytest.raises(FMICallException, match="discard"):
        g.s.doStep(0.0, 1e-3)
    # 1e9 N m: beyond the run-up's bound (1.32e4 N m for the Table 2 rotor, 1e6 rpm from rest in 1 ms): Discard
    g.s.setReal([vr["drive_torque"]], [1e9])
    with pytest.raises(FMICallException, match="discard"):
        g.s.doStep(0.0, 1e-3)
    g.s.setReal([vr["drive_torque"]], [0.01])
    g.s.doStep(0.0, 1e-3)  # recovered: the same step again, with a finite input
    assert np.all(np.isfinite(g.get(JOURNAL)))
    good = g.get(JOURNAL)
    g.s.setReal([vr["drive_torque"]], [math.nan])
    with pytest.raises(FMICallException, match="discard"):
        g.s.doStep(1e-3, 1e-3)
    g.s.setReal([vr["drive_torque"]], [0.01])
    with pytest.raises(FMICallException, match="discard"):  # a host that ignores the Discard and steps on from
        g.s.doStep(2e-3, 1e-3)  # the later time: refused too (the FMU is still at 1 ms), outputs those of 1 ms
    np.testing.assert_array_equal(g.get(JOURNAL), good)
    g.close()
    w = Slave(fmu, "wall", tmp_path)
    w.set({"housing_acceleration.y": -3e4})  # ~3000 g upwards on every mass: the rings reach their walls
    with pytest.raises(FMICallException, match="discard"):
        w.s.doStep(0.0, 1e-3)
    w.close()


def test_torque_from_a_second_fmu_gives_the_torque_driven_run_up(built, tmp_path):
    """The engine FMU with a time-only torque law (s = k = 0: T = T_0 (1 + a sin 2π f t)) drives the turbocharger at
    a 1 ms step (a Jacobi loop; the torque of each communication point held over the step). Reference: frb.runup with
    SpeedProfile.torque of the same torque sampled and held at 1 ms (tabulated at 50 µs). Speed within 0.1 %."""
    T = 0.2
    eng = Slave(built / "fmus" / "EngineTorque.fmu", "engine", tmp_path,
                {"turbine_torque_slope": 0.0, "compressor_coefficient": 0.0, "turbine_torque_0": 0.5})
    tcf = Slave(_fmu(built), "tc", tmp_path, {"speed_source": "torque", "speed_start": 30e3 * RPM,
                                              "speed_scale": 80e3 * RPM})
    speeds = []
    for k in range(int(round(T / 1e-3))):
        eng.set({"rotor_speed": tcf.get(["rotor_speed"])[0]})
        tq = eng.get(["drive_torque"])[0]
        tcf.set({"drive_torque": tq})
        for s in (eng, tcf):
            s.s.doStep(k * 1e-3, 1e-3)
        speeds.append(tcf.get(["rotor_speed"])[0])
    eng.close()
    tcf.close()
    law = lambda t: 0.5 * (1 + 0.3 * math.sin(2 * math.pi * 100.0 * math.floor(t / 1e-3 + 1e-9) * 1e-3))  # noqa
    run = runup(frb.turbocharger(C_O), profile=SpeedProfile.torque(law, 30e3, T, n=int(T / 5e-5) + 1),
                duration=T, output_rate_hz=1e3)
    ref = run.speed_rpm[1:] * RPM
    assert np.abs(np.array(speeds) / ref - 1).max() < 1e-3
    assert speeds[-1] > 1.2 * 30e3 * RPM  # and the torque did drive it


def test_kernels_are_loaded_in_initialization_not_in_the_first_step(built, tmp_path):
    """In a fresh process, after fmi2ExitInitializationMode and before any doStep, the integrator's compiled kernel
    is there (loaded from numba's cache or compiled): a host with a step timeout is not hit by it."""
    code = f"""
import sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
fmu = {str(_fmu(built))!r}
md = read_model_description(fmu)
s = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu, unzipdir={str(tmp_path / 'k')!r}),
              modelIdentifier=md.coSimulation.modelIdentifier, instanceName="k")
s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode(); s.exitInitializationMode()
import frbmodel.nonlinear.rosenbrock as r
print(len(r.rodas_chunk.signatures))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert int(out.stdout.split()[-1]) >= 1
    for name, kernel in (("FloatingRingBearing", "_ring_step"), ("TurbochargerRotor", "_rotor_macro_step")):
        split = code.replace(str(_fmu(built)), str(built / "fmus" / f"{name}.fmu")).replace(
            "import frbmodel.nonlinear.rosenbrock as r\nprint(len(r.rodas_chunk.signatures))",
            f"import frbmodel.nonlinear.components as r\nprint(len(r.{kernel}.signatures))")
        out = subprocess.run([sys.executable, "-c", split], capture_output=True, text=True, timeout=600)
        assert out.returncode == 0 and int(out.stdout.split()[-1]) >= 1, (name, out.stderr[-2000:])


def test_engine_ssp_runs_in_libcosim_and_frb_cosim(built, tmp_path):
    """The example SSP (engine driving the turbocharger FMU at 1 ms) runs unchanged in libcosim and in frb cosim's
    Jacobi master; their rotor speeds agree to 0.1 % (libcosim passes the engine's torque one macro step later: its
    outputs are read after it stepped, ~0.2 N m·ms / J_p on a 2e4 rad/s speed), and frb cosim writes the FMU's
    20 kHz record with the run's status."""
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    from frbmodel.cosim.system_master import SystemMaster

    T = 0.05
    d = tmp_path / "engine_ssp"
    with zipfile.ZipFile(built / "engine_turbocharger.ssp") as z:
        z.extractall(d)
    ex = CosimExecution.from_ssp_file(str(d))
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    i = ex.slave_index_from_instance_name("turbocharger")
    names = {(v.name.decode() if isinstance(v.name, bytes) else v.name): v.reference for v in ex.slave_variables(i)}
    ex.step(int(round(T / 1e-3)))
    lc = obs.last_real_values(i, [names["rotor_speed"]])[0]
    run = SystemMaster(d, stop_time=T).run(tmp_path / "cosim")
    ours = run.speed_rpm[-1] * RPM
    assert abs(lc / ours - 1) < 1e-3 and ours > 1.05 * 20e3 * RPM
    meta = json.loads((tmp_path / "cosim" / "runup.json").read_text())
    assert meta["status"] == "finished" and run.time.size == int(T * 20e3) + 1
    assert (tmp_path / "cosim" / "signals.csv").read_text().startswith("time [s],turbocharger.rotor_speed")


@pytest.mark.parametrize("h", [1e-4, 1e-3])
def test_libcosim_runs_the_turbocharger_fmu_from_an_ssp_like_the_run_up(built, tmp_path, reference, h):
    """The turbocharger FMU alone in an SSP, run by libcosim's fixed-step algorithm: the turbine journal equals
    frb.runup within 0.1 % of c_o over the first 0.1 s (the acceptance bound)."""
    pytest.importorskip("libcosimpy")
    import shutil
    from xml.etree import ElementTree as ET

    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    from frbmodel.cosim.ssp import NS, _ssv_tree, ssd_tree

    d = tmp_path / "single"
    (d / "resources").mkdir(parents=True)
    for k, v in NS.items():
        ET.register_namespace(k, v)
    ssd_tree("turbocharger", "the turbocharger FMU alone", [("turbocharger", "FloatingRingTurbocharger")], [],
             "co36", h, T_CHECK).write(d / "SystemStructure.ssd", xml_declaration=True, encoding="UTF-8")
    _ssv_tree("co36", {f"{b}_bearing.outer.clearance": ("Real", C_O, "m") for b in ("turbine", "compressor")}).write(
        d / "resources" / "co36_turbocharger.ssv", xml_declaration=True, encoding="UTF-8")
    shutil.copy(_fmu(built), d / "resources")
    ex = CosimExecution.from_ssp_file(str(d))
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    i = ex.slave_index_from_instance_name("turbocharger")
    names = {(v.name.decode() if isinstance(v.name, bytes) else v.name): v.reference for v in ex.slave_variables(i)}
    t_ref, x_ref = reference
    every = max(1, int(round(5e-5 / h)))
    dev = 0.0
    for k in range(1, int(round(T_CHECK / h)) + 1):
        ex.step(1)
        if k % every == 0:
            x = np.array(obs.last_real_values(i, [names[n] for n in JOURNAL]))
            dev = max(dev, float(np.abs(x - x_ref[int(round(k * h * 20e3))]).max()))
    assert dev < 1e-3 * C_O


def test_frb_cosim_runs_the_engine_example_and_refuses_the_split_options(built, tmp_path, capsys):
    """frb cosim on the engine SSP: the Jacobi master, the FMU's record, signals.csv and the system figure; options
    that belong to the bearing + rotor split are refused with exit code 2, before anything runs."""
    from frbmodel.cli import main

    ssp = str(built / "engine_turbocharger.ssp")
    assert main(["cosim", ssp, "--stop-time", "0.01", "--out", str(tmp_path / "run")]) == 0
    for f in ("runup.csv", "runup.json", "signals.csv", "system_run.png"):
        assert (tmp_path / "run" / f).is_file(), f
    for opt in (["--adaptive"], ["--rollback"], ["--speed-source", "torque"], ["--unvalidated-step"]):
        assert main(["cosim", ssp, *opt, "--out", str(tmp_path / "refused")]) == 2
        assert "applies to the bearing + rotor split" in capsys.readouterr().err
    assert not (tmp_path / "refused" / "runup.csv").exists()


@pytest.mark.parametrize("name, outs", [("FloatingRingBearing", ["force.x", "ring.x", "ring.speed"]),
                                         ("TurbochargerRotor", ["turbine_bearing.journal.y", "rotor_angle"])])
def test_the_split_fmus_serialize_their_state_too(built, tmp_path, name, outs):
    """canSerializeFMUstate of the bearing and rotor FMUs: a serialized and restored state replays a step bit for
    bit."""
    s = Slave(built / "fmus" / f"{name}.fmu", name, tmp_path)
    if name == "FloatingRingBearing":
        s.set({"journal.x": 5e-6, "journal.y": -1e-5, "rotor_speed": 3000.0})
    s.s.doStep(0.0, 1e-5)
    blob = s.s.serializeFMUstate(s.s.getFMUstate())
    s.s.doStep(1e-5, 1e-5)
    first = s.get(outs)
    s.s.setFMUstate(s.s.deSerializeFMUstate(blob))
    s.s.doStep(1e-5, 1e-5)
    np.testing.assert_array_equal(s.get(outs), first)
    s.close()


def test_a_second_fmu_instantiated_in_the_process_imports_the_stable_copy(built, tmp_path):
    """As a tool loads an SSP: the engine FMU instantiated first, then the turbocharger FMU, before either is
    initialized. The frbmodel the turbocharger imports must be the per-user copy (numba's cache survives fresh
    extractions there), not its own fresh extraction, which pythonfmu puts first on sys.path: that recompiled the
    kernels at every start (17 s in ecos) before each slave put the copy first again."""
    code = f"""
import sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
slaves = []
for name in ("EngineTorque", "FloatingRingTurbocharger"):
    fmu = {str(built / 'fmus')!r} + "/" + name + ".fmu"
    md = read_model_description(fmu)
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu, unzipdir={str(tmp_path)!r} + "/" + name),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    s.instantiate()
    slaves.append(s)
print(sys.modules["frbmodel"].__file__)
"""
    env = {**__import__("os").environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    assert Path(out.stdout.split()[-1]).is_relative_to(tmp_path / "cache" / "frbmodel" / "fmu-pkg"), out.stdout


def test_oil_supply_temperature_input_sets_the_power_loss_as_thermal_losses(built, tmp_path):
    """Acceptance of issue #25: the turbocharger FMU with the parameter oil = SAE 5W-30 at 100 krpm (speed_source
    input, perturbation 0: it starts at the thermal equilibrium), one 1 ms step per supply temperature: each
    bearing's power_loss output equals frb.thermal_losses at the oil_supply_temperature input within 0.1 % (the
    acceptance bound; the FMU interpolates a 49-speed table: measured 8.3e-5 in the component), at 333.15 K and at
    393.15 K (a fresh instance each: a supply change moves the equilibrium, which the state then follows in time);
    the film-temperature outputs within 5 mK. Without the oil, a changed supply input discards the step."""
    from frbmodel.linear.thermal import thermal_losses

    w = 100e3 * RPM
    names = [f"{b}_bearing.{q}" for b in ("turbine", "compressor") for q in ("power_loss", "inner_film_temperature",
                                                                              "oil_flow")]
    for t_s in (333.15, 393.15):
        s = Slave(_fmu(built), f"oil{t_s:.0f}", tmp_path, {"oil": "SAE 5W-30", "speed_source": "input",
                                                             "speed_in": w, "perturbation": 0.0,
                                                             "speed_scale": 250e3 * RPM,
                                                             "oil_supply_temperature": t_s})
        s.set({"speed_in": w, "oil_supply_temperature": t_s})
        s.s.doStep(0.0, 1e-3)
        out = s.get(names).reshape(2, 3)
        s.close()
        ref = thermal_losses(frb.turbocharger(), 100e3, frb.OILS["SAE 5W-30"], t_s)
        np.testing.assert_allclose(out[:, 0], ref["power loss [W]"], rtol=1e-3)
        np.testing.assert_allclose(out[:, 1], ref["inner film temperature [K]"], rtol=0, atol=5e-3)
        assert np.all(out[:, 2] > 0)
    plain = Slave(_fmu(built), "plain", tmp_path, {"speed_source": "input", "speed_in": w})
    plain.set({"speed_in": w, "oil_supply_temperature": 333.15})
    with pytest.raises(FMICallException, match="discard"):
        plain.s.doStep(0.0, 1e-3)
    plain.close()
