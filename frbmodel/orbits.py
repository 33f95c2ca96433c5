"""Orbits of a run-up or co-simulation over a time or speed window.

For each floating-ring bearing: the journal relative to the ring (inner film) and the ring relative to the housing
(outer film), drawn with their clearance circles in µm and as eccentricity ratios ε = e / C (the clearance circle
is then the unit circle); and the wheel (disc) orbits relative to the housing in µm. A speed window of a run-up
or run-down is the samples around the first time the rotor passes a speed: ± a number of revolutions, or a speed
span.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import ParameterError


def window_indices(run, speed_rpm=None, time_s=None, revolutions=20.0, span_rpm=None):
    """Sample indices of a time or speed window of a run.

    Parameters
    ----------
    run : RunupResult
        Any object with ``time`` [s] and ``speed_rpm`` [rpm] arrays.
    speed_rpm : float, optional
        Centre speed [rpm]: the window is centred on the first sample closest to it (a run-up or run-down passes
        it once).
    time_s : (float, float), optional
        Time window [s] (instead of ``speed_rpm``), ends included.
    revolutions : float
        With ``speed_rpm``: half-width of the window in rotor revolutions at that speed (± revolutions / f_rot).
    span_rpm : float, optional
        With ``speed_rpm``: the window is instead the samples within ± span_rpm / 2 of it.

    Returns
    -------
    ndarray of int
        Sample indices, increasing.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> t = np.arange(0.0, 1.0, 1e-3)
    >>> run = SimpleNamespace(time=t, speed_rpm=60e3 - 30e3 * t)     # run-down 60 -> 30 krpm
    >>> idx = window_indices(run, 45e3, revolutions=3)           # 750 Hz: ±4 ms about t = 0.5 s
    >>> float(t[idx[0]]), float(t[idx[-1]])
    (0.496, 0.504)
    >>> idx = window_indices(run, 45e3, span_rpm=300)
    >>> float(run.speed_rpm[idx].min()), float(run.speed_rpm[idx].max())
    (44850.0, 45150.0)
    """
    t, s = np.asarray(run.time), np.asarray(run.speed_rpm)
    if (speed_rpm is None) == (time_s is None):
        raise ParameterError("give exactly one of speed_rpm and time_s")
    if time_s is not None:
        idx = np.flatnonzero((t >= time_s[0]) & (t <= time_s[1]))
    else:
        if not s.min() <= speed_rpm <= s.max():
            raise ParameterError(f"speed_rpm = {speed_rpm:g} is invalid: valid range {s.min():g} ... {s.max():g} "
                                 "rpm (the run's speeds)")
        i0 = int(np.argmin(np.abs(s - speed_rpm)))
        if span_rpm is not None:
            # the contiguous stretch about i0 within the span (a run passes each speed once)
            ok = np.abs(s - speed_rpm) <= 0.5 * span_rpm + 1e-9 * abs(speed_rpm)
            lo, hi = i0, i0
            while lo > 0 and ok[lo - 1]:
                lo -= 1
            while hi < s.size - 1 and ok[hi + 1]:
                hi += 1
            idx = np.arange(lo, hi + 1)
        else:
            half = revolutions * 60.0 / speed_rpm
            idx = np.flatnonzero(np.abs(t - t[i0]) <= half * (1 + 1e-9))
    if idx.size < 2:
        raise ParameterError("the window holds fewer than 2 samples: widen it")
    return idx


def _clearances(meta):
    """Bearing name -> (inner, outer) film clearance [m], from the system in the run's metadata."""
    sys_d = (meta or {}).get("system")
    if not sys_d:
        raise ParameterError("the run has no system in its metadata: the clearances are unknown")
    return {b["name"]: (b["inner"]["clearance"], b["outer"]["clearance"]) for b in sys_d["bearings"]}


