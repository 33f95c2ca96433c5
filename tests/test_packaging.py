"""What ships: the wheel (installed outside the checkout, it builds FMUs that step) and where `frb build-fmus`
finds the FMU sources (the SSP reader: tests/test_ssp.py)."""
import json
import os
import shutil
import site
import subprocess
import sys
import time
import venv
import zipfile
from pathlib import Path

import pytest

import frbmodel as frb
from frbmodel.core.units import rpm_to_rad_s
from frbmodel.cosim.ssp import read_ssp

ROOT = Path(__file__).resolve().parents[1]
SETS = ["co36", "co40", "co42", "co46"]
#: not part of a source tree: caches, build output, results
JUNK = shutil.ignore_patterns(".git", "build", "dist", "results", "out", "*.egg-info", "__pycache__", "*.pyc",
                              "*.nbi", "*.nbc", ".pytest_cache", ".ruff_cache")

# Loads the bearing FMU with fmpy in an interpreter that cannot import an installed frbmodel (-I -S: no site
# packages, no .pth files; the test environment's site-packages are appended as plain folders), sets the
# operating point, reads the force, does one doStep and reads it again.
STEP = """
import importlib.util, json, sys
a = json.loads(sys.argv[1])
sys.path.extend(a["site"])
assert importlib.util.find_spec("frbmodel") is None, "frbmodel must come from the FMU"
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
md = read_model_description(a["fmu"])
vr = {v.name: v.valueReference for v in md.modelVariables}
s = FMU2Slave(guid=md.guid, unzipDirectory=extract(a["fmu"], unzipdir=a["unzip"]),
              modelIdentifier=md.coSimulation.modelIdentifier, instanceName="turbine")
s.instantiate()
s.setupExperiment(startTime=0.0)
s.enterInitializationMode()
s.setReal([vr[k] for k in a["parameters"]], list(a["parameters"].values()))
s.exitInitializationMode()
s.setReal([vr[k] for k in a["inputs"]], list(a["inputs"].values()))
before = s.getReal([vr["force.x"], vr["force.y"]])
s.doStep(0.0, 1e-5)
after = s.getReal([vr["force.x"], vr["force.y"]])
s.terminate()
s.freeInstance()
print(json.dumps({"before": before, "after": after, "frbmodel": sys.modules["frbmodel"].__file__}))
"""


def _run(cmd, cwd, env=None):
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"{' '.join(map(str, cmd))} failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r.stdout


def _clean_env():
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP")}
    env["MPLBACKEND"] = "Agg"
    return env


