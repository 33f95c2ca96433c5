"""Orbits as xarray / netCDF (frbmodel.signals.orbits.Orbits.to_xarray, .save, .load): closed-form circles in, the same
numbers with their units out, and ``xarray.open_dataset`` reads the files the CLI writes."""
import numpy as np
import pytest
import xarray as xr
from test_plot_cli import synthetic_run

from frbmodel.cli import main
from frbmodel.core.results import decode_attr
from frbmodel.nonlinear.recorder import RunupResult
from frbmodel.signals.orbits import Orbits, orbits

C = {"front": (30e-6, 50e-6), "rear": (40e-6, 60e-6)}  # inner, outer clearance [m]
R_J, R_R, R_W = 12e-6, 20e-6, 25e-6  # journal-in-ring, ring, wheel orbit radii [m]


def _circle(t, r, f_hz):
    return r * np.column_stack([np.cos(2 * np.pi * f_hz * t), np.sin(2 * np.pi * f_hz * t)])


def _run():
    """Ring on a circle of R_R at 100 Hz, journal = ring + a circle of R_J at 170 Hz, wheel on R_W at 200 Hz."""
    t = np.arange(0.0, 0.1, 1e-4)
    ring = {b: _circle(t, R_R, 100.0) for b in C}
    journal = {b: ring[b] + _circle(t, R_J, 170.0) for b in C}
    sys_d = {"name": "two circles", "bearings": [{"name": b, "inner": {"clearance": ci}, "outer": {"clearance": co}}
                                                 for b, (ci, co) in C.items()]}
    return RunupResult(t, 30e3 + 1e5 * t, np.zeros((t.size, 2)), journal, ring, np.zeros((t.size, 4)),
                       {"wheel": _circle(t, R_W, 200.0)}, meta={"system": sys_d})


def _check_dataset(ds, t):
    """Dimensions, units and values of an orbits dataset against the closed form, on the samples ``t``."""
    assert dict(ds["journal_in_ring"].sizes) == {"time": t.size, "bearing": 2, "axis": 2}
    assert dict(ds["wheel"].sizes) == {"time": t.size, "disc": 1, "axis": 2}
    units = {"journal_in_ring": "m", "ring_in_housing": "m", "eps_inner": "-", "eps_outer": "-", "wheel": "m",
             "inner_clearance": "m", "outer_clearance": "m", "time": "s", "speed": "rpm"}
    assert {k: ds[k].attrs["units"] for k in units} == units
    assert all(ds[k].attrs["long_name"] for k in units)
    assert list(ds["bearing"].values) == ["front", "rear"] and list(ds["axis"].values) == ["x", "y"]
    np.testing.assert_array_equal(ds["time"].values, t)
    np.testing.assert_array_equal(ds["speed"].values, 30e3 + 1e5 * t)
    for k, (ci, co) in enumerate(C.values()):
        # journal − ring undoes the sum that built the journal: round-off of ~3e-5 m numbers, < 1e-19 m
        np.testing.assert_allclose(ds["journal_in_ring"].values[:, k], _circle(t, R_J, 170.0), rtol=0, atol=1e-19)
        np.testing.assert_array_equal(ds["ring_in_housing"].values[:, k], _circle(t, R_R, 100.0))
        # ε = r / C on the whole circle (closed form), to round-off
        np.testing.assert_allclose(np.hypot(*ds["eps_inner"].values[:, k].T), R_J / ci, rtol=1e-12)
        np.testing.assert_allclose(np.hypot(*ds["eps_outer"].values[:, k].T), R_R / co, rtol=1e-12)
        assert (ds["inner_clearance"].values[k], ds["outer_clearance"].values[k]) == (ci, co)
    np.testing.assert_array_equal(ds["wheel"].values[:, 0], _circle(t, R_W, 200.0))


def test_to_xarray_holds_the_orbits_with_units():
    run = _run()
    o = orbits(run, speed_rpm=35e3, revolutions=10)
    ds = o.to_xarray()
    _check_dataset(ds, o.time)
    assert o.time[0] < 0.05 < o.time[-1]  # 35 krpm is passed at t = 0.05 s
    assert ds.attrs["window"] == o.label and decode_attr(ds.attrs["speed_rpm"]) == 35e3
    assert decode_attr(ds.attrs["system"])["name"] == "two circles"


def test_save_writes_a_netcdf_that_xarray_opens(tmp_path):
    o = orbits(_run(), time_s=(0.02, 0.06))
    paths = o.save(tmp_path)
    assert [p.name for p in paths] == [f"orbits_t{o.time[0]:g}-{o.time[-1]:g}s{x}" for x in
                                       (".png", ".html", ".csv", ".nc")]
    with xr.open_dataset(paths[-1]) as ds:  # the default engine, as a user opens it
        _check_dataset(ds, o.time)
        assert decode_attr(ds.attrs["time_s"]) == [0.02, 0.06]
    back = Orbits.load(paths[-1])
    assert back.label == o.label and back.clearances == o.clearances and back.meta == o.meta
    for b in C:
        np.testing.assert_array_equal(back.journal_in_ring[b], o.journal_in_ring[b])
        np.testing.assert_array_equal(back.ring[b], o.ring[b])
    np.testing.assert_array_equal(back.wheels["wheel"], o.wheels["wheel"])


def test_cli_plot_orbits_writes_netcdf(tmp_path):
    run = synthetic_run()
    run.save(tmp_path, nc=False)
    assert main(["plot", str(tmp_path), "--orbits", "45000", "--orders", "none"]) == 0
    for ext in (".png", ".html", ".csv", ".nc"):
        assert (tmp_path / f"orbits_45000{ext}").stat().st_size > 0
    with xr.open_dataset(tmp_path / "orbits_45000.nc") as ds:
        assert ds["wheel"].attrs["units"] == "m" and ds["speed"].attrs["units"] == "rpm"
        assert list(ds["disc"].values) == ["turbine_wheel", "compressor_wheel"]
        # the synthetic wheel orbit: 2 µm 1X + 4 µm 0.45X, so |z| <= 6 µm and reaches nearly 6 µm in 20 revolutions
        r = np.hypot(*ds["wheel"].values[:, 0].T)
        assert r.max() == pytest.approx(6e-6, rel=0.02) and r.max() <= 6e-6 * (1 + 1e-12)
        # ±20 revolutions about 45 krpm (the run passes it at t = 0.15 s): 2 × 20 / 750 Hz
        assert ds["time"].values[-1] - ds["time"].values[0] == pytest.approx(40 / 750.0, abs=2e-4)
