"""Orbits of a run-up or co-simulation over a time or speed window.

For each floating-ring bearing: the journal relative to the ring (inner film) and the ring relative to the housing
(outer film), drawn with their clearance circles in µm and as eccentricity ratios ε = e / C (the clearance circle
is then the unit circle); and the wheel (disc) orbits relative to the housing in µm. A speed window of a run-up
or run-down is the samples around the first time the rotor passes a speed: ± a number of revolutions, or a speed
span.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..plots.figures import write_html
from ..plots.orbits import orbit_panels_figure, orbit_panels_html, orbits_figure
from ..plots.style import readable


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
        what = (f"time window {time_s[0]:g} ... {time_s[1]:g} s" if time_s is not None else
                f"window about {speed_rpm:g} rpm")
        raise ParameterError(f"the {what} holds {idx.size} samples of the run (0 ... {t[-1]:g} s, every "
                             f"{np.median(np.diff(t)) if t.size > 1 else 0:.3g} s): valid range at least 2; widen it")
    return idx


def _clearances(meta):
    """Bearing name -> (inner, outer) film clearance [m], from the system in the run's metadata."""
    sys_d = (meta or {}).get("system")
    if not sys_d:
        raise ParameterError("the run has no system in its metadata: the clearances are unknown")
    return {b["name"]: (b["inner"]["clearance"], b["outer"]["clearance"]) for b in sys_d["bearings"]}


