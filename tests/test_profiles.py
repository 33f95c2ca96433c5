"""Speed profiles: CSV tables, run-up + run-down, their uniform grid and Ω̇, and ``frb runup --profile``.

Expected values come from the tables themselves (piecewise-linear speed written out by hand here), from the
conservation ∫Ω̇ dt = ΔΩ, or from the existing :meth:`SpeedProfile.ramp` (for the CSV that encodes the same ramp).
"""
import math

import numpy as np
import pytest
import xarray as xr

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.core.errors import ParameterError
from frbmodel.nonlinear.runup import MAX_PROFILE_POINTS, SEGMENT_STEPS, SpeedProfile

RPM = math.pi / 30.0  # rad/s per rpm, written out here (not taken from the package)


def write_csv(path, rows, header="time [s], speed [rpm]"):
    path.write_text(header + "\n" + "".join(f"{t!r}, {s!r}\n" for t, s in rows))
    return path


def test_two_row_csv_ramp_is_the_ramp_bit_for_bit(tmp_path):
    """Acceptance: a CSV that encodes the ramp 20 -> 60 krpm gives the identical run-up. Both tables hold the
    two end points on the grid [0, T] (a two-point table has no kink, so it is not refined) with the same
    floating-point operations, so the right-hand side is the same function and LSODA takes the same steps: the
    results must agree bit for bit, not merely to a tolerance."""
    T = 0.05
    csv = write_csv(tmp_path / "ramp.csv", [(0.0, 20000.0), (T, 60000.0)])
    p, q = SpeedProfile.from_csv(csv), SpeedProfile.ramp(20e3, 60e3, T)
    for name in ("t", "omega", "omega_dot"):
        assert np.array_equal(getattr(p, name), getattr(q, name)), name
    assert p.direction == q.direction == "up"
    tc = frb.turbocharger()
    a = frb.runup(tc, profile=p, duration=T, output_rate_hz=10e3)
    b = frb.runup(tc, profile=q, duration=T, output_rate_hz=10e3)
    assert a.status == b.status == "finished" and a.time.size == 501
    assert np.array_equal(a.to_dataframe().to_numpy(), b.to_dataframe().to_numpy(), equal_nan=True)
    # the speed really is the ramp (closed form), not merely the same in both runs
    np.testing.assert_allclose(a.speed_rpm, 20e3 + 40e3 * a.time / T, rtol=1e-12)

    # the command line with the CSV (duration from the CSV's last time) writes the same run, at full precision in .nc
    out = tmp_path / "cli"
    assert main(["runup", "--profile", str(csv), "--rate", "10000", "--no-figure", "--out", str(out)]) == 0
    with xr.open_dataset(out / "runup.nc") as ds:
        assert ds["time"].size == 501 and ds["time"].attrs["units"] == "s"
        assert np.array_equal(ds["speed"].values, a.speed_rpm)
        for disc in a.displacement:
            assert np.array_equal(ds["displacement"].sel(disc=disc).values, a.displacement[disc])


def test_uniform_table_keeps_its_own_grid_and_values(tmp_path):
    """A table with a uniform step and kinks: every row lies on the grid with its exact speed, the grid is the
    table's step refined to SEGMENT_STEPS steps per segment, and the speed in between is the linear one."""
    rows = [(0.0, 20000.0), (0.01, 30000.0), (0.02, 30000.0), (0.03, 25000.0)]
    p = SpeedProfile.from_csv(write_csv(tmp_path / "p.csv", rows))
    t_tab, s_tab = np.array(rows).T
    assert p.t.size == 3 * SEGMENT_STEPS + 1
    np.testing.assert_allclose(np.diff(p.t), 0.01 / SEGMENT_STEPS, rtol=1e-9)  # uniform; rtol: linspace round-off
    idx = np.arange(4) * SEGMENT_STEPS
    np.testing.assert_allclose(p.omega[idx], s_tab * RPM, rtol=1e-15)  # the rows' speeds (rtol: 2 pi / 60 rounding)
    t_any = np.linspace(0.0, 0.03, 977)
    np.testing.assert_allclose(p(t_any) / RPM, np.interp(t_any, t_tab, s_tab), rtol=1e-12)
    assert p.direction == "up-down"
    assert "every point of the table on the grid" in p.description


