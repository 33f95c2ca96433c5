"""Results as xarray datasets and netCDF files: layout, units, round trips, and every .nc the CLI writes.

The expected values are the results' own tables (``to_dataframe`` columns, addressed by name — an independent
layout), closed forms (a circular orbit's spectrum) and the in-memory results a file was written from.
"""
import json

import numpy as np
import pytest
import xarray as xr

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.core.results import decode_attr
from frbmodel.nonlinear.recorder import RunupSchema
from frbmodel.signals.spectral import spectrogram

#: variables whose values are labels (no physical unit)
LABELS = {"stability", "precession", "kind", "mode", "bearing", "film", "disc", "axis"}


def assert_units_everywhere(ds):
    """Every data variable and coordinate has a ``units`` attribute (labels: empty)."""
    for name in list(ds.data_vars) + list(ds.coords):
        assert "units" in ds[name].attrs, name
        assert (ds[name].attrs["units"] == "") == (name in LABELS), name


@pytest.fixture(scope="module")
def campbell_j():
    return frb.campbell(frb.turbocharger(), "J", np.linspace(10e3, 250e3, 9))


def test_campbell_dataset_and_round_trip(campbell_j, tmp_path):
    cd = campbell_j
    ds = cd.to_xarray()
    assert dict(ds["frequency"].sizes) == {"speed": 9, "mode": cd.n_modes}
    assert_units_everywhere(ds)
    assert ds["speed"].attrs["units"] == "rpm" and ds["growth_rate"].attrs["units"] == "1/s"
    # the long table (one row per speed and present mode) is the same data, addressed by speed and mode
    df = cd.to_dataframe()
    sel = ds.sel(speed=xr.DataArray(df["speed [rpm]"].to_numpy()), mode=xr.DataArray(df["mode [-]"].to_numpy()))
    np.testing.assert_array_equal(sel["frequency"].values, df["frequency [Hz]"])
    np.testing.assert_array_equal(sel["damping"].values, df["damping [-]"])
    np.testing.assert_array_equal(sel["growth_rate"].values, df["growth rate Re(lambda) [1/s]"])
    for var, col in (("stability", "stability"), ("precession", "precession"), ("kind", "kind")):
        assert sel[var].values.tolist() == df[col].tolist()
    films = cd.films_dataframe()
    for name in cd.film_labels:
        np.testing.assert_array_equal(ds["whirl_frequency"].sel(film=name).values, films[f"whirl {name} [Hz]"])
    # attributes: the system and method, dicts as JSON
    assert ds.attrs["method"] == "J"
    assert json.loads(ds.attrs["system"]) == frb.turbocharger().to_dict()

    paths = cd.save(tmp_path, png=False, html=False)
    assert tmp_path / "campbell_J.nc" in paths
    with xr.open_dataset(tmp_path / "campbell_J.nc") as back:
        assert_units_everywhere(back)
        assert decode_attr(back.attrs["films"]) == list(cd.film_labels)
    cd2 = frb.CampbellResult.load(tmp_path / "campbell_J.nc")
    for name in ("speeds_rpm", "frequencies_hz", "damping", "damping_tol", "ring_fraction", "ring_speed_ratio",
                 "eccentricity", "whirl_hz", "whirl_margin", "whirl_onset_rpm"):
        assert np.array_equal(getattr(cd2, name), getattr(cd, name), equal_nan=True), name
    assert np.array_equal(cd2.precession, cd.precession) and np.array_equal(cd2.mode_kind, cd.mode_kind)
    # λ = growth_rate + 2πi f: the imaginary part is rebuilt from f = Im λ / 2π (round-off of two operations)
    np.testing.assert_allclose(cd2.eigenvalues, cd.eigenvalues, rtol=1e-15)
    assert cd2.unstable_ranges().equals(cd.unstable_ranges())
    assert cd2.meta["whirl_onset_source"] == cd.meta["whirl_onset_source"]


