"""Named-column, streamed time-series results of run-ups and co-simulations.

The column schema follows the system: one group of columns per bearing (ring speed, RSR, journal and ring position, the
eccentricity ratio of its inner and outer film), per disc (its displacement), and last per bearing the film torque on
the journal and the bearing's friction power (:mod:`frbmodel.physics.losses`). Files written before the last two existed
load with NaN there. The monolithic run-up (:func:`frbmodel.nonlinear.runup.runup`) and the co-simulation master
(:mod:`frbmodel.cosim.master`) both fill rows by name through :meth:`RunupSchema.row` (the run-up a solver call's worth
at a time through :meth:`RunupSchema.rows`) and stream them with a :class:`Recorder`, so their files are read back by
the same :meth:`RunupResult.load`.

>>> schema = RunupSchema(bearings=("front", "rear"), discs=("impeller",))
>>> schema.columns[:4]
['time [s]', 'speed [rpm]', 'ring speed front [rad/s]', 'RSR front [-]']
>>> schema.film_labels
('front inner', 'front outer', 'rear inner', 'rear outer')
>>> RunupSchema.from_columns(schema.columns) == schema
True
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, read_json
from ..core.results import NETCDF_ENGINE, Result, decode_attr, netcdf_attrs, variable
from ..core.units import RPM
from ..plots.figures import write_html
from ..plots.runup import runup_overview, runup_overview_html

FILMS = ("inner", "outer")

#: run status values written to ``runup.json``
STATUSES = ("running", "finished", "stopped", "interrupted")


@dataclass(frozen=True)
class RunupSchema:
    """Column layout of a run-up result, derived from the system's bearing and disc names.

    Parameters
    ----------
    bearings : tuple of str
        Bearing names in the system's order (e.g. ``("turbine", "compressor")``).
    discs : tuple of str
        Disc names whose displacement is recorded (e.g. ``("turbine_wheel", "compressor_wheel")``).

    Examples
    --------
    >>> schema = RunupSchema(bearings=("front",), discs=("wheel",))
    >>> row = schema.row(0.5, 60e3 / (2 * np.pi), ring_speed=[300.0], journal=[[1e-6, -2e-6]], ring=[[0.0, -1e-6]],
    ...                  eps=[[0.2, 0.3]], discs=[[3e-6, 0.0]])
    >>> dict(zip(schema.columns, row.round(9).tolist()))  # doctest: +NORMALIZE_WHITESPACE
    {'time [s]': 0.5, 'speed [rpm]': 9549.296585514, 'ring speed front [rad/s]': 300.0, 'RSR front [-]': 0.3,
     'journal front x [m]': 1e-06, 'journal front y [m]': -2e-06, 'ring front x [m]': 0.0, 'ring front y [m]': -1e-06,
     'eps front inner [-]': 0.2, 'eps front outer [-]': 0.3, 'wheel x [m]': 3e-06, 'wheel y [m]': 0.0,
     'journal torque front [N m]': nan, 'power loss front [W]': nan}
    """

    bearings: tuple
    discs: tuple

    @classmethod
    def from_system(cls, system):
        """Schema of a :class:`~frbmodel.system.parameters.Turbocharger`: its bearings and the rotor's discs.

        Parameters
        ----------
        system : Turbocharger
            The system.

        Returns
        -------
        RunupSchema

        Examples
        --------
        >>> import frbmodel as frb
        >>> RunupSchema.from_system(frb.turbocharger()).bearings
        ('turbine', 'compressor')
        """
        return cls(tuple(b.name for b in system.bearings), tuple(d.name for d in system.rotor.discs))

    @classmethod
    def from_columns(cls, columns):
        """Schema read back from a CSV header (inverse of :attr:`columns`).

        Parameters
        ----------
        columns : sequence of str
            Column names, as in :attr:`columns` (the journal torque and power loss columns may be missing).

        Returns
        -------
        RunupSchema

        Raises
        ------
        ParameterError
            If the header lacks the time/speed columns or a bearing's column group is incomplete.
        """
        columns = list(columns)
        if columns[:2] != ["time [s]", "speed [rpm]"]:
            raise ParameterError(f"not a run-up result: the first columns are {columns[:2]}, expected "
                                 "['time [s]', 'speed [rpm]']")
        bearings = tuple(c[len("ring speed "):-len(" [rad/s]")] for c in columns
                         if c.startswith("ring speed ") and c.endswith(" [rad/s]"))
        taken = {c for b in bearings for c in cls._bearing_columns(b)} | {"time [s]", "speed [rpm]"}
        missing = [c for b in bearings for c in cls._bearing_columns(b) if c not in columns]
        if missing:
            raise ParameterError(f"run-up result is missing the columns {missing}")
        discs = tuple(c[:-len(" x [m]")] for c in columns if c.endswith(" x [m]") and c not in taken)
        return cls(bearings, discs)

    @staticmethod
    def _loss_columns(b):
        return [f"journal torque {b} [N m]", f"power loss {b} [W]"]

    @staticmethod
    def _bearing_columns(b):
        return [f"ring speed {b} [rad/s]", f"RSR {b} [-]", f"journal {b} x [m]", f"journal {b} y [m]",
                f"ring {b} x [m]", f"ring {b} y [m]", f"eps {b} inner [-]", f"eps {b} outer [-]"]

    @property
    def film_labels(self):
        """``"<bearing> inner"``, ``"<bearing> outer"`` per bearing, in column order."""
        return tuple(f"{b} {f}" for b in self.bearings for f in FILMS)

    @property
    def columns(self):
        """Column names with units (one group per bearing, then x/y per disc)."""
        cols = ["time [s]", "speed [rpm]"]
        for b in self.bearings:
            cols += [f"ring speed {b} [rad/s]", f"RSR {b} [-]"]
        for kind in ("journal", "ring"):
            cols += [f"{kind} {b} {q} [m]" for b in self.bearings for q in "xy"]
        cols += [f"eps {lab} [-]" for lab in self.film_labels]
        cols += [f"{d} {q} [m]" for d in self.discs for q in "xy"]
        cols += [c for b in self.bearings for c in self._loss_columns(b)]
        return cols

    def row(self, time_s, speed_rpm, ring_speed, journal, ring, eps, discs, journal_torque=None, power_loss=None):
        """One row by name; the RSR is computed as ring speed / rotor speed (NaN at zero rotor speed).

        Parameters
        ----------
        time_s : float
            Time [s].
        speed_rpm : float
            Rotor speed [rpm].
        ring_speed : array_like (nb,)
            Ring spin speeds [rad/s], bearings in :attr:`bearings` order.
        journal, ring : array_like (nb, 2)
            Journal and ring centre x, y [m] relative to the housing.
        eps : array_like (nb, 2)
            Inner and outer film eccentricity ratios [-].
        discs : array_like (nd, 2)
            Disc displacements x, y [m], discs in :attr:`discs` order.
        journal_torque : array_like (nb,), optional
            Film torques on the journals about +z [N m] (NaN when not given).
        power_loss : array_like (nb,), optional
            Friction power of each bearing [W] (NaN when not given).

        Returns
        -------
        ndarray (len(columns),)
            The row, in the order of :attr:`columns` (see the class example).
        """
        nb, nd = len(self.bearings), len(self.discs)
        ring_speed = np.asarray(ring_speed, dtype=float).reshape(nb)
        omega = speed_rpm * RPM
        rsr = ring_speed / omega if omega != 0.0 else np.full(nb, math.nan)
        torque = np.full(nb, math.nan) if journal_torque is None else np.asarray(journal_torque, dtype=float)
        power = np.full(nb, math.nan) if power_loss is None else np.asarray(power_loss, dtype=float)
        return np.concatenate([[time_s, speed_rpm], np.column_stack([ring_speed, rsr]).ravel(),
                               np.asarray(journal, dtype=float).reshape(2 * nb),
                               np.asarray(ring, dtype=float).reshape(2 * nb),
                               np.asarray(eps, dtype=float).reshape(2 * nb),
                               np.asarray(discs, dtype=float).reshape(2 * nd),
                               np.column_stack([torque.reshape(nb), power.reshape(nb)]).ravel()])

    def rows(self, time_s, speed_rpm, ring_speed, journal, ring, eps, discs, journal_torque=None, power_loss=None):
        """n rows at once, equal to n calls of :meth:`row` (which stays the cheaper way to build a single row, e.g.
        one per co-simulation macro step): each argument of :meth:`row` with a leading axis of n samples.

        Parameters
        ----------
        time_s, speed_rpm : array_like (n,)
            Times [s] and rotor speeds [rpm].
        ring_speed : array_like (n, nb)
            Ring spin speeds [rad/s].
        journal, ring : array_like (n, nb, 2)
            Journal and ring centre x, y [m] relative to the housing.
        eps : array_like (n, nb, 2) or (n, 2 nb)
            Inner and outer film eccentricity ratios [-] per bearing.
        discs : array_like (n, nd, 2)
            Disc displacements x, y [m].
        journal_torque, power_loss : array_like (n, nb), optional
            Film torques on the journals [N m] and friction power per bearing [W] (NaN when not given).

        Returns
        -------
        ndarray (n, len(columns))
            The rows; RSR = ring speed / (speed_rpm × 2π/60), NaN at zero rotor speed.

        Examples
        --------
        >>> s = RunupSchema(("b",), ())
        >>> s.rows([0.0, 1.0], [0.0, 30 / np.pi], [[5.0], [5.0]], np.zeros((2, 1, 2)), np.zeros((2, 1, 2)),
        ...        np.zeros((2, 2)), np.zeros((2, 0, 2)))[:, :4].tolist()
        [[0.0, 0.0, 5.0, nan], [1.0, 9.549296585513721, 5.0, 5.0]]
        """
        nb, nd = len(self.bearings), len(self.discs)
        time_s, speed_rpm = np.asarray(time_s, dtype=float).ravel(), np.asarray(speed_rpm, dtype=float).ravel()
        n = time_s.size
        ring_speed = np.asarray(ring_speed, dtype=float).reshape(n, nb)
        omega = speed_rpm * RPM
        with np.errstate(divide="ignore", invalid="ignore"):
            rsr = ring_speed / omega[:, None]
        rsr[omega == 0.0] = math.nan
        out = np.empty((n, len(self.columns)))
        out[:, 0], out[:, 1] = time_s, speed_rpm
        out[:, 2:2 + 2 * nb:2], out[:, 3:2 + 2 * nb:2] = ring_speed, rsr
        k = 2 + 2 * nb
        for block, width in ((journal, 2 * nb), (ring, 2 * nb), (eps, 2 * nb), (discs, 2 * nd)):
            out[:, k:k + width] = np.asarray(block, dtype=float).reshape(n, width)
            k += width
        for i, values in enumerate((journal_torque, power_loss)):
            out[:, k + i::2] = math.nan if values is None else np.asarray(values, dtype=float).reshape(n, nb)
        return out

    def eps_slice(self):
        """Slice of the eccentricity columns in a row.

        Returns
        -------
        slice

        Examples
        --------
        >>> s = RunupSchema(("a", "b"), ())
        >>> s.columns[s.eps_slice()]
        ['eps a inner [-]', 'eps a outer [-]', 'eps b inner [-]', 'eps b outer [-]']
        """
        start = 2 + 6 * len(self.bearings)
        return slice(start, start + 2 * len(self.bearings))


class Recorder:
    """Collects rows of a :class:`RunupSchema` in memory and streams them to ``<out_dir>/runup.csv`` (header with
    units) with the metadata and status in ``runup.json``.

    Use as a context manager: leaving the block by an exception marks the run ``"interrupted"`` (Ctrl-C,
    SIGTERM turned into an exception) or ``"stopped"`` and flushes what was recorded, so nothing computed is lost.

    Parameters
    ----------
    schema : RunupSchema
        Column layout of the rows.
    capacity : int
        Number of rows expected (grows if exceeded).
    out_dir : path, optional
        Folder to stream to (created); None keeps the rows in memory only.
    meta : dict, optional
        Metadata written to ``runup.json`` (status and message are added).
    flush_rows : int
        Rows buffered between two appends to the CSV.

    Examples
    --------
    >>> rec = Recorder(RunupSchema(("b",), ("d",)), capacity=2)
    >>> rec.append(rec.schema.row(0.0, 1000.0, [50.0], [[0, 0]], [[0, 0]], [[0.1, 0.2]], [[1e-6, 0]]))
    >>> rec.close("finished").eccentricity.tolist()
    [[0.1, 0.2]]

    Streamed to a folder, the status is ``"stopped"`` when the block ends by an exception:

    >>> import json, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     try:
    ...         with Recorder(RunupSchema(("b",), ()), out_dir=tmp) as rec:
    ...             rec.append(rec.schema.row(0.25, 1000.0, [50.0], [[0, 0]], [[0, 0]], [[0.1, 0.2]], []))
    ...             raise RuntimeError("FMU failed")
    ...     except RuntimeError:
    ...         pass
    ...     meta = json.loads((Path(tmp) / "runup.json").read_text())
    ...     lines = (Path(tmp) / "runup.csv").read_text().splitlines()
    >>> meta["status"], meta["message"], len(lines)
    ('stopped', 'RuntimeError: FMU failed at t = 0.25 s; results up to there are kept', 2)
    """

    def __init__(self, schema, capacity=1024, out_dir=None, meta=None, flush_rows=2000):
        self.schema = schema
        self.columns = schema.columns
        self.rows = np.full((max(int(capacity), 1), len(self.columns)), np.nan)
        self.n = 0
        self.flushed = 0
        self.flush_rows = int(flush_rows)
        self.meta = dict(meta or {})
        self.status = "running"
        self.dir = None if out_dir is None else Path(out_dir)
        if self.dir is not None:
            self.dir.mkdir(parents=True, exist_ok=True)
            self.csv = self.dir / "runup.csv"
            self.json = self.dir / "runup.json"
            with open(self.csv, "w") as fh:
                fh.write(",".join(self.columns) + "\n")
            self._write_meta("running", "")

    def append(self, row):
        """Add one row; streams every ``flush_rows`` rows.

        Parameters
        ----------
        row : ndarray (len(schema.columns),)
            A row from :meth:`RunupSchema.row`.
        """
        if self.n == self.rows.shape[0]:
            self.rows = np.vstack([self.rows, np.full_like(self.rows, np.nan)])
        self.rows[self.n] = row
        self.n += 1
        if self.dir is not None and self.n - self.flushed >= self.flush_rows:
            self.flush()

    def extend(self, rows):
        """Add several rows at once; streams at the same rows as the same :meth:`append` calls would.

        Parameters
        ----------
        rows : ndarray (n, len(schema.columns))
            Rows from :meth:`RunupSchema.rows` (n may be 0).
        """
        rows = np.asarray(rows, dtype=float).reshape(-1, len(self.columns))
        need = self.n + rows.shape[0]
        if need > self.rows.shape[0]:
            grown = np.full((max(need, 2 * self.rows.shape[0]), len(self.columns)), np.nan)
            grown[:self.n] = self.rows[:self.n]
            self.rows = grown
        start = 0
        while start < rows.shape[0]:
            take = rows.shape[0] - start
            if self.dir is not None:  # up to the row at which append would flush
                take = min(take, max(self.flush_rows - (self.n - self.flushed), 1))
            self.rows[self.n:self.n + take] = rows[start:start + take]
            self.n += take
            start += take
            if self.dir is not None and self.n - self.flushed >= self.flush_rows:
                self.flush()

    @property
    def last(self):
        """The last recorded row (or None)."""
        return self.rows[self.n - 1] if self.n else None

    def flush(self):
        """Append the rows not yet on disk to the CSV."""
        if self.dir is None or self.n == self.flushed:
            return
        with open(self.csv, "a") as fh:
            np.savetxt(fh, self.rows[self.flushed:self.n], delimiter=",", fmt="%.10g")
        self.flushed = self.n

    def truncate(self, t):
        """Forget the rows after time ``t`` [s] (a co-simulation master restored an earlier state and will step
        again from there); rows already on disk are rewritten.

        Parameters
        ----------
        t : float
            Keep the rows with time <= ``t``.

        Examples
        --------
        >>> rec = Recorder(RunupSchema(("b",), ()), capacity=3)
        >>> for t in (0.0, 0.1, 0.2):
        ...     rec.append(rec.schema.row(t, 1000.0, [50.0], [[0, 0]], [[0, 0]], [[0.1, 0.2]], []))
        >>> rec.truncate(0.1)
        >>> rec.result().time.tolist()
        [0.0, 0.1]
        """
        keep = int(np.searchsorted(self.rows[:self.n, 0], t, side="right"))
        if keep >= self.n:
            return
        self.n = keep
        if self.dir is not None and self.flushed > keep:
            with open(self.csv, "w") as fh:
                fh.write(",".join(self.columns) + "\n")
            self.flushed = 0
            self.flush()

    def _write_meta(self, status, message):
        self.meta.update({"status": status, "message": message})
        tmp = self.json.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(self.meta, indent=2, default=str))
        os.replace(tmp, self.json)

    def close(self, status, message="", **meta):
        """Flush, write the final status and return the :class:`RunupResult`.

        Parameters
        ----------
        status : {"running", "finished", "stopped", "interrupted"}
            Final status (one of :data:`STATUSES`).
        message : str
            Human-readable note (why the run stopped).
        **meta
            More metadata for ``runup.json`` (e.g. ``wall_time_s``).

        Returns
        -------
        RunupResult

        Raises
        ------
        ParameterError
            For an unknown status.
        """
        if status not in STATUSES:
            raise ParameterError(f"status = {status!r} is unknown; valid: {STATUSES}")
        self.status = status
        self.meta.update(meta, samples=int(self.n))
        if self.dir is not None:
            self.flush()
            self._write_meta(status, message)
        else:
            self.meta.update({"status": status, "message": message})
        return self.result()

    def result(self):
        """The recorded rows as a :class:`RunupResult` (also while the run is going on).

        Returns
        -------
        RunupResult
        """
        return RunupResult.from_rows(self.schema, self.rows[:self.n], self.meta)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None and self.status == "running":
            interrupted = issubclass(exc_type, (KeyboardInterrupt, SystemExit))
            t = self.last[0] if self.n else 0.0
            self.close("interrupted" if interrupted else "stopped",
                       f"{'interrupted' if interrupted else exc_type.__name__ + ': ' + str(exc)} at t = {t:.6g} s; "
                       "results up to there are kept", time_reached_s=float(t))
        return False


@dataclass
class RunupResult(Result):
    """Sampled result of a run-up or co-simulation (SI units; speeds also in rpm).

    Usually made by :func:`frbmodel.nonlinear.runup`, the co-simulation or :meth:`load`; see :meth:`from_rows` to build
    one from rows of a :class:`RunupSchema`.

    Attributes
    ----------
    time : ndarray (n,)
        Sample times [s].
    speed_rpm : ndarray (n,)
        Rotor speed [rpm].
    ring_speed : ndarray (n, nb)
        Ring spin speeds [rad/s], bearings in the system's order.
    journal, ring : dict of str to ndarray (n, 2)
        Bearing name -> journal / ring centre x, y [m] relative to the housing.
    eccentricity : ndarray (n, 2 nb)
        Film eccentricity ratios [-], in the order of :attr:`film_labels`.
    displacement : dict of str to ndarray (n, 2)
        Disc name -> displacement x, y [m].
    status : str
        Run status (one of :data:`STATUSES`).
    message : str
        Why the run stopped (empty if it finished).
    meta : dict
        Metadata of the run (system, tolerances, wall time, ...), as in ``runup.json``.
    journal_torque : dict of str to ndarray (n,)
        Bearing name -> film torque on the journal about +z [N m] (negative: braking).
    power_loss : dict of str to ndarray (n,)
        Bearing name -> friction power of both films of the bearing [W] (NaN where the run did not record them:
        linear springs, results of older versions, FMUs without the outputs).
    final_state : ndarray or None
        The full state vector [SI] at the last sample of a monolithic run-up (:func:`frbmodel.nonlinear.runup`), to
        continue from (e.g. :func:`frbmodel.limit_cycle`'s run-up guess); not saved: None for a loaded or co-simulated
        result.

    Examples
    --------
    >>> schema = RunupSchema(("front",), ("wheel",))
    >>> rows = [schema.row(t, 60e3 / (2 * np.pi), [500.0], [[0, 0]], [[0, 0]], [[0.1, 0.2]], [[0, 0]])
    ...         for t in (0.0, 0.5)]
    >>> res = RunupResult.from_rows(schema, rows)
    >>> res.time.tolist(), res.ring_speed_ratio[:, 0].round(12).tolist(), res.film_labels
    ([0.0, 0.5], [0.5, 0.5], ('front inner', 'front outer'))
    >>> df = res.to_dataframe()
    >>> RunupResult.from_dataframe(df).schema == schema
    True
    """

    time: np.ndarray
    speed_rpm: np.ndarray
    ring_speed: np.ndarray
    journal: dict
    ring: dict
    eccentricity: np.ndarray
    displacement: dict
    status: str = "finished"
    message: str = ""
    meta: dict = field(default_factory=dict)
    journal_torque: dict = field(default_factory=dict)
    power_loss: dict = field(default_factory=dict)
    final_state: np.ndarray = field(default=None, repr=False, compare=False)

    @property
    def schema(self):
        """The :class:`RunupSchema` of this result (bearings and discs it holds)."""
        return RunupSchema(tuple(self.journal), tuple(self.displacement))

    @property
    def bearing_names(self):
        """Bearing names, in the system's order (the keys of :attr:`journal`)."""
        return tuple(self.journal)

    @property
    def film_labels(self):
        """``"<bearing> inner"``, ``"<bearing> outer"`` per bearing: the columns of :attr:`eccentricity`."""
        return self.schema.film_labels

    @property
    def ring_speed_ratio(self):
        """Ring speed / rotor speed (n, nb) [-]."""
        return self.ring_speed / (self.speed_rpm * RPM)[:, None]

    def to_dataframe(self):
        """One row per sample; units in the column names (the layout of ``runup.csv``).

        Returns
        -------
        pandas.DataFrame
            Columns of :attr:`RunupSchema.columns` (see the class example).
        """
        import pandas as pd

        return pd.DataFrame(self._rows(), columns=self.schema.columns)

    def _rows(self):
        nb = len(self.journal)
        cols = [self.time, self.speed_rpm]
        for i in range(nb):
            cols += [self.ring_speed[:, i], self.ring_speed_ratio[:, i]]
        for d in (self.journal, self.ring):
            cols += [a[:, k] for a in d.values() for k in range(2)]
        cols += [self.eccentricity[:, k] for k in range(2 * nb)]
        cols += [a[:, k] for a in self.displacement.values() for k in range(2)]
        nan = np.full(self.time.shape, np.nan)
        for b in self.journal:
            cols += [self.journal_torque.get(b, nan), self.power_loss.get(b, nan)]
        return np.column_stack(cols)

    def to_xarray(self):
        """The result as an :class:`xarray.Dataset` along ``time``, bearings, discs, films and axes as dimensions.

        Returns
        -------
        xarray.Dataset
            Coordinates ``time`` [s], ``bearing``, ``disc``, ``axis`` ("x", "y") and ``film`` ("inner",
            "outer"); variables ``speed`` (time) [rpm], ``ring_speed`` (time, bearing) [rad/s],
            ``ring_speed_ratio`` (time, bearing) [-], ``journal`` and ``ring`` (time, bearing, axis) [m],
            ``eccentricity`` (time, bearing, film) [-], ``displacement`` (time, disc, axis) [m], ``journal_torque``
            (time, bearing) [N m] and ``power_loss`` (time, bearing) [W], each with ``units`` and ``long_name``;
            the attributes are :attr:`meta` (status, message, system, ...; dicts and lists as JSON text).

        Examples
        --------
        >>> schema = RunupSchema(("front", "rear"), ("wheel",))
        >>> rows = [schema.row(t, 6e4, [500.0, 400.0], [[0, 0], [1e-6, 0]], [[0, 0], [0, 0]], [[0.1, 0.2], [0.3, 0.4]],
        ...                    [[2e-6, 0]]) for t in (0.0, 0.5)]
        >>> ds = RunupResult.from_rows(schema, rows, {"status": "finished"}).to_xarray()
        >>> dict(ds["eccentricity"].sizes), ds["eccentricity"].attrs["units"], ds.attrs["status"]
        ({'time': 2, 'bearing': 2, 'film': 2}, '-', 'finished')
        >>> float(ds["eccentricity"].sel(bearing="rear", film="outer")[0]), float(ds["journal"].sel(bearing="rear",
        ...       axis="x")[1])
        (0.4, 1e-06)
        """
        import xarray as xr

        n, names = self.time.size, self.bearing_names
        nan = np.full(n, np.nan)

        def stack(d, keys, shape):
            return np.stack([d[k] for k in keys], axis=1) if keys else np.empty((n, 0) + shape)

        tb, tba = ("time", "bearing"), ("time", "bearing", "axis")
        data = {
            "speed": variable(("time",), self.speed_rpm, "rpm", "rotor speed"),
            "ring_speed": variable(tb, self.ring_speed, "rad/s", "ring spin speed"),
            "ring_speed_ratio": variable(tb, self.ring_speed_ratio, "-", "ring speed / rotor speed"),
            "journal": variable(tba, stack(self.journal, names, (2,)), "m", "journal centre relative to the housing"),
            "ring": variable(tba, stack(self.ring, names, (2,)), "m", "ring centre relative to the housing"),
            "eccentricity": variable(("time", "bearing", "film"), self.eccentricity.reshape(n, len(names), 2), "-",
                                     "film eccentricity ratio"),
            "displacement": variable(("time", "disc", "axis"), stack(self.displacement, tuple(self.displacement),
                                                                     (2,)), "m", "disc displacement"),
            "journal_torque": variable(tb, np.column_stack([self.journal_torque.get(b, nan) for b in names]), "N m",
                                       "film torque on the journal about +z"),
            "power_loss": variable(tb, np.column_stack([self.power_loss.get(b, nan) for b in names]), "W",
                                   "friction power of both films of the bearing"),
        }
        coords = {"time": variable(("time",), self.time, "s", "time"),
                  "bearing": variable(("bearing",), list(names), "", "bearing"),
                  "disc": variable(("disc",), list(self.displacement), "", "rotor disc"),
                  "axis": variable(("axis",), ["x", "y"], "", "housing-fixed axis (y up)"),
                  "film": variable(("film",), list(FILMS), "", "film of the bearing")}
        meta = {"title": "run-up result (frbmodel)", **self.meta, "status": self.status, "message": self.message}
        return xr.Dataset(data, coords, attrs=netcdf_attrs(meta))

    @classmethod
    def from_xarray(cls, ds):
        """The result from a dataset of :meth:`to_xarray` (e.g. a ``runup.nc`` file).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        RunupResult
        """
        meta = {k: decode_attr(v) for k, v in ds.attrs.items() if k != "title"}
        names = [str(b) for b in ds["bearing"].values]

        def per(name, key):
            return {str(k): ds[name].values[:, i] for i, k in enumerate(ds[key].values)}

        return cls(ds["time"].values, ds["speed"].values, ds["ring_speed"].values, per("journal", "bearing"),
                   per("ring", "bearing"), ds["eccentricity"].values.reshape(ds.sizes["time"], 2 * len(names)),
                   per("displacement", "disc"), meta.get("status", "finished"), meta.get("message", ""), meta,
                   per("journal_torque", "bearing"), per("power_loss", "bearing"))

    def _overview_args(self):
        """The arrays of the run-up overview figure (:mod:`frbmodel.plots.runup`)."""
        rsr = {b: self.ring_speed_ratio[:, k] for k, b in enumerate(self.journal)}
        eps = {f: self.eccentricity[:, k] for k, f in enumerate(self.film_labels)}
        return self.time, self.speed_rpm, rsr, eps, self.displacement

    def plot(self, title=None):
        """Overview figure: rotor speed, ring-speed ratios, film eccentricity ratios and disc orbit radii over time
        (:func:`frbmodel.plots.runup.runup_overview`; the spectral composites are :func:`frbmodel.spectrogram`'s).

        Returns
        -------
        matplotlib.figure.Figure
        """

        return runup_overview(*self._overview_args(), title=title or f"run ({self.status})")

    def plot_html(self, path=None, title=None, include_plotlyjs=None):
        """The panels of :meth:`plot` as an interactive page, written to ``path`` (HTML) if given
        (:func:`frbmodel.plots.figures.write_html`).

        Parameters
        ----------
        path : str or Path, optional
            The HTML file (not written if None).
        title : str, optional
            Figure title.
        include_plotlyjs : {"directory", True}, optional
            As for :func:`frbmodel.plots.figures.write_html`: plotly.js beside the page, or embedded in it.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        fig = runup_overview_html(*self._overview_args(), title=title or f"run ({self.status})")
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def save(self, out_dir, nc=True):
        """Write ``runup.csv`` (:meth:`to_dataframe`), ``runup.json`` (:attr:`meta` with status and message) and
        ``runup.nc`` (:meth:`to_xarray`) into ``out_dir`` — the files a streamed run writes, for a run kept in
        memory.

        Parameters
        ----------
        out_dir : str or Path
            Folder (created if missing).
        nc : bool
            Also write ``runup.nc``.

        Returns
        -------
        list of Path

        Examples
        --------
        >>> import tempfile
        >>> res = RunupResult.from_rows(RunupSchema(("b",), ()), [[0.0, 1e3, 50.0, 0.5, 0, 0, 0, 0, 0.1, 0.2, 0, 0]])
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     names = [p.name for p in res.save(tmp)]
        ...     back = RunupResult.load(Path(tmp) / "runup.nc")
        >>> names, back.eccentricity.tolist()
        (['runup.csv', 'runup.json', 'runup.nc'], [[0.1, 0.2]])
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        csv, meta_p = out / "runup.csv", out / "runup.json"
        with open(csv, "w") as fh:
            fh.write(",".join(self.schema.columns) + "\n")
            np.savetxt(fh, self._rows(), delimiter=",", fmt="%.10g")
        meta_p.write_text(json.dumps({**self.meta, "status": self.status, "message": self.message}, indent=2,
                                     default=str))
        return [csv, meta_p] + ([self.to_netcdf(out / "runup.nc")] if nc else [])

    @classmethod
    def load(cls, path):
        """Read a result written by :func:`frbmodel.nonlinear.runup` or :func:`frbmodel.cosim.cosimulate`.

        Parameters
        ----------
        path : str or Path
            A folder with ``runup.csv`` (and ``runup.json``), the CSV itself, or a ``runup.nc``
            (:meth:`to_xarray`).

        Returns
        -------
        RunupResult

        Raises
        ------
        ParameterError
            If there is no ``runup.csv`` or it is not a run-up result.

        Examples
        --------
        >>> import tempfile
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     rec = Recorder(RunupSchema(("b",), ()), out_dir=tmp, meta={"profile": "test"})
        ...     rec.append(rec.schema.row(0.0, 1000.0, [50.0], [[0, 0]], [[0, 0]], [[0.1, 0.2]], []))
        ...     _ = rec.close("finished")
        ...     res = RunupResult.load(tmp)
        >>> res.status, res.meta["profile"], res.eccentricity.tolist()
        ('finished', 'test', [[0.1, 0.2]])
        """
        import pandas as pd

        path = Path(path)
        if path.suffix == ".nc" and path.is_file():
            import xarray as xr

            return cls.from_xarray(xr.load_dataset(path, engine=NETCDF_ENGINE))
        csv = path / "runup.csv" if path.is_dir() else path
        if not csv.is_file():
            raise ParameterError(f"{csv}: no run-up result there (runup.csv not found)")
        meta_p = csv.with_suffix(".json")
        meta = read_json(meta_p, "run-up metadata") if meta_p.exists() else {}
        return cls.from_dataframe(pd.read_csv(csv), meta)

    @classmethod
    def from_dataframe(cls, df, meta=None):
        """Result from a table with the columns of :attr:`RunupSchema.columns`.

        Parameters
        ----------
        df : pandas.DataFrame
            The table; the journal torque and power loss columns may be missing (NaN then).
        meta : dict, optional
            Metadata (its ``status`` and ``message`` are taken over).

        Returns
        -------
        RunupResult
        """
        schema = RunupSchema.from_columns(df.columns)
        return cls.from_rows(schema, df.reindex(columns=schema.columns).to_numpy(dtype=float), meta)

    @classmethod
    def from_rows(cls, schema, rows, meta=None):
        """Result from rows laid out by ``schema`` (see :meth:`RunupSchema.row`).

        Parameters
        ----------
        schema : RunupSchema
            The column layout.
        rows : array_like (n, len(schema.columns))
            The rows.
        meta : dict, optional
            Metadata (its ``status`` and ``message`` are taken over; defaults ``"finished"`` and ``""``).

        Returns
        -------
        RunupResult
        """
        meta = dict(meta or {})
        rows = np.asarray(rows, dtype=float).reshape(-1, len(schema.columns))
        nb = len(schema.bearings)
        c = 2 + 2 * nb
        ring_speed = rows[:, 2:c:2]
        journal = {b: rows[:, c + 2 * i:c + 2 * i + 2] for i, b in enumerate(schema.bearings)}
        c += 2 * nb
        ring = {b: rows[:, c + 2 * i:c + 2 * i + 2] for i, b in enumerate(schema.bearings)}
        c += 2 * nb
        ecc = rows[:, c:c + 2 * nb]
        c += 2 * nb
        disp = {d: rows[:, c + 2 * i:c + 2 * i + 2] for i, d in enumerate(schema.discs)}
        c += 2 * len(schema.discs)
        torque = {b: rows[:, c + 2 * i] for i, b in enumerate(schema.bearings)}
        power = {b: rows[:, c + 2 * i + 1] for i, b in enumerate(schema.bearings)}
        return cls(rows[:, 0], rows[:, 1], ring_speed, journal, ring, ecc, disp, meta.get("status", "finished"),
                   meta.get("message", ""), meta, torque, power)
