"""Non-Python FMI hosts: the FMUs built by `frb build-fmus` run in a small C host (tests/c_host/fmi2_host.c)
started with an empty environment, give the same outputs as fmpy driving the same FMU, and the host exits 0."""
import math
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.cosim.loader import CONFIG_NAME, PYTHONFMU_SUFFIX, find_compiler, install_loader

if not sys.platform.startswith("linux"):
    pytest.skip("the FMUs' loader for non-Python hosts is built for Linux only", allow_module_level=True)
fmpy = pytest.importorskip("fmpy")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

HOST_SRC = Path(__file__).resolve().parent / "c_host" / "fmi2_host.c"
#: what `env -i PATH=/usr/bin:/bin` leaves: no HOME, no locale (C), no PYTHON* variables, no LD_PRELOAD
EMPTY_ENV = {"PATH": "/usr/bin:/bin"}
STEPS, H = 1000, 1e-5


def _user_copies():
    import pwd

    root = Path(pwd.getpwuid(os.getuid()).pw_dir) / ".cache" / "frbmodel" / "fmu-pkg"
    return set(root.glob("*")) if root.is_dir() else set()


@pytest.fixture(scope="module", autouse=True)
def _remove_new_user_copies():
    """The FMUs copy their bundled frbmodel into the user's cache (by design: numba's kernels survive fresh
    extractions). The copies these tests make are removed afterwards; copies that existed before stay. (With
    pytest-xdist the suite runs with --dist loadfile: no test of this module runs on another worker meanwhile, whose
    host could be using a copy removed here. Tests of other modules make no copies in the user's cache - the
    packaging test sets XDG_CACHE_HOME to its tmp path, Python hosts import the checkout's frbmodel - else a copy
    they made meanwhile would be removed too.)"""
    before = _user_copies()
    yield
    for d in _user_copies() - before:
        shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def c_host(tmp_path_factory):
    """The C host, compiled with the system C compiler."""
    cc = find_compiler()
    if cc is None:
        pytest.skip("no C compiler (cc/gcc/clang or $CC): the C host cannot be built, and `frb build-fmus` could "
                    "not install the FMUs' loader for non-Python hosts either")
    exe = tmp_path_factory.mktemp("c_host") / "fmi2_host"
    subprocess.run([*cc.split(), "-O2", "-o", str(exe), str(HOST_SRC), "-ldl", "-lpthread"], check=True)
    return exe


def _bearing_case():
    """Inputs: the journal on a circle of 0.3 inner clearances at 500 Hz (velocities consistent), 50 krpm."""
    film = frb.turbocharger().bearings[0].inner
    t = np.arange(STEPS) * H
    r, w = 0.3 * film.clearance, 2 * math.pi * 500.0
    inputs = {"journal.x": r * np.cos(w * t), "journal.y": r * np.sin(w * t),
              "journal.vx": -r * w * np.sin(w * t), "journal.vy": r * w * np.cos(w * t),
              "rotor_speed": np.full(STEPS, 50e3 * math.pi / 30)}
    return inputs, ["force.x", "force.y"]


def _rotor_case():
    """Inputs: each bearing carries its static load plus a 200 Hz ripple of 10 %; outputs at the journals."""
    tc = frb.turbocharger()
    t = np.arange(STEPS) * H
    s = np.sin(2 * math.pi * 200.0 * t)
    inputs, outputs = {}, []
    for b, load in zip(tc.bearings, tc.bearing_loads):
        inputs[f"{b.name}_bearing.force.x"] = 0.1 * load * s
        inputs[f"{b.name}_bearing.force.y"] = load * (1 + 0.1 * s)
        outputs += [f"{b.name}_bearing.journal.x", f"{b.name}_bearing.journal.y"]
    return inputs, outputs


def _turbocharger_case():
    """Inputs: the housing shaken vertically at 300 Hz with 5 m/s²; outputs: turbine journal, losses, housing force."""
    t = np.arange(STEPS) * H
    inputs = {"housing_acceleration.y": 5.0 * np.sin(2 * math.pi * 300.0 * t)}
    return inputs, ["turbine_bearing.journal.x", "turbine_bearing.journal.y", "turbine_bearing.power_loss",
                    "compressor_bearing.housing_force.y", "rotor_speed"]


CASES = {"FloatingRingBearing": _bearing_case, "TurbochargerRotor": _rotor_case,
         "FloatingRingTurbocharger": _turbocharger_case}


def _host_args(fmu, unzipdir, inputs, outputs, tmp):
    """fmi2_host options for one FMU: inputs written to a file (first line the value references)."""
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    names = list(inputs)
    table = np.column_stack([inputs[n] for n in names])
    f = tmp / f"{md.coSimulation.modelIdentifier}_inputs.txt"
    np.savetxt(f, table, fmt="%.17g", header=" ".join(str(vr[n]) for n in names), comments="")
    return ["-d", str(unzipdir), "-m", md.coSimulation.modelIdentifier, "-g", md.guid, "-n", str(STEPS),
            "-h", repr(H), "-i", str(f), "-o", ",".join(str(vr[n]) for n in outputs)]


def _parse_host_output(text):
    """{model identifier: array (steps, 1 + outputs)} from the '# MODEL' blocks of fmi2_host's output."""
    blocks, name = {}, None
    for line in text.splitlines():
        if line.startswith("# "):
            name = line[2:].strip()
            blocks[name] = []
        elif line.strip():
            blocks[name].append([float(x) for x in line.split()])
    return {k: np.array(v) for k, v in blocks.items()}


