"""Unbalance response and critical speeds: stored ROSS responses (A, B), a monolithic run-up (J), the synchronous
eigenproblem (critical speeds of A), sampled orbits, files and the command line."""
import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.linear.unbalance import UnbalanceResponse, critical_speeds, response_peaks, unbalance_force
from frbmodel.nonlinear.runup import SpeedProfile, Unbalance
from frbmodel.physics.dynamics import add_unbalance_forces

# Stored peer results: ROSS's run_unbalance_response on the same rotor and springs, written by
# tests/reference/make_ross_unbalance.py (which records the ROSS and Python versions and the date)
ROSS = json.loads((Path(__file__).parent / "reference" / "ross_unbalance_AB.json").read_text())
SPRINGS = {"A": {"k": 1e6}, "B": {"kx": 1e6, "ky": 2e6}}


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger()


def synchronous_critical_speeds(system, method, **springs):
    """Critical speeds [rpm] of an undamped rotor on springs, independent of the Campbell tracking: q = X e^{iΩt}
    in M q̈ + Ω G q̇ + K q = 0 gives K X = Ω² (M − i G) X, a generalized eigenproblem in Ω² (forward and backward
    synchronous whirl alike)."""
    ls = frb.linear_system(system, method, 1000.0, **springs)
    G = ls.C / (1000.0 * math.pi / 30)
    w2 = sla.eigvals(ls.K, ls.M - 1j * G)
    w2 = w2[np.isfinite(w2) & (np.abs(w2.imag) < 1e-9 * np.abs(w2)) & (w2.real > 0)].real
    return np.sort(np.sqrt(w2) * 30 / math.pi)


@pytest.mark.parametrize("method", ["A", "B"])
def test_methods_a_b_match_ross(tc, method):
    speeds = np.array(ROSS["speeds [rpm]"])
    unb = {u["disc"]: (u["m e [kg m]"], u["phase [rad]"]) for u in ROSS["unbalance"]}
    ur = frb.unbalance_response(tc, method, speeds, unb, critical=False, **SPRINGS[method])
    ref = ROSS["methods"][method]["response"]
    ours = np.column_stack([ur.orbit(f"node{i}")[k] for i in range(4) for k in range(2)])
    theirs = np.column_stack([np.array(ref[f"node{i} {a}"]["re [m]"]) + 1j * np.array(ref[f"node{i} {a}"]["im [m]"])
                              for i in range(4) for a in "xy"])
    crit = synchronous_critical_speeds(tc, method, **SPRINGS[method])
    away = np.min(np.abs(speeds[:, None] / crit[None, :] - 1), axis=1) > 0.02
    assert away.sum() >= 70  # most of the 84 speeds are compared
    # Same discretisation in both codes (test_methods.py: natural frequencies equal to ~1e-7). Near an isolated
    # mode the response goes as 1/(w_n^2 - W^2): a relative frequency difference d changes it by
    # 2 d w_n^2/|w_n^2 - W^2| <= 2 d / 0.04 = 50 d ~ 6e-6 at 2 % from the peak, plus the round-off of the solve;
    # 1e-5 of the response norm at each speed bounds that (the issue asks for 1 %; measured: 5e-12).
    err = np.linalg.norm(ours - theirs, axis=1) / np.linalg.norm(theirs, axis=1)
    assert np.all(err[away] < 1e-5), err[away].max()


def test_force_is_the_run_up_unbalance_load():
    """Re(F e^{iΩt}) equals the load that frbmodel.physics.dynamics.add_unbalance_forces gives the run-up at constant
    speed (rotation angle Ωt), for two discs and phases."""
    unb = [("a", 0, 2e-6, 0.7), ("b", 3, 1e-6, -2.0)]
    omega = 3000.0
    F = unbalance_force(16, unb, omega)
    for t in (0.0, 1.3e-4, 7.7e-4):
        f = np.zeros(16)
        add_unbalance_forces(f, omega * t, omega, 0.0, np.array([0, 3]), np.array([2e-6, 1e-6]), np.array([0.7, -2.0]))
        np.testing.assert_allclose((F * np.exp(1j * omega * t)).real, f, rtol=0, atol=1e-15 * np.abs(f).max())


