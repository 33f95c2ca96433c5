"""Figures of a bifurcation diagram (:class:`frbmodel.cycles.continuation.BifurcationDiagram`): orbit amplitude and
frequency vs rotor speed, stable branches solid, unstable dashed, bifurcation points marked; behind them the run-up
/ run-down envelopes, the spectrogram of a run, the unstable modes of the method-J Campbell diagram and the film
whirl lines. Matplotlib (PNG) and plotly (interactive HTML) draw the same content.
"""
from __future__ import annotations

import numpy as np

from .figures import unstable_lines, whirl_lines, write_html
from .style import html_layout, log_axis

#: marker of each bifurcation type (matplotlib / plotly symbol)
MARKS = {"Hopf": ("*", "star"), "Hopf (restabilizing)": ("h", "hexagon"), "fold": ("o", "circle"),
         "period doubling": ("s", "square"), "Neimark-Sacker": ("D", "diamond")}
#: dynamic range [dB] of the spectrogram drawn behind the frequency panel (the ~10 µm whirls on the branches show
#: beside ~100 µm ones)
SPECTROGRAM_DB = 40.0


def stability_runs(bd):
    """The branches cut into runs of equal stability, for drawing.

    Parameters
    ----------
    bd : BifurcationDiagram

    Returns
    -------
    list of tuple
        ``(stable, speeds [rpm], turbine-wheel orbit radius [µm], frequency [Hz])``; consecutive runs share their
        end point, so that the drawn branch has no gaps.

    Examples
    --------
    >>> import numpy as np
    >>> from frbmodel.cycles.continuation import BifurcationDiagram, BranchPoint
    >>> pts = [BranchPoint(s, 1e-3, np.ones(2), st, 1e-6, np.zeros(4))
    ...        for s, st in [(1e4, False), (2e4, True), (3e4, True), (4e4, False)]]
    >>> [(st, s.tolist()) for st, s, _, _ in stability_runs(BifurcationDiagram(pts, [], {"branches": [4]}))]
    [(False, [10000.0, 20000.0]), (True, [20000.0, 30000.0, 40000.0]), (False, [40000.0])]
    """
    runs, start = [], 0
    for count in bd.meta.get("branches", [len(bd.points)]):
        pts = bd.points[start:start + count]
        start += count
        if not pts:
            continue
        stab = [p.stable for p in pts]
        lo = 0
        for i in range(1, len(pts) + 1):
            if i == len(pts) or stab[i] != stab[lo]:
                seg = pts[lo:i + 1]  # with the next run's first point
                runs.append((stab[lo], np.array([p.speed_rpm for p in seg]),
                             np.array([p.turbine_radius_m for p in seg]) * 1e6, np.array([1 / p.period for p in seg])))
                lo = i
    return runs


def campbell_lines(cd, fmax_hz):
    """Unstable modes and film whirl lines of a Campbell diagram, for the frequency panel.

    Parameters
    ----------
    cd : CampbellResult
        Usually method J over the diagram's speed range.
    fmax_hz : float
        Modes entirely above this frequency [Hz] are left out.

    Returns
    -------
    list of tuple
        ``(kind, label, speeds [rpm], frequency [Hz] — NaN where not drawn, style or None)``: kind ``"mode"`` (a
        mode where it is unstable) or ``"whirl"`` (a film's whirl frequency past its onset, with its style of
        :func:`frbmodel.plots.figures.whirl_lines`: coincident curves interleaved, both visible).
    """

    out = []
    for sk, f, j in unstable_lines(cd, fmax_hz):
        kind = _mode_label(cd, j, f)
        onset = sk[np.flatnonzero(np.isfinite(f))[0]]
        out.append(("mode", f"unstable {kind or 'mode'} ({cd.method}), from {onset:.0f} krpm", sk * 1e3, f, None))
    for line in whirl_lines(cd):
        out.append(("whirl", line["label"], line["speeds_rpm"], line["whirl_hz"], line))
    return out


def _mode_label(cd, j, f):
    """Precession and kind of tracked mode ``j`` where it is unstable (the most common label there)."""
    sel = np.isfinite(f)
    labels = [f"{p} {k}" for p, k in zip(cd.precession[sel, j], cd.mode_kind[sel, j]) if p and k]
    return max(set(labels), key=labels.count) if labels else ""


