"""Build the bearing and rotor FMUs with pythonfmu and pack the SSP system.

The FMU sources (``fmu_src/``) and the SSP folder (``ssp/``) are top-level folders of the repository; the
wheel ships copies of both as ``frbmodel/_data/fmu_src`` and ``frbmodel/_data/ssp`` (pyproject.toml), so
``frb build-fmus`` works from a plain ``pip install`` as well as from a checkout.
"""
from __future__ import annotations

import json
import shutil
import sys
import tempfile
import zipfile
from pathlib import Path

import frbmodel

from .fmu_system import as_system, check_rotor_system, write_rotor_system
from .loader import install_loader
from .sources import PACKAGE, PACKAGE_DATA, find_source  # noqa: F401  (re-exported)
from .ssp import write_engine_ssp, write_ssp

#: build options inside each FMU's resources, read by the slaves (fmu_src/_fmu_common.py BUILD_OPTIONS)
BUILD_OPTIONS = "frb_build.json"

#: the component FMUs of the split (bearing, rotor: frb cosim's staggered scheme) and the whole turbocharger in one
#: FMU (for any master at any step)
FMUS = ("FloatingRingBearing", "TurbochargerRotor", "FloatingRingTurbocharger", "EngineTorque")
#: the FMUs of each packed SSP: the split (ssp/) and the example engine + turbocharger (ssp/engine/)
SPLIT_FMUS, ENGINE_FMUS = ("FloatingRingBearing", "TurbochargerRotor"), ("EngineTorque", "FloatingRingTurbocharger")
#: the example's SSP folder inside ssp/, packed as engine_turbocharger.ssp
ENGINE_SSP = "engine"
#: FMUs whose variables follow the system they are built for (``rotor_file``)
SYSTEM_FMUS = ("TurbochargerRotor", "FloatingRingTurbocharger")


def _bundle_ignore(dirname, names):
    """shutil.copytree filter for the frbmodel copy inside each FMU: no caches, no packaged FMU sources."""
    skip = {n for n in names if n == "__pycache__" or n.endswith((".pyc", ".nbi", ".nbc"))}
    if Path(dirname) == PACKAGE and "_data" in names:
        skip.add("_data")  # fmu_src/ and ssp/: already the FMU's own script and the SSP, not needed at run time
    return skip


