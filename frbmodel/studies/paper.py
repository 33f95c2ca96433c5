"""Regenerate the paper's linear figures (Figs. 4–11) for a system."""
from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_speed_count, check_system
from ..core.progress import counter_bar, note
from ..linear.campbell import campbell
from ..linear.equilibrium import equilibrium
from ..plots.figures import equilibrium_cost_figure, rsr_figure
from ..system.oil import check_no_oil
from ..system.presets import PAPER_SPEED_RANGE_RPM

#: figure number -> (method, extra options)
CAMPBELL_FIGURES = {4: "A", 5: "B", 6: "C", 7: "D", 8: "E", 9: "F"}


def equilibrium_sweep(system, method, speeds_rpm, repeat=5):
    """Equilibria of ``method`` over a speed sweep, with their cost (the data of Figs. 10 and 11).

    Parameters
    ----------
    system : Turbocharger
    method : {"C", "D", "F", "G", "I", "J"}
    speeds_rpm : sequence of float
        Rotor speeds [rpm], > 0.
    repeat : int
        Each equilibrium is timed this many times; the best time is kept.

    Returns
    -------
    rsr : ndarray (n, 2)
        Ring-speed ratio of each bearing [-].
    time_ms : ndarray (n,)
        CPU time per equilibrium [ms].
    iterations, evaluations : ndarray (n,) of int

    Examples
    --------
    >>> import frbmodel as frb
    >>> rsr, t_ms, its, evs = equilibrium_sweep(frb.turbocharger(), "F", [50e3], repeat=1)
    >>> round(float(rsr[0, 0]), 5)                   # eq. (6)
    0.19903
    """
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


def paper_figures(system, out_dir, n_speeds=100, progress: bool = False):
    """Regenerate the paper's linear figures with their data.

    Writes Figs. 4–9 (Campbell diagrams of methods A–F; Fig. 9 also zoomed to 0–500 Hz and its unstable modes as
    Markdown), Fig. 10 (RSR of F, G, I, J for both bearings) and Fig. 11 (equilibrium CPU time, iterations,
    evaluations) into ``out_dir``, each with its data (CSV, and JSON for the Campbell diagrams).

    Parameters
    ----------
    system : Turbocharger
    out_dir : str or Path
        Output folder (created if missing).
    n_speeds : int
        Speeds per Campbell diagram (10 ... 250 krpm), >= 2.
    progress : bool
        Show a progress bar over the figures and a line per figure (stderr).

    Returns
    -------
    list of Path
        The written files.
    """

    check_no_oil(check_system(system), "frb paper-figures (the paper's figures)")
    if isinstance(n_speeds, bool) or not isinstance(n_speeds, (int, np.integer)) or n_speeds < 2:
        raise ParameterError(f"n_speeds = {n_speeds!r} is invalid: expected an integer >= 2")
    check_speed_count(f"n_speeds = {n_speeds}", n_speeds)  # (1e8 speeds started a run of days)
    if callable(progress):
        warnings.warn("progress callbacks are no longer called: pass progress=True for a progress bar (tqdm)",
                      DeprecationWarning, stacklevel=2)
    show = bool(progress)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    speeds = np.linspace(*PAPER_SPEED_RANGE_RPM, n_speeds)
    with counter_bar(len(CAMPBELL_FIGURES) + 1, "paper figures", show, unit="figure") as bar:
        paths = _campbell_figures(system, out, speeds, show, bar)
        note("Fig. 10 / 11: ring-speed ratio and equilibrium cost, methods F, G, I, J", show)
        paths += _equilibrium_figures(system, out, n_speeds)
        bar.update(1)
    return paths


def _campbell_figures(system, out, speeds, show, bar):
    """Figs. 4-9 (Campbell diagrams of methods A-F) with their data."""
    import matplotlib.pyplot as plt

    paths = []
    for num, letter in CAMPBELL_FIGURES.items():
        note(f"Fig. {num}: Campbell diagram, method {letter}", show)
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
        bar.update(1)
    return paths


def _equilibrium_figures(system, out, n_speeds):
    """Figs. 10 and 11 (RSR and equilibrium cost of F, G, I, J) with their data."""
    import matplotlib.pyplot as plt
    import pandas as pd


    paths = []
    names = [b.name for b in system.bearings]
    eq_speeds = np.linspace(*PAPER_SPEED_RANGE_RPM, min(n_speeds, 50))
    rsr_data, stats, rows = {}, {}, []
    for letter in "FGIJ":
        rsr, t_ms, its, evs = equilibrium_sweep(system, letter, eq_speeds)
        rsr_data[letter] = (eq_speeds, rsr)
        stats[letter] = {"time_ms": t_ms, "iterations": its, "evaluations": evs}
        for i, s in enumerate(eq_speeds):
            rows.append({"method": letter, "speed [rpm]": s, **{f"RSR {n} [-]": rsr[i, k] for k, n in enumerate(names)},
                         "cpu time [ms]": t_ms[i], "iterations [-]": its[i], "evaluations [-]": evs[i]})
    p = out / "fig10_11_equilibria.csv"
    pd.DataFrame(rows).to_csv(p, index=False)
    paths.append(p)
    fig = rsr_figure(rsr_data, title=f"Fig. 10: ring-speed ratio, methods F, G, I, J ({system.name})",
                     bearing_names=names)
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
    """Markdown table of the unstable speed ranges of a Campbell result.

    Parameters
    ----------
    cd : CampbellResult

    Returns
    -------
    str
        A summary line (with the neutral-mode count) and one table row per unstable range.

    Examples
    --------
    >>> import frbmodel as frb
    >>> print(unstable_markdown(frb.campbell(frb.turbocharger(), "A", [50e3], whirl=False)).splitlines()[0])
    Unstable modes, method A (Table 2 turbocharger, c_o = 36 µm); max. 0 unstable and 16 neutral modes at one speed.
    """
    ur = cd.unstable_ranges()
    lines = [f"Unstable modes, method {cd.method} ({cd.system_name}); max. {int(cd.n_unstable.max())} unstable and "
             f"{int(cd.n_neutral.max())} neutral modes at one speed.", "",
             "| mode | kind | precession | from [rpm] | to [rpm] | f [Hz] (start → end) | min D |",
             "|---|---|---|---|---|---|---|"]
    for _, r in ur.iterrows():
        lines.append(f"| {r['mode']} | {r['kind']} | {r['precession']} | {r['from [rpm]']:,.0f} | "
                     f"{r['to [rpm]']:,.0f} | {r['f at start [Hz]']:.0f} → {r['f at end [Hz]']:.0f} | "
                     f"{r['min damping [-]']:.3f} |")
    return "\n".join(lines) + "\n"
