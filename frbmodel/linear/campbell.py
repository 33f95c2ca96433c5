"""Holistic Campbell diagram: frequencies, modal damping and precession of all modes vs rotor speed.

Stability of a mode at a speed is read from its modal damping D and the round-off bound of D
(:func:`frbmodel.linear.modal.damping_tolerance`): D > bound stable, |D| <= bound *neutral* (undamped: the computed sign
of D is round-off), D < −bound unstable. The undamped methods A, B and E therefore have neutral modes only.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import (
    ConvergenceError,
    FilmContactError,
    ParameterError,
    check_system,
)
from ..core.progress import counter_bar, progress_enabled
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..core.units import rpm_to_rad_s
from ..core.version import __version__
from ..plots.figures import campbell_figure, campbell_plotly, full_fmax, write_html
from ..system.methods import get_method
from ..system.presets import PAPER_SPEED_RANGE_RPM
from .assembly import linear_system
from .critical import critical_speeds
from .equilibrium import bearing_equilibrium
from .modal import (
    batch_modes,
    classify_precession,
    precession_index,
    ring_energy_fraction,
    shape_class,
    speed_modes,
    stability_labels,
    track,
)
from .modeshape import mode_shape, shape_hover_text
from .thermal import at_operating_point, check_oil_supply
from .whirl import FILM_NAMES, ONSET_SEARCH_RPM, bearing_whirl, film_names, film_onset_speeds

#: a mode is called a ring mode when the rings carry more than this share of its kinetic energy
RING_MODE_FRACTION = 0.5
#: how the onsets of :attr:`CampbellResult.whirl_onset_rpm` are computed by :func:`campbell`
EXACT_ONSET_SOURCE = ("frbmodel.film_onset_speeds: Lund threshold at the method-J equilibria, Brent root to 1e-6 rpm "
                      "(independent of the speed grid)")
GRID_ONSET_SOURCE = "linear interpolation of the whirl margin between the speeds of the grid"
#: what "neutral" means in the result files
NEUTRAL_RULE = ("|D| <= damping round-off bound N eps ||A_b||_F kappa_b / |lambda| "
                "(frbmodel.linear.modal.damping_tolerance): neutral; D below -bound: unstable; above +bound: stable")

_PER_MODE = ("frequencies_hz", "damping", "precession", "mode_kind", "ring_fraction", "eigenvalues", "damping_tol")
_PER_FILM = ("eccentricity", "whirl_hz", "whirl_margin")


@dataclass
class CampbellResult(Result):
    """Result of :func:`campbell` (and :func:`frbmodel.cosim.linearize.campbell_from_fmu`).

    Arrays are per speed (rows, ascending speed whatever the order of the grid given) and tracked mode (columns);
    where a tracked mode is absent at a speed (e.g. over-damped there) its numbers are NaN and its labels "".

    Attributes
    ----------
    method : str
        Method letter (the paper's Table 1).
    speeds_rpm : ndarray (n,)
        Rotor speeds [rpm], ascending.
    frequencies_hz : ndarray (n, m)
        Damped natural frequencies Im λ / 2π [Hz].
    damping : ndarray (n, m)
        Modal damping D = −Re λ / |λ| [-]; see :attr:`stability`.
    precession : ndarray (n, m) of str
        "forward" | "backward" | "mixed".
    mode_kind : ndarray (n, m) of str
        "cylindrical" | "conical" | "bending" (rotor modes, from the shaft's displacement pattern) or "ring" (the
        rings carry > 50 % of the kinetic energy).
    ring_fraction : ndarray (n, m)
        Ring share of the modal kinetic energy [-].
    eigenvalues : complex ndarray (n, m)
        λ [1/s] (NaN + NaN j where absent).
    ring_speed_ratio : ndarray (n, n_bearings)
        RSR of each bearing [-] (NaN for methods without film equilibrium).
    eccentricity : ndarray (n, 2 n_bearings)
        ε of the films at the whirl (method J) equilibrium, in the order of :attr:`film_labels`.
    whirl_hz : ndarray (n, 2 n_bearings)
        Film whirl frequencies γ ω_s / 2π [Hz] (method-J equilibria, docs/theory/whirl.md#film-whirl).
    whirl_margin : ndarray (n, 2 n_bearings)
        > 0 where the film is past its whirl onset [-].
    meta : dict
        Everything the result was computed with (system, method and options, film model, source); written to
        the JSON by :meth:`save`.
    damping_tol : ndarray (n, m)
        Round-off bound of ``damping`` [-] (:func:`frbmodel.linear.modal.damping_tolerance`; default 0).
    whirl_onset_rpm : ndarray (2 n_bearings,)
        Whirl onset speed of each film [rpm]: exact (:func:`frbmodel.film_onset_speeds`) when computed by
        :func:`campbell`, else interpolated on the grid; ``meta["whirl_onset_source"]`` says which. NaN: the film
        does not pass its threshold in the searched range.

    Examples
    --------
    >>> import numpy as np, frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "J", np.linspace(250e3, 10e3, 5))    # a descending grid
    >>> cd.speeds_rpm.tolist()
    [10000.0, 70000.0, 130000.0, 190000.0, 250000.0]
    >>> [round(float(x)) for x in cd.whirl_onset_rpm]    # exact, not interpolated on the 60 krpm grid
    [11073, 68146, 11821, 69224]
    >>> int(frb.campbell(frb.turbocharger(), "B", [50e3, 150e3], whirl=False).n_unstable.max())  # undamped: neutral
    0
    """

    NC_GLOB = "campbell*.nc"  # (Result.load of a folder)
    method: str
    speeds_rpm: np.ndarray
    frequencies_hz: np.ndarray
    damping: np.ndarray
    precession: np.ndarray
    mode_kind: np.ndarray
    ring_fraction: np.ndarray
    eigenvalues: np.ndarray
    ring_speed_ratio: np.ndarray
    eccentricity: np.ndarray
    whirl_hz: np.ndarray
    whirl_margin: np.ndarray
    meta: dict = field(default_factory=dict)
    damping_tol: np.ndarray | None = None
    whirl_onset_rpm: np.ndarray | None = None

    def __post_init__(self):
        self.speeds_rpm = np.asarray(self.speeds_rpm, dtype=float).ravel()
        n = self.speeds_rpm.size
        self.eigenvalues = np.asarray(self.eigenvalues, dtype=complex)
        if self.eigenvalues.ndim != 2:
            self.eigenvalues = self.eigenvalues.reshape(n, -1)
        m = self.eigenvalues.shape[1]
        if self.damping_tol is None:
            self.damping_tol = np.zeros((n, m))
        for name in _PER_MODE + ("ring_speed_ratio",) + _PER_FILM:
            a = np.asarray(getattr(self, name), dtype=object if name in ("precession", "mode_kind") else None)
            if a.ndim != 2 or a.shape[0] != n or (name in _PER_MODE and a.shape[1] != m):
                raise ParameterError(f"CampbellResult.{name} has shape {a.shape}; expected ({n}, "
                                     f"{m if name in _PER_MODE else 'k'}) for {n} speeds and {m} modes")
            setattr(self, name, a)
        self._mark_absent()
        self._sort_by_speed()
        if self.whirl_onset_rpm is None:
            self.whirl_onset_rpm = self.whirl_onset_on_grid()
            self.meta.setdefault("whirl_onset_source", GRID_ONSET_SOURCE)
        self.whirl_onset_rpm = np.asarray(self.whirl_onset_rpm, dtype=float)

    def _mark_absent(self):
        """Where a tracked mode is absent (non-finite λ): NaN numbers and empty labels in every array."""
        absent = ~np.isfinite(self.eigenvalues)
        if absent.any():
            self.eigenvalues[absent] = complex(math.nan, math.nan)
            for name in ("frequencies_hz", "damping", "ring_fraction", "damping_tol"):
                a = np.array(getattr(self, name), dtype=float)
                a[absent] = math.nan
                setattr(self, name, a)
            self.precession[absent] = ""
            self.mode_kind[absent] = ""

    def _sort_by_speed(self):
        order = np.argsort(self.speeds_rpm, kind="stable")
        if np.array_equal(order, np.arange(order.size)):
            return
        self.speeds_rpm = self.speeds_rpm[order]
        for name in _PER_MODE + ("ring_speed_ratio",) + _PER_FILM:
            setattr(self, name, getattr(self, name)[order])

    # ------------------------------------------------------------------ derived
    @property
    def n_modes(self) -> int:
        """Number of tracked modes (columns)."""
        return self.frequencies_hz.shape[1]

    @property
    def film_labels(self) -> tuple:
        """Film names in the order of the whirl columns (from the system; Table 2 order by default)."""
        n = self.whirl_hz.shape[1]
        names = tuple(self.meta.get("films") or FILM_NAMES)
        return tuple(names[k] if k < len(names) else f"film {k}" for k in range(n))

    @property
    def bearing_names(self) -> tuple:
        """Bearing names in the order of the RSR columns."""
        names = tuple(self.meta.get("bearings") or (lab.rsplit(" ", 1)[0] for lab in self.film_labels[::2]))
        return tuple(names[k] if k < len(names) else f"bearing {k}" for k in range(self.ring_speed_ratio.shape[1]))

    @property
    def system_name(self) -> str:
        """Name of the analysed system (for titles)."""
        name = self.meta.get("system_name", self.meta.get("system", ""))
        return name if isinstance(name, str) else ""

    @property
    def stability(self) -> np.ndarray:
        """(n, m) "stable" | "neutral" | "unstable" | "" (absent), from D and its round-off bound."""
        return stability_labels(self.damping, self.damping_tol)

    @property
    def unstable(self) -> np.ndarray:
        """(n, m) bool: D < −round-off bound (growing mode)."""
        with np.errstate(invalid="ignore"):
            return self.damping < -self.damping_tol

    @property
    def neutral(self) -> np.ndarray:
        """(n, m) bool: |D| <= round-off bound (undamped; the sign of the computed D is round-off)."""
        with np.errstate(invalid="ignore"):
            return np.abs(self.damping) <= self.damping_tol

    @property
    def n_unstable(self) -> np.ndarray:
        """Number of unstable modes per speed (n,) (neutral modes do not count)."""
        return np.sum(self.unstable, axis=1)

    @property
    def n_neutral(self) -> np.ndarray:
        """Number of neutral modes per speed (n,)."""
        return np.sum(self.neutral, axis=1)

    def whirl_onset_on_grid(self) -> np.ndarray:
        """First speed of the grid (linearly interpolated) where each film passes its onset.

        Returns
        -------
        ndarray (2 n_bearings,)
            [rpm]; the first grid speed if the film is past its onset there already, NaN if it never is.
        """
        out = np.full(self.whirl_margin.shape[1], np.nan)
        s = self.speeds_rpm
        for k in range(out.size):
            m = self.whirl_margin[:, k]
            idx = np.flatnonzero((m[:-1] <= 0) & (m[1:] > 0))
            if idx.size:
                j = idx[0]
                out[k] = s[j] + (s[j + 1] - s[j]) * (-m[j]) / (m[j + 1] - m[j])
            elif m.size and m[0] > 0:
                out[k] = s[0]
        return out

    def unstable_ranges(self):
        """Each mode's speed ranges with D < −round-off bound (neutral modes are not unstable).

        Returns
        -------
        pandas.DataFrame
            Columns: mode, kind, precession (the most frequent in the range), from [rpm], to [rpm] (from <= to),
            f at start [Hz], f at end [Hz], min damping [-]; sorted by "from [rpm]".
        """
        import pandas as pd

        rows = []
        uns = self.unstable
        for j in range(self.n_modes):
            if not uns[:, j].any():
                continue
            edges = np.diff(np.concatenate([[0], uns[:, j].astype(int), [0]]))
            starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
            for a, b in zip(starts, ends):
                vals, counts = np.unique(self.precession[a:b + 1, j], return_counts=True)
                kv, kc = np.unique(self.mode_kind[a:b + 1, j], return_counts=True)
                rows.append({"mode": j, "kind": kv[np.argmax(kc)], "precession": vals[np.argmax(counts)],
                             "from [rpm]": self.speeds_rpm[a], "to [rpm]": self.speeds_rpm[b],
                             "f at start [Hz]": self.frequencies_hz[a, j], "f at end [Hz]": self.frequencies_hz[b, j],
                             "min damping [-]": np.nanmin(self.damping[a:b + 1, j])})
        df = pd.DataFrame(rows, columns=["mode", "kind", "precession", "from [rpm]", "to [rpm]", "f at start [Hz]",
                                         "f at end [Hz]", "min damping [-]"])
        return df.sort_values("from [rpm]", kind="stable").reset_index(drop=True)

    def to_dataframe(self):
        """Long-format table: one row per speed and *present* mode (absent modes have no row).

        Returns
        -------
        pandas.DataFrame
            speed [rpm], mode [-], frequency [Hz], damping [-], damping round-off bound [-], growth rate
            Re(lambda) [1/s], stability (stable | neutral | unstable), precession, kind, ring energy fraction [-].
        """
        import pandas as pd

        ii, jj = np.nonzero(np.isfinite(self.eigenvalues))
        return pd.DataFrame({
            "speed [rpm]": self.speeds_rpm[ii],
            "mode [-]": jj,
            "frequency [Hz]": self.frequencies_hz[ii, jj],
            "damping [-]": self.damping[ii, jj],
            "damping round-off bound [-]": self.damping_tol[ii, jj],
            "growth rate Re(lambda) [1/s]": self.eigenvalues[ii, jj].real,
            "stability": self.stability[ii, jj],
            "precession": self.precession[ii, jj],
            "kind": self.mode_kind[ii, jj],
            "ring energy fraction [-]": self.ring_fraction[ii, jj],
        })

    def films_dataframe(self):
        """Per-speed film data: RSR, eccentricities, whirl frequencies and margins (units in the column names).

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        d = {"speed [rpm]": self.speeds_rpm}
        for i, name in enumerate(self.bearing_names):
            d[f"RSR {name} [-]"] = self.ring_speed_ratio[:, i]
        for k, name in enumerate(self.film_labels):
            d[f"eps {name} [-]"] = self.eccentricity[:, k]
            d[f"whirl {name} [Hz]"] = self.whirl_hz[:, k]
            d[f"whirl margin {name} [-]"] = self.whirl_margin[:, k]
        return pd.DataFrame(d)

    def onsets_dataframe(self):
        """Film whirl onsets with their source and whether they lie inside the speed grid.

        Returns
        -------
        pandas.DataFrame
            film, onset [rpm] (NaN: none found), inside grid (bool), past onset at grid start (bool), source.
        """
        import pandas as pd

        s0, s1 = self.speeds_rpm.min(), self.speeds_rpm.max()
        on = self.whirl_onset_rpm
        with np.errstate(invalid="ignore"):
            return pd.DataFrame({"film": list(self.film_labels), "onset [rpm]": on,
                                 "inside grid": (on >= s0) & (on <= s1),
                                 "past onset at grid start": self.whirl_margin[0] > 0,
                                 "source": self.meta.get("whirl_onset_source", "")})

    def mode_shape(self, speed_rpm, mode):
        """Shape of tracked mode ``mode`` at ``speed_rpm``, solved at exactly that speed.

        Delegates to :func:`frbmodel.linear.modeshape.mode_shape`.

        Parameters
        ----------
        speed_rpm : float
            Rotor speed [rpm] within the range where the mode is present.
        mode : int
            Column of the Campbell arrays.

        Returns
        -------
        frbmodel.linear.modeshape.ModeShape
        """
        return mode_shape(self, speed_rpm, mode)

    # ------------------------------------------------------------------ output
    def plot(self, fmax_hz=None, whirl=True, one_x=True, ax=None, title=None):
        """Holistic Campbell diagram (matplotlib); see :func:`frbmodel.plots.figures.campbell_figure`.

        Parameters
        ----------
        fmax_hz : float, optional
            Upper frequency limit [Hz].
        whirl, one_x : bool
            Draw the film whirl curves and the 1X line.
        ax : matplotlib.axes.Axes, optional
        title : str, optional

        Returns
        -------
        matplotlib.figure.Figure
        """

        critical = critical_speeds(self, refine=False) if one_x and self.speeds_rpm.size >= 2 else None
        return campbell_figure(self, fmax_hz=fmax_hz, whirl=whirl, one_x=one_x, ax=ax, title=title,
                               critical=critical)

    def plot_html(self, path=None, fmax_hz=None, whirl=True, one_x=True, shapes=True, include_plotlyjs=None):
        """Interactive plotly figure (hover: speed, frequency, D, stability, precession, mode kind and shape).

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there as HTML.
        fmax_hz : float, optional
            Upper frequency limit [Hz].
        whirl, one_x : bool
            Draw the film whirl curves and the 1X line.
        shapes : bool
            List each point's mode shape in its hover text: orbit semi-major axis (largest = 1), phase of x and
            whirl direction at every disc, journal and ring (:func:`frbmodel.linear.modeshape.shape_hover_text`;
            needs the system in :attr:`meta`).
        include_plotlyjs : {"directory", True}, optional
            ``"directory"``: plotly.js from ``plotly.min.js`` beside the file, one copy per folder (small file, shown
            offline); ``True``: embedded (self-contained, 4.8 MB larger). Default: ``"directory"``, or what
            :func:`frbmodel.plots.figures.html_plotlyjs` set. See :func:`frbmodel.plots.figures.write_html`.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        shown = np.isfinite(self.frequencies_hz) & (self.frequencies_hz <= (fmax_hz or full_fmax(self)))
        hover = shape_hover_text(self, shown) if shapes else None
        critical = critical_speeds(self, refine=False) if one_x and self.speeds_rpm.size >= 2 else None
        fig = campbell_plotly(self, fmax_hz=fmax_hz, whirl=whirl, one_x=one_x, hover=hover, critical=critical)
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def metadata(self) -> dict:
        """What the result was computed with and its summary, JSON-ready (the content of :meth:`save`'s JSON).

        Returns
        -------
        dict
            ``meta`` (system as :meth:`Turbocharger.to_dict`, method, method options, film model, source, ...) plus
            the speed grid [rpm], the whirl onsets [rpm] and their source, the film names, the stability rule and
            the units.
        """

        meta = dict(self.meta)
        meta.update({
            "method": self.method, "speeds_rpm": [float(s) for s in self.speeds_rpm],
            "whirl_onset_rpm": [None if not np.isfinite(x) else float(x) for x in self.whirl_onset_rpm],
            "films": list(self.film_labels), "bearings": list(self.bearing_names), "stability_rule": NEUTRAL_RULE,
            "max_unstable_modes": int(self.n_unstable.max(initial=0)),
            "max_neutral_modes": int(self.n_neutral.max(initial=0)), "frbmodel_version": __version__,
            "units": {"speed": "rpm", "frequency": "Hz", "damping": "-", "eccentricity": "-", "clearance": "m"}})
        return meta

    def to_xarray(self):
        """The diagram as an :class:`xarray.Dataset` with dimensions speed × mode (and bearing, film).

        Returns
        -------
        xarray.Dataset
            Coordinates ``speed`` [rpm], ``mode`` (tracked mode index), ``bearing`` and ``film`` (names); per
            speed and mode ``frequency`` [Hz], ``damping`` [-], ``damping_tol`` [-] (its round-off bound),
            ``growth_rate`` Re λ [1/s] (λ = growth_rate + 2πi frequency), ``stability``, ``precession``, ``kind``
            (strings, "" where the mode is absent) and ``ring_energy_fraction`` [-]; per speed and bearing
            ``ring_speed_ratio`` [-]; per speed and film ``eccentricity`` [-], ``whirl_frequency`` [Hz] and
            ``whirl_margin`` [-]; per film ``whirl_onset`` [rpm]. Every variable has ``units`` and
            ``long_name``; the attributes are :meth:`metadata` (dicts and lists as JSON text).

        Examples
        --------
        >>> import frbmodel as frb
        >>> ds = frb.campbell(frb.turbocharger(), "A", [50e3, 100e3], whirl=False).to_xarray()
        >>> dict(ds["frequency"].sizes), ds["frequency"].attrs["units"], ds.attrs["method"]
        ({'speed': 2, 'mode': 16}, 'Hz', 'A')
        """
        import xarray as xr

        sm, sb, sf = ("speed", "mode"), ("speed", "bearing"), ("speed", "film")
        labels = {"stability": self.stability, "precession": self.precession, "kind": self.mode_kind}
        data = {
            "frequency": variable(sm, self.frequencies_hz, "Hz", "damped natural frequency Im(lambda)/(2 pi)"),
            "damping": variable(sm, self.damping, "-", "modal damping D = -Re(lambda)/|lambda|"),
            "damping_tol": variable(sm, self.damping_tol, "-", "round-off bound of the modal damping"),
            "growth_rate": variable(sm, self.eigenvalues.real, "1/s", "growth rate Re(lambda)"),
            **{k: variable(sm, v.astype(str), "", k) for k, v in labels.items()},
            "ring_energy_fraction": variable(sm, self.ring_fraction, "-", "ring share of the modal kinetic energy"),
            "ring_speed_ratio": variable(sb, self.ring_speed_ratio, "-", "ring speed / rotor speed"),
            "eccentricity": variable(sf, self.eccentricity, "-", "film eccentricity ratio (method-J equilibrium)"),
            "whirl_frequency": variable(sf, self.whirl_hz, "Hz", "film whirl frequency"),
            "whirl_margin": variable(sf, self.whirl_margin, "-", "film whirl margin (> 0: past the whirl onset)"),
            "whirl_onset": variable(("film",), self.whirl_onset_rpm, "rpm", "film whirl onset speed"),
        }
        coords = {"speed": variable(("speed",), self.speeds_rpm, "rpm", "rotor speed"),
                  "mode": variable(("mode",), np.arange(self.n_modes), "", "tracked mode index"),
                  "bearing": variable(("bearing",), list(self.bearing_names), "", "bearing"),
                  "film": variable(("film",), list(self.film_labels), "", "film (bearing and inner/outer)")}
        title = f"Campbell diagram, method {self.method}" + (f", {self.system_name}" if self.system_name else "")
        return xr.Dataset(data, coords, attrs={"title": title, **netcdf_attrs(self.metadata())})

    #: keys of :meth:`metadata` derived from the arrays (not kept in ``meta`` when a result is read back)
    _DERIVED_META = ("method", "speeds_rpm", "whirl_onset_rpm", "max_unstable_modes", "max_neutral_modes",
                     "stability_rule", "units", "frbmodel_version", "title")

    @classmethod
    def from_xarray(cls, ds):
        """The result from a dataset of :meth:`to_xarray` (e.g. read from a ``.nc`` file written by :meth:`save`).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        CampbellResult
            Equal to the saved one (λ rebuilt as growth_rate + 2πi frequency, to round-off in its imaginary part).
        """
        meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        method = meta["method"]
        arr = {k: ds[k].values for k in ds.data_vars}
        lam = arr["growth_rate"] + 2j * np.pi * arr["frequency"]
        meta = {k: v for k, v in meta.items() if k not in cls._DERIVED_META}
        return cls(method, ds["speed"].values, arr["frequency"], arr["damping"], arr["precession"].astype(object),
                   arr["kind"].astype(object), arr["ring_energy_fraction"], lam, arr["ring_speed_ratio"],
                   arr["eccentricity"], arr["whirl_frequency"], arr["whirl_margin"], meta, arr["damping_tol"],
                   arr["whirl_onset"])

    @classmethod
    def load(cls, path):
        """Read a Campbell diagram saved by :meth:`save` (its ``.nc`` file).

        Parameters
        ----------
        path : str or Path
            The ``.nc`` file, or a folder holding exactly one ``campbell*.nc``.

        Returns
        -------
        CampbellResult

        Raises
        ------
        ParameterError
            If there is no such file or the folder holds several.

        Examples
        --------
        >>> import tempfile, frbmodel as frb
        >>> cd = frb.campbell(frb.turbocharger(), "A", [50e3, 100e3], whirl=False)
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     _ = cd.save(tmp, png=False, html=False)
        ...     back = CampbellResult.load(tmp)
        >>> back.method, bool(np.array_equal(back.damping, cd.damping)), back.meta["system_name"] == cd.system_name
        ('A', True, True)
        """
        return super().load(path)

    def save(self, out_dir, stem=None, fmax_hz=None, png=True, html=True, nc=True):
        """Write the tables, the metadata, the dataset and the figures into ``out_dir``.

        Parameters
        ----------
        out_dir : str or Path
            Folder (created if missing).
        stem : str, optional
            File name stem (default ``campbell_<method>``).
        fmax_hz : float, optional
            Upper frequency limit of the figures [Hz].
        png, html : bool
            Write the matplotlib PNG / plotly HTML figure.
        nc : bool
            Write ``<stem>.nc``: :meth:`to_xarray` as netCDF-4 (read it with ``xarray.open_dataset`` or
            :meth:`load`).

        Returns
        -------
        list of Path
            ``<stem>_modes.csv`` (:meth:`to_dataframe`), ``<stem>_films.csv``, ``<stem>_unstable.csv``,
            ``<stem>.json`` (:meth:`metadata`), ``<stem>.nc`` and the figures.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = stem or f"campbell_{self.method}"
        paths = []
        for suffix, table in (("modes", self.to_dataframe), ("films", self.films_dataframe),
                              ("unstable", self.unstable_ranges)):
            p = out / f"{stem}_{suffix}.csv"
            table().to_csv(p, index=False)
            paths.append(p)
        p = out / f"{stem}.json"
        p.write_text(json.dumps(self.metadata(), indent=2, default=str))
        paths.append(p)
        if nc:
            paths.append(self.to_netcdf(out / f"{stem}.nc"))
        if png:
            import matplotlib.pyplot as plt

            fig = self.plot(fmax_hz=fmax_hz)
            p = out / f"{stem}.png"
            fig.savefig(p, dpi=130, bbox_inches="tight")
            plt.close(fig)
            paths.append(p)
        if html:
            p = out / f"{stem}.html"
            self.plot_html(p, fmax_hz=fmax_hz)
            paths.append(p)
        return paths


def speed_grid_order(speeds_rpm) -> str:
    """"ascending", "descending" or "unsorted": the order of a speed grid as the user gave it (for the metadata).

    Parameters
    ----------
    speeds_rpm : ndarray (n,)

    Returns
    -------
    str

    Examples
    --------
    >>> speed_grid_order(np.array([3.0, 2.0, 1.0]))
    'descending'
    """
    d = np.diff(speeds_rpm)
    return "ascending" if np.all(d >= 0) else "descending" if np.all(d <= 0) else "unsorted"


def exact_onsets(system, speeds_rpm, oil_supply=None):
    """Film whirl onsets [rpm] of ``system`` by :func:`frbmodel.film_onset_speeds` over a range that covers the
    default search range and the grid.

    Parameters
    ----------
    system : Turbocharger
    speeds_rpm : ndarray
        The sweep's speeds [rpm].
    oil_supply : OilSupply, optional
        The thermal model (each onset at the film temperatures of its speed), see :func:`film_onset_speeds`.

    Returns
    -------
    onsets : ndarray (2 n_bearings,) or None
        [rpm]; None if the search failed (then ``source`` says why).
    source : str
        How they were computed, for the result's metadata.

    Examples
    --------
    >>> import frbmodel as frb
    >>> on, source = exact_onsets(frb.turbocharger(), np.array([10e3, 250e3]))
    >>> [round(float(x)) for x in on], source.split(":")[0]
    ([11073, 68146, 11821, 69224], 'frbmodel.film_onset_speeds')
    """
    pos = speeds_rpm[speeds_rpm > 0]
    lo = min(ONSET_SEARCH_RPM[0], pos.min()) if pos.size else ONSET_SEARCH_RPM[0]
    hi = max(ONSET_SEARCH_RPM[1], speeds_rpm.max())
    try:
        on = film_onset_speeds(system, "J", (lo, hi), oil_supply)
    except (ConvergenceError, FilmContactError) as exc:
        return None, f"{GRID_ONSET_SOURCE} (the exact search in {lo:g}..{hi:g} rpm failed: {exc})"
    where = "" if oil_supply is None else ", each at the film viscosities of its speed's thermal operating point"
    return on, f"{EXACT_ONSET_SOURCE}{where}, searched in {lo:g}..{hi:g} rpm"


def _system_meta(system, m, kw):
    return {"system_name": system.name, "system": system.to_dict(), "film_model": system.film_model,
            "method_title": m.title, "method_options": m.options(**kw),
            "outer_clearance_m": [b.outer.clearance for b in system.bearings],
            "films": list(film_names(system)), "bearings": [b.name for b in system.bearings]}


def _sweep(system, m, speeds, whirl, bar, kw, oil_supply=None):
    """Per speed: film equilibria, linear systems (film methods) and whirl rows, with an oil supply at that speed's
    thermal operating point. Returns the arrays (cut to the speeds done), the films' viscosities [Pa s] per speed,
    the timing and the Ctrl-C / SIGTERM that stopped the sweep (else None)."""
    loads = system.bearing_loads
    nb = len(system.bearings)
    rsr = np.full((speeds.size, nb), np.nan)
    ecc, whirl_hz, margin = (np.full((speeds.size, 2 * nb), np.nan) for _ in range(3))
    mu = np.full((speeds.size, 2 * nb), np.nan)
    t_eq = 0.0
    systems = []
    i, stopped = 0, None
    try:
        for i, s in enumerate(speeds):
            sys_s = at_operating_point(system, s, oil_supply, m.letter)
            mu[i] = [f.viscosity for b in sys_s.bearings for f in (b.inner, b.outer)]
            # the whirl lines are method J's (Lund threshold at the torque balance), at J's own thermal point
            sys_w = sys_s if oil_supply is None or m.letter == "J" or not whirl else \
                at_operating_point(system, s, oil_supply, "J")
            t_eq += _speed_row(sys_s, m, s, whirl, kw, loads, systems, (rsr, ecc, whirl_hz, margin), i, sys_w)
            bar.update(1)
        i = speeds.size
    except KeyboardInterrupt as exc:  # keep the speeds done: the caller returns them with the interruption
        stopped = exc
        del systems[i:]
    return systems, rsr[:i], ecc[:i], whirl_hz[:i], margin[:i], mu[:i], t_eq, stopped


def _speed_row(system, m, s, whirl, kw, loads, systems, rows, i, whirl_system=None):
    """One speed of :func:`_sweep`: appends the linear system (film methods) to ``systems`` and fills row ``i`` of
    ``rows`` = (rsr, ecc, whirl_hz, margin), the whirl rows from ``whirl_system`` (default ``system``). Returns the
    time spent in equilibria [s]."""
    rsr, ecc, whirl_hz, margin = rows
    t_eq = 0.0
    omega = rpm_to_rad_s(s)
    eqs = None
    if m.needs_films:
        te = time.perf_counter()
        eqs = tuple(bearing_equilibrium(b, loads[k], omega, m.letter, system.film_model, system.gravity)
                    for k, b in enumerate(system.bearings))
        t_eq += time.perf_counter() - te
        rsr[i] = [e.ring_speed_ratio for e in eqs]
        systems.append(linear_system(system, m.letter, s, equilibria=eqs, **kw))
    if whirl and omega > 0:
        ws = system if whirl_system is None else whirl_system
        weqs = eqs if m.letter == "J" and ws is system else tuple(
            bearing_equilibrium(b, loads[k], omega, "J", ws.film_model, ws.gravity) for k, b in enumerate(ws.bearings))
        whirl_hz[i], margin[i], ecc[i] = film_whirl_rows(ws, weqs)
    return t_eq


def campbell(system, method="J", speeds_rpm=None, whirl=True, progress: bool = False, oil_supply=None,
             **kw) -> CampbellResult:
    """Holistic Campbell diagram of ``system`` for bearing-modelling ``method``.

    Parameters
    ----------
    system : Turbocharger
    method : {"A", "B", "C", "D", "E", "F", "G", "I", "J"}
    speeds_rpm : array_like, optional
        Rotor speeds [rpm] in any order (the result is sorted ascending); default 10 000 ... 250 000, 100 points.
        Must be > 0 for the film methods.
    whirl : bool
        Also compute the film whirl curves (method-J equilibria at every speed) and the exact whirl onset of each
        film (:func:`frbmodel.film_onset_speeds`, independent of the grid).
    progress : bool
        Show a progress bar over the speeds (tqdm, on stderr).
    oil_supply : OilSupply, optional
        The thermal model (film methods C, D, F, G, I, J): at each speed the films' viscosities are those of that
        speed's thermal operating point solved with this method's equilibrium
        (:func:`frbmodel.linear.thermal.thermal_system`); the whirl curves and the exact onsets are method J's, at
        J's thermal operating point (each onset at the temperatures of its onset speed). ``meta`` records it
        (``oil_supply``) and the films' viscosities per speed (``film_viscosities_Pa_s``). None (default): the
        constant viscosities, bit for bit.
    **kw
        Spring stiffnesses of A, B, E: ``k``, ``kx``, ``ky`` [N/m].

    Returns
    -------
    CampbellResult
        Its ``meta`` records the system (``system.to_dict()``), the method, its options and the film model.

    Raises
    ------
    ParameterError
        Not a system, an unknown method or option, invalid speeds, an oil supply with a method other than J.
    KeyboardInterrupt
        Ctrl-C (or :class:`~frbmodel.core.interrupt.Terminated`, SIGTERM) during the sweep; after the first speed its
        ``.result`` is the diagram of the speeds done, ``meta["status"] = "interrupted"``.

    Examples
    --------
    >>> import numpy as np, frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "A", np.array([1.0, 100e3]), whirl=False)
    >>> [round(float(f), 1) for f in cd.frequencies_hz[1, :3]]     # docs/theory/parameters.md#reference-numbers
    [60.2, 192.5, 297.3]
    >>> set(cd.stability.ravel())                                   # undamped springs: every mode neutral
    {'neutral'}
    """
    check_system(system)
    m = get_method(method)
    supply = check_oil_supply(oil_supply, m.letter, system.bearings)
    given = np.linspace(*PAPER_SPEED_RANGE_RPM, 100) if speeds_rpm is None else speeds_rpm
    speeds = m.check_speeds(given)
    order = speed_grid_order(speeds)
    speeds = np.sort(speeds)
    m.options(**kw)  # validate early
    t0 = time.perf_counter()
    with counter_bar(speeds.size, f"campbell {m.letter}", progress_enabled(progress), unit="speed") as bar:
        systems, rsr, ecc, whirl_hz, margin, mu, t_eq, stopped = _sweep(system, m, speeds, whirl, bar, kw, supply)
    if stopped is not None and not rsr.shape[0]:
        raise stopped
    requested, speeds = speeds.size, speeds[:rsr.shape[0]]
    if m.needs_films:
        mode_sets = batch_modes(systems)
        mass, ring_dofs = systems[0].M, systems[0].ring_dofs
    else:  # speed-independent M, K, bearing damping: assemble once, all speeds in one stacked solve
        ls0 = linear_system(system, m.letter, 0.0, **kw)
        G = np.zeros_like(ls0.M)
        G[:system.rotor.n_dof, :system.rotor.n_dof] = system.rotor.G
        mode_sets = speed_modes(ls0.M, ls0.K, ls0.C, G, rpm_to_rad_s(speeds), ls0.planes())
        mass, ring_dofs = ls0.M, ls0.ring_dofs
    skipped = "not computed (interrupted)" if stopped is not None else "not computed (whirl=False)"
    onsets, source = exact_onsets(system, speeds, supply) if whirl and stopped is None else (
        np.full(2 * len(system.bearings), np.nan), skipped)
    meta = {**_system_meta(system, m, kw), "source": "frbmodel.linear.campbell", "whirl": bool(whirl),
            "speed_grid_order": order, "equilibrium_time_s": t_eq, "whirl_onset_source": source}
    if supply is not None:
        meta.update(oil_supply=supply.to_dict(), film_viscosities_Pa_s=mu.tolist())
    res = campbell_from_modes(m.letter, speeds, mode_sets, system.rotor, mass, ring_dofs, rsr, ecc, whirl_hz, margin,
                              meta, whirl_onset_rpm=onsets)
    res.meta["cpu_time_s"] = time.perf_counter() - t0
    if stopped is not None:  # the speeds done, marked, on the interruption: the caller saves them
        res.meta.update(status="interrupted", speeds_requested=requested)
        stopped.result = res
        raise stopped
    return res


def film_whirl_rows(system, equilibria):
    """Per-film whirl data at one speed from the bearings' equilibria (docs/theory/whirl.md#film-whirl).

    Parameters
    ----------
    system : Turbocharger
    equilibria : sequence of BearingEquilibrium
        One per bearing of ``system``.

    Returns
    -------
    whirl_hz, margin, eps : ndarray (2 · n_bearings,)
        Whirl frequency [Hz], instability margin [-] (> 0: past onset) and eccentricity ratio of each film, in
        the order (bearing 0 inner, outer, bearing 1 inner, outer).

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> w, margin, eps = film_whirl_rows(tc, frb.equilibrium(tc, "J", 30e3).bearings)
    >>> # onsets 11.1/68.1/11.8/69.2 krpm: docs/theory/parameters.md#reference-numbers
    >>> round(float(w[0]), 1), (margin > 0).tolist()
    (306.0, [True, False, True, False])
    """
    whirl_hz, margin, eps = (np.empty(2 * len(system.bearings)) for _ in range(3))
    for k, (b, e) in enumerate(zip(system.bearings, equilibria)):
        wi, wo, mi, mo = bearing_whirl(b, e, system.film_model, system.gravity)
        whirl_hz[2 * k:2 * k + 2] = np.array([wi, wo]) / (2 * math.pi)
        margin[2 * k:2 * k + 2] = [mi, mo]
        eps[2 * k:2 * k + 2] = [e.eps_inner, e.eps_outer]
    return whirl_hz, margin, eps


def _classify(shape_list, rotor, mass, ring_dofs):
    """Precession, ring energy fraction and shape class of every mode at every speed."""
    nn = rotor.n_nodes
    v_idx, w_idx = np.arange(nn) * 4, np.arange(nn) * 4 + 1
    if len({sh.shape for sh in shape_list}) == 1:  # same mode count at all speeds: one vectorised pass
        stack = np.stack(shape_list)
        return (list(classify_precession(*precession_index(stack, v_idx, w_idx))),
                list(ring_energy_fraction(stack, mass, ring_dofs)),
                list(shape_class(stack, v_idx, w_idx, rotor.node_z)))
    return ([classify_precession(*precession_index(sh, v_idx, w_idx)) for sh in shape_list],
            [ring_energy_fraction(sh, mass, ring_dofs) for sh in shape_list],
            [shape_class(sh, v_idx, w_idx, rotor.node_z) for sh in shape_list])


def campbell_from_modes(letter, speeds, mode_sets, rotor, mass, ring_dofs, rsr, ecc, whirl_hz, margin, meta,
                        whirl_onset_rpm=None):
    """Campbell post-processing (precession, mode kind, tracking) of per-speed modes.

    Used by :func:`campbell` and by the FMU linearization.

    Parameters
    ----------
    letter : str
        Method letter.
    speeds : ndarray (n,)
        Speeds [rpm] of ``mode_sets`` (tracking follows this order; the result is sorted ascending).
    mode_sets : list of Modes
        Per speed; displacement DoFs are the rotor's followed by the rings' (x, y).
    rotor : Rotor
    mass : ndarray
        Global mass matrix (for the ring energy fraction) [kg ...].
    ring_dofs : list of (int, int) or None
        Global (x, y) indices of each ring.
    rsr, ecc, whirl_hz, margin : ndarray
        Per-speed bearing and film data (see :class:`CampbellResult`).
    meta : dict
        What the result was computed with.
    whirl_onset_rpm : ndarray, optional
        Exact film onsets [rpm] (default: interpolated on the grid).

    Returns
    -------
    CampbellResult
        Absent modes are NaN (λ = NaN + NaN j) in every array.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> speeds = np.array([100e3, 50e3])
    >>> systems = [frb.linear_system(tc, "J", s) for s in speeds]
    >>> from frbmodel.linear.modal import batch_modes
    >>> cd = campbell_from_modes("J", speeds, batch_modes(systems), tc.rotor, systems[0].M, systems[0].ring_dofs,
    ...                          np.full((2, 2), np.nan), *(np.full((2, 4), np.nan) for _ in range(3)), {})
    >>> cd.speeds_rpm.tolist(), cd.n_modes
    ([50000.0, 100000.0], 19)
    """
    lam_list = [md.eigenvalues for md in mode_sets]
    shape_list = [md.shapes for md in mode_sets]
    tol_list = [md.damping_tol for md in mode_sets]
    prec_list, ring_list, form_list = _classify(shape_list, rotor, mass, ring_dofs)
    perm = track(lam_list, shape_list)
    n_tr = perm[0].size if perm else 0
    lam = np.full((speeds.size, n_tr), complex(math.nan, math.nan))
    prec = np.full((speeds.size, n_tr), "", dtype=object)
    form = np.full((speeds.size, n_tr), "", dtype=object)
    ringf = np.full((speeds.size, n_tr), np.nan)
    tol = np.full((speeds.size, n_tr), np.nan)
    P = np.array(perm)
    if np.all(P >= 0) and len({x.size for x in lam_list}) == 1:  # full tracks: gather all speeds at once
        lam, prec, ringf, form, tol = (np.take_along_axis(np.stack(x), P, axis=1)
                                       for x in (lam_list, prec_list, ring_list, form_list, tol_list))
    else:
        for i, p in enumerate(perm):
            ok = p >= 0
            lam[i, ok] = lam_list[i][p[ok]]
            prec[i, ok] = prec_list[i][p[ok]]
            ringf[i, ok] = ring_list[i][p[ok]]
            form[i, ok] = form_list[i][p[ok]]
            tol[i, ok] = tol_list[i][p[ok]]
    kind = np.where(np.isfinite(ringf), np.where(ringf > RING_MODE_FRACTION, "ring", form), "").astype(object)
    # order tracks by their mean frequency
    order = np.argsort(np.nanmean(np.where(np.isfinite(lam.imag), lam.imag, np.nan), axis=0))
    lam, prec, kind, ringf, tol = lam[:, order], prec[:, order], kind[:, order], ringf[:, order], tol[:, order]
    freq = lam.imag / (2 * math.pi)
    damp = -lam.real / np.abs(lam)
    return CampbellResult(letter, speeds, freq, damp, prec, kind, ringf, lam, rsr, ecc, whirl_hz, margin, meta,
                          damping_tol=tol, whirl_onset_rpm=whirl_onset_rpm)
