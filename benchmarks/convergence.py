"""Tolerance convergence of the reported run-up onsets (issue #10): the main job's run-up (20 -> 250 krpm in 1 s,
c_o = 36 um) and the `frb compare` run-ups (1 -> 250 krpm exponential in 4 s, c_o = 36/40/42/46 um), each at the
default tolerances and with rtol and atol both tightened tenfold (and a hundredfold for reference).

    python benchmarks/convergence.py simulate --out results/convergence     # ~20 min on 2 cores
    python benchmarks/convergence.py analyse --out results/convergence      # tables (markdown) from the runs

The simulation phase writes one folder per run (runup.csv/json); the analysis phase applies the current spectral
post-processing, so it can be rerun after changes to the tracking without re-integrating.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _cli import run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb
from frbmodel.nonlinear.runup import SpeedProfile

#: (label, rtol, atol [m]): the former defaults ("default"), both x0.1 (today's defaults), x0.01, and each alone x0.1
LEVELS = (("default", 1e-6, 1e-9), ("x0.1", 1e-7, 1e-10), ("x0.01", 1e-8, 1e-11), ("atol0.1", 1e-6, 1e-10),
          ("rtol0.1", 1e-7, 1e-9))
CASES = {"main": (36e-6, "ramp", 20e3, 250e3, 1.0, None)}
CASES.update({f"compare{int(c * 1e6)}": (c, "exponential", 1e3, 250e3, 4.0, 0.1) for c in (36e-6, 40e-6, 42e-6, 46e-6)})


def simulate(out, cases, levels):
    for name in cases:
        c, kind, lo, hi, dur, _ = CASES[name]
        tc = frb.turbocharger(c)
        prof = SpeedProfile.exponential(lo, hi, dur) if kind == "exponential" else SpeedProfile.ramp(lo, hi, dur)
        for label, rtol, atol in LEVELS:
            if label not in levels:
                continue
            folder = out / name / label
            if (folder / "runup.json").exists() and '"finished"' in (folder / "runup.json").read_text():
                continue
            print(f"{name} {label}: {prof.description}", flush=True)
            try:
                frb.runup(tc, profile=prof, duration=dur, rtol=rtol, atol=atol, out_dir=folder,
                          progress=True)
            except frb.RunupStopped as exc:
                print(f"  stopped: {exc}")


def onsets(folder, segment_s, node="turbine_wheel"):
    run = frb.RunupResult.load(folder)
    sp = frb.spectrogram(run, node, segment_s=segment_s)
    return {c.label: c for c in sp.components() if c.label.startswith("sub")}, run.meta.get("wall_time_s")


def analyse(out, ref="default", tight="x0.1"):
    print(f"| run | component | onset {ref} [rpm] | {tight} [rpm] | moved | first detection {ref} | {tight} | moved |"
          f" f {ref} [Hz] | {tight} [Hz] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, (_c, _kind, _lo, _hi, dur, seg) in CASES.items():
        if not (out / name / ref).exists() or not (out / name / tight).exists():
            continue
        seg = seg or min(max(dur / 40.0, 0.01), 0.05)
        a, wa = onsets(out / name / ref, seg)
        b, wb = onsets(out / name / tight, seg)
        for lab in sorted(set(a) | set(b), key=lambda s: int(s[3:])):
            ca, cb = a.get(lab), b.get(lab)
            if ca is None or cb is None:
                print(f"| {name} | {lab} | {'-' if ca is None else f'{ca.onset_rpm:,.0f}'} | "
                      f"{'-' if cb is None else f'{cb.onset_rpm:,.0f}'} | only in one | | | | | |")
                continue
            m1 = cb.onset_rpm / ca.onset_rpm - 1
            m2 = cb.onset_threshold_rpm / ca.onset_threshold_rpm - 1
            print(f"| {name} | {lab} | {ca.onset_rpm:,.0f} | {cb.onset_rpm:,.0f} | {m1:+.1%} | "
                  f"{ca.onset_threshold_rpm:,.0f} | {cb.onset_threshold_rpm:,.0f} | {m2:+.1%} | "
                  f"{ca.onset_hz:.1f} | {cb.onset_hz:.1f} |")
        print(f"| {name} | wall time | {wa:.1f} s | {wb:.1f} s | | | | | | |")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("phase", choices=["simulate", "analyse"])
    p.add_argument("--out", default="results/convergence")
    p.add_argument("--cases", default=",".join(CASES))
    p.add_argument("--levels", default="default,x0.1", help="levels to simulate, or the pair to compare")
    a = p.parse_args()
    out = Path(a.out)
    if a.phase == "simulate":
        simulate(out, a.cases.split(","), a.levels.split(","))
    else:
        analyse(out, *a.levels.split(",")[:2])


if __name__ == "__main__":
    np.seterr(all="ignore")
    run_script(main)
