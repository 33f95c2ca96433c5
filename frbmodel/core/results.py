"""The shared contract of analysis results: labelled arrays (xarray) and netCDF files.

Every result class (Campbell diagram, run-up, spectrogram, ...) offers ``.plot()`` (matplotlib), ``.plot_html()``
(plotly), ``.to_dataframe()`` (pandas, units in the column names) and ``.to_xarray()`` (an
:class:`xarray.Dataset`, units in the ``units`` attribute of every variable and coordinate). :class:`Result` is the
small base that turns ``to_xarray()`` into a netCDF-4 file (:meth:`Result.to_netcdf`, engine h5netcdf), so that
every ``.nc`` the package writes opens with ``xarray.open_dataset`` and carries its units and metadata.

netCDF attributes can only be strings, numbers or 1-D arrays of numbers: :func:`netcdf_attrs` JSON-encodes
everything else (dicts, lists of strings, None, booleans), and :func:`decode_attr` reads such an attribute back.

>>> attrs = netcdf_attrs({"method": "J", "speeds_rpm": [1.0, 2.0], "system": {"name": "tc"}, "ok": True})
>>> attrs["method"], attrs["speeds_rpm"], attrs["system"], attrs["ok"]
('J', '[1.0, 2.0]', '{"name": "tc"}', 'true')
>>> decode_attr(attrs["system"])["name"], decode_attr(attrs["method"])
('tc', 'J')
"""
from __future__ import annotations

import json
from numbers import Integral, Real
from pathlib import Path

from .errors import ParameterError

#: xarray backend used for every netCDF file the package writes (netCDF-4/HDF5 through h5py; no C netCDF library)
NETCDF_ENGINE = "h5netcdf"


def _json_default(obj):
    """JSON for numpy scalars and arrays (and anything else as its str)."""
    import numpy as np

    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


def netcdf_attrs(meta):
    """Attributes that netCDF can store: strings and finite or non-finite numbers are kept, everything else
    (dicts, lists, None, booleans, numpy arrays) is written as JSON text.

    Parameters
    ----------
    meta : dict
        Attribute name -> value (any JSON-serialisable value, numpy scalars and arrays included).

    Returns
    -------
    dict
        Attribute name -> str, int or float.

    Examples
    --------
    >>> import numpy as np
    >>> netcdf_attrs({"n": np.int64(3), "x": 0.5, "none": None, "arr": np.array([1, 2])})
    {'n': 3, 'x': 0.5, 'none': 'null', 'arr': '[1, 2]'}
    """
    out = {}
    for key, value in meta.items():
        if isinstance(value, str):
            out[str(key)] = value
        elif isinstance(value, (Integral, Real)) and not isinstance(value, bool):
            out[str(key)] = int(value) if isinstance(value, Integral) else float(value)
        else:
            out[str(key)] = json.dumps(value, default=_json_default)
    return out


def decode_attr(value):
    """An attribute written by :func:`netcdf_attrs` back as Python data: JSON text decoded, other values as read.

    Parameters
    ----------
    value : object
        An attribute value of a dataset read from a ``.nc`` file.

    Returns
    -------
    object
        The decoded value (a string that is not JSON is returned unchanged).

    Examples
    --------
    >>> decode_attr('{"a": [1, null]}'), decode_attr("run-up"), decode_attr(2.5)
    ({'a': [1, None]}, 'run-up', 2.5)
    """
    if not isinstance(value, str):
        return value
    try:
        return json.loads(value)
    except ValueError:
        return value


def variable(dims, data, units, description):
    """One variable of a dataset: ``(dims, data, attrs)`` with its ``units`` and ``long_name``.

    Parameters
    ----------
    dims : tuple of str
        Dimension names.
    data : array_like
        Values, in ``units``.
    units : str
        Unit (``"-"`` for dimensionless; ``""`` for labels).
    description : str
        Human-readable meaning (netCDF ``long_name``).

    Returns
    -------
    tuple
        ``(dims, data, {"units": units, "long_name": description})``, as :class:`xarray.Dataset` takes it.

    Examples
    --------
    >>> variable(("time",), [0.0, 1.0], "s", "time")[2]
    {'units': 's', 'long_name': 'time'}
    """
    return tuple(dims), data, {"units": units, "long_name": description}