@dataclass
class Orbits(Result):
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
    meta : dict
        Where the orbits come from: the run's system (as :meth:`Turbocharger.to_dict`), status and source, the
        window (``speed_rpm`` [rpm] and ``revolutions`` or ``span_rpm`` [rpm], or ``time_s`` [s]).
    """

    NC_GLOB = "orbits*.nc"  # (Result.load of a folder)
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

    def to_xarray(self):
        """The orbits as an :class:`xarray.Dataset` with dimensions time × bearing / disc × axis.

        Returns
        -------
        xarray.Dataset
            Coordinates ``time`` [s], ``speed`` [rpm] (along time), ``bearing``, ``disc`` and ``axis`` ("x", "y");
            variables ``journal_in_ring`` and ``ring_in_housing`` [m] (time, bearing, axis), ``eps_inner`` and
            ``eps_outer`` [-] (the same over the film clearances), ``wheel`` [m] (time, disc, axis),
            ``inner_clearance`` and ``outer_clearance`` [m] (bearing); each with ``units`` and ``long_name``.
            Attributes: ``title``, ``window`` (:attr:`label`) and :attr:`meta` (dicts as JSON text).

        Examples
        --------
        >>> t = np.linspace(0.0, 0.01, 5)
        >>> xy = np.zeros((5, 2))
        >>> o = Orbits(t, np.full(5, 3e4), {"b": xy}, {"b": xy}, {"wheel": xy}, {"b": (40e-6, 50e-6)}, "test")
        >>> ds = o.to_xarray()
        >>> dict(ds["journal_in_ring"].sizes), ds["eps_outer"].attrs["units"], ds["speed"].attrs["units"]
        ({'time': 5, 'bearing': 1, 'axis': 2}, '-', 'rpm')
        """
        import xarray as xr

        bearings, discs = list(self.clearances), list(self.wheels)
        tba, tda = ("time", "bearing", "axis"), ("time", "disc", "axis")

        def stack(arrays):  # (time, item, axis), also for no items
            return np.stack(arrays, axis=1) if arrays else np.zeros((self.time.size, 0, 2))

        def per_bearing(get):
            return stack([get(b) for b in bearings])

        data = {
            "journal_in_ring": variable(tba, per_bearing(self.journal_in_ring.get), "m",
                                        "journal centre relative to the ring centre"),
            "ring_in_housing": variable(tba, per_bearing(self.ring.get), "m", "ring centre relative to the housing"),
            "eps_inner": variable(tba, per_bearing(self.eps_inner), "-", "journal in ring / inner clearance"),
            "eps_outer": variable(tba, per_bearing(self.eps_outer), "-", "ring in housing / outer clearance"),
            "wheel": variable(tda, stack([self.wheels[d] for d in discs]), "m",
                              "disc displacement relative to the housing"),
            "inner_clearance": variable(("bearing",), [self.clearances[b][0] for b in bearings], "m",
                                        "inner film radial clearance"),
            "outer_clearance": variable(("bearing",), [self.clearances[b][1] for b in bearings], "m",
                                        "outer film radial clearance")}
        coords = {"time": variable(("time",), self.time, "s", "time"),
                  "speed": variable(("time",), self.speed_rpm, "rpm", "rotor speed"),
                  "bearing": variable(("bearing",), bearings, "", "bearing"),
                  "disc": variable(("disc",), discs, "", "disc"),
                  "axis": variable(("axis",), ["x", "y"], "", "x horizontal, y vertical")}
        attrs = {"title": f"orbits, {self.label}", "window": self.label, **self.meta}
        return xr.Dataset(data, coords, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The orbits from a dataset of :meth:`to_xarray` (e.g. read from a ``.nc`` of :meth:`save`).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        Orbits
        """
        attrs = {k: decode_attr(v) for k, v in ds.attrs.items()}
        label = str(attrs.pop("window", ""))
        attrs.pop("title", None)
        bearings = [str(b) for b in ds["bearing"].values]
        discs = [str(d) for d in ds["disc"].values]
        return cls(ds["time"].values, ds["speed"].values,
                   {b: ds["journal_in_ring"].values[:, k] for k, b in enumerate(bearings)},
                   {b: ds["ring_in_housing"].values[:, k] for k, b in enumerate(bearings)},
                   {d: ds["wheel"].values[:, k] for k, d in enumerate(discs)},
                   {b: (float(ds["inner_clearance"].values[k]), float(ds["outer_clearance"].values[k]))
                    for k, b in enumerate(bearings)}, label, attrs)

    @property
    def stem(self) -> str:
        """Default file name stem: ``orbits_<rpm>`` for a speed window, ``orbits_t<t0>-<t1>s`` for a time window."""
        if "speed_rpm" in self.meta:
            return f"orbits_{float(self.meta['speed_rpm']):.0f}"
        return f"orbits_t{self.time[0]:g}-{self.time[-1]:g}s"

    def save(self, out_dir, stem=None, png=True, html=True, csv=True, nc=True):
        """Write the figures, the table and the dataset into ``out_dir``.

        Parameters
        ----------
        out_dir : str or Path
            Folder (created if missing).
        stem : str, optional
            File name stem (default :attr:`stem`).
        png, html, csv, nc : bool
            Write ``<stem>.png`` (:meth:`plot`), ``.html`` (:meth:`plot_html`), ``.csv`` (:meth:`to_dataframe`)
            and ``.nc`` (:meth:`to_xarray`, read back by :meth:`load` and ``xarray.open_dataset``).

        Returns
        -------
        list of Path
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = stem or self.stem
        paths = []
        if png:
            import matplotlib.pyplot as plt

            fig = self.plot()
            paths.append(out / f"{stem}.png")  # not with_suffix: a time window's stem holds dots
            fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
            plt.close(fig)
        if html:
            paths.append(out / f"{stem}.html")
            self.plot_html(paths[-1])
        if csv:
            paths.append(out / f"{stem}.csv")
            self.to_dataframe().to_csv(paths[-1], index=False)
        if nc:
            paths.append(self.to_netcdf(out / f"{stem}.nc"))
        return paths

    @classmethod
    def load(cls, path):
        """Read orbits saved by :meth:`save` (the ``.nc`` file, or a folder holding exactly one ``orbits*.nc``).

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        Orbits

        Examples
        --------
        >>> import tempfile
        >>> t = np.linspace(0.0, 0.01, 5)
        >>> xy = np.column_stack([t, -t])
        >>> o = Orbits(t, np.full(5, 3e4), {"b": xy}, {"b": 2 * xy}, {}, {"b": (40e-6, 50e-6)}, "test")
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     back = Orbits.load(o.save(tmp, png=False, html=False, csv=False)[0])
        >>> bool(np.array_equal(back.ring["b"], o.ring["b"])), back.clearances, back.label
        (True, {'b': (4e-05, 5e-05)}, 'test')
        """
        return super().load(path)

    def panels(self):
        """The panels of the figures: (title, x [unit], y [unit], clearance circle radius or None, unit).

        Row 1 in µm (journal in ring, ring in housing per bearing, then the wheels), row 2 in ε.

        Returns
        -------
        list of list of tuple
        """
        um, eps = [], []
        for b, (ci, co) in self.clearances.items():
            j, r, e_in, e_out = self.journal_in_ring[b], self.ring[b], self.eps_inner(b), self.eps_outer(b)
            b = readable(b)
            um += [(f"{b}: journal in ring", j[:, 0] * 1e6, j[:, 1] * 1e6, ci * 1e6, "µm"),
                   (f"{b}: ring in housing", r[:, 0] * 1e6, r[:, 1] * 1e6, co * 1e6, "µm")]
            eps += [(f"{b}: journal in ring", e_in[:, 0], e_in[:, 1], 1.0, "ε"),
                    (f"{b}: ring in housing", e_out[:, 0], e_out[:, 1], 1.0, "ε")]
        for d, xy in self.wheels.items():
            um.append((readable(d), xy[:, 0] * 1e6, xy[:, 1] * 1e6, None, "µm"))
        return [um, eps]

    def plot(self, title=None, zoom=True):
        """Orbits in µm (top row: films with their clearance circles, then the wheels) and in ε (bottom row).

        Parameters
        ----------
        title : str, optional
        zoom : bool
            In the µm row, zoom onto a film orbit that spans less than
            :data:`frbmodel.plots.orbits.ZOOM_FRACTION` of its clearance
            circle's diameter (below a whirl onset the orbits are a small 1X ellipse about the static equilibrium);
            the ε row always shows the whole clearance.

        Returns
        -------
        matplotlib.figure.Figure
        """

        return orbit_panels_figure(self.panels(), title or f"Orbits, {self.label} (dashed: clearance circle; dot: "
                                   "last sample)", zoom)

    def plot_html(self, path=None, title=None, include_plotlyjs=None):
        """Interactive orbits (plotly), the panels of :meth:`plot`; written to ``path`` (HTML) if given.

        Parameters
        ----------
        path : str or Path, optional
            The HTML file.
        title : str, optional
            Figure title.
        include_plotlyjs : {"directory", True}, optional
            ``"directory"``: plotly.js from ``plotly.min.js`` beside the file, one copy per folder (small file, shown
            offline); ``True``: embedded (self-contained, 4.8 MB larger). Default: ``"directory"``, or what
            :func:`frbmodel.plots.figures.html_plotlyjs` set. See :func:`frbmodel.plots.figures.write_html`.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        fig = orbit_panels_html(self.panels(), title or f"Orbits, {self.label}")
        if path is not None:
            write_html(fig, path, include_plotlyjs)
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
    run_meta = run.meta or {}
    window = ({"speed_rpm": float(speed_rpm)} | ({"span_rpm": float(span_rpm)} if span_rpm is not None else
                                                 {"revolutions": float(revolutions)})
              if speed_rpm is not None else {"time_s": [float(time_s[0]), float(time_s[1])]})
    meta = {"system": run_meta.get("system"), "status": getattr(run, "status", ""),
            "source": "frbmodel.signals.orbits of a run-up / co-simulation", **window}
    return Orbits(np.asarray(run.time)[idx], np.asarray(run.speed_rpm)[idx],
                  {b: run.journal[b][idx] - run.ring[b][idx] for b in run.journal},
                  {b: run.ring[b][idx] for b in run.journal},
                  {d: xy[idx] for d, xy in run.displacement.items()},
                  {b: clear[b] for b in run.journal}, label, meta)


__all__ = ["Orbits", "orbits", "orbits_figure", "window_indices"]
