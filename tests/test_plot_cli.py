"""``frb plot DIR``: order lines from the command line on a run-up folder (synthetic run, no integration)."""
import base64
import json
import re

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.cli import build_parser, main, parse_orders

FS = 10000.0  # sampling rate of the synthetic run [Hz]


def figure_data(path):
    """The traces of a plotly HTML file as dicts, typed arrays ({"dtype", "bdata"[, "shape"]}) decoded to numpy.

    Independent of plotly's Python side: reads the JSON argument of ``Plotly.newPlot`` in the file."""
    text = path.read_text()
    start = text.index("[", text.rindex("Plotly.newPlot("))  # the call, after any embedded plotly.js
    traces, _ = json.JSONDecoder().raw_decode(text[start:])

    def decode(v):
        if isinstance(v, dict) and "bdata" in v:
            a = np.frombuffer(base64.b64decode(v["bdata"]), dtype=np.dtype(v["dtype"]))
            shape = v.get("shape")
            if shape is not None:
                a = a.reshape([int(n) for n in re.split(r"\s*,\s*", str(shape))])
            return a
        if isinstance(v, dict):
            return {k: decode(x) for k, x in v.items()}
        return v

    return [decode(t) for t in traces]


def synthetic_run(speed_rpm=(30e3, 60e3), duration=0.3):
    """A run-up of the Table 2 system (system in its metadata) with closed-form orbits: both wheels whirl 1X at
    2 µm plus a forward 0.45X whirl of 4 µm; journals and rings at rest."""
    tc = frb.turbocharger(36e-6)
    t = np.arange(0.0, duration, 1.0 / FS)
    rpm = np.linspace(*speed_rpm, t.size)
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    z = 2e-6 * np.exp(1j * phase) + 4e-6 * np.exp(0.45j * phase)
    disc = {d.name: np.column_stack([z.real, z.imag]) for d in tc.rotor.discs}
    names = [b.name for b in tc.bearings]
    zeros2 = np.zeros((t.size, 2))
    return frb.RunupResult(t, rpm, np.zeros((t.size, len(names))), {b: zeros2 for b in names},
                           {b: zeros2 for b in names}, np.zeros((t.size, 2 * len(names))), disc,
                           meta={"system": tc.to_dict()})


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    synthetic_run().save(out, nc=False)
    return out


def test_orders_option_default_and_parsing():
    assert parse_orders(build_parser().parse_args(["plot", "d"]).orders) == (0.5, 1.0)  # 0.5X and 1X by default
    assert parse_orders("1, 2,0.25") == (1.0, 2.0, 0.25) and parse_orders("none") == ()
    with pytest.raises(frb.ParameterError, match="--orders"):
        parse_orders("1,-0.5")


def test_plot_draws_the_order_lines(run_dir, capsys):
    assert main(["plot", str(run_dir), "--orders", "0.5,1,2", "--waterfall"]) == 0
    for disc in ("turbine_wheel", "compressor_wheel"):
        for stem in ("composite", "waterfall"):
            assert (run_dir / f"{stem}_{disc}.png").stat().st_size > 0
        traces = {t.get("name"): t for t in figure_data(run_dir / f"composite_{disc}.html")}
        for k in (0.5, 1.0, 2.0):
            line = traces[f"{k:g}X"]
            x, y = np.asarray(line["x"], float), np.asarray(line["y"], float)
            # the spectrogram's segment centres: within the run, half a 10 ms segment (500 rpm) from its ends
            assert 30e3 < x.min() < 31e3 and 59e3 < x.max() < 60e3
            # k × f_rot [Hz] of the speed [rpm]; 1e-6: the arrays may be stored in single precision (7 digits)
            np.testing.assert_allclose(y, k * x / 60.0, rtol=1e-6)
        waterfall = {t.get("name") for t in figure_data(run_dir / f"waterfall_{disc}.html")}
        assert {"0.5X", "1X", "2X"} <= waterfall
    assert main(["plot", str(run_dir), "--orders", "-1"]) == 2
    assert "--orders = '-1' is invalid" in capsys.readouterr().err