def test_acceleration_is_piecewise_constant_with_honest_kinks():
    """Ω̇ equals each segment's slope (by hand: 4e5, 0, −2.5e5 rpm/s here) at every grid point but the kinks, the
    mean of both slopes at a kink (so the interpolated Ω̇ departs from the step only within one grid step either
    side), and its linear interpolation integrates to the speed change over the run (trapezoid rule of a
    piecewise-linear function: exact up to round-off)."""
    t_tab = [0.0, 0.1, 0.3, 0.35]  # non-uniform steps: the grid must hold 0.1, 0.3 and 0.35 (step 0.05 / refine)
    s_tab = [20e3, 60e3, 60e3, 47.5e3]
    p = SpeedProfile.piecewise_linear(t_tab, s_tab)
    dt = p.t[1] - p.t[0]
    slopes = np.array([4e5, 0.0, -2.5e5])  # [rpm/s]
    for tk in t_tab:  # every row on the grid
        assert np.min(np.abs(p.t - tk)) < 1e-9 * dt
    seg = np.searchsorted(t_tab, p.t, side="right") - 1
    near_kink = np.min(np.abs(p.t[:, None] - np.array(t_tab[1:3])[None, :]), axis=1) < 0.5 * dt
    inside = ~near_kink
    np.testing.assert_allclose(p.omega_dot[inside] / RPM, slopes[np.minimum(seg[inside], 2)], rtol=1e-9, atol=1e-6)
    for j, tk in enumerate(t_tab[1:3]):
        k = int(np.argmin(np.abs(p.t - tk)))
        assert p.omega_dot[k] / RPM == pytest.approx(0.5 * (slopes[j] + slopes[j + 1]), rel=1e-9, abs=1e-6)
    integral = np.sum(0.5 * (p.omega_dot[1:] + p.omega_dot[:-1]) * np.diff(p.t))
    assert integral == pytest.approx(p.omega[-1] - p.omega[0], rel=1e-10)  # rel: round-off of ~1e3 terms
    assert (np.diff(p.t)[0] * SEGMENT_STEPS) == pytest.approx(0.05, rel=1e-9)  # 100 steps on the 0.05 s segment


def test_table_off_any_grid_reports_how_close_it_is():
    """Rows at irrational times fit no uniform grid: the table is sampled on a grid at most its smallest step
    (refined at the kinks) and the description states the largest deviation at the rows, which is then checked."""
    t_tab = [0.0, 0.1 * math.sqrt(2), 0.2 * math.sqrt(3), 0.5]
    s_tab = [20e3, 40e3, 35e3, 50e3]
    p = SpeedProfile.piecewise_linear(t_tab, s_tab)
    assert "points off the grid" in p.description
    dev = float(p.description.split("within ")[1].split(" rpm")[0])
    at_rows = np.abs(p(np.array(t_tab)) / RPM - np.array(s_tab))
    assert at_rows.max() <= dev * 1.001 + 1e-9  # the reported deviation (3 significant digits) bounds the true one
    # a kink between grid points is cut by at most |Δslope| dt / 4 (the chord across one cell)
    dt = p.t[1] - p.t[0]
    assert dev <= max(abs(2e4 / 0.1414 + 5e3 / 0.2050), abs(5e3 / 0.2050 + 15e3 / 0.1536)) * dt / 4 * 1.01
    assert p.t.size <= MAX_PROFILE_POINTS and np.allclose(np.diff(p.t), dt)


def test_up_down_profile():
    p = SpeedProfile.up_down(20e3, 60e3, 0.5)
    assert p.direction == "up-down" and float(p.t[-1]) == 1.0
    t = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(p(t) / RPM, 20e3 + 40e3 * (1.0 - np.abs(t - 0.5) / 0.5), rtol=1e-12)
    h = SpeedProfile.up_down(20e3, 60e3, 0.5, hold_s=0.2, end_rpm=30e3)
    assert h.direction == "up-down" and float(h.t[-1]) == pytest.approx(1.2, rel=1e-15)
    np.testing.assert_allclose(h(np.array([0.5, 0.6, 0.7, 0.95, 1.2])) / RPM, [60e3, 60e3, 60e3, 45e3, 30e3],
                               rtol=1e-12)
    with pytest.raises(ParameterError, match=r"top speed = 20000.0 rpm is invalid: valid range > 30000"):
        SpeedProfile.up_down(30e3, 20e3, 0.5)
    with pytest.raises(ParameterError, match="hold time"):
        SpeedProfile.up_down(20e3, 60e3, 0.5, hold_s=-1.0)


def test_direction_of_profiles():
    assert SpeedProfile.ramp(60e3, 20e3, 1.0).direction == "down"
    assert SpeedProfile.constant(60e3, 1.0).direction == "constant"
    assert SpeedProfile.exponential(1e3, 250e3, 1.0).direction == "up"
    assert SpeedProfile.piecewise_linear([0, 1, 2], [60e3, 20e3, 60e3]).direction == "mixed"
    assert SpeedProfile.torque(1e-3, 20e3, 0.1).direction == "up"