def _stable_copy_with_kernels(fmu):
    """The per-user copy (fmu_src/_fmu_common.py) of the FMU's bundled frbmodel holding numba cache indexes, in
    the cache folder of a process without HOME or XDG_CACHE_HOME (the password database's home)."""
    import pwd

    root = Path(pwd.getpwuid(os.getuid()).pw_dir) / ".cache" / "frbmodel" / "fmu-pkg"
    with zipfile.ZipFile(fmu) as z:
        bundled = {n[len("resources/frbmodel/"):]: z.read(n) for n in z.namelist()
                   if n.startswith("resources/frbmodel/") and n.endswith(".py")}
    for d in root.glob(f"{frb.__version__}-*"):
        if all((d / "frbmodel" / n).is_file() and (d / "frbmodel" / n).read_bytes() == b for n, b in bundled.items()):
            return any((d / "frbmodel").rglob("__pycache__/*.nbi"))
    return False


def _fmpy_run(fmu, tmp, inputs, outputs):
    """The same inputs through fmpy in this (Python) process: the loader only forwards here."""
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(fmu), unzipdir=str(tmp / f"fmpy_{md.coSimulation.modelIdentifier}"))
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="fmpy")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    in_vr, out_vr = [vr[n] for n in inputs], [vr[n] for n in outputs]
    table = np.column_stack(list(inputs.values()))
    rows = []
    for k in range(STEPS):
        s.setReal(in_vr, list(table[k]))
        s.doStep(currentCommunicationPoint=k * H, communicationStepSize=H)
        rows.append([(k + 1) * H, *s.getReal(out_vr)])
    s.terminate()
    s.freeInstance()
    return np.array(rows)


def test_fmus_run_in_a_c_host_from_an_empty_environment(built, c_host, tmp_path):
    fmus = {name: built / "fmus" / f"{name}.fmu" for name in CASES}
    args, cases = [], {}
    for name, fmu in fmus.items():
        with zipfile.ZipFile(fmu) as z:
            assert f"binaries/linux64/{name}{PYTHONFMU_SUFFIX}" in z.namelist(), (
                f"{fmu.name} has no loader for non-Python hosts: frb build-fmus must call "
                "frbmodel.cosim.loader.install_loader on every FMU it builds")
        cases[name] = CASES[name]()
        unzipdir = tmp_path / f"c_{name}"  # a fresh extraction, as a tool makes at every start
        with zipfile.ZipFile(fmu) as z:
            z.extractall(unzipdir)
        args += (["--"] if args else []) + _host_args(fmu, unzipdir, *cases[name], tmp_path)
    # the FMUs in one host process (the later ones find the Python the first one started)
    r = subprocess.run([str(c_host), *args], env=EMPTY_ENV, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"exit status {r.returncode}\n{r.stderr[-3000:]}"
    got = _parse_host_output(r.stdout)
    # the host imported the FMU's frbmodel from its per-user copy outside the extraction, where numba cached the
    # kernels (the next start, from another fresh extraction, finds them: benchmarks/fmu_startup.py)
    assert _stable_copy_with_kernels(fmus["FloatingRingBearing"]), "no per-user copy of the bundled frbmodel"
    for name, fmu in fmus.items():
        ref = _fmpy_run(fmu, tmp_path, *cases[name])
        assert got[name].shape == ref.shape == (STEPS, 1 + len(cases[name][1]))
        # the same kernels on the same inputs in both processes (the C host imports its own copy of the bundled
        # frbmodel, compiled separately by numba): equal to round-off. 1e-10 relative to each output's magnitude
        # over the run (a pointwise relative test would be ill-posed where a force or position crosses zero)
        err = np.abs(got[name] - ref).max(axis=0) / np.abs(ref).max(axis=0)
        assert np.all(err <= 1e-10), (name, err)


def test_python_description_can_be_overridden(built, c_host, tmp_path):
    """FRB_FMU_PYTHON_CFG names the Python description instead of the FMU's: a missing file is reported by
    fmi2Instantiate (no crash), a valid one is used."""
    fmu = built / "fmus" / "FloatingRingBearing.fmu"
    d = tmp_path / "fmu"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    inputs, outputs = _bearing_case()
    args = _host_args(fmu, d, inputs, outputs, tmp_path)
    args[args.index("-n") + 1] = "1"
    missing = tmp_path / "missing.cfg"
    r = subprocess.run([str(c_host), *args], env={**EMPTY_ENV, "FRB_FMU_PYTHON_CFG": str(missing)},
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and str(missing) in r.stderr, r.stderr
    moved = tmp_path / "python.cfg"
    shutil.move(d / CONFIG_NAME, moved)  # the FMU's own description is gone: only the variable can point to it
    r = subprocess.run([str(c_host), *args], env={**EMPTY_ENV, "FRB_FMU_PYTHON_CFG": str(moved)},
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]


def test_install_loader_is_idempotent(built, tmp_path):
    """Installing twice keeps pythonfmu's binary once, unchanged, and replaces loader and description."""
    if find_compiler() is None:
        pytest.skip("no C compiler")
    fmu = tmp_path / "FloatingRingBearing.fmu"
    shutil.copy(built / "fmus" / fmu.name, fmu)
    with zipfile.ZipFile(fmu) as z:
        before = {n: z.read(n) for n in z.namelist()}
    assert install_loader(fmu, progress=lambda m: None)
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        after = {n: z.read(n) for n in names}
    assert len(names) == len(set(names)) == len(before)
    kept = f"binaries/linux64/FloatingRingBearing{PYTHONFMU_SUFFIX}"
    assert after[kept] == before[kept] and after == before