def test_plot_orbit_time_windows_and_revolutions(run_dir):
    from frbmodel.cli import parse_time_windows

    assert parse_time_windows("0.1:0.2,0:0.05") == [(0.1, 0.2), (0.0, 0.05)]
    for bad in ("0.2:0.1", "0.1", "a:b"):
        with pytest.raises(frb.ParameterError, match="--orbit-times"):
            parse_time_windows(bad)
    assert main(["plot", str(run_dir), "--orders", "none", "--orbit-times", "0.1:0.2", "--orbits", "45000",
                 "--revolutions", "5"]) == 0
    import xarray as xr

    with xr.open_dataset(run_dir / "orbits_t0.1-0.2s.nc") as ds:
        t = ds["time"].values
        assert t[0] >= 0.1 and t[-1] <= 0.2 and t.size == pytest.approx(0.1 * FS, abs=1)  # ends included
    with xr.open_dataset(run_dir / "orbits_45000.nc") as ds:
        # ±5 revolutions at 45 krpm (750 Hz): 2 × 5 / 750 s, to a sample either side
        assert ds["time"].values[-1] - ds["time"].values[0] == pytest.approx(10 / 750.0, abs=2 / FS)


def test_orbit_figure_zooms_onto_small_film_orbits():
    import matplotlib.pyplot as plt

    from frbmodel.signals.orbits import Orbits

    t = np.linspace(0.0, 0.04, 401)
    circle = np.column_stack([np.cos(2 * np.pi * 25.0 * t), np.sin(2 * np.pi * 25.0 * t)])
    small = np.array([10e-6, -20e-6]) + 1e-6 * circle  # 1 µm about (10, -20) µm: spans 2 µm < 10 % of 60 µm
    large = 20e-6 * circle  # spans 40 µm: the whole clearance is shown
    o = Orbits(t, np.full(t.size, 1500.0), {"b": small}, {"b": large}, {}, {"b": (30e-6, 40e-6)}, "test")
    fig = o.plot()
    try:
        ax = {a.get_title(): a for a in fig.axes if a.get_xlabel() == "x [µm]"}  # the µm row
        zoomed = ax["b: journal in ring (zoomed)"]
        # centre of the orbit ± 0.6 × its 2 µm span
        assert zoomed.get_xlim() == pytest.approx((10 - 1.2, 10 + 1.2)) and \
            zoomed.get_ylim() == pytest.approx((-20 - 1.2, -20 + 1.2))
        lo, hi = ax["b: ring in housing"].get_xlim()
        assert lo <= -40.0 and hi >= 40.0  # the clearance circle of radius 40 µm in view
        eps = [a for a in fig.axes if a.get_xlabel() == "x [ε]"]
        assert len(eps) == 2 and all(a.get_xlim()[0] <= -1.0 and a.get_xlim()[1] >= 1.0 for a in eps)
    finally:
        plt.close(fig)


def test_run_figures_and_replot_are_one_path(tmp_path):
    """``frb runup``/``frb cosim`` (write_composites, 1X by default) and ``frb plot --orders 1`` write the same
    files with the same traces: one code path draws both."""
    from frbmodel.studies.run_outputs import write_composites

    first, again = tmp_path / "first", tmp_path / "again"
    for out in (first, again):
        synthetic_run().save(out, nc=False)
    run = frb.RunupResult.load(first)  # the data frb plot reads (the CSV round trip rounds in the last digit)
    paths = write_composites(run, frb.turbocharger(36e-6), first, title="run-up (finished)")
    discs = ("turbine_wheel", "compressor_wheel")
    assert sorted(p.name for p in paths) == sorted(f"{s}_{d}.{e}" for d in discs
                                                   for s, e in (("composite", "png"), ("composite", "html"),
                                                                ("components", "csv")))
    assert main(["plot", str(again), "--orders", "1"]) == 0
    for d in discs:
        drawn, redrawn = (figure_data(f / f"composite_{d}.html") for f in (first, again))
        assert [t.get("name") for t in drawn] == [t.get("name") for t in redrawn]
        assert "1X" in [t.get("name") for t in drawn] and "0.5X" not in [t.get("name") for t in drawn]
        for a, b in zip(drawn, redrawn):
            for key in ("x", "y", "z"):
                if key in a:
                    np.testing.assert_array_equal(np.asarray(a[key], float), np.asarray(b[key], float))
        assert (first / f"components_{d}.csv").read_text() == (again / f"components_{d}.csv").read_text()