def _pack_ssp(ssp, ssp_src, fmus):
    """Zip the SSP folder ``ssp_src`` (SSDs and parameter sets; not the example's subfolder) and the FMUs into the
    archive ``ssp``."""
    with zipfile.ZipFile(ssp, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(ssp_src.rglob("*")):
            rel = f.relative_to(ssp_src)
            if (f.is_file() and "__pycache__" not in rel.parts and rel.parts[0] != ENGINE_SSP
                    and f.suffix not in (".py", ".pyc", ".fmu")):
                z.write(f, rel)
        for fmu in fmus:
            z.write(fmu, f"resources/{fmu.name}")


def build_fmus(out_dir="build", src=None, progress=print, rotor_file=None, linearization=False):
    """Build the FMUs (each bundling this frbmodel) and the SSP archive.

    Parameters
    ----------
    out_dir : str or Path
        Output folder; gets ``fmus/FloatingRingBearing.fmu``, ``fmus/TurbochargerRotor.fmu``,
        ``fmus/FloatingRingTurbocharger.fmu``, ``fmus/EngineTorque.fmu``, ``turbocharger.ssp`` (the ``ssp/``
        folder plus the bearing and rotor FMUs) and ``engine_turbocharger.ssp`` (``ssp/engine/`` plus the engine
        and turbocharger FMUs).
    src : str or Path, optional
        Folder with ``fmu_src/`` and ``ssp/`` (see :func:`find_source`).
    progress : callable, optional
        Called with one message per written file.
    rotor_file : Turbocharger or str or Path, optional
        The system the rotor and turbocharger FMUs are built for (a file written by ``frb system``): its discs,
        bearings and node count define their variables. Default: the Table 2 turbocharger.
    linearization : bool
        Give the bearing and rotor FMUs their linearization outputs (nx, nu, ny, A_i_j ... D_i_j) for
        ``frb linearize``; without it they have none (a host reading all outputs reads 1440 numbers less per step).

    Returns
    -------
    list of Path
        The four FMUs and the two SSP archives.

    Each FMU gets the loader of :mod:`frbmodel.cosim.loader` in front of pythonfmu's binary, so that it runs in
    non-Python hosts too (skipped with a warning where no C compiler or shared libpython is found).
    """
    src = find_source(src)  # before importing pythonfmu: a missing source is named even without the fmi extra

    if rotor_file is not None:  # (read and checked before any folder is made)
        rotor_file = check_rotor_system(rotor_file)
    out = Path(out_dir)
    (out / "fmus").mkdir(parents=True, exist_ok=True)
    paths = []
    with tempfile.TemporaryDirectory(prefix="frb_fmu_") as tmp:
        bundle = Path(tmp) / "frbmodel"
        shutil.copytree(PACKAGE, bundle, ignore=_bundle_ignore)
        options = Path(tmp) / BUILD_OPTIONS
        options.write_text(json.dumps({"linearization": bool(linearization)}), encoding="utf-8")
        system = [write_rotor_system(rotor_file, tmp)] if rotor_file is not None else []
        for name in FMUS:
            extra = [options, *(system if name in SYSTEM_FMUS else [])]
            paths.append(_build_one(src, name, out / "fmus", [bundle, src / "fmu_src" / "_fmu_common.py", *extra],
                                    progress))
    split = [p for p in paths if p.stem in SPLIT_FMUS]
    engine = [p for p in paths if p.stem in ENGINE_FMUS]
    ssps = (out / "turbocharger.ssp", out / "engine_turbocharger.ssp")
    if rotor_file is None:
        _pack_ssp(ssps[0], src / "ssp", split)
        _pack_ssp(ssps[1], src / "ssp" / ENGINE_SSP, engine)
    else:  # the SSPs of that system: its bearing components, connections and parameter sets
        with tempfile.TemporaryDirectory(prefix="frb_ssp_src_") as tmp:
            write_ssp(Path(tmp) / "ssp", system=as_system(rotor_file))
            write_engine_ssp(Path(tmp) / "engine", system=as_system(rotor_file))
            _pack_ssp(ssps[0], Path(tmp) / "ssp", split)
            _pack_ssp(ssps[1], Path(tmp) / "engine", engine)
    paths += list(ssps)
    progress(f"packed {ssps[0]} (SSD variants, parameter sets, the bearing and rotor FMUs)")
    progress(f"packed {ssps[1]} (the example engine driving the turbocharger FMU at a 1 ms step)")
    return paths


def _build_one(src, name, dest, project_files, progress):
    """Build one FMU with pythonfmu, put the loader in front of its binary and drop the binaries it cannot run
    with (pythonfmu ships a win64 DLL too, which the Linux-only loader configuration cannot start)."""
    from pythonfmu import FmuBuilder


    saved = list(sys.path)  # pythonfmu's builder puts the script's folder on sys.path and leaves it there
    try:
        fmu = Path(FmuBuilder.build_FMU(src / "fmu_src" / f"{name}.py", dest=dest, project_files=project_files,
                                        canGetAndSetFMUstate=True, canSerializeFMUstate=True,
                                        needsExecutionTool=False))
    finally:
        sys.path[:] = saved
    install_loader(fmu, src=src, progress=progress)
    progress(f"built {fmu} (bundles frbmodel {frbmodel.__version__})")
    return fmu


def built_ssp(out_dir="build", src=None, progress=print) -> Path:
    """The SSP archive in ``out_dir``, building the FMUs first if it is not there yet.

    Parameters
    ----------
    out_dir, src, progress
        As for :func:`build_fmus`.

    Returns
    -------
    Path
        ``<out_dir>/turbocharger.ssp``.
    """
    ssp = Path(out_dir) / "turbocharger.ssp"
    if not ssp.exists():
        build_fmus(out_dir, src, progress)
    return ssp
