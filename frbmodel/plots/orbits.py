"""Orbit figures: journal in ring and ring in housing per bearing and the wheels, in µm and in ε
(:class:`frbmodel.signals.orbits.Orbits` ``.plot()`` / ``.plot_html()``), and several windows side by side. They
take the panels' arrays (or the windows' orbits) and compute nothing else."""
from __future__ import annotations

import numpy as np

from .style import HTML_HEIGHT_PX, readable

__all__ = ["ZOOM_FRACTION", "orbit_panels_figure", "orbit_panels_html", "orbits_figure"]

#: the µm row zooms onto a film orbit that spans less than this fraction of its clearance circle's diameter
ZOOM_FRACTION = 0.1


def orbit_panels_figure(rows, title, zoom=True):
    """Matplotlib figure of :meth:`frbmodel.signals.orbits.Orbits.panels` (rows of (title, x, y, clearance radius
    or None, unit)); ``zoom``: see :data:`ZOOM_FRACTION`."""
    import matplotlib.pyplot as plt

    ncol = max(len(r) for r in rows)
    fig, axs = plt.subplots(2, ncol, figsize=(2.9 * ncol, 6.0), squeeze=False)
    th = np.linspace(0, 2 * np.pi, 200)
    for i, row in enumerate(rows):
        for j in range(ncol):
            ax = axs[i, j]
            if j >= len(row):
                ax.axis("off")
                continue
            name, x, y, c, unit = row[j]
            ax.plot(x, y, lw=0.8)
            ax.plot(x[-1], y[-1], "o", ms=3, color="C3")
            if c is not None:
                ax.plot(c * np.cos(th), c * np.sin(th), "k--", lw=0.8)
            span = max(np.ptp(x), np.ptp(y))
            if zoom and i == 0 and c is not None and span < ZOOM_FRACTION * 2 * c:
                half = 0.6 * max(span, 1e-3 * c)  # a margin of 10 % each side; a still journal: ±0.06 % of c
                xc, yc = 0.5 * (x.min() + x.max()), 0.5 * (y.min() + y.max())
                ax.set_xlim(xc - half, xc + half)
                ax.set_ylim(yc - half, yc + half)
                ax.set_aspect("equal", adjustable="box")
                name += " (zoomed)"
            else:
                ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(name, fontsize=8)
            ax.set_xlabel(f"x [{unit}]", fontsize=8)
            ax.set_ylabel(f"y [{unit}]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def orbit_panels_html(rows, title):
    """The panels of :func:`orbit_panels_figure` as a plotly figure."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    ncol = max(len(r) for r in rows)
    titles = [row[j][0] if j < len(row) else "" for row in rows for j in range(ncol)]
    fig = make_subplots(rows=2, cols=ncol, subplot_titles=titles, horizontal_spacing=min(0.2, 0.4 / ncol),
                        vertical_spacing=0.16)  # (room for each panel's y title beside its neighbour's ticks)
    th = np.linspace(0, 2 * np.pi, 100)
    for i, row in enumerate(rows):
        for j, (name, x, y, c, unit) in enumerate(row):
            fig.add_trace(go.Scatter(x=x, y=y, mode="lines", name=f"{name} [{unit}]", line=dict(width=1)),
                          row=i + 1, col=j + 1)
            if c is not None:
                fig.add_trace(go.Scatter(x=c * np.cos(th), y=c * np.sin(th), mode="lines", showlegend=False,
                                         line=dict(dash="dash", color="black", width=1)), row=i + 1, col=j + 1)
            fig.update_xaxes(title_text=f"x [{unit}]", row=i + 1, col=j + 1)
            fig.update_yaxes(title_text=f"y [{unit}]", scaleanchor=f"x{i * ncol + j + 1}", row=i + 1,
                             col=j + 1)
    fig.update_layout(title=title, showlegend=False, height=HTML_HEIGHT_PX)
    return fig


def orbits_figure(windows, title=None):
    """Orbits of several windows side by side, one row each: per bearing the journal in the ring and the ring in
    the housing as ε (unit clearance circle dashed), and the wheels in µm.

    Parameters
    ----------
    windows : sequence of Orbits
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    bearings = list(windows[0].clearances)
    ncol = 2 * len(bearings) + 1
    fig, axs = plt.subplots(len(windows), ncol, figsize=(2.6 * ncol, 2.7 * len(windows)), squeeze=False)
    th = np.linspace(0, 2 * np.pi, 200)
    for i, o in enumerate(windows):
        cells = [(f"{readable(b)}: {w}", e) for b in bearings
                 for w, e in (("journal in ring", o.eps_inner(b)), ("ring in housing", o.eps_outer(b)))]
        for j, (name, e) in enumerate(cells):
            ax = axs[i, j]
            ax.plot(e[:, 0], e[:, 1], lw=0.7)
            ax.plot(np.cos(th), np.sin(th), "k--", lw=0.8)
            ax.set_xlim(-1.1, 1.1)
            ax.set_ylim(-1.1, 1.1)
            ax.set_aspect("equal")
            ax.set_title(f"{name}, ε", fontsize=8)
        ax = axs[i, -1]
        for d, xy in o.wheels.items():
            ax.plot(xy[:, 0] * 1e6, xy[:, 1] * 1e6, lw=0.7, label=readable(d))
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("wheels [µm]", fontsize=8)
        ax.legend(fontsize=6, loc="upper right")
        axs[i, 0].set_ylabel(o.label, fontsize=8)
        for ax in axs[i]:
            ax.tick_params(labelsize=6)
            ax.grid(alpha=0.3)
    fig.suptitle(title or "Orbits (dashed: clearance circle)", fontsize=10)
    fig.tight_layout()
    return fig
