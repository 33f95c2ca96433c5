"""The whole-turbocharger FMU in several masters at several macro steps (issue #22), one run:

* accuracy: the main job (20 -> 250 krpm in 1 s, c_o = 36 um) through FloatingRingTurbocharger.fmu in fmpy (an
  FMU2Slave loop), libcosim (an SSP of the FMU alone, its fixed-step algorithm), the repository's C host (from an
  empty environment) and frb cosim's Jacobi master, at macro steps 10 us, 100 us, 1 ms and 10 ms: the largest
  deviation of the turbine journal from frb.runup over the first 0.1 s [fraction of c_o];
* onsets over the full 1 s: the FMU's own 20 kHz record at a 1 ms (and 10 ms) macro step against frb.runup:
  the tracked components' onsets and onset frequencies [%];
* speed: the main job through the FMU at a 1 ms macro step (recording 20 kHz inside) against frb.runup of the
  same run (20 kHz output), alternately, median wall and ratio; the wall of one getReal of all outputs; the time
  from spawning a Python to the end of its first doStep with the kernels cached (warm start).

    python benchmarks/turbocharger_fmu.py [--build build] [--repeats 3] [--skip-onsets]

~6 min on 2 cores (the onset part ~3 min). Prints markdown tables (README "Put the turbocharger into your tool").
"""
from __future__ import annotations

import argparse
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
from _cli import count, run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb
from frbmodel.nonlinear.runup import SpeedProfile, runup

ROOT = Path(__file__).resolve().parents[1]
C_O, T_CHECK, STEPS = 36e-6, 0.1, (1e-5, 1e-4, 1e-3, 1e-2)
JOURNAL = ["turbine_bearing.journal.x", "turbine_bearing.journal.y"]


def _slave(fmu, tmp, name, params=None):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), unzipdir=str(Path(tmp) / name)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    for k, v in (params or {}).items():
        (s.setString if isinstance(v, str) else s.setReal)([vr[k]], [v])
    s.exitInitializationMode()
    return s, vr, md


def fmpy_run(fmu, h, t_end, tmp, params=None):
    """Journal samples every 50 us (or every step, if longer) of an fmpy loop at step ``h``."""
    s, vr, _ = _slave(fmu, tmp, f"fmpy{h:g}", params)
    out, every = [vr[n] for n in JOURNAL], max(1, int(round(5e-5 / h)))
    xs = []
    for k in range(int(round(t_end / h))):
        s.doStep(k * h, h)
        if (k + 1) % every == 0:
            xs.append(s.getReal(out))
    s.terminate()
    s.freeInstance()
    return np.array(xs)


def _single_ssp(fmu, folder, h, t_end, params=None):
    """An SSP folder of the turbocharger FMU alone (main job, macro step ``h``)."""
    from frbmodel.cosim.ssp import NS, _ssv_tree, ssd_tree

    (folder / "resources").mkdir(parents=True, exist_ok=True)
    for k, v in NS.items():
        ET.register_namespace(k, v)
    ssd_tree("turbocharger", "the turbocharger FMU alone", [("turbocharger", "FloatingRingTurbocharger")], [],
             "co36", h, t_end).write(folder / "SystemStructure.ssd", xml_declaration=True, encoding="UTF-8")
    p = {f"{b}_bearing.outer.clearance": ("Real", C_O, "m") for b in ("turbine", "compressor")}
    p.update({k: ("String" if isinstance(v, str) else "Real", v, None) for k, v in (params or {}).items()})
    _ssv_tree("co36", p).write(folder / "resources" / "co36_turbocharger.ssv", xml_declaration=True, encoding="UTF-8")
    shutil.copy(fmu, folder / "resources")
    return folder


def libcosim_run(fmu, h, t_end, tmp):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    ex = CosimExecution.from_ssp_file(str(_single_ssp(fmu, Path(tmp) / f"lc{h:g}", h, t_end)))
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    i = ex.slave_index_from_instance_name("turbocharger")
    names = {(v.name.decode() if isinstance(v.name, bytes) else v.name): v.reference for v in ex.slave_variables(i)}
    every, xs = max(1, int(round(5e-5 / h))), []
    for k in range(1, int(round(t_end / h)) + 1):
        ex.step(1)
        if k % every == 0:
            xs.append(obs.last_real_values(i, [names[n] for n in JOURNAL]))
    return np.array(xs)