def netcdf_file(path, pattern="*.nc", what="result"):
    """``path`` if it is a file, else the one file matching ``pattern`` in the folder ``path``.

    Raises
    ------
    ParameterError
        Neither (the message names the folder, the pattern and what it holds).
    """

    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob(pattern))
        if len(found) != 1:
            raise ParameterError(f"{path}: {len(found)} {what} files ({pattern}) found {[p.name for p in found]}; "
                                 "name the .nc file")
        path = found[0]
    if not path.is_file():
        raise ParameterError(f"{path}: no {what} there (file not found)")
    return path


class Result:
    """Base of the analysis results: the labelled-array and netCDF part of their common contract.

    Subclasses implement :meth:`to_xarray` (and, each in its own way, ``plot``, ``plot_html``, ``to_dataframe``,
    ``save`` and ``load``); :meth:`to_netcdf` is shared.

    Examples
    --------
    >>> import tempfile, xarray as xr
    >>> class Tiny(Result):
    ...     def to_xarray(self):
    ...         return xr.Dataset({"x": variable(("time",), [1e-6, 2e-6], "m", "orbit x")},
    ...                           attrs=netcdf_attrs({"meta": {"status": "finished"}}))
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with xr.open_dataset(Tiny().to_netcdf(f"{tmp}/tiny.nc")) as ds:
    ...         print(ds["x"].attrs["units"], decode_attr(ds.attrs["meta"])["status"])
    m finished
    """

    #: glob of the netCDF file of this type in a results folder (``Type.load(folder)``)
    NC_GLOB = "*.nc"

    def to_xarray(self):
        """The result as an :class:`xarray.Dataset` (units in the attributes of every variable).

        Returns
        -------
        xarray.Dataset
        """
        raise NotImplementedError(f"{type(self).__name__} has no to_xarray()")

    @classmethod
    def from_xarray(cls, ds):
        """The result from a dataset of :meth:`to_xarray` (the inverse; each result type implements it)."""
        raise NotImplementedError(f"{cls.__name__} has no from_xarray()")

    @classmethod
    def load(cls, path):
        """Read a result saved by ``save``: its ``.nc`` file, or the folder holding exactly one file of this type
        (:attr:`NC_GLOB`).

        Parameters
        ----------
        path : str or Path

        Raises
        ------
        ParameterError
            No such file, or a folder with none or several of them.
        """
        import xarray as xr

        return cls.from_xarray(xr.load_dataset(netcdf_file(path, cls.NC_GLOB, cls.__name__), engine=NETCDF_ENGINE))

    def save_files(self, out_dir, stem, dpi=130):
        """Write ``<stem>.csv`` (``to_dataframe()``), ``<stem>.nc`` (:meth:`to_xarray`), ``<stem>.png`` (``plot()``)
        and ``<stem>.html`` (``plot_html(path)``) into ``out_dir`` (created if missing): the ``save`` of a result
        with no files of its own. Returns the paths."""
        import matplotlib.pyplot as plt

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / f"{stem}{ext}" for ext in (".csv", ".nc", ".png", ".html")]
        self.to_dataframe().to_csv(paths[0], index=False)
        self.to_netcdf(paths[1])
        fig = self.plot()
        fig.savefig(paths[2], dpi=dpi, bbox_inches="tight")
        plt.close(fig)
        self.plot_html(paths[3])
        return paths

    def to_netcdf(self, path):
        """Write :meth:`to_xarray` as a netCDF-4 file (engine :data:`NETCDF_ENGINE`).

        Parameters
        ----------
        path : str or Path
            The ``.nc`` file (its folder must exist; an existing file is replaced).

        Returns
        -------
        Path
            ``path``.
        """
        import contextlib
        import sys

        path = Path(path)
        ds = self.to_xarray()
        # the arrays are in memory: write them here, whatever dask scheduler or client the session has (a default
        # distributed client would make xarray take a cluster-wide lock for the file)
        quiet = (sys.modules["dask"].config.set(scheduler="synchronous") if "dask" in sys.modules
                 else contextlib.nullcontext())
        with quiet:
            ds.to_netcdf(path, engine=NETCDF_ENGINE)
        return path


__all__ = ["NETCDF_ENGINE", "Result", "decode_attr", "netcdf_attrs", "netcdf_file", "variable"]
