"""What a run folder gets beside its data: the composite figures with the Campbell overlay, the halves of a
run-up and run-down, the tolerance-convergence labels, orbit windows and waterfalls, and the redrawn figures of an
unbalance folder. The workflows of ``frb runup``, ``frb cosim``, ``frb compare`` and ``frb plot``, callable from
Python (the CLI only parses the options and calls them)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, RunStopped
from ..linear.campbell import campbell
from ..linear.unbalance import UnbalanceResponse, bode_figure
from ..nonlinear.recorder import RunupResult
from ..plots.style import readable
from ..signals.convergence import convergence_table, unconverged_summary
from ..signals.orbits import orbits
from ..signals.spectral import spectrogram

__all__ = ["check_convergence", "orbit_windows", "replot_unbalance", "run_envelope", "save_bifurcation_diagram",
           "write_composites", "write_orbits", "write_up_down_halves", "write_waterfalls"]


def _mkdir(folder):
    """``folder`` created with its parents."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _kept(fn, folder):
    """``fn()``, or the result a :class:`RunStopped` run kept."""
    try:
        return fn()
    except RunStopped as exc:
        print(f"stopped: {exc}")
        return exc.result


def write_composites(run, system, out, xscale="linear", title="run-up", orders=(1.0,)):
    """Composite figures (PNG + HTML) and component tables of every disc, with the method-J Campbell diagram.

    Writes ``composite_<disc>.png``, ``composite_<disc>.html`` and ``components_<disc>.csv`` into ``out``
    (:meth:`SpectrogramResult.save`; the HTML loads plotly.js from ``plotly.min.js`` in ``out``) and prints the
    component tables. Used by ``frb runup``, ``frb cosim`` and ``frb plot``.

    Parameters
    ----------
    run : RunupResult
        The run (at least 64 samples, for the spectrogram).
    system : Turbocharger
        The run's system (for the Campbell overlay over the run's speed range).
    out : Path
        Output folder (must exist).
    xscale : {"linear", "log"}
        Speed axis scale of the PNG figures.
    title : str
        Figure title prefix (e.g. ``"run-down"``).
    orders : sequence of float
        Order lines k × f_rot (multiples of the rotor frequency) on the spectrograms; 1X by default.

    Returns
    -------
    list of Path
        The files written.
    """

    lo, hi = float(run.speed_rpm.min()), float(run.speed_rpm.max())
    cd = campbell(system, "J", np.linspace(max(lo, 500.0), max(hi, lo + 1.0), 150)) if hi > lo else None
    paths = []
    for node in run.displacement:  # the system's discs
        sp = spectrogram(run, node)
        paths += sp.save(out, campbell=cd, xscale=xscale, title=f"{title}, {readable(node)}", orders=orders,
                         nc=False)
        tab = sp.components_table()
        print(f"components at the {node}:")
        print(tab.to_string(index=False, float_format=lambda x: f"{x:.4g}") if len(tab) else "  none")
    return paths


def run_envelope(folder, run, segment_s=0.005):
    """(label, speeds [rpm], turbine-wheel orbit radius [µm]) per segment of the run-up / run-down ``run`` (read
    from ``folder``)."""
    name = run.schema.discs[0]
    n = max(2, int(round(segment_s / float(run.time[1] - run.time[0]))))
    speeds, radius = [], []
    for k in range(0, run.time.size - n + 1, n):
        xy = run.displacement[name][k:k + n]
        speeds.append(float(np.mean(run.speed_rpm[k:k + n])))
        radius.append(float(np.max(np.hypot(*(xy - xy.mean(axis=0)).T))) * 1e6)
    return (f"{run.meta.get('profile', folder)}", np.array(speeds), np.array(radius))


def write_up_down_halves(run, system, out, make_dir=None):
    """Composite figures of each half of a run-up and run-down, in ``out/run-up`` and ``out/run-down``: the
    spectrogram of the whole run puts the segments of both halves side by side along the speed axis, the halves
    show each direction on its own (the hysteresis between them). The run-up ends where the top speed is first
    reached, the run-down starts where it is last held.

    Parameters
    ----------
    run : RunupResult
        A run whose speed rises to its top and then falls.
    system : Turbocharger
        The run's system.
    out : Path
        Output folder of the run.
    make_dir : callable, optional
        ``make_dir(folder) -> Path``: how a half's folder is made (default: created with its parents; the CLI
        passes its results-folder claim).
    """

    make_dir = make_dir or _mkdir
    df, top = run.to_dataframe(), np.flatnonzero(run.speed_rpm == run.speed_rpm.max())
    for name, rows in (("run-up", slice(0, top[0] + 1)), ("run-down", slice(top[-1], None))):
        half = RunupResult.from_dataframe(df.iloc[rows], run.meta)
        if half.time.size >= 64:
            print(f"{name} half:")
            write_composites(half, system, make_dir(out / name), title=f"{name} (of a run-up and run-down)")