def c_host_run(fmu, h, t_end, tmp, host):
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = Path(tmp) / f"c{h:g}"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    n = int(round(t_end / h))
    r = subprocess.run([str(host), "-d", str(d), "-m", md.coSimulation.modelIdentifier, "-g", md.guid, "-n", str(n),
                        "-h", repr(h), "-o", ",".join(str(vr[x]) for x in JOURNAL)], env={"PATH": "/usr/bin:/bin"},
                       capture_output=True, text=True, timeout=3600)
    if r.returncode != 0:
        raise RuntimeError(f"C host exit {r.returncode}: {r.stderr[-500:]}")
    rows = np.array([[float(x) for x in line.split()] for line in r.stdout.splitlines()
                     if line.strip() and not line.startswith("#")])
    every = max(1, int(round(5e-5 / h)))
    return rows[every - 1::every, 1:]


def frb_cosim_run(fmu, h, t_end, tmp):
    from frbmodel.cosim.system_master import SystemMaster

    out = Path(tmp) / f"frb{h:g}"
    master = SystemMaster(_single_ssp(fmu, Path(tmp) / f"fs{h:g}", h, t_end), stop_time=t_end)
    run = master.run(out)  # the FMU's own 20 kHz record; the communication points are samples of it
    every = max(1, int(round(h * 20e3)))
    return np.column_stack([run.journal["turbine"][1:, 0], run.journal["turbine"][1:, 1]])[every - 1::every]


def _c_host(tmp):
    from frbmodel.cosim.loader import find_compiler

    exe = Path(tmp) / "fmi2_host"
    cc = find_compiler()
    if cc is None:
        return None
    subprocess.run([*cc.split(), "-O2", "-o", str(exe), str(ROOT / "tests" / "c_host" / "fmi2_host.c"), "-ldl",
                    "-lpthread"], check=True)
    return exe


def accuracy(fmu, tmp):
    """Markdown table: master x step -> largest deviation of the turbine journal from frb.runup / c_o."""
    run = runup(frb.turbocharger(C_O), profile=SpeedProfile.ramp(20e3, 250e3, 1.0), duration=T_CHECK,
                output_rate_hz=20e3)
    df = run.to_dataframe()
    ref = df[["journal turbine x [m]", "journal turbine y [m]"]].to_numpy()
    host = _c_host(tmp)
    masters = {"fmpy (FMU2Slave loop)": lambda h: fmpy_run(fmu, h, T_CHECK, tmp),
               "libcosim (SSP, fixed step)": lambda h: libcosim_run(fmu, h, T_CHECK, tmp),
               "C host (env -i)": (lambda h: c_host_run(fmu, h, T_CHECK, tmp, host)) if host else None,
               "frb cosim (Jacobi master)": lambda h: frb_cosim_run(fmu, h, T_CHECK, tmp)}
    print(f"\nturbine journal vs frb.runup over the first {T_CHECK:g} s, largest deviation / c_o "
          "(acceptance: < 1e-3)\n")
    print("| master | " + " | ".join(f"{h * 1e3:g} ms" for h in STEPS) + " | wall at 10 us |")
    print("|---|" + "---|" * (len(STEPS) + 1))
    for name, job in masters.items():
        if job is None:
            print(f"| {name} | no C compiler |")
            continue
        cells, wall10 = [], math.nan
        for h in STEPS:
            t0 = time.perf_counter()
            xs = job(h)
            if h == STEPS[0]:
                wall10 = time.perf_counter() - t0
            every = max(1, int(round(5e-5 / h)))
            idx = (np.arange(1, xs.shape[0] + 1) * every * h * 20e3).round().astype(int)
            cells.append(f"{np.abs(xs - ref[idx]).max() / C_O:.1e}")
        print(f"| {name} | " + " | ".join(cells) + f" | {wall10:.1f} s |", flush=True)


def onsets(fmu, tmp, steps=(1e-3, 1e-2)):
    """Markdown table: the FMU's record at each macro step against frb.runup over the whole main job."""
    from frbmodel.signals.convergence import match_components
    from frbmodel.signals.spectral import spectrogram

    ref = runup(frb.turbocharger(C_O), speed_rpm=(20e3, 250e3), duration=1.0)
    ref_c = spectrogram(ref, "turbine_wheel").components()
    print("\nonsets over the whole main job (1 s): the FMU's own 20 kHz record vs frb.runup (acceptance: 0.5 %)\n")
    print("| macro step | component | onset frb.runup [rpm] | onset FMU [rpm] | onset moved [%] | f moved [%] |")
    print("|---|---|---|---|---|---|")
    for h in steps:
        rec = Path(tmp) / f"record{h:g}"
        s, vr, _ = _slave(fmu, tmp, f"rec{h:g}", {"record_folder": str(rec)})
        for k in range(int(round(1.0 / h))):
            s.doStep(k * h, h)
        s.terminate()
        s.freeInstance()
        got = spectrogram(frb.RunupResult.load(rec), "turbine_wheel").components()
        for a, b in match_components(ref_c, got):
            if b is None:
                print(f"| {h * 1e3:g} ms | {a.label} | {a.onset_rpm:.0f} | not found | | |")
                continue
            ds = 100 * (b.onset_rpm / a.onset_rpm - 1) if math.isfinite(a.onset_rpm) else math.nan
            dfq = 100 * (b.onset_hz / a.onset_hz - 1) if math.isfinite(a.onset_hz) else math.nan
            print(f"| {h * 1e3:g} ms | {a.label} | {a.onset_rpm:.0f} | {b.onset_rpm:.0f} | {ds:+.3f} | {dfq:+.3f} |",
                  flush=True)