def test_orbit_axes_and_precession_equal_the_sampled_orbit(tc):
    """Method B (orthotropic springs): elliptic orbits. Semi-axes = largest/smallest radius of the sampled orbit
    x(t) = Re(X e^{iΩt}); precession = sense of rotation of the sampled orbit."""
    ur = frb.unbalance_response(tc, "B", [15e3, 40e3, 120e3], {"turbine_wheel": (1e-6, 0.3)}, critical=False)
    th = np.linspace(0, 2 * np.pi, 20001)
    for name in ("turbine_wheel", "compressor_wheel", "node1"):
        X, Y = ur.orbit(name)
        for i in range(3):
            x, y = (X[i] * np.exp(1j * th)).real, (Y[i] * np.exp(1j * th)).real
            r = np.hypot(x, y)
            # sampling at 2π/20000: the extremes of r(θ) are missed by at most r'' (Δθ)²/8 ~ 1e-8 relative
            assert ur.major_axis(name)[i] == pytest.approx(r.max(), rel=1e-7)
            assert ur.minor_axis(name)[i] == pytest.approx(r.min(), rel=1e-7, abs=1e-7 * r.max())
            sense = np.sign(np.mean(x[:-1] * np.diff(y) - y[:-1] * np.diff(x)))  # > 0: CCW = with the rotation
            assert ur.precession(name)[i] == {1.0: "forward", -1.0: "backward"}[sense]


def test_isotropic_rotor_has_no_backward_response(tc):
    """Isotropic springs (A): a forward-rotating force excites forward circular orbits only (symmetry)."""
    ur = frb.unbalance_response(tc, "A", np.linspace(2e3, 250e3, 30), {"compressor_wheel": (1e-6, 1.0)},
                                critical=False)
    for name in ("turbine_wheel", "compressor_wheel", "turbine journal"):
        assert np.all(np.abs(ur.backward(name)) <= 1e-12 * np.abs(ur.forward(name)))


def test_critical_speeds_of_a_are_the_1x_crossings_and_the_peaks(tc):
    speeds = np.linspace(1e3, 250e3, 100)
    cd = frb.campbell(tc, "A", speeds, whirl=False)
    exact = synchronous_critical_speeds(tc, "A", k=1e6)
    exact = exact[exact <= speeds[-1]]
    cs = critical_speeds(cd)
    assert len(cs) == exact.size and cs["refined"].all()
    # the acceptance asks for 0.1 %; the root solve goes to 1e-9 and both eigen-solvers to ~1e-7
    np.testing.assert_allclose(cs["speed [rpm]"], exact, rtol=1e-6)
    coarse = critical_speeds(cd, refine=False)  # grid interpolation only (2.5 krpm steps)
    np.testing.assert_allclose(coarse["speed [rpm]"], exact, rtol=1e-2)
    # the unbalance response peaks at the forward crossings, and only there (backward modes are not excited)
    ur = frb.unbalance_response(tc, "A", speeds, {"turbine_wheel": (1e-6, 0.0)}, critical=False)
    pk = response_peaks(ur, cd)
    forward = cs.loc[cs["precession"] == "forward", "speed [rpm]"].to_numpy()
    for name in ("turbine_wheel", "compressor_wheel"):
        s = pk.loc[pk["location"] == name, "speed [rpm]"].to_numpy()
        np.testing.assert_allclose(s, forward, rtol=1e-3)  # 0.1 % (acceptance); measured ~1e-8
        assert (pk.loc[pk["location"] == name, "precession"] == "forward").all()


def test_refined_crossings_of_j_lie_on_the_1x_line(tc):
    """Method J: at each refined crossing speed one eigenvalue of the linear system (independent eigen-solve,
    frbmodel.modes) has the frequency speed/60."""
    ur = frb.unbalance_response(tc, "J", np.linspace(2e3, 200e3, 34))
    cs = ur.critical_speeds()
    cross = cs[cs["source"] == "1X crossing"]
    assert len(cross) >= 3 and cross["refined"].all()
    for s in cross["speed [rpm]"]:
        ls = frb.linear_system(tc, "J", s)
        f = frb.modes(ls.M, ls.C, ls.K).frequencies_hz
        assert np.min(np.abs(f - s / 60)) < 1e-6 * s / 60
    peaks = cs[cs["source"] == "response peak"]
    assert set(peaks["location"]) == {"turbine_wheel", "compressor_wheel"}
    assert (peaks["amplitude [m]"] > 0).all()


