"""Start-up time of the FMUs in a non-Python FMI host (issue #11): the C host tests/c_host/fmi2_host.c, started with
an empty environment, to the end of its first doStep.

Usage::

    python benchmarks/fmu_startup.py [--build build] [--steps 1]

Uses the FMUs in ``--build`` (building them if needed), compiles the C host with the system C compiler and
starts it twice per FMU, each time on a fresh extraction of the FMU (as FMI tools do). Both starts share a new,
empty cache folder (XDG_CACHE_HOME, the only variable set besides PATH): the first start copies the bundled
frbmodel there and numba compiles its kernels; the second start finds both. Target: second start < 2 s.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from _cli import count, run_script  # (benchmarks/ is the script's folder)

from frbmodel.cosim.build import built_ssp
from frbmodel.cosim.loader import PYTHONFMU_SUFFIX, find_compiler, install_loader

HOST_SRC = Path(__file__).resolve().parents[1] / "tests" / "c_host" / "fmi2_host.c"
FMUS = ("FloatingRingBearing", "TurbochargerRotor", "FloatingRingTurbocharger")


def start(host, fmu, workdir, env, steps):
    """One start of the C host on a fresh extraction: (seconds to the end of the first doStep as timed by the
    host, process wall time [s])."""
    d = Path(tempfile.mkdtemp(dir=workdir))
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
        md = ET.fromstring(z.read("modelDescription.xml"))
    mid = md.find("CoSimulation").get("modelIdentifier")
    cmd = [str(host), "-d", str(d), "-m", mid, "-g", md.get("guid"), "-n", str(steps), "-h", "1e-5", "-t"]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"{fmu.name}: exit status {r.returncode}\n{r.stderr[-2000:]}")
    first = next(float(line.split()[-1]) for line in r.stderr.splitlines() if "first_step_s" in line)
    return first, wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--steps", type=count, default=1)
    args = ap.parse_args(argv)
    cc = find_compiler()
    if cc is None:
        raise SystemExit("no C compiler: cannot build the C host")
    fmu_dir = built_ssp(args.build).parent / "fmus"
    with tempfile.TemporaryDirectory(prefix="frb_startup_") as tmp:
        tmp = Path(tmp)
        host = tmp / "fmi2_host"
        subprocess.run([*cc.split(), "-O2", "-o", str(host), str(HOST_SRC), "-ldl", "-lpthread"], check=True)
        env = {"PATH": "/usr/bin:/bin", "XDG_CACHE_HOME": str(tmp / "cache")}
        print(f"C host, empty environment (PATH, and XDG_CACHE_HOME = a new empty folder), {args.steps} step(s)")
        print(f"{'FMU':<26}{'start':>8}{'to 1st doStep [s]':>20}{'process wall [s]':>18}")
        for name in FMUS:
            fmu = tmp / f"{name}.fmu"
            shutil.copy(fmu_dir / fmu.name, fmu)
            with zipfile.ZipFile(fmu) as z:
                has_loader = f"binaries/linux64/{name}{PYTHONFMU_SUFFIX}" in z.namelist()
            if not has_loader:  # an FMU built before the loader was wired into frb build-fmus
                install_loader(fmu, progress=lambda m: None)
            for k, label in enumerate(("first", "second")):
                first, wall = start(host, fmu, tmp, env, args.steps)
                target = "   (target < 2 s)" if k else ""
                print(f"{name:<26}{label:>8}{first:20.2f}{wall:18.2f}{target}")


if __name__ == "__main__":
    run_script(main)
