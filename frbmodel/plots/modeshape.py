"""Mode-shape figures: deflection lines and node orbits of one mode, the 3-D whirling shaft, a grid of modes
(:class:`frbmodel.linear.modeshape.ModeShape` ``.plot()`` / ``.plot_html()``). They take the mode (its shape and
orbit methods) and compute nothing else."""
from __future__ import annotations

import math

import numpy as np

from .figures import write_html

__all__ = ["RING_DRAW_FRACTION", "plot_mode_shape", "plot_mode_shape_html", "plot_mode_shapes"]

#: a ring's orbit is drawn when its semi-major axis exceeds this share of the largest rotor node orbit (the rings
#: are light: a ring that moves as much as the journal may carry < 1 % of the modal kinetic energy)
RING_DRAW_FRACTION = 0.02


def _orbit_points(a, b, n=73):
    phi = np.linspace(0.0, 2 * math.pi, n)
    return np.real(a * np.exp(1j * phi)), np.real(b * np.exp(1j * phi))


def plot_mode_shape(ms, ax=None, n_phases=8, title=None):
    """Deflection lines x(z) at ``n_phases`` phases and orbit ellipses at the nodes (see :meth:`ModeShape.plot`)."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 3.6))
    else:
        fig = ax.figure
    L = ms.node_z[-1]
    z = np.linspace(0.0, L, 300)
    for k in range(n_phases):
        x, _ = ms.deflection(z, 2 * math.pi * k / n_phases)
        ax.plot(z * 1e3, x, color=plt.cm.viridis(k / n_phases), lw=1.0, alpha=0.8)
    ax.axhline(0.0, color="0.6", lw=0.6)
    v, w, _, _ = ms.node_dofs()
    forward, rings = ms.node_forward(), ms.ring_major_axes()
    s = 0.35 * np.min(np.diff(ms.node_z)) * 1e3   # orbit scale on the z axis [mm per unit amplitude]
    for i in range(ms.n_nodes):
        ox, oy = _orbit_points(v[i], w[i])
        ax.plot(ms.node_z[i] * 1e3 + s * ox, oy, color="tab:red" if forward[i] else "tab:blue", lw=0.9)
    for name, node in ms.discs.items():
        ax.plot(ms.node_z[node] * 1e3, 0.0, "s", ms=10, mfc="none", mec="k")
        ax.annotate(name.replace("_", " "), (ms.node_z[node] * 1e3, -1.12), ha="center", fontsize=7)
    for k, node in enumerate(ms.bearings.values()):
        ax.plot(ms.node_z[node] * 1e3, -1.0, "^", color="0.3", ms=8)
        if rings.size and rings[k] > RING_DRAW_FRACTION:
            ox, oy = _orbit_points(*ms.ring_shapes()[k])
            ax.plot(ms.node_z[node] * 1e3 + s * ox, oy, color="tab:orange", lw=1.6, ls="--")
            ax.annotate(f"ring ({ms.ring_energy[k]:.1%} of energy)", (ms.node_z[node] * 1e3, 1.08), ha="center",
                        fontsize=7, color="tab:orange")
    ax.set_ylim(-1.25, 1.25)
    ax.set_xlabel("z [mm]")
    ax.set_ylabel("x / largest orbit semi-axis [-]")
    ax.set_title(title or ms.title, fontsize=9)
    return fig


def plot_mode_shape_html(ms, path=None, n_frames=24, include_plotlyjs=None):
    """Interactive 3-D (plotly) whirling shaft with a phase slider (see :meth:`ModeShape.plot_html`); written to
    ``path`` by :func:`frbmodel.plots.figures.write_html` if given."""
    import plotly.graph_objects as go


    z = np.linspace(0.0, ms.node_z[-1], 120) * 1e3
    xc, yc = ms.complex_deflection(z / 1e3)
    v, w, _, _ = ms.node_dofs()
    forward, rings = ms.node_forward(), ms.ring_major_axes()
    traces = []
    for i in range(ms.n_nodes):
        ox, oy = _orbit_points(v[i], w[i])
        traces.append(go.Scatter3d(x=np.full(ox.size, ms.node_z[i] * 1e3), y=ox, z=oy, mode="lines",
                                   line={"color": "red" if forward[i] else "blue", "width": 2},
                                   name=f"node {i} orbit", showlegend=False))
    for k, (name, node) in enumerate(ms.bearings.items()):
        if rings.size and rings[k] > RING_DRAW_FRACTION:
            ox, oy = _orbit_points(*ms.ring_shapes()[k])
            traces.append(go.Scatter3d(x=np.full(ox.size, ms.node_z[node] * 1e3), y=ox, z=oy, mode="lines",
                                       line={"color": "orange", "width": 5, "dash": "dash"},
                                       name=f"ring {name} ({ms.ring_energy[k]:.1%} of energy)"))
    dz = np.array([ms.node_z[n] * 1e3 for n in ms.discs.values()])

    def shaft(phi):
        e = np.exp(1j * phi)
        xd, yd = np.real(v * e), np.real(w * e)
        nodes = [ms.discs[n] for n in ms.discs]
        return [go.Scatter3d(x=z, y=np.real(xc * e), z=np.real(yc * e), mode="lines", line={"width": 7,
                             "color": "black"}, name="shaft"),
                go.Scatter3d(x=dz, y=xd[nodes], z=yd[nodes], mode="markers+text", text=list(ms.discs),
                             marker={"size": 9, "color": "green"}, name="wheels")]

    phases = np.linspace(0.0, 2 * math.pi, n_frames, endpoint=False)
    fig = go.Figure(data=shaft(0.0) + traces,
                    frames=[go.Frame(data=shaft(p), traces=[0, 1], name=f"{math.degrees(p):.0f}") for p in phases])
    steps = [{"args": [[f.name], {"frame": {"duration": 0, "redraw": True}, "mode": "immediate"}],
              "label": f.name + "°", "method": "animate"} for f in fig.frames]
    fig.update_layout(title=ms.title, sliders=[{"steps": steps, "currentvalue": {"prefix": "phase "}}],
                      updatemenus=[{"type": "buttons", "buttons": [{"label": "play", "method": "animate", "args": [
                          None, {"frame": {"duration": 60, "redraw": True}, "fromcurrent": True}]}]}],
                      scene={"xaxis_title": "z [mm]", "yaxis_title": "x [-]", "zaxis_title": "y [-]",
                             "yaxis": {"range": [-1.1, 1.1]}, "zaxis": {"range": [-1.1, 1.1]},
                             "aspectmode": "manual", "aspectratio": {"x": 2.5, "y": 1, "z": 1}})
    if path is not None:
        write_html(fig, path, include_plotlyjs)
    return fig


def plot_mode_shapes(shapes, ncols=2, n_phases=8, title=None):
    """Grid of :meth:`ModeShape.plot` panels, one per shape.

    Parameters
    ----------
    shapes : sequence of ModeShape
    ncols : int
    n_phases : int
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    n = len(shapes)
    ncols = max(1, min(ncols, n))
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.2 * ncols, 3.0 * nrows), squeeze=False)
    for ax, ms in zip(axes.ravel(), shapes):
        plot_mode_shape(ms, ax=ax, n_phases=n_phases)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    if title:
        _suptitle_clear(fig, fig.suptitle(title, fontsize=10))
    return fig


def _suptitle_clear(fig, text):
    """Lower the panels until the figure title ``text`` covers none of their titles (a tall figure's tight layout
    leaves too little room above the first row)."""
    renderer = getattr(fig.canvas, "get_renderer", lambda: None)()
    if renderer is None:
        return
    bottom = text.get_window_extent(renderer).y0
    top = max(ax.title.get_window_extent(renderer).y1 for ax in fig.axes if ax.get_visible())
    if top > bottom - 8:
        fig.subplots_adjust(top=fig.subplotpars.top - (top - bottom + 10) / fig.bbox.height)
