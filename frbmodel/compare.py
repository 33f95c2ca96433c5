"""Linear vs nonlinear: run-ups, their sub-synchronous components and the method-J stability predictions.

For each outer clearance the run-up's sub-synchronous components are paired with the method-J mode that is
closest in frequency at the component's onset among the modes that lose stability somewhere in the speed
range; the linear prediction of the onset is the speed where that mode loses stability (the start of its
unstable range nearest to the nonlinear onset).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .campbell import campbell
from .runup import RunupStopped, SpeedProfile, runup
from .spectral import spectrogram


def associate(component, cd, window=1.5):
    """Pair a run-up component with a Campbell mode: among the modes with an unstable range that starts within a
    factor ``window`` of the component's onset speed (or contains it), the one closest in frequency there.

    Parameters
    ----------
    component : Component
        A sub-synchronous component of the run-up (:meth:`SpectrogramResult.components`).
    cd : CampbellResult
    window : float
        Speed factor [-] around the component's onset in which an unstable range may start.

    Returns
    -------
    dict or None
        Keys "cost" (relative frequency mismatch [-]), "mode", "kind", "precession", "linear onset [rpm]",
        "linear f at onset [Hz]", "starts at sweep begin"; None if no mode qualifies.
    """
    best = None
    s_on = component.onset_rpm
    f_on = component.onset_hz
    ur = cd.unstable_ranges()
    for j in sorted(set(ur["mode"])):
        f_mode = np.interp(s_on, cd.speeds_rpm, cd.frequencies_hz[:, j], left=np.nan, right=np.nan)
        if not np.isfinite(f_mode):
            continue
        rows = ur[ur["mode"] == j]
        starts, ends = rows["from [rpm]"].to_numpy(), rows["to [rpm]"].to_numpy()
        near = ((starts <= s_on) & (ends >= s_on)) | ((starts >= s_on / window) & (starts <= s_on * window))
        if not near.any():
            continue
        cand = np.flatnonzero(near)
        k = int(cand[np.argmin(np.abs(starts[cand] - s_on))])
        cost = abs(f_mode - f_on) / f_on
        if best is None or cost < best["cost"]:
            r = rows.iloc[k]
            best = {"cost": cost, "mode": int(j), "kind": r["kind"], "precession": r["precession"],
                    "linear onset [rpm]": float(r["from [rpm]"]), "linear f at onset [Hz]": float(r["f at start [Hz]"]),
                    "starts at sweep begin": bool(r["from [rpm]"] <= cd.speeds_rpm[0])}
    return best


def write_spectrogram(sp, cd, folder, title, xscale="linear", fmax_hz=None):
    """Write the composite figure (PNG + HTML) and the components table of a spectrogram into ``folder``.

    Parameters
    ----------
    sp : SpectrogramResult
    cd : CampbellResult
        Method-J Campbell diagram for the overlay.
    folder : Path
    title : str
    xscale : {"linear", "log"}
    fmax_hz : float, optional
        Upper frequency limit [Hz].

    Returns
    -------
    list of Path
        ``composite.png``, ``composite.html``, ``components.csv``.
    """
    import matplotlib.pyplot as plt

    fig = sp.plot(campbell=cd, title=title, xscale=xscale, fmax_hz=fmax_hz)
    paths = [folder / "composite.png", folder / "composite.html", folder / "components.csv"]
    fig.savefig(paths[0], dpi=110, bbox_inches="tight")
    plt.close(fig)
    sp.plot_html(paths[1], campbell=cd, fmax_hz=fmax_hz)
    sp.components_table().to_csv(paths[2], index=False)
    return paths


def comparison_rows(clearance, sp, comps, cd, status):
    """Rows of the linear-vs-nonlinear table for one outer clearance: one per sub-synchronous component (with its
    associated method-J mode, :func:`associate`) and one per internal resonance.

    Parameters
    ----------
    clearance : float
        Outer clearance [m].
    sp : SpectrogramResult
    comps : list of Component
        ``sp.components()``.
    cd : CampbellResult
    status : str
        "finished" or "stopped" (the run-up's).

    Returns
    -------
    list of dict
    """
    rows = []
    for comp in comps:
        if not comp.label.startswith("sub"):
            continue
        a = associate(comp, cd)
        row = {"c_o [um]": clearance * 1e6, "component": comp.label, "direction": comp.direction,
               "nonlinear onset [rpm]": comp.onset_rpm, "first detection [rpm]": comp.onset_threshold_rpm,
               "f at onset [Hz]": comp.onset_hz, "end [rpm]": comp.end_rpm,
               "max amplitude [um]": float(comp.amplitude_m.max() * 1e6), "run-up": status}
        if a:
            row.update({"J mode": f"{a['precession']} {a['kind']}", "linear onset [rpm]": a["linear onset [rpm]"],
                        "linear f [Hz]": a["linear f at onset [Hz]"],
                        "rel. difference [-]": comp.onset_rpm / a["linear onset [rpm]"] - 1.0,
                        "frequency mismatch [-]": a["cost"]})
        rows.append(row)
    for res in sp.internal_resonances(comps):
        rows.append({"c_o [um]": clearance * 1e6, "component": "total instability?",
                     "direction": f"{res['components'][0]} & {res['components'][1]}: {res['condition']}",
                     "nonlinear onset [rpm]": res["from [rpm]"], "end [rpm]": res["to [rpm]"], "run-up": status})
    return rows


def compare(system, clearances=(36e-6, 40e-6, 42e-6, 46e-6), speed_rpm=(1e3, 250e3), duration=4.0,
            profile="exponential", node="turbine_wheel", out_dir="results/compare", n_speeds=300, progress=print,
            runup_kw=None, segment_s=0.1, fmax_hz=1000.0):
    """Run the run-up and the method-J Campbell diagram per outer clearance; write per clearance the run-up
    data, the composite figure (PNG + HTML) and the components; return and write the comparison table.

    Parameters
    ----------
    system : Turbocharger
    clearances : sequence of float
        Outer film clearances [m].
    speed_rpm : (float, float)
        Start and end speed [rpm] of the run-ups and the Campbell sweeps.
    duration : float
        Run-up duration [s].
    profile : {"exponential", "ramp"}
        Speed profile of the run-ups (and spacing of the Campbell speeds).
    node : str
        Node whose orbit is analysed.
    out_dir : path
    n_speeds : int
        Speeds of the Campbell sweeps.
    progress : callable
        Called with a message per step.
    runup_kw : dict, optional
        Further arguments of :func:`frbmodel.runup`.
    segment_s : float
        Spectrogram segment length [s] (at most duration / 8).
    fmax_hz : float
        Upper frequency limit of the figures [Hz].

    Returns
    -------
    table : pandas.DataFrame
        :func:`comparison_rows` of all clearances (also written as ``linear_vs_nonlinear.csv`` / ``.md``).
    paths : list of Path
        Files written.
    """
    import pandas as pd

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows, paths = [], []
    lo, hi = speed_rpm
    for c in clearances:
        tag = f"co{c * 1e6:.0f}um"
        tc = system.with_outer_clearance(c)
        progress(f"[{tag}] method-J Campbell diagram")
        cd = campbell(tc, "J", np.geomspace(lo, hi, n_speeds) if profile == "exponential" else
                      np.linspace(lo, hi, n_speeds))
        paths += cd.save(out / tag, stem="campbell_J", png=False, html=False)
        prof = SpeedProfile.exponential(lo, hi, duration) if profile == "exponential" else \
            SpeedProfile.ramp(lo, hi, duration)
        progress(f"[{tag}] run-up {prof.description}")
        status = "finished"
        try:
            run = runup(tc, profile=prof, duration=duration, out_dir=out / tag, **(runup_kw or {}))
        except RunupStopped as exc:
            progress(f"[{tag}] run-up stopped: {exc}")
            run, status = exc.result, "stopped"
        paths += [out / tag / "runup.csv", out / tag / "runup.json"]
        sp = spectrogram(run, node, segment_s=min(segment_s, duration / 8))
        comps = sp.components()
        title = f"c_o = {c * 1e6:.0f} um: run-up spectrogram ({node}) vs method J"
        paths += write_spectrogram(sp, cd, out / tag, title, "log" if profile == "exponential" else "linear", fmax_hz)
        rows += comparison_rows(c, sp, comps, cd, status)
    table = pd.DataFrame(rows)
    p = out / "linear_vs_nonlinear.csv"
    table.to_csv(p, index=False)
    paths.append(p)
    p = out / "linear_vs_nonlinear.md"
    p.write_text(table_markdown(table))
    paths.append(p)
    return table, paths


def table_markdown(table) -> str:
    """The main columns of a :func:`compare` table as a Markdown table (speeds with thousands separators,
    relative differences in %).

    Parameters
    ----------
    table : pandas.DataFrame

    Returns
    -------
    str
    """
    cols = ["c_o [um]", "component", "direction", "nonlinear onset [rpm]", "first detection [rpm]", "f at onset [Hz]",
            "J mode", "linear onset [rpm]", "linear f [Hz]", "rel. difference [-]"]
    cols = [c for c in cols if c in table.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]

    def fmt(v, c):
        if isinstance(v, float):
            if math.isnan(v):
                return ""
            if "rel." in c:
                return f"{v:+.1%}"
            if "rpm" in c:
                return f"{v:,.0f}"
            return f"{v:.0f}" if "Hz" in c or "c_o" in c else f"{v:.3g}"
        return str(v)

    for _, r in table.iterrows():
        lines.append("| " + " | ".join(fmt(r.get(c, ""), c) for c in cols) + " |")
    return "\n".join(lines) + "\n"
