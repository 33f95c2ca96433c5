"""What ships: the wheel (installed outside the checkout, it builds FMUs that step) and the SSP folder (its
parameter sets are bound by the SSDs, one SSP variant per set)."""
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
from frbmodel.cosim.ssp import read_ssp
from frbmodel.units import rpm_to_rad_s

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
            [*(ROOT / "fmu_src").glob("*.py"), *(ROOT / "ssp").glob("*.ssd"), *(ROOT / "ssp").rglob("*.ssv")]}
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

    parameters, inputs, load = _bearing_operating_point()
    env = _clean_env()
    # numba compiles the FMU's freshly extracted frbmodel copy on first use (~6 s, its cache is keyed by file
    # path); this test is about what ships, so the kernels run as Python here. test_fmi.py steps the compiled
    # FMUs (same code, built from the checkout).
    env["NUMBA_DISABLE_JIT"] = "1"
    arg = json.dumps({"site": site.getsitepackages(), "fmu": str(fmu), "unzip": str(tmp_path / "unzipped"),
                      "parameters": parameters, "inputs": inputs})
    r = json.loads(_run([sys.executable, "-I", "-S", "-c", STEP, arg], cwd=elsewhere, env=env).splitlines()[-1])
    assert Path(r["frbmodel"]).is_relative_to(tmp_path / "unzipped")  # the FMU's own copy of frbmodel
    # at the equilibrium the film force carries exactly the static reaction (closed-form short-bearing force)
    assert r["before"] == pytest.approx([0.0, load], abs=1e-9)
    # the ring starts at its equilibrium, a fixed point of its equations of motion: one 10 µs step leaves the
    # force at the load; 1e-6 relative leaves room for the equilibrium solver's residual
    assert r["after"] == pytest.approx([0.0, load], rel=1e-6, abs=1e-9)
    print(f"wheel test: {time.perf_counter() - t0:.1f} s")


# ----------------------------------------------------------------- the SSP: parameter sets bound by the SSDs
def _copy_ssp(tmp_path):
    d = tmp_path / "ssp"
    shutil.copytree(ROOT / "ssp", d)
    return d


def _edit(path, old, new):
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new))


def test_ssp_parameter_sets_come_from_the_ssd_bindings_not_file_names(tmp_path):
    d = _copy_ssp(tmp_path)
    # move one bound file and bind it from its new place; add a stray .ssv that no SSD binds
    (d / "resources" / "by_clearance").mkdir()
    moved = d / "resources" / "by_clearance" / "turbine_40um.ssv"
    (d / "resources" / "co40_turbine.ssv").rename(moved)
    _edit(d / "co40.ssd", 'source="resources/co40_turbine.ssv"', 'source="resources/by_clearance/turbine_40um.ssv"')
    shutil.copy(d / "resources" / "co36_rotor.ssv", d / "resources" / "co99_rotor.ssv")
    s = read_ssp(d)
    assert sorted(s.parameter_sets) == SETS and s.default_set == "co36"
    assert s.parameter_files["co40"]["turbine"] == (moved,)
    # the set named co<N> has outer clearance N µm in both bearings; the inner one is Table 2's 34 µm
    for name, c in (("co36", 36e-6), ("co40", 40e-6), ("co46", 46e-6)):
        p = s.parameters(name)
        assert p["turbine"]["outer.clearance"] == ("Real", c) and p["compressor"]["outer.clearance"] == ("Real", c)
        assert p["turbine"]["inner.clearance"] == ("Real", 34e-6)
    assert s.parameters() == s.parameters("co36")


def test_ssp_bindings_merge_in_order_with_inline_values(tmp_path):
    d = _copy_ssp(tmp_path)
    inline = ('<ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="co36" '
              'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"><ssv:Parameters>'
              '<ssv:Parameter name="ring.mass"><ssv:Real value="0.008" /></ssv:Parameter>'
              '</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding>')
    bound = '<ssd:ParameterBinding source="resources/co36_compressor.ssv" />'
    _edit(d / "SystemStructure.ssd", bound, bound + inline)
    p = read_ssp(d).parameters("co36")
    # SSP 1.0: a later binding overrides an earlier one; the other values stay those of the file
    assert p["compressor"]["ring.mass"] == ("Real", 0.008) and p["turbine"]["ring.mass"] == ("Real", 7.2e-3)
    assert p["compressor"]["outer.clearance"] == ("Real", 36e-6)


def test_ssp_missing_set_or_bad_variant_is_a_parameter_error(tmp_path):
    with pytest.raises(frb.ParameterError) as e:
        read_ssp(ROOT / "ssp").parameters("co50")
    assert str(ROOT / "ssp") in str(e.value) and "'co50'" in str(e.value) and str(SETS) in str(e.value)
    d = _copy_ssp(tmp_path)
    shutil.copy(d / "co42.ssd", d / "co42_copy.ssd")
    with pytest.raises(frb.ParameterError, match="co42_copy.ssd binds parameter set 'co42', which another SSD"):
        read_ssp(d)
    (d / "co42_copy.ssd").unlink()
    _edit(d / "co42.ssd", 'endElement="compressor" endConnector="journal.x"',
          'endElement="compressor" endConnector="journal.y"')
    with pytest.raises(frb.ParameterError, match="co42.ssd has other components or connections"):
        read_ssp(d)


def test_committed_ssp_variants_validate_against_the_ssp_schema():
    pytest.importorskip("fmpy")
    from fmpy.ssp.ssd import validate_tree
    from lxml import etree

    files = sorted((ROOT / "ssp").glob("*.ssd"))
    assert [f.name for f in files] == ["SystemStructure.ssd"] + [f"{s}.ssd" for s in SETS[1:]]
    for f in files:
        validate_tree(etree.parse(str(f)).getroot(), "SystemStructureDescription.xsd")
    for f in sorted((ROOT / "ssp" / "resources").glob("*.ssv")):
        validate_tree(etree.parse(str(f)).getroot(), "SystemStructureParameterValues.xsd")


def test_find_source_takes_the_checkout_and_rejects_a_bad_src(tmp_path):
    from frbmodel.cosim.build import find_source

    if Path(frb.__file__).resolve().parents[1] == ROOT:  # an editable install (the README's test command)
        assert find_source() == ROOT  # the wheel case: test_wheel_installed_outside_the_checkout_...
    with pytest.raises(frb.ParameterError, match="fmu_src/ and ssp/"):
        find_source(tmp_path)