@pytest.mark.parametrize("text, line, words", [
    ("speed [rpm], time [s]\n0, 1\n", 1, ["header 'speed [rpm], time [s]' is invalid", "'time [s], speed [rpm]'"]),
    ("time, speed\n0, 1\n", 1, ["header 'time, speed' is invalid"]),
    ("0, 20000\n1, 30000\n", 1, ["header '0, 20000' is invalid"]),
    ("time [s], speed [rpm]\n0, 20000\n1, 30000, 5\n", 3, ["has 3 values; expected 2"]),
    ("time [s], speed [rpm]\n0, 20000\n1; 30000\n", 3, ["has 1 values"]),
    ("time [s], speed [rpm]\n0, 20000\n1, fast\n", 3, ["speed [rpm] = 'fast' is not a number"]),
    ("time [s], speed [rpm]\n0, 20000\n1, nan\n", 3, ["speed = nan rpm is invalid: valid range is finite and > 0"]),
    ("time [s], speed [rpm]\n0, 20000\n1, -5\n", 3, ["speed = -5.0 rpm is invalid"]),
    ("time [s], speed [rpm]\n0, 20000\n1, 0\n", 3, ["speed = 0.0 rpm is invalid"]),
    ("time [s], speed [rpm]\n0, 20000\n1, 2e6\n", 3, ["speed = 2000000.0 rpm is invalid: valid range 0 < speed"]),
    ("time [s], speed [rpm]\n0, 20000\n0.5, 30000\n0.5, 40000\n", 4,
     ["time = 0.5 s is invalid: valid range > 0.5 s", "times must increase"]),
    ("time [s], speed [rpm]\n0, 20000\n0.5, 30000\n\n# note\n0.2, 40000\n", 6, ["time = 0.2 s is invalid"]),
    ("time [s], speed [rpm]\n0.1, 20000\n1, 30000\n", 2, ["time = 0.1 s is invalid: the profile must start at t = 0"]),
    ("time [s], speed [rpm]\n0, 20000\ninf, 30000\n", 3, ["time = inf s is invalid: it must be finite"]),
])
def test_bad_csv_rows_are_named_by_file_line_value_and_range(tmp_path, text, line, words):
    path = tmp_path / "profile.csv"
    path.write_text(text)
    with pytest.raises(ParameterError) as exc:
        SpeedProfile.from_csv(path)
    msg = str(exc.value)
    assert msg.startswith(f"{path}, line {line}: "), msg
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize("text, words", [
    ("time [s], speed [rpm]\n0, 20000\n", "1 point(s); a speed profile needs at least 2"),
    ("time [s], speed [rpm]\n", "0 point(s)"),
    ("", "empty; expected the header 'time [s], speed [rpm]'"),
])
def test_too_short_csv(tmp_path, text, words):
    path = tmp_path / "short.csv"
    path.write_text(text)
    with pytest.raises(ParameterError, match=r"short\.csv") as exc:
        SpeedProfile.from_csv(path)
    assert words in str(exc.value)


def test_csv_header_tolerates_case_spaces_and_a_byte_order_mark(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes("\ufeffTime  [s] ,Speed [RPM]\r\n0,20000\r\n0.5,30000\r\n".encode("utf-8"))
    p = SpeedProfile.from_csv(path)
    assert p.t.tolist() == [0.0, 0.5] and "excel.csv" in p.description


def test_missing_csv_is_a_clean_error(tmp_path):
    with pytest.raises(ParameterError, match=r"nope\.csv: cannot read the speed profile"):
        SpeedProfile.from_csv(tmp_path / "nope.csv")


def test_cli_up_down_and_csv_errors(tmp_path, capsys):
    """``--profile up-down``: START -> TOP -> START, half the duration each way, labelled as a run-up and run-down;
    the recorded speed is that triangle (closed form). CSV errors and a --duration beyond the table: exit 2."""
    out = tmp_path / "ud"
    assert main(["runup", "--profile", "up-down", "--speeds", "20000:40000", "--duration", "0.02", "--rate", "10000",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.startswith("run-up and run-down: run-up and run-down 20000 -> 40000 -> 20000 rpm, 0.01 s each way")
    assert text.rstrip().endswith(f"results in {out.resolve()}")
    run = frb.RunupResult.load(out / "runup.nc")
    np.testing.assert_allclose(run.speed_rpm, 20e3 + 20e3 * (1.0 - np.abs(run.time - 0.01) / 0.01), rtol=1e-12)
    # the whole run's composite, and each half on its own
    assert (out / "composite_turbine_wheel.png").exists()
    for half in ("run-up", "run-down"):
        assert (out / half / "composite_turbine_wheel.png").exists()
        assert (out / half / "components_turbine_wheel.csv").exists()

    csv = write_csv(tmp_path / "p.csv", [(0.0, 20000.0), (0.01, 30000.0)])
    assert main(["runup", "--profile", str(csv), "--duration", "0.02", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "--duration = 0.02 s is invalid" in err and "last time, 0.01 s" in err and "Traceback" not in err
    bad = tmp_path / "bad.csv"
    bad.write_text("time [s], speed [rpm]\n0, 20000\n0.01, -1\n")
    assert main(["runup", "--profile", str(bad), "--out", str(tmp_path / "y")]) == 2
    err = capsys.readouterr().err
    assert f"{bad}, line 3: speed = -1.0 rpm is invalid" in err and "Traceback" not in err
    assert main(["runup", "--profile", "up-down", "--speeds", "40000:20000", "--out", str(tmp_path / "z")]) == 2
    assert "top speed = 20000.0 rpm is invalid" in capsys.readouterr().err