def speed(fmu, tmp, repeats):
    """Median walls of the main job through the FMU at 1 ms (20 kHz record) and of frb.runup, alternately."""
    tc = frb.turbocharger(C_O)
    runup(tc, speed_rpm=(20e3, 21e3), duration=1e-3)  # kernels loaded
    walls = {"fmu": [], "runup": []}
    for r in range(repeats):
        t0 = time.perf_counter()
        runup(tc, speed_rpm=(20e3, 250e3), duration=1.0, out_dir=Path(tmp) / f"mono{r}")
        walls["runup"].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        s, vr, md = _slave(fmu, tmp, f"speed{r}", {"record_folder": str(Path(tmp) / f"fmu{r}")})
        for k in range(1000):
            s.doStep(k * 1e-3, 1e-3)
        s.terminate()
        s.freeInstance()
        walls["fmu"].append(time.perf_counter() - t0)
    fm, rm = statistics.median(walls["fmu"]), statistics.median(walls["runup"])
    print(f"\nmain job, {repeats} alternating runs: FMU at a 1 ms macro step (20 kHz record) median {fm:.2f} s "
          f"(min {min(walls['fmu']):.2f}, max {max(walls['fmu']):.2f}); frb.runup (20 kHz output) median {rm:.2f} s "
          f"(min {min(walls['runup']):.2f}, max {max(walls['runup']):.2f}); ratio {fm / rm:.2f} (acceptance <= 1.2)")
    s, vr, md = _slave(fmu, tmp, "getreal")
    s.doStep(0.0, 1e-3)
    outs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    s.getReal(outs)
    t0 = time.perf_counter()
    for _ in range(2000):
        s.getReal(outs)
    per = (time.perf_counter() - t0) / 2000
    s.terminate()
    s.freeInstance()
    print(f"getReal of all {len(outs)} outputs: {per * 1e3:.4f} ms (acceptance <= 0.05 ms)")
    code = ("import time, sys\nt0 = float(sys.argv[1])\nfrom fmpy import extract, read_model_description\n"
            "from fmpy.fmi2 import FMU2Slave\nfmu = sys.argv[2]\nmd = read_model_description(fmu)\n"
            "s = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu), modelIdentifier=md.coSimulation.modelIdentifier,"
            " instanceName='w')\ns.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode()\n"
            "s.exitInitializationMode(); t1 = time.time(); s.doStep(0.0, 1e-3); t2 = time.time()\n"
            "print(t2 - t0, t2 - t1)\n")
    spans = []
    for _ in range(3):
        out = subprocess.run([sys.executable, "-c", code, repr(time.time()), str(fmu)], capture_output=True, text=True,
                             timeout=600)
        spans.append([float(x) for x in out.stdout.split()])
    spans = np.array(spans)
    print(f"warm start (kernels cached), spawn -> end of the first doStep: median {np.median(spans[:, 0]):.2f} s "
          f"(first doStep alone {np.median(spans[:, 1]) * 1e3:.1f} ms; acceptance <= 2 s)")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--build", default=None, help="folder with fmus/ from frb build-fmus (default: build them here)")
    p.add_argument("--repeats", type=count, default=3, help="alternating runs of the speed comparison")
    p.add_argument("--skip-onsets", action="store_true", help="leave out the 1 s onset comparison (~3 min)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="frb_bench_tc_") as tmp:
        build = Path(args.build) if args.build else Path(tmp) / "build"
        if not args.build:
            from frbmodel.cosim.build import build_fmus

            build_fmus(build, ROOT, progress=lambda m: None)
        fmu = build / "fmus" / "FloatingRingTurbocharger.fmu"
        if not fmu.is_file():
            p.error(f"--build {args.build}: no fmus/FloatingRingTurbocharger.fmu there (run frb build-fmus --out "
                    f"{args.build}, or leave --build out to build them here)")
        speed(fmu, tmp, args.repeats)
        accuracy(fmu, tmp)
        if not args.skip_onsets:
            onsets(fmu, tmp)


if __name__ == "__main__":
    run_script(main)
