"""Build the bearing and rotor FMUs with pythonfmu and pack the SSP system."""
from __future__ import annotations

import shutil
import tempfile
import zipfile
from pathlib import Path

import frbmodel

FMUS = ("FloatingRingBearing", "TurbochargerRotor")


def find_source(root=None) -> Path:
    """The project checkout that holds ``fmu_src/`` and ``ssp/`` (default: the current directory or the
    checkout this frbmodel was imported from)."""
    cands = [Path(root)] if root else [Path.cwd(), Path(frbmodel.__file__).resolve().parents[1]]
    for c in cands:
        if (c / "fmu_src").is_dir() and (c / "ssp").is_dir():
            return c
    raise FileNotFoundError("fmu_src/ and ssp/ not found: run from a frbmodel checkout (git clone) or pass --src")


def build_fmus(out_dir="build", src=None, progress=print):
    """Build ``<out>/fmus/FloatingRingBearing.fmu`` and ``TurbochargerRotor.fmu`` (bundling frbmodel) and
    ``<out>/turbocharger.ssp``. Returns the list of written paths."""
    from pythonfmu import FmuBuilder

    src = find_source(src)
    out = Path(out_dir)
    (out / "fmus").mkdir(parents=True, exist_ok=True)
    pkg = Path(frbmodel.__file__).resolve().parent
    paths = []
    with tempfile.TemporaryDirectory(prefix="frb_fmu_") as tmp:
        bundle = Path(tmp) / "frbmodel"
        shutil.copytree(pkg, bundle, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc"))
        for name in FMUS:
            fmu = FmuBuilder.build_FMU(src / "fmu_src" / f"{name}.py", dest=out / "fmus",
                                       project_files=[bundle, src / "fmu_src" / "_fmu_common.py"],
                                       canGetAndSetFMUstate=True, canSerializeFMUstate=False,
                                       needsExecutionTool=True)
            paths.append(Path(fmu))
            progress(f"built {fmu} (bundles frbmodel {frbmodel.__version__})")
    ssp = out / "turbocharger.ssp"
    with zipfile.ZipFile(ssp, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted((src / "ssp").rglob("*")):
            if f.is_file():
                z.write(f, f.relative_to(src / "ssp"))
        for fmu in paths:
            z.write(fmu, f"resources/{fmu.name}")
    paths.append(ssp)
    progress(f"packed {ssp} (SystemStructure.ssd, parameter sets, both FMUs)")
    return paths


def built_ssp(out_dir="build", src=None, progress=print) -> Path:
    """``<out>/turbocharger.ssp``, building the FMUs first if it is not there yet."""
    ssp = Path(out_dir) / "turbocharger.ssp"
    if not ssp.exists():
        build_fmus(out_dir, src, progress)
    return ssp