@dataclass
class Orbits:
    """Orbits over a window of a run-up or co-simulation.

    Attributes
    ----------
    time : (n,) ndarray
        Sample times [s].
    speed_rpm : (n,) ndarray
        Rotor speed [rpm].
    journal_in_ring : dict of str to (n, 2) ndarray
        Bearing -> journal centre relative to the ring centre, x, y [m].
    ring : dict of str to (n, 2) ndarray
        Bearing -> ring centre relative to the housing, x, y [m].
    wheels : dict of str to (n, 2) ndarray
        Disc -> displacement x, y [m] relative to the housing.
    clearances : dict of str to (float, float)
        Bearing -> (inner, outer) radial clearance [m].
    label : str
        The window ("60000 rpm ± 20 rev", ...).
    """

    time: np.ndarray
    speed_rpm: np.ndarray
    journal_in_ring: dict
    ring: dict
    wheels: dict
    clearances: dict
    label: str = ""
    meta: dict = field(default_factory=dict)

    def eps_inner(self, bearing):
        """Journal-in-ring orbit as eccentricity ratio (x, y) / C_inner [-], (n, 2)."""
        return self.journal_in_ring[bearing] / self.clearances[bearing][0]

    def eps_outer(self, bearing):
        """Ring-in-housing orbit as eccentricity ratio (x, y) / C_outer [-], (n, 2)."""
        return self.ring[bearing] / self.clearances[bearing][1]

    def to_dataframe(self):
        """One row per sample: time [s], speed [rpm], per bearing the journal-in-ring and ring-in-housing x, y
        [µm] and ε [-], per disc x, y [µm].

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        cols = {"time [s]": self.time, "speed [rpm]": self.speed_rpm}
        for b in self.journal_in_ring:
            for what, xy, eps in (("journal in ring", self.journal_in_ring[b], self.eps_inner(b)),
                                  ("ring in housing", self.ring[b], self.eps_outer(b))):
                for k, ax in enumerate("xy"):
                    cols[f"{b} {what} {ax} [um]"] = xy[:, k] * 1e6
                    cols[f"{b} {what} eps_{ax} [-]"] = eps[:, k]
        for d, xy in self.wheels.items():
            for k, ax in enumerate("xy"):
                cols[f"{d} {ax} [um]"] = xy[:, k] * 1e6
        return pd.DataFrame(cols)

    def panels(self):
        """The panels of the figures: (title, x [unit], y [unit], clearance circle radius or None, unit).

        Row 1 in µm (journal in ring, ring in housing per bearing, then the wheels), row 2 in ε.

        Returns
        -------
        list of list of tuple
        """
        um, eps = [], []
        for b, (ci, co) in self.clearances.items():
            j, r = self.journal_in_ring[b], self.ring[b]
            um += [(f"{b}: journal in ring", j[:, 0] * 1e6, j[:, 1] * 1e6, ci * 1e6, "µm"),
                   (f"{b}: ring in housing", r[:, 0] * 1e6, r[:, 1] * 1e6, co * 1e6, "µm")]
            eps += [(f"{b}: journal in ring", self.eps_inner(b)[:, 0], self.eps_inner(b)[:, 1], 1.0, "ε"),
                    (f"{b}: ring in housing", self.eps_outer(b)[:, 0], self.eps_outer(b)[:, 1], 1.0, "ε")]
        for d, xy in self.wheels.items():
            um.append((f"{d}", xy[:, 0] * 1e6, xy[:, 1] * 1e6, None, "µm"))
        return [um, eps]

    def plot(self, title=None):
        """Orbits in µm (top row: films with their clearance circles, then the wheels) and in ε (bottom row).

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt

        rows = self.panels()
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
                ax.set_aspect("equal", adjustable="datalim")
                ax.set_title(name, fontsize=8)
                ax.set_xlabel(f"x [{unit}]", fontsize=8)
                ax.set_ylabel(f"y [{unit}]", fontsize=8)
                ax.tick_params(labelsize=7)
                ax.grid(alpha=0.3)
        fig.suptitle(title or f"Orbits, {self.label} (dashed: clearance circle; dot: last sample)", fontsize=10)
        fig.tight_layout()
        return fig

    def plot_html(self, path=None, title=None):
        """Interactive orbits (plotly), the panels of :meth:`plot`; written to ``path`` (HTML) if given.

        Returns
        -------
        plotly.graph_objects.Figure
        """
        import plotly.graph_objects as go
        from plotly.subplots import make_subplots

        rows = self.panels()
        ncol = max(len(r) for r in rows)
        titles = [row[j][0] if j < len(row) else "" for row in rows for j in range(ncol)]
        fig = make_subplots(rows=2, cols=ncol, subplot_titles=titles)
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
        fig.update_layout(title=title or f"Orbits, {self.label}", showlegend=False)
        if path is not None:
            fig.write_html(str(path), include_plotlyjs="cdn")
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
        cells = [(f"{b}: {w}", e) for b in bearings
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
            ax.plot(xy[:, 0] * 1e6, xy[:, 1] * 1e6, lw=0.7, label=d)
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


def orbits(run, speed_rpm=None, time_s=None, revolutions=20.0, span_rpm=None):
    """Orbits of a run-up / co-simulation over a window (see :func:`window_indices`).

    Parameters
    ----------
    run : RunupResult
        With the system in ``run.meta["system"]`` (for the clearances).
    speed_rpm, time_s, revolutions, span_rpm
        The window, as for :func:`window_indices`.

    Returns
    -------
    Orbits

    Examples
    --------
    A journal circling in its ring at radius 10 µm, the ring still, inner clearance 40 µm:

    >>> from types import SimpleNamespace
    >>> t = np.linspace(0, 0.01, 101)
    >>> c = 10e-6 * np.column_stack([np.cos(2e3 * t), np.sin(2e3 * t)])
    >>> sys_d = {"bearings": [{"name": "b", "inner": {"clearance": 40e-6}, "outer": {"clearance": 50e-6}}]}
    >>> run = SimpleNamespace(time=t, speed_rpm=np.full(t.size, 3e4), journal={"b": c},
    ...                       ring={"b": 0 * c}, displacement={}, meta={"system": sys_d})
    >>> o = orbits(run, time_s=(0, 0.01))
    >>> float(np.hypot(*o.eps_inner("b").T).max().round(12))
    0.25
    """
    idx = window_indices(run, speed_rpm, time_s, revolutions, span_rpm)
    clear = _clearances(run.meta)
    if speed_rpm is not None:
        label = f"{speed_rpm:.0f} rpm " + (f"± {span_rpm / 2:g} rpm" if span_rpm is not None
                                           else f"± {revolutions:g} revolutions")
    else:
        label = f"t = {time_s[0]:g} ... {time_s[1]:g} s"
    return Orbits(np.asarray(run.time)[idx], np.asarray(run.speed_rpm)[idx],
                  {b: run.journal[b][idx] - run.ring[b][idx] for b in run.journal},
                  {b: run.ring[b][idx] for b in run.journal},
                  {d: xy[idx] for d, xy in run.displacement.items()},
                  {b: clear[b] for b in run.journal}, label)


__all__ = ["Orbits", "orbits", "orbits_figure", "window_indices"]
