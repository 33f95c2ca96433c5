"""A parameter study as a result of the one contract (:class:`frbmodel.core.results.Result`): its stability map
(one row per onset of every finished case, :func:`frbmodel.studies.sweep.stability_map`) with ``.plot()``,
``.plot_html()``, ``.to_dataframe()``, ``.to_xarray()`` / ``from_xarray()``, ``.save(folder)`` / ``load(folder)``."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..plots.figures import write_html
from ..plots.studies import stability_map_figures
from .sweep import PARAMETERS, stability_map

__all__ = ["StudyResult", "study_result"]

_UNIT = re.compile(r"^(?P<name>.*?) \[(?P<unit>[^\]]*)\]$")


@dataclass
class StudyResult(Result):
    """The onsets of a parameter study (:func:`study_result` reads them from the study's folder).

    Attributes
    ----------
    table : pandas.DataFrame
        :func:`frbmodel.studies.sweep.stability_map`: ``case_id``, ``analysis``, the swept parameters with units,
        ``kind``, ``method``, ``item``, ``onset [rpm]``, ``f at onset [Hz]``, ...
    parameter : str
        The swept parameter's column drawn on the x axis (e.g. ``"outer_clearance [m]"``).
    meta : dict
        The study's folder.
    """

    NC_GLOB = "study.nc"  # (Result.load of a folder)
    table: object
    parameter: str
    meta: dict = field(default_factory=dict)

    def to_dataframe(self):
        """The stability map (a copy; units in the column names)."""
        return self.table.copy()

    def to_xarray(self):
        """Every column of the table as a variable along ``row`` (the unit from its ``[unit]``; text columns
        unit-less, ``"-"``); the column order in the attributes.

        Returns
        -------
        xarray.Dataset
        """
        import xarray as xr

        data = {}
        for k, col in enumerate(self.table.columns):
            m = _UNIT.match(str(col))
            values = self.table[col].to_numpy()
            if values.dtype == object:
                values = values.astype(str)
            data[f"c{k}"] = variable(("row",), values, m["unit"] if m else "-", str(col))
        attrs = {"columns": [str(c) for c in self.table.columns], "parameter": self.parameter, **self.meta}
        return xr.Dataset(data, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The study from a dataset of :meth:`to_xarray`."""
        import pandas as pd

        meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        cols = meta.pop("columns")
        table = pd.DataFrame({c: ds[f"c{k}"].values for k, c in enumerate(cols)})
        return cls(table, str(meta.pop("parameter")), meta)

    @classmethod
    def load(cls, path):
        """Read a study saved by :meth:`save` (``study.nc`` or its folder), or the folder of a study that
        :func:`frbmodel.studies.sweep.run_study` wrote (:func:`study_result`)."""
        p = Path(path)
        if p.is_dir() and not (p / "study.nc").exists() and (p / "index.csv").exists():
            return study_result(p)
        return super().load(path)

    def plot(self):
        """The stability map: onset speed vs the swept parameter
        (:func:`frbmodel.plots.studies.stability_map_figures`)."""
        return stability_map_figures(self.table, self.parameter)[0]

    def plot_html(self, path=None, include_plotlyjs=None):
        """The stability map as an interactive figure, written to ``path`` (HTML) if given."""

        fig = stability_map_figures(self.table, self.parameter)[1]
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def save(self, out_dir):
        """Write ``study.csv``, ``study.nc`` and the figures ``study.png`` / ``.html`` into ``out_dir`` (created if
        missing); returns the paths."""
        return self.save_files(out_dir, "study", dpi=110)


def study_result(out_dir, parameter=None):
    """The :class:`StudyResult` of the study in ``out_dir`` (its finished cases).

    Parameters
    ----------
    out_dir : str or Path
        Folder of a study (:func:`frbmodel.studies.sweep.run_study`).
    parameter : str, optional
        Swept parameter on the figures' x axis (default: the first).

    Raises
    ------
    ParameterError
        No finished case with onsets in the folder.
    """

    table = stability_map(out_dir)
    if table.empty:
        raise ParameterError(f"study folder = {str(out_dir)!r} holds no finished case with onsets")
    pcols = [c for c in table.columns if c.split(" [")[0] in PARAMETERS]
    pcol = next((c for c in pcols if parameter and c.startswith(parameter)), pcols[0] if pcols else None)
    return StudyResult(table, pcol, {"folder": str(Path(out_dir).resolve()), "cases": int(np.unique(
        table["case_id"]).size)})