def _fresh_venv(path, wheel):
    """A venv with only the wheel installed (no dependencies), then the test environment's site-packages
    appended as plain folders (.pth), so numpy, pythonfmu... need no download and the editable frbmodel of
    the test environment (a .pth hook there, not run from an appended folder) stays invisible."""
    venv.EnvBuilder(with_pip=False).create(path)
    py = path / ("Scripts" if os.name == "nt" else "bin") / "python"
    _run([sys.executable, "-m", "pip", "--python", py, "install", "--no-deps", "--no-index",
          "--disable-pip-version-check", wheel], cwd=path, env=_clean_env())
    purelib = Path(_run([py, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"], cwd=path).strip())
    dirs = site.getsitepackages() + ([site.getusersitepackages()] if site.ENABLE_USER_SITE else [])
    (purelib / "zz_test_environment.pth").write_text("\n".join(dirs) + "\n")
    return py, purelib


def _bearing_operating_point():
    """Turbine bearing at its method-J equilibrium (36 µm, 50 krpm), and its static load [N]."""
    tc = frb.turbocharger(36e-6)
    b, e = tc.bearings[0], frb.equilibrium(tc, "J", 50e3).bearings[0]
    parameters = {"inner.viscosity": b.inner.viscosity, "outer.viscosity": b.outer.viscosity,
                  "ring.x0": float(e.ring[0]), "ring.y0": float(e.ring[1]), "ring.speed0": float(e.ring_speed)}
    inputs = {"journal.x": float(e.journal[0]), "journal.y": float(e.journal[1]),
              "rotor_speed": rpm_to_rad_s(50e3)}
    return parameters, inputs, float(tc.bearing_loads[0])


def test_wheel_installed_outside_the_checkout_builds_fmus_that_step(tmp_path):
    """pip wheel -> fresh venv -> `frb build-fmus --out` from a folder outside the checkout -> one doStep of
    the bearing FMU (~8 s: wheel build 3 s with pip's cached setuptools, install 1 s, FMU build 2 s, step 1 s)."""
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    t0 = time.perf_counter()
    src, dist, elsewhere = tmp_path / "src", tmp_path / "dist", tmp_path / "elsewhere"
    shutil.copytree(ROOT, src, ignore=JUNK)
    elsewhere.mkdir()
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--disable-pip-version-check", "-w", dist, src],
         cwd=elsewhere, env=_clean_env())
    (wheel,) = dist.glob("frbmodel-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    modules = {f"frbmodel/{p.relative_to(ROOT / 'frbmodel').as_posix()}" for p in (ROOT / "frbmodel").rglob("*.py")}
    assert modules <= names, f"modules missing in the wheel (pyproject [tool.setuptools] packages): {modules - names}"
    data = {f"frbmodel/_data/{p.relative_to(ROOT).as_posix()}" for p in
            [*(ROOT / "fmu_src").glob("*.py"), *(ROOT / "fmu_src" / "loader").glob("*.c"),
             *(ROOT / "ssp").rglob("*.ssd"), *(ROOT / "ssp").rglob("*.ssv")]}
    assert data <= names, f"FMU sources / SSP missing in the wheel: {data - names}"

    py, purelib = _fresh_venv(tmp_path / "venv", wheel)
    where = _run([py, "-c", "import frbmodel.cosim.build as b; print(b.__file__); print(b.find_source())"],
                 cwd=elsewhere, env=_clean_env()).splitlines()
    assert Path(where[0]).is_relative_to(purelib) and Path(where[1]) == purelib / "frbmodel" / "_data"
    out = tmp_path / "fmus_out"
    _run([py.parent / "frb", "build-fmus", "--out", out], cwd=elsewhere, env=_clean_env())
    fmu = out / "fmus" / "FloatingRingBearing.fmu"
    bundled = zipfile.ZipFile(fmu).namelist()
    assert "resources/frbmodel/__init__.py" in bundled
    assert not [n for n in bundled if n.startswith("resources/frbmodel/_data")]  # not shipped twice
    ssp = read_ssp(out / "turbocharger.ssp")
    assert sorted(ssp.parameter_sets) == SETS and all(p.is_file() for p in ssp.components.values())
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(out / "fmus" / "FloatingRingTurbocharger.fmu")) == []  # the whole turbocharger too
    engine = read_ssp(out / "engine_turbocharger.ssp")
    assert sorted(engine.components) == ["engine", "turbocharger"] and all(p.is_file() for p in
                                                                           engine.components.values())

    parameters, inputs, load = _bearing_operating_point()
    env = _clean_env()
    # numba compiles the FMU's freshly extracted frbmodel copy on first use (~6 s, its cache is keyed by file
    # path); this test is about what ships, so the kernels run as Python here. test_fmi.py steps the compiled
    # FMUs (same code, built from the checkout).
    env["NUMBA_DISABLE_JIT"] = "1"
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    arg = json.dumps({"site": site.getsitepackages(), "fmu": str(fmu), "unzip": str(tmp_path / "unzipped"),
                      "parameters": parameters, "inputs": inputs})
    r = json.loads(_run([sys.executable, "-I", "-S", "-c", STEP, arg], cwd=elsewhere, env=env).splitlines()[-1])
    # the FMU's own copy of frbmodel, imported from its per-user copy (stable path: numba's cache survives extractions)
    assert Path(r["frbmodel"]).is_relative_to(tmp_path / "cache" / "frbmodel" / "fmu-pkg")
    # at the equilibrium the film force carries exactly the static reaction (closed-form short-bearing force)
    assert r["before"] == pytest.approx([0.0, load], abs=1e-9)
    # the ring starts at its equilibrium, a fixed point of its equations of motion: one 10 µs step leaves the
    # force at the load; 1e-6 relative leaves room for the equilibrium solver's residual
    assert r["after"] == pytest.approx([0.0, load], rel=1e-6, abs=1e-9)
    print(f"wheel test: {time.perf_counter() - t0:.1f} s")


# ----------------------------------------------------------------- finding the FMU sources
def test_find_source_takes_the_checkout_and_rejects_a_bad_src(tmp_path):
    from frbmodel.cosim.build import find_source

    if Path(frb.__file__).resolve().parents[1] == ROOT:  # an editable install (the README's test command)
        assert find_source() == ROOT  # the wheel case: test_wheel_installed_outside_the_checkout_...
    with pytest.raises(frb.ParameterError, match="lacks fmu_src/ and ssp/SystemStructure.ssd; pass the root of"):
        find_source(tmp_path)
    (tmp_path / "fmu_src").mkdir()
    with pytest.raises(frb.ParameterError, match="lacks ssp/SystemStructure.ssd; pass the root of a frbmodel"):
        find_source(tmp_path)


def test_build_fmus_without_sources_names_what_is_missing_and_the_fix(tmp_path, monkeypatch, capsys):
    """A broken install (no package data) used outside a checkout: `frb build-fmus` exits 2 naming the missing
    folders, where it looked, and the two fixes (reinstall, --src)."""
    import frbmodel.cosim.sources as build  # (where the FMU sources are looked up)
    from frbmodel.cli import main

    package = tmp_path / "site-packages" / "frbmodel"  # an installed package: no pyproject.toml above it
    (package / "_data" / "fmu_src").mkdir(parents=True)  # the FMU sources there, the SSP folder lost
    monkeypatch.setattr(build, "PACKAGE", package)
    monkeypatch.setattr(build, "PACKAGE_DATA", package / "_data")
    assert main(["build-fmus", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"the installed package lacks ssp/SystemStructure.ssd (in '{package / '_data'}')" in err
    assert f"'{package}' is not inside a checkout" in err
    assert "pip install --force-reinstall" in err and "--src with the root of a frbmodel checkout" in err
    assert not (tmp_path / "out").exists()  # nothing built or created before the check
    # a checkout that lost its fmu_src/ (pyproject.toml next to the package) is named as such
    checkout = tmp_path / "checkout"
    (checkout / "frbmodel" / "_data").mkdir(parents=True)
    (checkout / "pyproject.toml").write_text("")
    (checkout / "ssp").mkdir()
    (checkout / "ssp" / "SystemStructure.ssd").write_text("")
    monkeypatch.setattr(build, "PACKAGE", checkout / "frbmodel")
    monkeypatch.setattr(build, "PACKAGE_DATA", checkout / "frbmodel" / "_data")
    with pytest.raises(frb.FRBError, match=f"the checkout '{checkout}' lacks fmu_src/"):
        build.find_source()


@pytest.mark.parametrize("script, args, words", [
    ("build_fmu.py", ["--out", "x"], ["unrecognized arguments: --out"]),
    ("benchmarks/cosim.py", ["--duration", "-1"], ["argument --duration: '-1' is invalid", "finite and > 0"]),
    ("benchmarks/cosim.py", ["--unbalance=-1e-7"], ["argument --unbalance", "finite and >= 0"]),
    ("benchmarks/masters.py", ["--halvings", "-1"], ["argument --halvings", "an integer >= 0"]),
    ("benchmarks/sweep.py", ["--duration", "nan"], ["argument --duration: 'nan' is invalid"]),
    ("benchmarks/continuation.py", ["--points", "x"], ["argument --points: 'x' is not a number"]),
    ("benchmarks/thermal_table.py", ["--supply-pressure=-1"], ["argument --supply-pressure", "finite and >= 0"]),
    ("benchmarks/thermal_table.py", ["--supply-pressure", "3e7"], ["supply_pressure_Pa = 30000000.0 Pa is invalid"]),
])
def test_scripts_refuse_bad_arguments_with_exit_2_before_any_work(tmp_path, script, args, words):
    """The scripts a user runs from the checkout: a bad argument is one line naming it, its value and the valid
    range, exit status 2, nothing created (build_fmu.py once took '--help' or '--out' for its output folder)."""
    p = subprocess.run([sys.executable, str(ROOT / script), *args], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr and all(w in p.stderr for w in words), p.stderr
    assert list(tmp_path.iterdir()) == []
    if script == "build_fmu.py":
        p = subprocess.run([sys.executable, str(ROOT / script), "--help"], cwd=tmp_path, capture_output=True,
                           text=True, timeout=120)
        assert p.returncode == 0 and "out_dir" in p.stdout and list(tmp_path.iterdir()) == []
