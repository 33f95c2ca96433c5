"""Regenerate the paper's linear figures (Figs. 4–11) for a system."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .campbell import campbell
from .equilibrium import equilibrium
from .presets import PAPER_SPEED_RANGE_RPM

#: figure number -> (method, extra options)
CAMPBELL_FIGURES = {4: "A", 5: "B", 6: "C", 7: "D", 8: "E", 9: "F"}


def equilibrium_sweep(system, method, speeds_rpm, repeat=5):
    """RSR (n, 2), CPU time per equilibrium [ms] (best of ``repeat``), iterations and evaluations (n,)."""
    rsr = np.zeros((len(speeds_rpm), 2))
    t_ms = np.zeros(len(speeds_rpm))
    its = np.zeros(len(speeds_rpm), dtype=int)
    evs = np.zeros(len(speeds_rpm), dtype=int)
    for i, s in enumerate(speeds_rpm):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            eq = equilibrium(system, method, s)
            best = min(best, time.perf_counter() - t0)
        rsr[i] = [b.ring_speed_ratio for b in eq.bearings]
        t_ms[i] = best * 1e3
        its[i] = eq.iterations
        evs[i] = eq.evaluations
    return rsr, t_ms, its, evs


def paper_figures(system, out_dir, n_speeds=100, progress=print):
    """Write Figs. 4–9 (Campbell diagrams of methods A–F; Fig. 9 also zoomed to 0–500 Hz), Fig. 10 (RSR of
    F, G, I, J for both bearings) and Fig. 11 (equilibrium CPU time, iterations, evaluations) into
    ``out_dir`` with their data (CSV). Returns the written paths."""
    import matplotlib.pyplot as plt
    import pandas as pd

    from .plots import equilibrium_cost_figure, rsr_figure

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    speeds = np.linspace(*PAPER_SPEED_RANGE_RPM, n_speeds)
    paths = []
    for num, letter in CAMPBELL_FIGURES.items():
        progress(f"Fig. {num}: Campbell diagram, method {letter}")
        cd = campbell(system, letter, speeds)
        paths += cd.save(out, stem=f"fig{num:02d}_campbell_{letter}", fmax_hz=3000.0)
        if letter == "F":
            fig = cd.plot(fmax_hz=500.0, title=f"Fig. 9 zoom: method F, 0-500 Hz ({system.name})")
            p = out / "fig09_campbell_F_zoom500Hz.png"
            fig.savefig(p, dpi=130, bbox_inches="tight")
            plt.close(fig)
            paths.append(p)
            p = out / "fig09_campbell_F_unstable.md"
            p.write_text(unstable_markdown(cd))
            paths.append(p)
    progress("Fig. 10 / 11: ring-speed ratio and equilibrium cost, methods F, G, I, J")
    eq_speeds = np.linspace(*PAPER_SPEED_RANGE_RPM, min(n_speeds, 50))
    rsr_data, stats, rows = {}, {}, []
    for letter in "FGIJ":
        rsr, t_ms, its, evs = equilibrium_sweep(system, letter, eq_speeds)
        rsr_data[letter] = (eq_speeds, rsr)
        stats[letter] = {"time_ms": t_ms, "iterations": its, "evaluations": evs}
        for i, s in enumerate(eq_speeds):
            rows.append({"method": letter, "speed [rpm]": s, "RSR turbine [-]": rsr[i, 0],
                         "RSR compressor [-]": rsr[i, 1], "cpu time [ms]": t_ms[i], "iterations [-]": its[i],
                         "evaluations [-]": evs[i]})
    p = out / "fig10_11_equilibria.csv"
    pd.DataFrame(rows).to_csv(p, index=False)
    paths.append(p)
    fig = rsr_figure(rsr_data, title=f"Fig. 10: ring-speed ratio, methods F, G, I, J ({system.name})")
    p = out / "fig10_rsr.png"
    fig.savefig(p, dpi=130, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)
    fig = equilibrium_cost_figure(stats, title=f"Fig. 11: equilibrium cost per speed ({system.name})")
    p = out / "fig11_equilibrium_cost.png"
    fig.savefig(p, dpi=130, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)
    return paths


def unstable_markdown(cd) -> str:
    """Markdown table of the unstable speed ranges of a Campbell result."""
    ur = cd.unstable_ranges()
    lines = [f"Unstable modes, method {cd.method} ({cd.meta.get('system', '')}); "
             f"max. {int(cd.n_unstable.max())} unstable modes at one speed.", "",
             "| mode | kind | precession | from [rpm] | to [rpm] | f [Hz] (start → end) | min D |",
             "|---|---|---|---|---|---|---|"]
    for _, r in ur.iterrows():
        lines.append(f"| {r['mode']} | {r['kind']} | {r['precession']} | {r['from [rpm]']:,.0f} | "
                     f"{r['to [rpm]']:,.0f} | {r['f at start [Hz]']:.0f} → {r['f at end [Hz]']:.0f} | "
                     f"{r['min damping [-]']:.3f} |")
    return "\n".join(lines) + "\n"