def check_convergence(run, rerun, out, what, runner=None):
    """Rerun (``rerun(folder)``) at tightened tolerances into ``out/convergence_check`` and label every component's
    onset as converged or seeded by round-off: ``convergence_<disc>.csv``, and the columns "converged" and "note"
    added to ``components_<disc>.csv``.

    Parameters
    ----------
    run : RunupResult
        The run at the normal tolerances.
    rerun : callable
        ``rerun(folder) -> RunupResult``: the same run at tightened tolerances (or a smaller macro step),
        streamed into ``folder``.
    out : Path
        Output folder of ``run``.
    what : str
        What was tightened, for the printed summary (e.g. ``"tolerances x0.1"``).
    runner : callable, optional
        ``runner(fn, folder) -> RunupResult``: runs ``fn()`` (default: a run that stops early gives what it
        computed, :class:`~frbmodel.core.errors.RunStopped`'s result; the CLI passes its interruption handling).
    """
    import pandas as pd


    folder = out / "convergence_check"
    tight = (runner or _kept)(lambda: rerun(folder), folder)
    for node in run.displacement:
        tab = convergence_table(spectrogram(run, node).components(), spectrogram(tight, node).components())
        tab.to_csv(out / f"convergence_{node}.csv", index=False)
        comp_csv = out / f"components_{node}.csv"
        if comp_csv.exists() and len(tab):
            comps = pd.read_csv(comp_csv).drop(columns=["converged", "note"], errors="ignore")
            comps.merge(tab[["component", "converged", "note"]], on="component", how="left").to_csv(comp_csv,
                                                                                                   index=False)
        print(f"{node} ({what}): {unconverged_summary(tab) if len(tab) else 'no sub-synchronous component'}")


def replot_unbalance(out, names=None):
    """Redraw the figures of a folder written by ``frb unbalance`` from its saved data.

    Every ``unbalance_<M>.json`` (with its ``_dofs.csv`` and ``_critical.csv``) is read back
    (:meth:`UnbalanceResponse.load`) and drawn again as ``unbalance_<M>.png`` and ``.html``; with several methods
    also the common Bode figure ``unbalance_bode_<methods>.png`` (methods in the order of an existing Bode figure's
    name, else alphabetical). The tables are not rewritten.

    Parameters
    ----------
    out : Path
        The folder.
    names : sequence of str, optional
        Locations drawn (default: the discs).

    Returns
    -------
    list of Path
        The figures written.
    """
    import matplotlib.pyplot as plt


    stems = sorted(p.stem for p in out.glob("unbalance_*.json"))
    results = [UnbalanceResponse.load(out, stem=s) for s in stems]
    bad = [n for n in names or [] if n not in results[0].names]
    if bad:
        raise ParameterError(f"--locations {bad[0]!r} is unknown; valid: {', '.join(results[0].names)}")
    paths = []
    for s, ur in zip(stems, results):
        stem = out / s
        fig = ur.plot(names)
        fig.savefig(stem.with_suffix(".png"), dpi=130, bbox_inches="tight")
        plt.close(fig)
        ur.plot_html(stem.with_suffix(".html"), names)
        paths += [stem.with_suffix(".png"), stem.with_suffix(".html")]
    if len(results) > 1:
        letters = sorted(r.method for r in results)
        for p in out.glob("unbalance_bode_*.png"):  # keep the method order of the first drawing
            if sorted(p.stem.removeprefix("unbalance_bode_")) == letters:
                letters = list(p.stem.removeprefix("unbalance_bode_"))
        results.sort(key=lambda r: letters.index(r.method))
        fig = bode_figure(results, names)
        paths.append(out / f"unbalance_bode_{''.join(letters)}.png")
        fig.savefig(paths[-1], dpi=130, bbox_inches="tight")
        plt.close(fig)
    return paths