def test_method_j_equals_the_1x_orbit_of_a_monolithic_run(tc):
    """Method J at 1500 rpm (all modes stable there, D >= 0.1) vs the nonlinear run at that constant speed: the
    1X component of the last 0.2 s (5 revolutions), fitted by least squares, equals the linear response.

    1 g mm gives 1.2 µm at the turbine wheel: 0.8 % of the inner clearance at ε = 0.78 (third-order nonlinearity
    ~0.1 %), 1e3 times atol. Run 0.4 s: the slowest mode (2.5 Hz, D = 0.28) decays by e^-1.8 before the fitted
    window. Measured differences at 0.4 s: wheels 0.2-0.8 %, journals 0.7-1.2 %; at 1 s: wheels 0.1-0.3 %,
    compressor journal 0.2 %, turbine journal 1.0-1.3 % — the same at 1/4 of the unbalance, so a linear modelling
    difference, not a transient or nonlinearity; it is consistent with the ring speed, which oscillates at 1X by
    0.15 % in the run, a perturbation DoF that method J leaves out
    (docs/theory/equations-of-motion.md#equations-of-motion). The rings' own orbits differ
    by up to 6 % on the turbine side for the same reason and are not compared. Hence the 2 % bound."""
    rpm, me, T, fs = 1500.0, 1e-6, 0.4, 2000.0
    run = frb.runup(tc, profile=SpeedProfile.constant(rpm, T), duration=T, unbalance=[Unbalance("turbine_wheel", me)],
                    output_rate_hz=fs, perturbation=0.0, rtol=1e-6, atol=1e-9)
    assert run.status == "finished"
    ur = frb.unbalance_response(tc, "J", [rpm], {"turbine_wheel": (me, 0.0)}, critical=False)
    sel = run.time >= T - 0.2 - 1e-9
    om_t = rpm * math.pi / 30 * run.time[sel]
    basis = np.column_stack([np.cos(om_t), -np.sin(om_t), np.ones_like(om_t)])  # Re(X e^{iΩt}) + mean

    def one_x(signal):
        c = np.linalg.lstsq(basis, signal, rcond=None)[0]
        return c[0] + 1j * c[1]

    series = {"turbine_wheel": run.displacement["turbine_wheel"], "compressor_wheel": run.displacement[
        "compressor_wheel"], "turbine journal": run.journal["turbine"], "compressor journal": run.journal["compressor"]}
    for name, xy in series.items():
        X, Y = ur.orbit(name)
        assert abs(one_x(xy[sel, 0]) - X[0]) < 0.02 * abs(X[0]), name
        assert abs(one_x(xy[sel, 1]) - Y[0]) < 0.02 * abs(Y[0]), name


def test_film_orbits_per_method(tc):
    """Ring methods: inner film = journal − ring, outer = ring; C: inner film rigid (0), outer = journal; A: no
    films (NaN). Fractions are over each film's clearance."""
    b = tc.bearings[0]
    j = frb.unbalance_response(tc, "J", [80e3], critical=False)
    jx, rx = j.orbit("turbine journal")[0], j.orbit("turbine ring")[0]
    assert j.orbit("turbine inner")[0] == pytest.approx(jx - rx)
    assert j.clearance_fraction("turbine outer") == pytest.approx(j.major_axis("turbine ring") / b.outer.clearance)
    assert j.clearance_fraction("turbine inner") == pytest.approx(j.major_axis("turbine inner") / b.inner.clearance)
    c = frb.unbalance_response(tc, "C", [80e3], critical=False)
    assert c.major_axis("turbine inner")[0] == 0.0
    assert c.major_axis("turbine outer") == pytest.approx(c.major_axis("turbine journal"))
    a = frb.unbalance_response(tc, "A", [80e3], critical=False)
    assert np.isnan(a.clearance_fraction("turbine outer")).all()