def test_plot_redraws_a_bifurcation_folder(tmp_path):
    """``frb plot DIR`` on a folder of ``frb bifurcation``: the diagram is drawn again from branch.nc (PNG and HTML);
    the HTML holds the branch points and the bifurcation points with their type, mode and film (read back from
    the file's plotly JSON)."""
    from frbmodel.cycles.continuation import BifurcationDiagram, BranchPoint

    tc = frb.turbocharger(36e-6)
    pts = [BranchPoint(2e4 + 1e4 * i, 1 / (200.0 + 50 * i), np.array([1.0, 0.5 + 0.2 * i], dtype=complex), i < 2,
                       (5 + i) * 1e-6, np.full(4, 0.3)) for i in range(4)]
    fold = {"speed_rpm": 3.5e4, "type": "fold", "criticality": "", "frequency_hz": 275.0, "turbine_radius_um": 6.5,
            "mode": "forward conical", "film": "turbine outer (eps 0.30)", "between": [1, 2]}
    BifurcationDiagram(pts, [fold], {"system": tc.to_dict(), "speed_range_rpm": [2e4, 5e4], "branches": [4]}).save(
        tmp_path)
    (tmp_path / "bifurcation.png").unlink()
    assert main(["plot", str(tmp_path)]) == 0
    assert (tmp_path / "bifurcation.png").exists()
    traces = figure_data(tmp_path / "bifurcation.html")
    branch_x = np.concatenate([t["x"] for t in traces if t.get("name") in ("stable branch", "unstable branch")
                               and t.get("yaxis", "y") == "y"])
    assert set(branch_x) == {2e4, 3e4, 4e4, 5e4}
    marks = [t for t in traces if t.get("name") == "fold"]
    assert marks and "forward conical" in marks[0]["text"][0] and "turbine outer" in marks[0]["text"][0]


@pytest.mark.parametrize("argv, words", [
    (["--orbits", "500000"], ["--orbits 500000: speed_rpm = 500000 is invalid: valid range 30000 ... 60000 rpm"]),
    (["--orbits", "fast"], ["--orbits = 'fast' is invalid: this command takes a speed grid, START:STOP:COUNT"]),
    (["--orbit-times", "5:6"], ["--orbit-times 5:6: the time window 5 ... 6 s holds 0 samples", "at least 2"]),
    (["--revolutions", "5"], ["--revolutions 5 applies only with --orbits"]),
    (["--revolutions=-3"], ["--revolutions = -3.0 revolutions is invalid: valid range is finite and > 0"]),
    (["--orbits", "45000", "--revolutions=-3"], ["--revolutions = -3.0 revolutions is invalid", "> 0"]),
])
def test_plot_checks_its_orbit_options_before_it_redraws_anything(run_dir, argv, words, capsys, monkeypatch):
    """Issue #24 item 7: --orbits 500000, --orbit-times 5:6, --revolutions=-3 and --orbits fast were checked only
    after the composites were redrawn (6 s), --revolutions without --orbits was ignored, and 'fast' was reported as
    --speeds. Now each is refused first (the composites are replaced by a function that fails the test if called),
    naming its option, with no file added to the folder."""
    import frbmodel.cli

    def redrawn(*args, **kwargs):
        raise AssertionError("the composites were redrawn before the options were checked")

    monkeypatch.setattr(frbmodel.cli, "write_composites", redrawn)
    before = sorted(p.name for p in run_dir.iterdir())
    assert main(["plot", str(run_dir), *argv]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words) and "Traceback" not in err, err
    assert sorted(p.name for p in run_dir.iterdir()) == before
