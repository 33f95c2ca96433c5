"""The figure of a static equilibrium: each bearing's journal in its ring and ring in the housing, as eccentricity
vectors in the clearance circles (:meth:`frbmodel.linear.equilibrium.EquilibriumResult.plot`). Takes arrays only."""
from __future__ import annotations

import numpy as np

from .style import html_layout, readable

__all__ = ["equilibrium_figure", "equilibrium_figure_html"]

#: the two films of a bearing: (title, key of the position in ``rows``)
FILMS = (("journal in ring (inner film)", "inner"), ("ring in housing (outer film)", "outer"))


def _points(rows):
    """Per bearing and film: (label, ε x, ε y) — the position over the clearance [-]."""
    out = []
    for r in rows:
        for title, key in FILMS:
            x, y = np.asarray(r[key]) / r[f"{key}_clearance"]
            out.append((f"{readable(r['name'])}: {title}", float(x), float(y)))
    return out


def equilibrium_figure(rows, title=None):
    """Matplotlib figure, one panel per film: the unit clearance circle and the eccentricity vector.

    Parameters
    ----------
    rows : list of dict
        Per bearing: ``name``, ``inner`` (journal minus ring centre [m], (2,)), ``outer`` (ring centre [m], (2,)),
        ``inner_clearance``, ``outer_clearance`` [m].
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    pts = _points(rows)
    fig, axes = plt.subplots(1, len(pts), figsize=(3.2 * len(pts), 3.6), layout="constrained", squeeze=False)
    phi = np.linspace(0.0, 2 * np.pi, 200)
    for ax, (label, x, y) in zip(axes[0], pts):
        ax.plot(np.cos(phi), np.sin(phi), color="0.5", lw=0.8)
        ax.plot([0.0, x], [0.0, y], color="C3", lw=1.5)
        ax.plot([x], [y], "o", color="C3")
        ax.set_aspect("equal")
        ax.set_xlim(-1.1, 1.1)
        ax.set_ylim(-1.1, 1.1)
        ax.set_title(f"{label}\nε = {np.hypot(x, y):.3f}", fontsize=9)
        ax.set_xlabel("x / c [-]")
        ax.set_ylabel("y / c [-]")
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig


def equilibrium_figure_html(rows, title=None):
    """The panels of :func:`equilibrium_figure` as a plotly figure."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    pts = _points(rows)
    fig = make_subplots(rows=1, cols=len(pts), subplot_titles=[f"{lab}, ε = {np.hypot(x, y):.3f}"
                                                               for lab, x, y in pts])
    phi = np.linspace(0.0, 2 * np.pi, 200)
    for k, (label, x, y) in enumerate(pts, 1):
        fig.add_trace(go.Scatter(x=np.cos(phi), y=np.sin(phi), mode="lines", line={"color": "grey", "width": 1},
                                 name="clearance circle", showlegend=k == 1), row=1, col=k)
        fig.add_trace(go.Scatter(x=[0.0, x], y=[0.0, y], mode="lines+markers", name=label, line={"width": 2}),
                      row=1, col=k)
        fig.update_xaxes(title_text="x / c [-]", range=[-1.1, 1.1], row=1, col=k)
        fig.update_yaxes(title_text="y / c [-]", range=[-1.1, 1.1], scaleanchor=f"x{k if k > 1 else ''}", row=1,
                         col=k)
    fig.update_layout(**html_layout(height=520), title=title)
    return fig
