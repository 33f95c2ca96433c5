"""Figures of parameter studies: the stability map (onset speed vs a swept parameter) and the two-parameter
stability chart (:mod:`frbmodel.studies.sweep` writes them). They take the study's tables and compute nothing."""
from __future__ import annotations

import numpy as np

from .style import html_layout, readable

__all__ = ["stability_chart_figure", "stability_map_figures"]


def stability_map_figures(df, pcol):
    """The stability map's figures: onset speed vs the parameter ``pcol``, one line per linear mode / nonlinear
    component (markers only for bifurcation points), the legend beside the plot (not on the data), the parameter
    named in words and metres shown in µm.

    Parameters
    ----------
    df : pandas.DataFrame
        :func:`stability_map` (not empty).
    pcol : str
        Its parameter column, e.g. ``"outer_clearance [m]"``.

    Returns
    -------
    fig : matplotlib.figure.Figure
    pfig : plotly.graph_objects.Figure
    """
    import matplotlib.pyplot as plt
    import plotly.graph_objects as go

    scale, xlabel = (1e6, readable(pcol).replace("[m]", "[µm]")) if pcol.endswith("[m]") else (1.0, readable(pcol))
    fig, ax = plt.subplots(figsize=(9, 5.5))
    pfig = go.Figure()
    for (kind, method, item), g in df.groupby(["kind", "method", "item"]):
        g = g.sort_values(pcol)
        x = g[pcol].to_numpy() * scale
        y = g["onset [rpm]"].to_numpy() / 1e3
        lab = f"{method}: {item}"
        # a case can have several bifurcation points of one type (two folds): markers only, no line joining them
        ls = "-" if kind == "linear" else "--" if kind != "bifurcation" else "none"
        mk = "o" if kind == "linear" else "s" if kind != "bifurcation" else "D"
        ax.plot(x, y, ls, marker=mk, label=lab)
        pfig.add_trace(go.Scatter(x=x, y=y, mode="markers" if kind == "bifurcation" else "lines+markers", name=lab,
                                  line=dict(dash="solid" if kind == "linear" else "dash"),
                                  customdata=g["f at onset [Hz]"].to_numpy(),
                                  hovertemplate=f"{xlabel} %{{x:.4g}}<br>onset %{{y:.1f}} krpm<br>"
                                                f"f %{{customdata:.1f}} Hz<extra>{lab}</extra>"))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("onset speed [krpm]")
    ax.set_title("Stability map: linear (solid) and nonlinear (dashed) onsets", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the plot, never on the data
    fig.tight_layout()
    pfig.update_layout(xaxis_title=xlabel, yaxis_title="onset speed [krpm]", title="Stability map",
                       **html_layout(legend_below=False))
    return fig, pfig


def stability_chart_figure(x, y, onset_rpm, xcol, ycol, item):
    """Filled contour of an onset speed over two swept parameters (the stability chart).

    Parameters
    ----------
    x, y : ndarray
        Parameter values of the grid's columns and rows (SI; metres are drawn in µm).
    onset_rpm : ndarray (y.size, x.size)
        Onset speed [rpm].
    xcol, ycol : str
        The parameters' column names with their units, e.g. ``"outer_clearance [m]"``.
    item : str
        The onset drawn.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    sx = 1e6 if xcol.endswith("[m]") else 1.0
    sy = 1e6 if ycol.endswith("[m]") else 1.0
    fig, ax = plt.subplots(figsize=(7, 5))
    cs = ax.contourf(np.asarray(x) * sx, np.asarray(y) * sy, np.asarray(onset_rpm) / 1e3, levels=12, cmap="viridis")
    ax.contour(cs, colors="k", linewidths=0.4)
    fig.colorbar(cs, ax=ax, label=f"onset of {item} [krpm]")
    ax.set_xlabel(readable(xcol).replace("[m]", "[µm]"))  # (metres are drawn in µm)
    ax.set_ylabel(readable(ycol).replace("[m]", "[µm]"))
    ax.set_title(f"Stability chart: rotor speed at which {item} sets in", fontsize=10)
    return fig