def test_save_load_tables_and_figures(tc, tmp_path):
    import xarray as xr

    ur = frb.unbalance_response(tc, "J", np.linspace(5e3, 100e3, 12), {"turbine_wheel": (1e-6, 0.0),
                                                                       "compressor_wheel": (5e-7, 2.0)})
    paths = ur.save(tmp_path)
    assert {p.suffix for p in paths} == {".csv", ".json", ".png", ".html", ".nc"}
    back = UnbalanceResponse.load(tmp_path)
    assert np.array_equal(back.response, ur.response) and back.unbalance == ur.unbalance
    assert back.critical_speeds().equals(ur.critical_speeds())
    df = ur.to_dataframe()
    assert df["turbine_wheel major semi-axis [m]"].to_numpy() == pytest.approx(ur.major_axis("turbine_wheel"))
    assert "turbine outer major semi-axis / clearance [-]" in df
    with xr.open_dataset(tmp_path / "unbalance_J.nc") as ds:
        assert ds["major_semi_axis"].attrs["units"] == "m" and ds["speed"].attrs["units"] == "rpm"
    meta = json.loads((tmp_path / "unbalance_J.json").read_text())
    assert meta["method"] == "J" and meta["system"]["name"] == tc.name and len(meta["unbalance"]) == 2


@pytest.mark.parametrize("kw,match", [
    (dict(unbalance={"no_such_wheel": (1e-6, 0.0)}), "disc name"),
    (dict(unbalance={"turbine_wheel": (-1e-6, 0.0)}), "m e of turbine_wheel"),
    (dict(unbalance={}), "at least one disc"),
    (dict(unbalance={"turbine_wheel": 0.0}), "every m e is 0"),
    (dict(unbalance={"turbine_wheel": (1e-6, 0.0, 1.0)}), "m e"),
    (dict(speeds_rpm=[0.0, 1e4]), "speeds"),
    (dict(method="H"), "method"),
])
def test_bad_input(tc, kw, match):
    args = {"method": "J", "speeds_rpm": [1e4], "unbalance": {"turbine_wheel": (1e-6, 0.0)}, "critical": False, **kw}
    with pytest.raises(frb.ParameterError, match=match):
        frb.unbalance_response(tc, **args)


