"""Benchmark of the linear toolchain: Campbell time per method, equilibrium time per method, ROSS ratio.

Usage::

    python benchmarks/linear.py [--ross-python PATH] [--repeat N]

Prints tables; every ratio is between timings measured in this run on this machine. ROSS
(ross-rotordynamics >= 3 needs Python >= 3.12) is timed in-process when importable, else through the
interpreter given by ``--ross-python`` or the environment variable ``FRB_ROSS_PYTHON``; otherwise that part
is skipped with a message.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _cli import count, run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb

HERE = Path(__file__).resolve().parent


def best_time(fn, repeat):
    fn()  # warm-up (imports, caches)
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def ross_times(counts, python, repeat):
    """Run benchmarks/_ross_campbell.py in-process or in another interpreter; returns its JSON or None."""
    script = HERE / "_ross_campbell.py"
    try:
        import ross  # noqa: F401

        python = sys.executable
    except ImportError:
        pass
    if not python:
        print("ROSS: not importable here (ross-rotordynamics 3.x needs Python >= 3.12) and no --ross-python / "
              "FRB_ROSS_PYTHON given: ROSS comparison skipped")
        return None
    try:
        out = subprocess.run([python, str(script), str(repeat), *map(str, counts)], capture_output=True, text=True,
                             timeout=900, cwd=HERE)
    except (OSError, subprocess.TimeoutExpired) as exc:
        print(f"ROSS: could not run {python}: {exc}; comparison skipped")
        return None
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if out.returncode != 0 or not lines:
        print(f"ROSS: {python} failed (exit {out.returncode}): {out.stderr.strip()[-400:]}; comparison skipped")
        return None
    return json.loads(lines[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ross-python", default=os.environ.get("FRB_ROSS_PYTHON"))
    ap.add_argument("--repeat", type=count, default=5)
    args = ap.parse_args(argv)
    tc = frb.turbocharger(36e-6)
    print(f"frbmodel {frb.__version__}, numpy {np.__version__}, Python {sys.version.split()[0]}")
    print("\nCampbell diagram wall time [ms] (best of %d), speeds 10k..250k rpm, c_o = 36 um" % args.repeat)
    print(f"{'method':>6} {'26 speeds':>10} {'200 speeds':>11} {'26 no whirl':>12} {'200 no whirl':>13}")
    campbell_ms = {}
    for m in frb.METHODS:
        row = []
        for whirl in (True, False):
            for n in (26, 200):
                s = np.linspace(10e3, 250e3, n)
                run = lambda m=m, s=s, whirl=whirl: frb.campbell(tc, m, s, whirl=whirl)  # noqa: E731
                row.append(best_time(run, args.repeat if n == 26 else 2) * 1e3)
        campbell_ms[m] = row
        print(f"{m:>6} {row[0]:10.2f} {row[1]:11.1f} {row[2]:12.2f} {row[3]:13.1f}")

    print("\nEquilibrium wall time per speed [ms] (mean over 50 speeds, best of %d), iterations, evaluations"
          % args.repeat)
    print(f"{'method':>6} {'time/speed':>11} {'max':>8} {'iterations':>11} {'evaluations':>12}")
    speeds = np.linspace(10e3, 250e3, 50)
    for m in "CDFGIJ":
        times, its, evs = [], [], []
        for s in speeds:
            t = best_time(lambda m=m, s=s: frb.equilibrium(tc, m, s), args.repeat)
            eq = frb.equilibrium(tc, m, s)
            times.append(t * 1e3)
            its.append(eq.iterations)
            evs.append(eq.evaluations)
        print(f"{m:>6} {np.mean(times):11.3f} {np.max(times):8.3f} {np.mean(its):11.1f} {np.mean(evs):12.1f}")

    print("\nTargets (issue #2): method J with equilibria, 200 speeds < 1 s: "
          f"{campbell_ms['J'][1] / 1e3:.3f} s incl. whirl curves, {campbell_ms['J'][3] / 1e3:.3f} s without")
    res = ross_times([26, 200], args.ross_python, args.repeat)
    if res:
        r26, r200 = res["times_s"]["26"] * 1e3, res["times_s"]["200"] * 1e3
        a26, a200 = campbell_ms["A"][2], campbell_ms["A"][3]
        print(f"\nROSS {res['version']} run_campbell, same rotor with method-A bearings (k = 1e6 N/m), same run "
              f"(best of {args.repeat} for 26 speeds, 1 run for 200):")
        print(f"{'speeds':>7} {'ROSS [ms]':>10} {'frbmodel A [ms]':>16} {'speed-up':>9}")
        print(f"{26:>7} {r26:10.1f} {a26:16.2f} {r26 / a26:8.1f}x")
        print(f"{200:>7} {r200:10.1f} {a200:16.2f} {r200 / a200:8.1f}x")
        ours = frb.campbell(tc, "A", [100e3], whirl=False).frequencies_hz[0][:8]
        print("cross-check at 100 krpm [Hz]: ROSS " + " ".join(f"{f:.1f}" for f in res["freq_hz_100krpm"]))
        print("                             ours " + " ".join(f"{f:.1f}" for f in ours))
        print("(ROSS 3 adds axial/torsional DoFs, so it lists extra modes, e.g. near 965 Hz)")


if __name__ == "__main__":
    run_script(main)