def orbit_windows(run, speeds_rpm=(), revolutions=20.0, time_windows=()):
    """Orbits of a run at given speeds and over time windows (:func:`frbmodel.signals.orbits.orbits`).

    Parameters
    ----------
    run : RunupResult
        With the system in its metadata (clearances).
    speeds_rpm : sequence of float
        Window centres [rpm] (each within the run's speeds).
    revolutions : float
        Half-width of each speed window in rotor revolutions.
    time_windows : sequence of (float, float)
        Time windows [s] (e.g. the settled end of a constant-speed run), each holding >= 2 samples.

    Returns
    -------
    list of Orbits
    """

    return ([orbits(run, speed_rpm=float(s), revolutions=revolutions) for s in speeds_rpm]
            + [orbits(run, time_s=w) for w in time_windows])


def write_orbits(windows, out, data=False):
    """Orbit figures (:meth:`Orbits.save`): ``orbits_<rpm>.png`` and ``.html``, or ``orbits_t<t0>-<t1>s.png`` and
    ``.html``, in ``out``.

    Parameters
    ----------
    windows : sequence of Orbits
        From :func:`orbit_windows`.
    out : Path
        Output folder (must exist).
    data : bool
        Also write the samples: ``orbits_<...>.csv`` and ``orbits_<...>.nc`` (:meth:`Orbits.to_xarray`).

    Returns
    -------
    list of Path
        The files written.
    """
    paths = []
    for o in windows:
        written = o.save(out, csv=data, nc=data)
        paths += written
        print(f"wrote {out / o.stem}" + "/".join(p.suffix for p in written))
    return paths


def write_waterfalls(run, out, orders=(1.0,)):
    """3-D waterfall of every disc of a run: ``waterfall_<disc>.png`` and ``.html`` in ``out``.

    Parameters
    ----------
    run : RunupResult
        At least 64 samples.
    out : Path
        Output folder (must exist).
    orders : sequence of float
        Order lines k × f_rot on the floor of the waterfall.

    Returns
    -------
    list of Path
        The files written.
    """
    import matplotlib.pyplot as plt


    paths = []
    for node in run.displacement:
        sp = spectrogram(run, node)
        fig = sp.waterfall(orders=orders)
        fig.savefig(out / f"waterfall_{node}.png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        sp.waterfall_html(out / f"waterfall_{node}.html", orders=orders)
        paths += [out / f"waterfall_{node}.png", out / f"waterfall_{node}.html"]
        print(f"wrote {out / f'waterfall_{node}'}.png/.html")
    return paths


#: speeds of the method-J Campbell diagram drawn in the bifurcation diagram's frequency panel (~1.5 s for 120)
BIFURCATION_CAMPBELL_SPEEDS = 120


def save_bifurcation_diagram(bd, system, out, speed_range_rpm, runs=(), campbell_speeds=BIFURCATION_CAMPBELL_SPEEDS,
                             oil_supply=None):
    """Write a bifurcation diagram (:meth:`BifurcationDiagram.save`) with the envelopes of the run-up results
    ``runs`` (``[(folder, RunupResult)]``), the first run's spectrogram behind the branch frequencies and the
    method-J Campbell diagram's unstable modes and film whirl lines over the speed range.

    Parameters
    ----------
    bd : BifurcationDiagram
    system : Turbocharger
        For the Campbell diagram.
    out : Path
        Output folder.
    speed_range_rpm : (float, float)
        Speed range [rpm] of the Campbell lines (widened to the first run's spectrogram).
    runs : sequence of (str, RunupResult)
    campbell_speeds : int
        Speeds of the Campbell diagram.
    oil_supply : OilSupply, optional
        The supply the diagram was computed with: the Campbell diagram then has each speed's thermal operating
        point too.

    Returns
    -------
    list of Path
    """

    lo, hi = speed_range_rpm
    envelopes = [run_envelope(folder, r) for folder, r in runs]
    sp = None
    if runs:  # the first run's spectrogram behind the branch frequencies
        run = runs[0][1]
        sp = spectrogram(run, run.schema.discs[0])
        lo, hi = min(lo, sp.speeds_rpm.min()), max(hi, sp.speeds_rpm.max())
    cd = campbell(system, "J", np.linspace(lo, hi, campbell_speeds), oil_supply=oil_supply)
    return bd.save(out, envelopes=envelopes, spectrogram=sp, campbell=cd)
