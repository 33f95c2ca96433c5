"""Is the default run-up converged inside the developed whirl, and at what cost? (issue #24 item 1)

Usage::

    python benchmarks/default_convergence.py [--repeats 3] [--out results/default_convergence]
                                             [--filing-commit 5fe3afe | --filing-commit none]

The main job's run-up (Table 2 turbocharger, c_o = 36 µm, 20 -> 250 krpm in 1 s, output at 40 kHz).

The issue's target is the wall of the default when it was filed. ``filing default`` is that run with that code:
the package of commit ``--filing-commit`` (5fe3afe, the last commit before the issue's work: rtol 1e-7, atol
1e-10 m, error norm per state, RODAS with its Jacobian by differences of the whole right-hand side and one LU of all
states), exported with ``git archive`` into a temporary folder and run in a subprocess
(benchmarks/_timed_default_runup.py), alternating ``--repeats`` times with ``default (subprocess)``, today's
package run the same way. Both subprocesses load the compiled kernels before the timed run.

In this process, for the convergence and for what each change costs:

- ``filing tolerances``: the filing's tolerances and norm with today's code and plain RODAS
  (:data:`frbmodel.nonlinear.rosenbrock.RODAS4`): what the tighter defaults cost with today's kernels (it shares
  every speed-up of the kernels, so it is not the issue's baseline), alternating with ``default`` and
  ``default, plain RODAS``;
- ``default, plain RODAS``: the defaults' tolerances and norm with the plain RODAS code (the default until
  2026-12-02 noon); the default itself is the same method with each film's Jacobian columns differenced alone and
  the ring blocks eliminated before the LU (:data:`frbmodel.nonlinear.rosenbrock.RODAS4_FAST`);
- ``rodas5p`` / ``rodas5p x0.1``: Rodas5P (order 5(4), :data:`frbmodel.nonlinear.rosenbrock.RODAS5P`) at the
  defaults and tightened tenfold;
- ``per-state 1e-11``: atol 1e-11 m with the error norm per state (the default of 2026-12-02 morning);
- ``default``: today's defaults (rtol 1e-7, atol 1e-11 m, the rotor's error in free-free modal coordinates,
  :func:`frbmodel.nonlinear.runup.modal_error_basis`, RODAS4_FAST);
- ``default x0.1``: both tolerances tightened tenfold (1e-8, 1e-12 m);
- ``lsoda x0.1``: scipy's LSODA at 1e-8 / 1e-12 m (the second integrator, its own error norm per state);
- ``…, offset ±1e-9``: the same with the initial journal offset (5 % of the clearance) changed by a relative 1e-9,
  i.e. 1.8e-15 m: what moves then is the model's own sensitivity inside the developed whirl, not the integrator's.

For each: wall time (median over ``--repeats`` for the alternating runs; also min and max), solver steps, the three
strongest peaks of the turbine wheel's x spectrum between 0.05 and 0.9 X at 150 / 170 / 200 / 230 krpm (4096 samples
about the speed, Hann window; a bin is 9.8 Hz) and the onsets of the sub-synchronous components
(:func:`frbmodel.spectrogram`). The per-state runs replace ``modal_error_basis`` with the identity for that run, a
RODAS variant passes its method code to the compiled integrator for that run (a benchmark, not the API). Writes
``default_convergence.csv`` and prints a markdown table; the ratio against ``filing default`` is the issue's.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _cli import count, run_script  # (benchmarks/ is the script's folder)
from scipy.signal import find_peaks

import frbmodel as frb
import frbmodel.nonlinear.runup as ru
from frbmodel.nonlinear.rosenbrock import METHODS, NO_MODAL

#: (label, rtol, atol [m], integrator, modal error norm, initial perturbation [of the clearance]); "rodas" with a
#: variant: "rodas:<name of METHODS>"
P0, DP = 0.05, 1e-9  # the default initial offset; a relative change of it (1.8e-15 m) far below every tolerance
PAIRED = 3  # the first PAIRED runs alternate --repeats times
RUNS = (("filing tolerances", 1e-7, 1e-10, "rodas:rodas4", False, P0), ("default", 1e-7, 1e-11, "rodas", True, P0),
        ("default, plain RODAS", 1e-7, 1e-11, "rodas:rodas4", True, P0),
        ("rodas5p", 1e-7, 1e-11, "rodas:rodas5p", True, P0), ("rodas5p x0.1", 1e-8, 1e-12, "rodas:rodas5p", True, P0),
        ("per-state 1e-11", 1e-7, 1e-11, "rodas", False, P0), ("default x0.1", 1e-8, 1e-12, "rodas", True, P0),
        ("lsoda x0.1", 1e-8, 1e-12, "lsoda", False, P0),
        ("default, offset +1e-9", 1e-7, 1e-11, "rodas", True, P0 * (1 + DP)),
        ("default, offset -1e-9", 1e-7, 1e-11, "rodas", True, P0 * (1 - DP)),
        ("default x0.1, offset +1e-9", 1e-8, 1e-12, "rodas", True, P0 * (1 + DP)),
        ("lsoda x0.1, offset +1e-9", 1e-8, 1e-12, "lsoda", False, P0 * (1 + DP)))
SPEEDS_RPM = (150e3, 170e3, 200e3, 230e3)
ROOT = Path(__file__).resolve().parent.parent
FILING_COMMIT = "5fe3afe"  # the last commit before issue #24's work: the defaults (and code) of its filing


def filing_package(commit, into):
    """Export ``frbmodel/`` of ``commit`` into the folder ``into`` (git archive); refuses a commit this clone lacks."""
    try:
        blob = subprocess.run(["git", "-C", str(ROOT), "archive", commit, "frbmodel"], check=True,
                              capture_output=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        raise SystemExit(f"--filing-commit {commit}: not in this clone's history ({exc}); fetch it or pass "
                         "--filing-commit none") from None
    subprocess.run(["tar", "-x", "-C", str(into)], input=blob, check=True)


def timed_subprocess(package_root):
    """(wall [s], steps) of benchmarks/_timed_default_runup.py with ``package_root`` first on sys.path."""
    env = dict(os.environ, PYTHONPATH=str(package_root))
    out = subprocess.run([sys.executable, str(Path(__file__).with_name("_timed_default_runup.py"))], check=True,
                         capture_output=True, text=True, env=env).stdout
    rec = json.loads(out.strip().splitlines()[-1])
    if not rec["frbmodel"].startswith(str(package_root)):
        raise SystemExit(f"the subprocess imported {rec['frbmodel']}, not the package under {package_root}")
    return rec["wall_s"], rec["solver_steps"]


def filing_rows(commit, repeats):
    """(rows ``filing default (<commit>)`` and ``default (subprocess)``, the filing default's median wall [s]): walls
    alternating ``repeats`` times."""
    walls, steps = {"filing": [], "today": []}, {}
    with tempfile.TemporaryDirectory() as tmp:
        filing_package(commit, tmp)
        for _ in range(repeats):
            for key, root in (("filing", Path(tmp)), ("today", ROOT)):
                w, steps[key] = timed_subprocess(root)
                walls[key].append(w)
    base = statistics.median(walls["filing"])
    return [{"run": label, "wall [s]": round(statistics.median(walls[k]), 2),
             "wall min / max [s]": f"{min(walls[k]):.2f} / {max(walls[k]):.2f}",
             "wall / filing default [-]": round(statistics.median(walls[k]) / base, 2), "solver work": steps[k]}
            for label, k in ((f"filing default ({commit})", "filing"), ("default (subprocess)", "today"))], base


def peaks_hz(run, rpm, n=4096):
    """The three strongest spectral peaks [Hz] of the turbine wheel's x between 0.05 and 0.9 X about ``rpm``."""
    i0 = int(np.argmin(np.abs(run.speed_rpm - rpm)))
    x = run.displacement["turbine_wheel"][i0 - n // 2:i0 + n // 2, 0]
    spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size)))
    f = np.fft.rfftfreq(x.size, run.time[1] - run.time[0])
    band = (f > 0.05 * rpm / 60) & (f < 0.9 * rpm / 60)
    idx, _ = find_peaks(np.where(band, spec, 0.0))
    return [round(float(f[k])) for k in idx[np.argsort(spec[idx])[::-1][:3]]]


