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
    Returns dict(mode, kind, precession, linear onset [rpm], linear f [Hz], cost) or None."""
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


def compare(system, clearances=(36e-6, 40e-6, 42e-6, 46e-6), speed_rpm=(1e3, 250e3), duration=4.0,
            profile="exponential", node="turbine_wheel", out_dir="results/compare", n_speeds=300, progress=print,
            runup_kw=None, segment_s=0.1, fmax_hz=1000.0):
    """Run the run-up and the method-J Campbell diagram per outer clearance; write per clearance the run-up
    data, the composite figure (PNG + HTML) and the components; return and write the comparison table.

    Returns ``(table: pandas.DataFrame, paths: list)``.
    """
    import matplotlib.pyplot as plt
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
        fig = sp.plot(campbell=cd, title=f"c_o = {c * 1e6:.0f} um: run-up spectrogram ({node}) vs method J",
                      xscale="log" if profile == "exponential" else "linear", fmax_hz=fmax_hz)
        p = out / tag / "composite.png"
        fig.savefig(p, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(p)
        p = out / tag / "composite.html"
        sp.plot_html(p, campbell=cd, fmax_hz=fmax_hz)
        paths.append(p)
        p = out / tag / "components.csv"
        sp.components_table().to_csv(p, index=False)
        paths.append(p)
        for comp in comps:
            if not comp.label.startswith("sub"):
                continue
            a = associate(comp, cd)
            row = {"c_o [um]": c * 1e6, "component": comp.label, "direction": comp.direction,
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
            rows.append({"c_o [um]": c * 1e6, "component": "total instability?",
                         "direction": f"{res['components'][0]} & {res['components'][1]}: {res['condition']}",
                         "nonlinear onset [rpm]": res["from [rpm]"], "end [rpm]": res["to [rpm]"], "run-up": status})
    table = pd.DataFrame(rows)
    p = out / "linear_vs_nonlinear.csv"
    table.to_csv(p, index=False)
    paths.append(p)
    p = out / "linear_vs_nonlinear.md"
    p.write_text(table_markdown(table))
    paths.append(p)
    return table, paths


def table_markdown(table) -> str:
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
