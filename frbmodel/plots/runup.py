"""The overview figure of a run-up: rotor speed, ring-speed ratios, film eccentricity ratios and disc orbit radii
over time (:meth:`frbmodel.nonlinear.recorder.RunupResult.plot` / ``plot_html``). Takes arrays only."""
from __future__ import annotations

import numpy as np

from .style import html_layout, readable

__all__ = ["runup_overview", "runup_overview_html"]

#: (panel title, y-axis label) of the four panels, top to bottom
PANELS = (("rotor speed", "speed [krpm]"), ("ring-speed ratio", "RSR = ω_FR / ω_R [-]"),
          ("film eccentricity ratios", "ε [-]"), ("disc orbit radius", "radius [µm]"))


def _series(time_s, speed_rpm, rsr, eps, discs):
    """Per panel, the (label, y) pairs to draw (units of :data:`PANELS`)."""
    radius = {name: np.hypot(xy[:, 0], xy[:, 1]) * 1e6 for name, xy in discs.items()}
    return ([("rotor", np.asarray(speed_rpm) / 1e3)], [(readable(k), v) for k, v in rsr.items()],
            [(readable(k), v) for k, v in eps.items()], [(readable(k), v) for k, v in radius.items()])


def runup_overview(time_s, speed_rpm, rsr, eps, discs, title=None):
    """Matplotlib figure, four panels over time [s] (:data:`PANELS`).

    Parameters
    ----------
    time_s, speed_rpm : ndarray (n,)
        Sample times [s] and rotor speed [rpm].
    rsr, eps : dict of str to ndarray (n,)
        Ring-speed ratio per bearing [-]; eccentricity ratio per film [-].
    discs : dict of str to ndarray (n, 2)
        Disc displacement x, y [m] per disc.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, figsize=(9, 9), sharex=True, layout="constrained")
    for ax, (name, ylabel), series in zip(axes, PANELS, _series(time_s, speed_rpm, rsr, eps, discs)):
        for label, y in series:
            ax.plot(time_s, y, lw=0.8, label=label)
        ax.set_title(name, fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if len(series) > 1:
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    axes[-1].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    return fig


def runup_overview_html(time_s, speed_rpm, rsr, eps, discs, title=None):
    """The panels of :func:`runup_overview` as a plotly figure (one row each, shared time axis)."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    fig = make_subplots(rows=4, cols=1, shared_xaxes=True, subplot_titles=[p[0] for p in PANELS],
                        vertical_spacing=0.06)
    for row, ((_, ylabel), series) in enumerate(zip(PANELS, _series(time_s, speed_rpm, rsr, eps, discs)), 1):
        for label, y in series:
            fig.add_trace(go.Scattergl(x=time_s, y=y, name=label, mode="lines", line={"width": 1},
                                       legendgroup=str(row), showlegend=len(series) > 1), row=row, col=1)
        fig.update_yaxes(title_text=ylabel, row=row, col=1)
    fig.update_xaxes(title_text="time [s]", row=4, col=1)
    fig.update_layout(**html_layout(legend_below=False), title=title)
    return fig
