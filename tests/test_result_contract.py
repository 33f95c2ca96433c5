"""The one result contract (issue #23 item 4): every result type goes through the same calls — ``.plot()``,
``.plot_html(path)``, ``.to_dataframe()``, ``.to_xarray()`` / ``Type.from_xarray(ds)``, ``.save(folder)`` /
``Type.load(folder)`` — and what comes back from the dataset and from the folder is the result it was made from
(its table equal, value for value; netCDF stores float64, so exactly)."""
import inspect

import matplotlib
import numpy as np
import pandas as pd
import pytest

import frbmodel as frb
from frbmodel.core.results import Result
from frbmodel.cycles.branch import BranchPoint
from frbmodel.cycles.continuation import BifurcationDiagram
from frbmodel.cycles.limitcycle import LimitCycle
from frbmodel.linear.modeshape import mode_shape
from frbmodel.signals.orbits import orbits

matplotlib.use("Agg")
FS = 20e3  # sampling rate of the synthetic run [Hz]


def _run():
    """A 0.3 s run-up record of the Table 2 system with closed-form orbits (1X of 2 µm plus a 0.45X whirl of
    4 µm at both wheels; journals and rings at rest), built directly: the contract, not the integrator, is tested."""
    tc = frb.turbocharger(36e-6)
    t = np.arange(0.0, 0.3, 1.0 / FS)
    rpm = np.linspace(30e3, 60e3, t.size)
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    z = 2e-6 * np.exp(1j * phase) + 4e-6 * np.exp(0.45j * phase)
    disc = {d.name: np.column_stack([z.real, z.imag]) for d in tc.rotor.discs}
    names = [b.name for b in tc.bearings]
    rest = np.zeros((t.size, 2))
    return frb.RunupResult(t, rpm, np.full((t.size, 2), 0.2 * rpm[:, None] * np.pi / 30), {b: rest for b in names},
                           {b: rest for b in names}, np.full((t.size, 4), 0.1), disc, meta={"system": tc.to_dict()},
                           journal_torque={b: np.full(t.size, -0.01) for b in names},
                           power_loss={b: np.full(t.size, 20.0) for b in names})


def _branch():
    pts = [BranchPoint(1e4 + 1e3 * i, 1e-3, np.array([1.0, 0.5 + 0.1 * i]), True, 1e-6 * (1 + i),
                       np.full(4, 0.2 + 0.1 * i)) for i in range(4)]
    return BifurcationDiagram(pts, [{"speed_rpm": 1.25e4, "type": "fold", "frequency_hz": 1e3,
                                     "turbine_radius_um": 1.0, "between": [2, 3]}], {"branches": [4]})


def _study():
    """A stability map of two cases (the columns of frbmodel.studies.sweep.stability_map)."""
    from frbmodel.studies.result import StudyResult

    table = pd.DataFrame({"case_id": ["a", "a", "b", "b"], "analysis": ["campbell"] * 4,
                          "outer_clearance [m]": [36e-6, 36e-6, 40e-6, 40e-6], "kind": ["linear"] * 4,
                          "method": ["J"] * 4, "item": ["forward conical #1", "forward cylindrical #1"] * 2,
                          "onset [rpm]": [58.5e3, 14.1e3, 51.1e3, 13.0e3],
                          "f at onset [Hz]": [107.5, 123.3, 99.0, 120.1]})
    return StudyResult(table, "outer_clearance [m]", {"cases": 2})


def _limit_cycle():
    run = _run()
    return LimitCycle(45e3, 0.02, run, np.array([1.0, 0.3 + 0.1j, 0.3 - 0.1j]), True, np.arange(5.0), True,
                      {"integrator": "rodas"})


def _make(kind):
    tc = frb.turbocharger(36e-6)
    if kind == "campbell":
        return frb.campbell(tc, "J", [30e3, 60e3, 90e3], whirl=False)
    if kind == "equilibrium":
        return frb.equilibrium(tc, "J", 100e3)
    if kind == "unbalance":
        return frb.unbalance_response(tc, "J", [20e3, 40e3, 60e3], {"turbine_wheel": 1e-6}, critical=False)
    if kind == "mode shape":
        return mode_shape(frb.campbell(tc, "J", [50e3, 60e3], whirl=False), 60e3, 3)
    if kind == "run-up":
        return _run()
    if kind == "spectrogram":
        return frb.spectrogram(_run(), "turbine_wheel")
    if kind == "orbits":
        return orbits(_run(), time_s=(0.1, 0.12))
    if kind == "limit cycle":
        return _limit_cycle()
    if kind == "study":
        return _study()
    return _branch()


KINDS = ("campbell", "equilibrium", "unbalance", "mode shape", "run-up", "spectrogram", "orbits", "limit cycle",
         "bifurcation diagram", "study")


@pytest.mark.parametrize("kind", KINDS)
def test_every_result_type_keeps_the_one_contract(kind, tmp_path):
    import matplotlib.pyplot as plt
    import plotly.graph_objects as go

    r = _make(kind)
    cls = type(r)
    assert isinstance(r, Result)
    args = {m: list(inspect.signature(getattr(cls, m)).parameters) for m in ("plot_html", "save", "load")}
    assert args["plot_html"][1] == "path" and "include_plotlyjs" in args["plot_html"], args  # the same signatures
    assert args["save"][1] == "out_dir" and args["load"][0] == "path", args
    fig = r.plot()
    assert isinstance(fig, matplotlib.figure.Figure)
    plt.close(fig)
    page = tmp_path / "page.html"
    assert isinstance(r.plot_html(page), go.Figure) and page.stat().st_size > 1000
    df = r.to_dataframe()
    assert isinstance(df, pd.DataFrame) and len(df) > 0
    assert any("[" in str(c) for c in df.columns)  # units in the column names
    ds = r.to_xarray()
    assert all("units" in ds[v].attrs for v in ds.data_vars), [v for v in ds.data_vars if "units" not in ds[v].attrs]
    pd.testing.assert_frame_equal(cls.from_xarray(ds).to_dataframe(), df, check_dtype=False)
    folder = tmp_path / "saved"
    paths = r.save(folder)
    assert paths and all(p.exists() for p in paths)
    pd.testing.assert_frame_equal(cls.load(folder).to_dataframe(), df, check_dtype=False)