def _speed_range(bd, envelopes):
    speeds = [p.speed_rpm for p in bd.points] + [s for _, sp, _ in envelopes for s in np.ravel(sp)]
    return (min(speeds), max(speeds)) if speeds else (0.0, 1.0)


def _fmax(bd, spectrogram, cd):
    top = max([1 / p.period for p in bd.points] + [1.0])
    if spectrogram is not None or cd is not None:
        return 1.3 * top
    return None


def diagram_figure(bd, title=None, envelopes=(), spectrogram=None, campbell=None):
    """The bifurcation diagram (matplotlib): turbine-wheel orbit radius [µm] and orbit frequency [Hz] vs speed.

    Parameters
    ----------
    bd : BifurcationDiagram
    title : str, optional
    envelopes : sequence of (label, speeds [rpm], radius [µm])
        Run-up / run-down envelopes drawn behind the branches (the radius axis becomes logarithmic).
    spectrogram : SpectrogramResult, optional
        A run's spectrogram behind the frequency panel (forward + backward amplitude, dB re its maximum over
        :data:`SPECTROGRAM_DB`).
    campbell : CampbellResult, optional
        Its unstable modes (solid, coloured) and film whirl lines (dashed) in the frequency panel.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, (ax, axf) = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True)
    if spectrogram is not None:
        _draw_spectrogram(axf, spectrogram)
    for label, s, r in envelopes:
        ax.plot(s, r, lw=0.8, alpha=0.6, label=label)
    fmax = _fmax(bd, spectrogram, campbell)
    if campbell is not None:
        _draw_campbell(axf, campbell, fmax, _speed_range(bd, envelopes))
    for stable, s, r, f in stability_runs(bd):
        kw = dict(color="k", lw=2.2, ls="-") if stable else dict(color="0.45", lw=1.4, ls="--")
        ax.plot(s, r, **kw)
        axf.plot(s, f, **kw)
    for b in bd.bifurcations:
        if envelopes and b["turbine_radius_um"] <= 0:  # a Hopf point (radius 0) on the log axis: at its foot
            ax.plot(b["speed_rpm"], 0.03, MARKS[b["type"]][0], color="C3", ms=7, label=b["type"],
                    transform=ax.get_xaxis_transform(), clip_on=False)
        else:
            ax.plot(b["speed_rpm"], b["turbine_radius_um"], MARKS[b["type"]][0], color="C3", ms=7, label=b["type"])
        axf.plot(b["speed_rpm"], b["frequency_hz"], MARKS[b["type"]][0], color="C3", ms=7)
    for a in (ax, axf):
        handles, labels = a.get_legend_handles_labels()
        uniq = dict(zip(labels, handles))
        if uniq:
            a.legend(uniq.values(), uniq.keys(), fontsize=7, loc="best", framealpha=0.7)  # where it hides least
        a.grid(alpha=0.3)
    if envelopes:
        ax.set_yscale("log")  # branches of a few µm next to whirls of 100 µm
    ax.set_ylabel("turbine wheel orbit radius [µm]")
    axf.set_ylabel("orbit frequency [Hz]")
    if fmax is not None:
        axf.set_ylim(0, fmax)
    axf.set_xlabel("rotor speed [rpm]")
    ax.set_title(title or "limit-cycle branches (black solid: stable, grey dashed: unstable)")
    fig.tight_layout()
    return fig


def _draw_spectrogram(axf, sp):
    amp = sp.forward + sp.backward
    db = 20 * np.log10(np.maximum(amp, 1e-300) / amp.max())
    order = np.argsort(sp.speeds_rpm)
    axf.pcolormesh(sp.speeds_rpm[order], sp.freqs_hz, db[:, order], cmap="Greys", vmin=-SPECTROGRAM_DB, vmax=0,
                   shading="nearest", alpha=0.6, rasterized=True)


def _draw_campbell(axf, cd, fmax, speed_range):
    lo, hi = speed_range
    colors = iter(f"C{i}" for i in (0, 2, 4, 6, 8, 9, 1, 5))
    for kind, label, s, f, style in campbell_lines(cd, fmax):
        sel = (s >= lo) & (s <= hi)
        if not np.isfinite(f[sel]).any():
            continue
        if kind == "mode":
            axf.plot(s[sel], f[sel], "-", lw=1.3, alpha=0.8, color=next(colors, "C0"), label=label)
        else:
            axf.plot(s[sel], f[sel], ls=style["ls"], lw=1.0, color=style["color"], alpha=0.8, label=label)


def diagram_html(bd, path=None, title=None, envelopes=(), campbell=None, include_plotlyjs=None):
    """The bifurcation diagram as an interactive HTML page (plotly; the content of :func:`diagram_figure` without
    the spectrogram; hover shows speed, radius, frequency and each bifurcation point's type, mode and film).

    Parameters
    ----------
    bd : BifurcationDiagram
    path : str or Path, optional
        The HTML file (None: only the figure).
    title : str, optional
    envelopes, campbell
        As for :func:`diagram_figure`.
    include_plotlyjs : {"directory", True}, optional
        See :func:`frbmodel.plots.figures.write_html`.

    Returns
    -------
    plotly.graph_objects.Figure
    """
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots


    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, vertical_spacing=0.06)
    for label, s, r in envelopes:
        fig.add_trace(go.Scatter(x=s, y=r, mode="lines", name=label, line=dict(width=1), opacity=0.6), 1, 1)
    fmax = _fmax(bd, None, campbell)
    if campbell is not None:
        lo, hi = _speed_range(bd, envelopes)
        for kind, label, s, f, style in campbell_lines(campbell, fmax):
            sel = (s >= lo) & (s <= hi)
            line = dict(width=1.3) if kind == "mode" else dict(width=1.3, dash=style["dash"], color=style["color"])
            fig.add_trace(go.Scatter(x=s[sel], y=f[sel], mode="lines", name=label, legendgroup=label, line=line),
                          2, 1)
    hover = "%{x:.0f} rpm<br>%{y:.3g}<extra>%{fullData.name}</extra>"
    for stable, s, r, f in stability_runs(bd):
        name = "stable branch" if stable else "unstable branch"
        line = dict(color="black", width=2.5) if stable else dict(color="grey", width=1.5, dash="dash")
        for row, y in ((1, r), (2, f)):
            fig.add_trace(go.Scatter(x=s, y=y, mode="lines", name=name, legendgroup=name, showlegend=False,
                                     line=line, hovertemplate=hover), row, 1)
    for kind, (_, symbol) in MARKS.items():
        sel = [b for b in bd.bifurcations if b["type"] == kind]
        if not sel:
            continue
        text = [f"{kind} {b.get('criticality', '')}<br>mode: {b.get('mode', '')}<br>film: {b.get('film', '')}"
                for b in sel]
        for row, key in ((1, "turbine_radius_um"), (2, "frequency_hz")):
            fig.add_trace(go.Scatter(x=[b["speed_rpm"] for b in sel], y=[b[key] for b in sel], mode="markers",
                                     name=kind, legendgroup=kind, showlegend=row == 1, text=text,
                                     marker=dict(symbol=symbol, size=10, color="crimson"),
                                     hovertemplate="%{x:.0f} rpm, %{y:.4g}<br>%{text}<extra></extra>"), row, 1)
    radius = "turbine wheel orbit radius [µm]"
    if envelopes:  # (decade ticks with plain numbers, over the radii drawn)
        radii = [t.y for t in fig.data if t.yaxis == "y" and t.y is not None]
        fig.update_yaxes(**log_axis(radius, np.concatenate([np.ravel(r) for r in radii])), row=1)
    else:
        fig.update_yaxes(title_text=radius, row=1)
    fig.update_yaxes(title_text="orbit frequency [Hz]", row=2, range=[0, fmax] if fmax else None)
    fig.update_xaxes(title_text="rotor speed [rpm]", row=2)
    fig.update_layout(title=title or "limit-cycle branches (solid: stable, dashed: unstable)",
                      **html_layout(legend_below=False))
    if path is not None:
        write_html(fig, path, include_plotlyjs)
    return fig