@contextlib.contextmanager
def rosenbrock_method(variant):
    """frb.runup's compiled Rosenbrock integrator with the method ``variant`` (a name of METHODS; "": the default)."""
    real = ru.rodas_chunk
    if variant:
        ru.rodas_chunk = lambda *a: real(*a, METHODS[variant])
    try:
        yield
    finally:
        ru.rodas_chunk = real


def one_run(tc, rtol, atol, integrator, modal, perturbation):
    """(run, wall [s]) of the main job at these tolerances and initial offset."""
    real = ru.modal_error_basis
    if not modal:
        ru.modal_error_basis = lambda problem, a, speed_scale=None: (NO_MODAL, a)
    integrator, _, variant = integrator.partition(":")
    try:
        with rosenbrock_method(variant):
            t0 = time.perf_counter()
            run = frb.runup(tc, speed_rpm=(20e3, 250e3), duration=1.0, rtol=rtol, atol=atol, integrator=integrator,
                            output_rate_hz=40e3, perturbation=perturbation)
            return run, time.perf_counter() - t0
    finally:
        ru.modal_error_basis = real


def row(label, run, walls, filing_s, tolerances_s):
    """One table row: wall (also against the filing default and against the filing tolerances in this process),
    steps, peaks and onsets of ``run``."""
    comps = {c.label: c.onset_rpm for c in frb.spectrogram(run, "turbine_wheel").components()
             if c.label.startswith("sub")}
    wall = statistics.median(walls)
    return {"run": label, "wall [s]": round(wall, 2), "wall min / max [s]": f"{min(walls):.2f} / {max(walls):.2f}",
            "wall / filing default [-]": round(wall / filing_s, 2) if filing_s else "-",
            "wall / filing tolerances [-]": round(wall / tolerances_s, 2),
            "solver work": run.meta.get("solver_steps", run.meta.get("rhs_evaluations")),
            **{f"peaks {s / 1e3:.0f} krpm [Hz]": " / ".join(map(str, peaks_hz(run, s))) for s in SPEEDS_RPM},
            **{f"{k} onset [rpm]": (f"{v:,.0f}" if np.isfinite(v) else "-") for k, v in sorted(comps.items())}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=count, default=3,
                    help="alternating repeats of the filing default and today's default (subprocesses), and of the "
                         "filing tolerances, default and plain RODAS in this process (wall: median)")
    ap.add_argument("--filing-commit", default=FILING_COMMIT,
                    help="the commit whose package gives the issue's baseline ('none': skip that pair)")
    ap.add_argument("--out", default="results/default_convergence", help="output folder")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    first, filing_s = filing_rows(args.filing_commit, args.repeats) if args.filing_commit != "none" else ([], None)
    tc = frb.turbocharger(36e-6)
    frb.runup(tc, speed_rpm=(20e3, 25e3), duration=0.01)  # load the kernels (not timed), also the variants'
    for variant in METHODS:
        with rosenbrock_method(variant):
            frb.runup(tc, speed_rpm=(20e3, 25e3), duration=0.01)
    runs, walls = {}, {label: [] for label, *_ in RUNS}
    for _ in range(args.repeats):  # filing tolerances, default and plain RODAS alternate: one machine state
        for label, *cfg in RUNS[:PAIRED]:
            runs[label], w = one_run(tc, *cfg)
            walls[label].append(w)
    for label, *cfg in RUNS[PAIRED:]:
        runs[label], w = one_run(tc, *cfg)
        walls[label].append(w)
    tol_s = statistics.median(walls["filing tolerances"])
    for r in first:
        r["wall / filing tolerances [-]"] = "-"
    rows = first + [row(label, runs[label], walls[label], filing_s, tol_s) for label, *_ in RUNS]
    import pandas as pd

    df = pd.DataFrame(rows)
    df.to_csv(out / "default_convergence.csv", index=False)
    print("| " + " | ".join(df.columns) + " |\n|" + "---|" * len(df.columns))
    for _, r in df.iterrows():
        print("| " + " | ".join(str(v) for v in r) + " |")
    for label, *_ in RUNS[:PAIRED]:
        print(f"{label} walls: {', '.join(f'{w:.2f}' for w in walls[label])} s")
    print(f"wrote {out / 'default_convergence.csv'}")


if __name__ == "__main__":
    run_script(main)