def test_cli_unbalance(tmp_path, capsys):
    out = tmp_path / "ub"
    assert main(["unbalance", "--method", "A,B", "--speeds", "3000:30000:10", "--unbalance",
                 "compressor_wheel:2e-6:1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "critical speeds" in text and "1X crossing" in text and "response peak" in text
    for name in ("unbalance_A.csv", "unbalance_B_critical.csv", "unbalance_A.png", "unbalance_bode_AB.png"):
        assert (out / name).exists(), name
    assert UnbalanceResponse.load(out, stem="unbalance_B").unbalance[0]["disc"] == "compressor_wheel"


@pytest.mark.parametrize("argv,match", [
    (["--unbalance", "nowheel:1e-6"], "disc name = 'nowheel'"),
    (["--unbalance", "turbine_wheel:abc"], "--unbalance 'turbine_wheel:abc'"),
    (["--unbalance", "turbine_wheel:-1e-6"], "valid range"),
    (["--method", "J,X"], "method = 'X'"),
    (["--k", "2e6", "--method", "J"], "--k"),
    (["--locations", "turbine_wheel,nowhere"], "--locations 'nowhere'"),
    (["--speeds", "1:2"], "--speeds"),
])
def test_cli_bad_input(tmp_path, capsys, argv, match):
    assert main(["unbalance", "--out", str(tmp_path / "x"), *argv]) == 2
    assert match in capsys.readouterr().err


def test_cli_refuses_unwritable_out_before_computing(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["unbalance", "--out", str(blocker / "sub")]) == 2
    assert "--out" in capsys.readouterr().err


def test_cli_help_shows_defaults(capsys):
    with pytest.raises(SystemExit):
        main(["unbalance", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: 1000:250000:200)" in text and "(default: J)" in text and "results/unbalance" in text


def test_cli_campbell_writes_critical_speeds(tmp_path, capsys):
    assert main(["campbell", "--method", "A", "--speeds", "1000:30000:30", "--no-whirl", "--out", str(tmp_path)]) == 0
    assert "1X crossing" in capsys.readouterr().out
    import pandas as pd

    cs = pd.read_csv(tmp_path / "campbell_A_critical.csv")
    exact = synchronous_critical_speeds(frb.turbocharger(), "A", k=1e6)
    np.testing.assert_allclose(cs["speed [rpm]"], exact[exact <= 30e3], rtol=1e-6)


def test_campbell_figure_marks_the_critical_speeds():
    """The stars on the 1X line are the grid crossings of the damped branches with 1X, computed here
    independently by sign changes of f_mode - n/60 and linear interpolation."""
    import matplotlib.pyplot as plt

    speeds = np.linspace(1e3, 60e3, 60)
    cd = frb.campbell(frb.turbocharger(), "A", speeds, whirl=False)
    fig = cd.plot(fmax_hz=2000)
    stars = [c for c in fig.axes[0].collections if c.get_label() == "critical speeds (1X crossings)"]
    assert len(stars) == 1
    got = np.sort(stars[0].get_offsets()[:, 0] * 1e3)
    expected = []
    for j in range(cd.frequencies_hz.shape[1]):
        g = cd.frequencies_hz[:, j] - speeds / 60.0
        for k in np.flatnonzero(np.isfinite(g[:-1]) & np.isfinite(g[1:]) & (np.sign(g[:-1]) != np.sign(g[1:]))):
            expected.append(speeds[k] - g[k] * (speeds[k + 1] - speeds[k]) / (g[k + 1] - g[k]))
    plt.close(fig)
    np.testing.assert_allclose(got, np.sort(expected), rtol=1e-9)  # same interpolation: round-off only


def test_a_jump_between_two_modes_is_not_taken_for_a_critical_speed(monkeypatch):
    """Inside a grid interval the eigenvalue nearest to the interpolated one can switch to another branch (where
    two veer). Two branches 5 Hz above and 5 Hz below the 1X line, the tracked one passing from the upper to the
    lower between the grid speeds: f − n/60 jumps from +5 to −5 Hz without crossing zero. Brent's method took the
    jump for a root (a critical speed that does not exist); it is refused, so the crossing keeps the grid's linear
    interpolation (``refined`` False). A true crossing (one branch through 1X) is still refined to its closed form."""
    import types

    import frbmodel.linear.critical as unb  # (the critical-speed search)

    def branch(offset_hz):
        return lambda n: 1j * 2 * math.pi * (n / 60.0 + offset_hz) - 10.0

    upper, lower = branch(5.0), branch(-5.0)

    def nearest(system, m, x, guess, kw, oil_supply=None):
        cands = [upper(x), lower(x)]
        return min(cands, key=lambda lam: abs(lam - guess))

    monkeypatch.setattr(unb, "_eigenvalue_near", nearest)
    cd = types.SimpleNamespace(speeds_rpm=np.array([60e3, 61e3]),
                               eigenvalues=np.array([[upper(60e3)], [lower(61e3)]]))
    assert unb._refine_crossing(None, None, cd, 0, 0, {}) is None
    # a branch that does cross: f = n/60 + 5 Hz − (n − 60 krpm) / 100 Hz/rpm → crossing at 60.5 krpm exactly
    crossing = lambda n: 1j * 2 * math.pi * (n / 60.0 + 5.0 - (n - 60e3) / 100.0) - 10.0  # noqa: E731
    monkeypatch.setattr(unb, "_eigenvalue_near", lambda system, m, x, guess, kw, oil_supply=None: crossing(x))
    cd.eigenvalues = np.array([[crossing(60e3)], [crossing(61e3)]])
    speed, lam = unb._refine_crossing(None, None, cd, 0, 0, {})
    assert speed == pytest.approx(60.5e3, rel=1e-9)  # Brent's xtol, 1e-9 of the speed