def test_runup_dataset_matches_the_named_columns(tmp_path):
    schema = RunupSchema(("front", "rear"), ("wheel", "impeller"))
    rng = np.random.default_rng(1)
    rows = np.array([schema.row(0.001 * k, 3e4 + k, rng.random(2) * 300, rng.random((2, 2)) * 1e-5,
                                rng.random((2, 2)) * 1e-5, rng.random((2, 2)), rng.random((2, 2)) * 1e-5,
                                journal_torque=-rng.random(2) * 1e-3, power_loss=rng.random(2) * 50)
                     for k in range(5)])
    res = frb.RunupResult.from_rows(schema, rows, {"status": "stopped", "message": "wall", "system": {"a": [1, 2]}})
    ds = res.to_xarray()
    assert_units_everywhere(ds)
    df = res.to_dataframe()
    for b in schema.bearings:
        np.testing.assert_array_equal(ds["ring_speed"].sel(bearing=b), df[f"ring speed {b} [rad/s]"])
        np.testing.assert_array_equal(ds["ring_speed_ratio"].sel(bearing=b), df[f"RSR {b} [-]"])
        np.testing.assert_array_equal(ds["journal_torque"].sel(bearing=b), df[f"journal torque {b} [N m]"])
        np.testing.assert_array_equal(ds["power_loss"].sel(bearing=b), df[f"power loss {b} [W]"])
        for q in "xy":
            np.testing.assert_array_equal(ds["journal"].sel(bearing=b, axis=q), df[f"journal {b} {q} [m]"])
            np.testing.assert_array_equal(ds["ring"].sel(bearing=b, axis=q), df[f"ring {b} {q} [m]"])
        for f in ("inner", "outer"):
            np.testing.assert_array_equal(ds["eccentricity"].sel(bearing=b, film=f), df[f"eps {b} {f} [-]"])
    for d in schema.discs:
        for q in "xy":
            np.testing.assert_array_equal(ds["displacement"].sel(disc=d, axis=q), df[f"{d} {q} [m]"])
    assert ds.attrs["status"] == "stopped" and decode_attr(ds.attrs["system"]) == {"a": [1, 2]}
    paths = res.save(tmp_path)
    back = frb.RunupResult.load(paths[-1])
    assert back.status == "stopped" and back.message == "wall"
    np.testing.assert_array_equal(back.to_dataframe().to_numpy(), df.to_numpy())
    # the CSV written next to it is the recorder's format (10 significant digits)
    np.testing.assert_allclose(frb.RunupResult.load(tmp_path).to_dataframe().to_numpy(), df.to_numpy(), rtol=1e-9)


def test_spectrogram_dataset_of_a_circular_orbit():
    """A forward circular orbit of radius 1 µm at 200 Hz: the dataset holds the spectrogram's arrays along named
    dimensions, its forward peak is at 200 Hz with 1 µm (the spectrum is normalised to the orbit radius) and the
    backward spectrum is far below it."""
    from types import SimpleNamespace

    t = np.arange(0, 0.5, 1e-4)
    z = 1e-6 * np.exp(2j * np.pi * 200.0 * t)
    speed = np.linspace(30e3, 31e3, t.size)
    run = SimpleNamespace(time=t, speed_rpm=speed, meta={}, displacement={"wheel": np.column_stack([z.real, z.imag])})
    sp = spectrogram(run, segment_s=0.05)
    ds = sp.to_xarray()
    assert ds["forward"].dims == ("frequency", "time") and ds["speed"].dims == ("time",)
    assert_units_everywhere(ds)
    assert ds["forward"].attrs["units"] == "m" and ds["speed"].attrs["units"] == "rpm"
    assert ds.attrs["node"] == "wheel" and ds.attrs["direction"] == "up" and ds.attrs["segment_s"] == 0.05
    for name, arr in (("forward", sp.forward), ("backward", sp.backward), ("frequency", sp.freqs_hz),
                      ("time", sp.times), ("speed", sp.speeds_rpm)):
        assert np.array_equal(ds[name].values, arr), name
    peak = ds["forward"].isel(time=3)
    df = float(ds["frequency"][1] - ds["frequency"][0])
    k = int(np.argmax(peak.values))
    assert abs(float(peak["frequency"][k]) - 200.0) <= df / 2
    # Hann window, 4x zero padding: the bin next to the true frequency is at most 0.1 dB (1.2 %) low
    assert float(peak.max()) == pytest.approx(1e-6, rel=0.012)
    # at -200 Hz only leakage: the Hann sidelobes of the +200 Hz line and of the detrending residue near 0 Hz
    assert float(ds["backward"].isel(time=3, frequency=k)) < 1e-3 * float(peak.max())
    np.testing.assert_allclose(ds["speed"].values, np.interp(ds["time"].values, t, speed), rtol=1e-12)


def test_every_nc_the_cli_writes_opens_with_units(tmp_path, built):
    """frb campbell, frb runup and frb cosim (briefly): each .nc opens with xarray.open_dataset (its default
    engine), every variable and coordinate has units, and the attributes carry the system."""
    written = []
    assert main(["campbell", "--speeds", "20000:60000:3", "--no-whirl", "--out", str(tmp_path / "c")]) == 0
    written.append(tmp_path / "c" / "campbell_J.nc")
    assert main(["runup", "--speeds", "20000:21000", "--duration", "0.01", "--rate", "10000", "--no-figure",
                 "--out", str(tmp_path / "r")]) == 0
    written.append(tmp_path / "r" / "runup.nc")
    assert main(["cosim", str(built / "turbocharger.ssp"), "--stop-time", "0.001", "--no-figure",
                 "--out", str(tmp_path / "s")]) == 0
    written.append(tmp_path / "s" / "runup.nc")
    assert sorted(tmp_path.rglob("*.nc")) == sorted(written)  # no other .nc is written
    for path in written:
        with xr.open_dataset(path) as ds:
            assert_units_everywhere(ds)
            assert "name" in json.loads(ds.attrs["system"])
    with xr.open_dataset(tmp_path / "s" / "runup.nc") as ds:
        assert ds.attrs["status"] == "finished" and float(ds["time"][-1]) == pytest.approx(0.001)
