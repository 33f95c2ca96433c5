"""Hopf points, branch continuation and bifurcation detection (frbmodel.cycles.continuation)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq, curve_fit

import frbmodel as frb
from frbmodel.cycles.continuation import BifurcationDiagram, BranchPoint, _classify, continuation, hopf_points
from frbmodel.linear.modal import state_matrix


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger(36e-6)


def _method_j_crossing(tc, near_rpm, f_hz):
    """Speed [rpm] and frequency [Hz] where the method-J linear mode near f_hz crosses to instability (the paper's
    linear analysis: equilibrium, film coefficients, ring speed fixed by the torque balance), by Brent's method."""
    def lam(s):
        ls = frb.linear_system(tc, "J", s)
        ev = np.linalg.eigvals(state_matrix(ls.M, ls.C, ls.K))
        ev = ev[ev.imag > 0]
        return ev[np.argmin(np.abs(ev.imag / (2 * math.pi) - f_hz))]
    s = brentq(lambda s: lam(s).real, 0.95 * near_rpm, 1.05 * near_rpm, xtol=1e-3)
    return s, lam(s).imag / (2 * math.pi)


def test_hopf_points_are_the_method_j_onsets(tc):
    """Acceptance (issue #14): the branches start at the linear Hopf speeds of method J (0.5 %) with the linear
    frequency (0.5 %). The full model's Jacobian also has the rings' spin, which method J fixes by the torque balance;
    measured agreement <= 0.03 %."""
    hps = hopf_points(tc, (1e3, 120e3))
    assert len(hps) == 4  # 2.0, 14.1, 58.5, 95.9 krpm: each a forward mode of the Campbell diagram going unstable
    for hp in hps:
        s, f = _method_j_crossing(tc, hp.speed_rpm, hp.frequency_hz)
        assert hp.speed_rpm == pytest.approx(s, rel=0.005)
        assert hp.frequency_hz == pytest.approx(f, rel=0.005)


@pytest.mark.parametrize("clearance, window", [(36e-6, (25e3, 35e3)), (46e-6, (10e3, 15e3))])
def test_restabilizing_hopf_points_are_method_j_crossings_back_to_stability(clearance, window):
    """With ``restabilizing=True`` the crossings back to stability are listed too, flagged: the forward conical mode
    that loses stability at 2.0 krpm regains it at ~30.8 krpm at 36 um (the end of the large whirl branch), at
    ~12.8 krpm at 46 um (where, in the grid interval, the eigenvalue nearest in frequency switches to a heavily
    damped one: a sign change of the tracked real part that is no crossing, at 12.5 krpm). The speed and frequency
    equal the method-J crossing (0.5 %, as the onsets), and method J's eigenvalue is unstable 1 % below the point
    and stable 1 % above (the independent linear analysis decides the direction)."""
    tc = frb.turbocharger(clearance)
    onsets = hopf_points(tc, (1e3, 120e3))
    hps = hopf_points(tc, (1e3, 120e3), restabilizing=True)
    back = [hp for hp in hps if hp.restabilizing]
    assert [hp.speed_rpm for hp in hps if not hp.restabilizing] == [hp.speed_rpm for hp in onsets]
    assert len(back) == 1 and window[0] < back[0].speed_rpm < window[1]
    hp = back[0]
    s, f = _method_j_crossing(tc, hp.speed_rpm, hp.frequency_hz)
    assert hp.speed_rpm == pytest.approx(s, rel=0.005)
    assert hp.frequency_hz == pytest.approx(f, rel=0.005)
    for factor, unstable in ((0.99, True), (1.01, False)):
        ls = frb.linear_system(tc, "J", factor * hp.speed_rpm)
        ev = np.linalg.eigvals(state_matrix(ls.M, ls.C, ls.K))
        ev = ev[ev.imag > 0]
        assert (ev[np.argmin(np.abs(ev.imag / (2 * math.pi) - f))].real > 0) == unstable


def test_branch_collapsing_onto_the_equilibrium_ends_at_the_full_models_hopf_point(tc):
    """A branch through a given orbit that shrinks onto the equilibrium is recorded as ending at the full model's
    Hopf point there (either crossing direction; its speed and frequency, not the last point's), with criticality
    from the side the branch grows to; branches from Hopf points and through orbits keep all their points when
    mixed (one origin per branch). Synthetic branch points near the 30.8 krpm restabilizing point (116 Hz), growing
    towards lower speeds: the unstable side there, so supercritical."""
    from frbmodel.cycles.continuation import _diagram

    hp = hopf_points(tc, (29e3, 33e3), n_grid=8, restabilizing=True)[0]
    f = hp.frequency_hz
    through = [_bp(hp.speed_rpm * (1 - 0.002 * k), [0.5, 0.4]) for k in range(5)]
    for k, p in enumerate(through):
        p.period, p.turbine_radius_m = 1 / f, (1 + 100 * k) * 1e-6  # 1 um at the end (< COLLAPSE x largest)
    from_hopf = [_bp(2.2e3 + 10 * k, [0.5, 0.4]) for k in range(3)]
    start = hopf_points(tc, (1.5e3, 2.5e3), n_grid=4)[0]
    bd = _diagram(tc, "short", [from_hopf, through[::-1]], [start, None], 1e3, 40e3)
    assert len(bd.points) == 8
    both = _diagram(tc, "short", [through[::-1], through], [hp, None], 1e3, 40e3)  # the point from both sides
    assert [b["type"] for b in both.bifurcations].count("Hopf (restabilizing)") == 1
    end = [b for b in bd.bifurcations if b["type"].startswith("Hopf") and b["speed_rpm"] > 20e3]
    assert len(end) == 1 and end[0]["type"] == "Hopf (restabilizing)"
    # the same crossing, refined from another grid bracket: equal within the refinement's 1e-6
    assert end[0]["speed_rpm"] == pytest.approx(hp.speed_rpm, rel=2e-6)
    assert end[0]["frequency_hz"] == pytest.approx(hp.frequency_hz, rel=2e-6)
    assert end[0]["criticality"] == "supercritical" and end[0]["mode"]


def _bp(speed, mults):
    return BranchPoint(speed, 1e-3, np.array([1.0] + list(mults), dtype=complex), bool(np.all(np.abs(mults) < 1)),
                       1e-6, np.zeros(4))


@pytest.mark.parametrize("a, b, kind, frac", [
    ([0.9, 0.5], [1.1, 0.5], "fold", 0.5),
    ([-0.8, 0.5], [-1.2, 0.5], "period doubling", 0.5),
    ([0.95 * np.exp(1j), 0.95 * np.exp(-1j)], [1.05 * np.exp(1.1j), 1.05 * np.exp(-1.1j)], "Neimark-Sacker", 0.5),
    ([1.3, 0.5], [0.9, 0.5], "fold", 0.75),
    ([0.5, 0.4], [0.6, 0.3], None, None),
])
def test_bifurcation_type_and_location_from_multipliers(a, b, kind, frac):
    """A multiplier leaving (or entering) the unit circle at angle 0 is a fold, at pi a period doubling, a complex
    pair a Neimark-Sacker point; located where its modulus, linear between the points, is 1 (closed form here)."""
    found = _classify(_bp(1e4, a), _bp(2e4, b))
    if kind is None:
        assert found == []
    else:
        assert found == [(kind, pytest.approx(frac, abs=1e-12))]


def test_fold_where_the_branch_turns_back_in_speed():
    """A branch that turns back in speed has a fold at the turning point (the point of extreme speed); multiplier
    changes right beside it are the fold's, not separate events (the synthetic multipliers would otherwise read as a
    Neimark-Sacker pair)."""
    from frbmodel.cycles.continuation import _branch_events

    speeds = [1.0e4, 1.1e4, 1.2e4, 1.25e4, 1.2e4, 1.1e4, 1.0e4, 0.9e4]
    mults = [[0.5], [0.6], [0.8], [0.9 + 0.2j, 0.9 - 0.2j], [1.1 + 0.1j, 1.1 - 0.1j], [1.2], [1.3], [1.4]]
    events = _branch_events([_bp(s, m) for s, m in zip(speeds, mults)], 0)
    assert [e["type"] for e in events] == ["fold"] and events[0]["speed_rpm"] == 1.25e4


def test_no_fold_from_speed_jitter_on_a_vertical_branch():
    """Where the orbit grows at one speed (a vertical branch, as at the 2.0 krpm Hopf point of the 36 um system)
    the computed speeds jitter by ~4e-6 relative and the radial multiplier sits at 1 within the monodromy's
    accuracy: neither makes a fold or any other bifurcation (measured jitter and multipliers of that branch)."""
    from frbmodel.cycles.continuation import _branch_events

    jitter = [0.0, 3.7e-6, 1.5e-6, 3.1e-6, -0.6e-6, -3.0e-6, -0.7e-6, -4.3e-6, -1.1e-6, -0.8e-6]
    radial = [0.999, 1.0014, 0.9975, 0.9985, 1.0037, 0.9981, 1.0011, 0.9985, 0.9979, 1.0016]
    pts = [_bp(2011.76 * (1 + j), [r, 0.786 * np.exp(1j), 0.786 * np.exp(-1j)]) for j, r in zip(jitter, radial)]
    assert _branch_events(pts, 0) == []


def test_branch_stops_where_it_reaches_the_equilibrium():
    """A branch whose orbit shrinks to the equilibrium has reached a Hopf point: it stops there (continuing would
    pass through it and retrace the same orbits half a period shifted) and the end is marked as a Hopf point."""
    from frbmodel.cycles.branch import _collapsed

    radii = [15e-6, 8e-6, 2e-6, 0.5e-6, 0.2e-6, 0.4e-6]
    stops = [k for k in range(1, len(radii) + 1) if _collapsed(
        [BranchPoint(1e4, 1e-3, np.ones(2), True, r, np.zeros(4)) for r in radii[:k]])]
    assert stops[0] == 5  # 0.2 um < 2 % of 15 um and shrinking


def test_diagram_writes_readable_files(tc, tmp_path):
    import xarray as xr

    pts = [_bp(1e4 + 1e3 * i, [0.5 + 0.2 * i]) for i in range(4)]
    bd = BifurcationDiagram(pts, [{"speed_rpm": 1.25e4, "type": "fold", "frequency_hz": 1e3, "turbine_radius_um": 1.0,
                                   "between": [2, 3]}], {"branches": [4]})
    from types import SimpleNamespace

    sp = SimpleNamespace(speeds_rpm=np.linspace(1e4, 1.3e4, 5), freqs_hz=np.linspace(0, 2e3, 9), db_range=25.0,
                         forward=np.ones((9, 5)) * 1e-6, backward=np.zeros((9, 5)))  # a run's spectrogram behind
    cd = frb.campbell(tc, "J", np.linspace(1e4, 1.3e4, 7))
    paths = bd.save(tmp_path, spectrogram=sp, campbell=cd)
    assert all(p.exists() for p in paths) and (tmp_path / "bifurcation.html").exists()
    with xr.open_dataset(tmp_path / "branch.nc") as ds:
        assert ds["speed"].attrs["units"] == "rpm" and ds["turbine_radius"].attrs["units"] == "m"
        np.testing.assert_allclose(ds["speed"].values, [1e4, 1.1e4, 1.2e4, 1.3e4])


def test_frequency_panel_shows_the_unstable_campbell_modes_and_whirl_lines(tc):
    """The frequency panel draws each Campbell mode where it is unstable (its frequency there, nothing where it is
    stable) and each film's whirl frequency past the film's onset: the drawn data equal the Campbell result's."""
    pts = [_bp(1e4 + 2e4 * i, [0.5]) for i in range(4)]
    bd = BifurcationDiagram(pts, [], {"branches": [4]})
    cd = frb.campbell(tc, "J", np.linspace(1e4, 7e4, 13))
    fig = bd.plot(campbell=cd)
    lines = {ln.get_label(): ln for ln in fig.axes[1].get_lines() if not ln.get_label().startswith("_")}
    modes = [ln for ln in fig.axes[1].get_lines() if ln.get_label().startswith("unstable ")]
    fmax = 1.3 * 1e3  # 1.3 x the branch frequency: modes entirely above are left out
    shown = [j for j in range(cd.n_modes) if cd.unstable[:, j].any() and
             np.nanmin(np.where(cd.unstable[:, j], cd.frequencies_hz[:, j], np.nan)) < fmax]
    assert len(modes) == len(shown) > 0
    for ln in modes:
        y = np.asarray(ln.get_ydata(), float)
        j = int(np.nanargmin([np.nansum(np.abs(np.where(cd.unstable[:, k], cd.frequencies_hz[:, k], np.nan) - y))
                              if np.array_equal(np.isfinite(y), cd.unstable[:, k]) else np.inf
                              for k in range(cd.n_modes)]))
        np.testing.assert_array_equal(y[cd.unstable[:, j]], cd.frequencies_hz[cd.unstable[:, j], j])
    for k, name in enumerate(frb.linear.whirl.FILM_NAMES):
        past = cd.whirl_margin[:, k] > 0
        if past.any():
            # (a curve on another one is labelled "whirl <film> (on <other film>)", frbmodel.plots.figures.whirl_lines)
            label = next(lab for lab in lines if lab == f"whirl {name}" or lab.startswith(f"whirl {name} (on "))
            y = np.asarray(lines[label].get_ydata(), float)
            np.testing.assert_array_equal(y[past], cd.whirl_hz[past, k])
            assert np.isnan(y[~past]).all()


def test_hopf_record_criticality_mode_and_film(tc):
    """A Hopf point is supercritical when its branch grows towards the speeds where the crossing mode is unstable
    (above it: hopf_points lists crossings to instability), subcritical when it grows backwards. Its mode is the
    Campbell mode at that speed and frequency (the 2.0 krpm one: forward conical, README table), its film the one
    moving most relative to its clearance in the eigenvector, with the four shares summing to 100 %. A branch that
    stays at the Hopf speed within the jitter of a vertical branch (FOLD_MIN_REL) leaves the criticality open; the
    first excursion beyond it decides."""
    from frbmodel.cycles.continuation import hopf_record

    hp = hopf_points(tc, (1.5e3, 2.5e3), n_grid=4)[0]
    up, down = ([_bp(hp.speed_rpm + d * k, [0.5]) for k in (1, 2, 3)] for d in (+1.0, -1.0))
    assert hopf_record(tc, hp, up)["criticality"] == "supercritical"
    assert hopf_record(tc, hp, down)["criticality"] == "subcritical"
    vertical = [_bp(hp.speed_rpm + d, [0.5]) for d in (4e-3, -3e-3, 5e-3)]  # speed jitter of a vertical branch
    assert hopf_record(tc, hp, vertical)["criticality"] == ""
    # small first steps within the jitter, then the branch bends back (the 2.0 and 58.5 krpm branches of 36 um)
    bends = [_bp(hp.speed_rpm + d, [0.5]) for d in (4e-3, -3e-3, 5e-3, -0.2, -1.0)]
    assert hopf_record(tc, hp, bends)["criticality"] == "subcritical"
    rec = hopf_record(tc, hp)
    assert rec["criticality"] == "" and rec["mode"] == "forward conical"
    assert rec["film"].split(" (")[0] in frb.linear.whirl.FILM_NAMES


@pytest.mark.slow
@pytest.mark.parametrize("speeds, points", [((13.5e3, 15e3), 6), ((95e3, 97.5e3), 8)])
def test_branch_from_a_hopf_point_grows_as_a_square_root(tc, speeds, points):
    """Acceptance (issue #14): near a Hopf point the orbit amplitude grows as |Omega - Omega_H|^beta with
    beta = 0.5 +/- 0.05 (the normal form's square root), and the branch's own onset (fitted Omega_H) is the Hopf
    speed (0.5 %). The subcritical 14.1 krpm branch (forward cylindrical mode) and the supercritical 95.9 krpm one
    (forward conical; strongly unstable orbits, largest multiplier ~150); points with radius < 1 um keep the fit in
    the square-root regime (measured beta 0.53 at 95.9 krpm)."""
    bd = continuation(tc, speeds, "hopf", max_points=points)
    s = np.array([p.speed_rpm for p in bd.points])
    r = np.array([p.turbine_radius_m for p in bd.points]) * 1e6
    keep = r < 1.0
    hopf = [b["speed_rpm"] for b in bd.bifurcations if b["type"] == "Hopf"][0]
    sign = np.sign(np.mean(s[keep]) - hopf)
    (a, s0, beta), _ = curve_fit(lambda x, a, s0, beta: a * np.abs(x - s0) ** beta, s[keep], r[keep],
                                 p0=(0.1, hopf, 0.5), bounds=([0, hopf - 50 * sign - 50, 0.1], [10, hopf + 50, 2]))
    assert beta == pytest.approx(0.5, abs=0.05)
    assert s0 == pytest.approx(hopf, rel=0.005)


def test_two_parameter_stability_chart(tmp_path):
    """A Hopf-point study over outer clearance x viscosity (frbmodel.studies.sweep, resumable like the other studies)
    gives the
    chart's grid: each cell is the first Hopf speed of that system, which equals method J's linear onset (0.5 %,
    as for the default system); the CLI's --analysis hopf writes the chart."""
    import pandas as pd

    from frbmodel.studies.sweep import build_case_system, grid, plot_stability_chart, run_study

    cases = grid({"outer_clearance": [36e-6, 46e-6], "viscosity_scale": [0.7, 1.0]}, "hopf", speed_rpm=(1e3, 30e3))
    run_study(cases, tmp_path, scheduler="serial")
    paths = plot_stability_chart(tmp_path, "outer_clearance", "viscosity_scale")
    chart = pd.read_csv(paths[0], index_col=0)
    assert chart.shape == (2, 2) and paths[1].exists()
    tc, _ = build_case_system({"outer_clearance": 46e-6, "viscosity_scale": 0.7})
    first = float(chart.loc[0.7].iloc[-1])  # 46 um, viscosity x0.7
    hp = hopf_points(tc, (1e3, 30e3))[0]
    assert first == hp.speed_rpm
    assert first == pytest.approx(_method_j_crossing(tc, first, hp.frequency_hz)[0], rel=0.005)


def test_bifurcation_study_writes_each_cases_diagram_and_its_points(tmp_path):
    """A ``bifurcation`` study (frbmodel.studies.sweep): per case the limit-cycle branches from its Hopf points, the
    diagram
    in ``cases/<id>/`` (loadable) and one stability-map row per bifurcation point, equal to the saved table; resumable
    (a second run computes nothing). Two outer clearances, 29-32 krpm, 2 points per branch: the restabilizing Hopf
    point there is the case's Hopf row (the same as hopf_points, checked against method J above)."""
    import pandas as pd

    from frbmodel.core.errors import ParameterError
    from frbmodel.studies.sweep import (
        build_case_system,
        grid,
        plot_stability_chart,
        plot_stability_map,
        run_study,
        stability_map,
    )

    with pytest.raises(ParameterError, match="bifurcation max_points = 1 is invalid"):
        grid({"outer_clearance": [36e-6]}, "bifurcation", speed_rpm=(29e3, 32e3), max_points=1)
    with pytest.raises(ParameterError, match="bifurcation start = 50000 rpm is outside speed_rpm 29000:32000 rpm"):
        grid({"outer_clearance": [36e-6]}, "bifurcation", speed_rpm=(29e3, 32e3), start=[30e3, 50e3])
    cases = grid({"outer_clearance": [36e-6]}, "bifurcation", speed_rpm=(29e3, 32e3), max_points=2)
    run_study(cases, tmp_path, scheduler="serial")
    folder = tmp_path / "cases" / cases[0].case_id
    bd = BifurcationDiagram.load(folder / "branch.nc")
    table = pd.read_csv(folder / "bifurcations.csv")
    sm = stability_map(tmp_path)
    assert len(bd.points) >= 2 and (folder / "bifurcation.png").exists()
    assert sorted(sm["onset [rpm]"]) == pytest.approx(sorted(table["speed_rpm"]), rel=1e-12)
    hp = hopf_points(build_case_system({"outer_clearance": 36e-6})[0], (29e3, 32e3), restabilizing=True)[0]
    hopf_row = sm[sm["item"].str.startswith("Hopf (restabilizing)")]
    assert hopf_row["onset [rpm]"].tolist() == pytest.approx([hp.speed_rpm], rel=1e-9)
    # its map draws the points (markers), and a two-parameter chart of linear onsets has none to draw (no crash)
    assert plot_stability_map(tmp_path)[1].exists()
    assert plot_stability_chart(tmp_path, "outer_clearance", "viscosity_scale") == []
    mtime = (tmp_path / "cases" / f"{cases[0].case_id}.json").stat().st_mtime
    run_study(cases, tmp_path, scheduler="serial")  # resumed: the finished case is kept
    assert (tmp_path / "cases" / f"{cases[0].case_id}.json").stat().st_mtime == mtime


@pytest.mark.slow
def test_multiple_shooting_follows_a_strongly_unstable_branch(tc):
    """The branch of the 58.5 krpm Hopf point (36 um) runs through orbits whose largest multiplier is ~335 (a flow
    over the whole period amplifies errors by |mu|, a segment by ~|mu|^(1/4)); with 4 segments the branch is followed.
    (With the chord corrector single shooting stopped after its first point there; with the Broyden corrector it
    follows the branch too, to 5e-7 of the orbit per LSODA against 2e-8 with 4 segments.) Each point is checked by
    another integrator: scipy's LSODA from the point's state over its period returns to it within 1e-4 of the orbit's
    size (errors grow by |mu| = 335 over the period from LSODA's 1e-10 and the segments' 3e-9 tolerances), and the
    orbits grow away from the equilibrium."""
    from scipy.integrate import solve_ivp

    from frbmodel.nonlinear.runup import SpeedProfile, build_problem

    bd = continuation(tc, (57e3, 62e3), "hopf", max_points=8, segments=4)
    assert len(bd.points) == 8
    r = [p.turbine_radius_m for p in bd.points]
    assert all(b > a for a, b in zip(r, r[1:]))
    j = 4 * tc.bearings[0].node
    for p in bd.points[::3]:
        prob = build_problem(tc, SpeedProfile.constant(p.speed_rpm, 1.0), tc.film_model)
        end = solve_ivp(lambda t, y, prob=prob: prob.rhs(t, y, np.empty(y.size)).copy(), (0.0, p.period),
                        np.append(p.state, 0.0), method="LSODA", rtol=1e-10, atol=1e-16).y[:-1, -1]
        assert np.hypot(*(end[j:j + 2] - p.state[j:j + 2])) < 1e-4 * p.turbine_radius_m


@pytest.mark.slow
def test_vertical_branch_of_the_first_hopf_point_grows(tc):
    """The branch born at the 2.0 krpm Hopf point (36 um, forward conical mode) is vertical: its amplitude is neutral
    to first order, the speed fixed only by higher-order terms (condition of the corrector's system ~1e4). With the
    plain chord corrector it stalled at tiny steps (0.17 um after 15 points, 99 s); with Broyden's update 12 points
    must take the turbine-wheel orbit beyond 1 um, and the speed must have moved by less than 0.1 % until then (the
    branch is vertical: measured 1.07 um at 0.014 %; 7.4 um after 12 points). The last orbit is checked by another
    integrator: LSODA from its state over its period returns within 1e-3 of the orbit's size (LSODA's 1e-10 and the
    flows' 3e-9 tolerances over a 50 ms period, multipliers ~1)."""
    from scipy.integrate import solve_ivp

    from frbmodel.nonlinear.runup import SpeedProfile, build_problem

    bd = continuation(tc, (1000.0, 6000.0), "hopf", max_points=12)
    hopf = [b["speed_rpm"] for b in bd.bifurcations if b["type"] == "Hopf"][0]
    p = bd.points[-1]
    assert len(bd.points) == 12 and p.turbine_radius_m > 1e-6
    first_um = next(i for i, q in enumerate(bd.points) if q.turbine_radius_m > 1e-6)
    assert all(q.speed_rpm == pytest.approx(hopf, rel=1e-3) for q in bd.points[:first_um + 1])
    prob = build_problem(tc, SpeedProfile.constant(p.speed_rpm, 1.0), tc.film_model)
    end = solve_ivp(lambda t, y: prob.rhs(t, y, np.empty(y.size)).copy(), (0.0, p.period), np.append(p.state, 0.0),
                    method="LSODA", rtol=1e-10, atol=1e-16).y[:-1, -1]
    j = 4 * tc.rotor.discs[0].node
    assert np.hypot(*(end[j:j + 2] - p.state[j:j + 2])) < 1e-3 * p.turbine_radius_m


@pytest.mark.parametrize("segments", [1, 3])
def test_shooting_jacobian_equals_differences_of_the_residual(segments):
    """The continuation's Jacobian — segment monodromies, the coupling to the next start (with the wrap from the
    last segment to the first), the period and speed columns, the phase row — equals central differences of its
    residual, for single and multiple shooting. A linear flow exp(A(Omega) t) z with a speed-dependent rotation
    stands in for the FRB flow (its monodromy by forward differences is exact to round-off); the differences'
    truncation and round-off are ~1e-8 of the entries at the 1e-5 step used."""
    from scipy.linalg import expm

    from frbmodel.cycles.branch import ContinuationProblem, _jacobian

    def a_of(speed):
        w = 2.0 + 1e-4 * speed
        return np.array([[-0.3, -w, 0.0], [w, -0.3, 0.0], [0.0, 0.0, -1.0]])

    class Flow:
        method = "linear"

        def __init__(self, speed):
            self.a = a_of(speed)

        def __call__(self, z, t):
            return expm(self.a * t) @ z

        def rhs(self, z):
            return self.a @ z

    br = object.__new__(ContinuationProblem)
    br.scale_vec, br.workers = np.array([1e-6, 2e-6, 5.0]), 1
    br.flow = lambda speed, like=None: Flow(speed)
    br.set_segments(segments)
    n_all, t_ref, w_ref = 3 * segments, 0.1, 100.0
    rng = np.random.default_rng(1)
    x = np.concatenate([rng.normal(size=n_all), [13.0, 50.0]])  # T = 1.3, speed 5000
    f_ref = rng.normal(size=n_all)

    def residual(x):
        z, T, speed = x[:n_all] * br.scale(), x[n_all] * t_ref, x[n_all + 1] * w_ref
        return np.append(br.residual(z, br.ends(z, T, speed)[0]), f_ref @ x[:n_all])

    z, T, speed = x[:n_all] * br.scale(), x[n_all] * t_ref, x[n_all + 1] * w_ref
    res, jac, mono, _ = _jacobian(br, z, T, speed, br.scale(), t_ref, w_ref, f_ref)
    np.testing.assert_allclose(res[:-1], residual(x)[:-1], rtol=1e-12)
    fd = np.column_stack([(residual(x + 1e-5 * e) - residual(x - 1e-5 * e)) / 2e-5 for e in np.eye(x.size)])
    np.testing.assert_allclose(jac, fd, atol=1e-7 * np.abs(fd).max())
    np.testing.assert_allclose(mono, expm(a_of(speed) * T), atol=1e-9)  # the segments' product: the whole period


@pytest.mark.parametrize("opt, value, shown", [("--segments", "0", "--segments = 0 is invalid: valid range >= 1"),
                                               ("--max-points", "1", "--max-points = 1 is invalid: valid range >= 2"),
                                               ("--start", "25000,fast", "--start = '25000,fast' is invalid"),
                                               ("--start", "hopf,300000",
                                                "--start = 300000 rpm is outside --speeds 1000:250000 rpm")])
def test_cli_bifurcation_refuses_bad_counts_before_computing(opt, value, shown, tmp_path, capsys):
    """Bad counts exit 2 with one line naming option, value and valid range — before the Hopf points are searched
    (nothing printed on stdout)."""
    from frbmodel.cli import main

    assert main(["bifurcation", opt, value, "--out", str(tmp_path / "b")]) == 2
    out = capsys.readouterr()
    assert shown in out.err and "Traceback" not in out.err and "Hopf points" not in out.out


#: degenerate Hopf normal form r' = r (mu - r^4), theta' = OMEGA, mu = K (speed - S_H): its cycles r^4 = mu form a
#: branch that leaves the Hopf point vertically (d speed / dr = 4 r^3 / K), with radial multiplier exp(-4 mu T)
K_DH, S_H, OMEGA_DH = 1e-3, 1000.0, 2 * math.pi


class _DegenerateHopfFlow:
    """The normal form's flow in closed form (s = r^-4 obeys s' = 4 - 4 mu s)."""

    method = "closed form"

    def __init__(self, speed):
        self.mu = K_DH * (speed - S_H)

    def __call__(self, z, t):
        r0, th = math.hypot(z[0], z[1]), math.atan2(z[1], z[0]) + OMEGA_DH * t
        mu, s0 = self.mu, math.hypot(z[0], z[1]) ** -4
        s = s0 + 4 * t if mu == 0 else 1 / mu + (s0 - 1 / mu) * math.exp(-4 * mu * t)
        r = s ** -0.25 if r0 > 0 else 0.0
        return np.array([r * math.cos(th), r * math.sin(th)])

    def rhs(self, z):
        g = self.mu - (z @ z) ** 2
        return np.array([g * z[0] - OMEGA_DH * z[1], g * z[1] + OMEGA_DH * z[0]])


def test_corrector_converges_on_a_vertical_branch_despite_an_inexact_monodromy(monkeypatch):
    """On a nearly vertical branch (amplitude neutral to first order, as at the 2.0 krpm Hopf point of the 36 um
    system) the continuation's linear system is ill-conditioned, and the difference monodromy's error (~3e-4 per
    column for the FRB flows, SHOOT_RTOL / FD_STEP) decides whether the corrector converges. Here the monodromy is
    deliberately wrong by 3e-4 (the same entries every time, like the FRB flows' systematic difference error); the
    corrector must still land on the closed-form branch r^4 = mu, period 2 pi / OMEGA, within the accuracy its
    residual tolerance (1e-6, scaled) allows through the problem's condition (radial multiplier <= 1 - 4e-4 from r =
    0.1 on: a residual of 1e-6 moves r by at most ~1e-6 / 4e-4 = 2.5e-3 relative; 1e-2 is asserted). Both starts of
    the iteration: a Jacobian computed at the predicted point, and the previous point's with another phase row (as
    the continuation passes it from point to point; the corrector puts the current phase normal in)."""
    import frbmodel.cycles.shooting
    from frbmodel.cycles import branch as cont

    exact = frbmodel.cycles.shooting.monodromy
    monkeypatch.setattr(frbmodel.cycles.shooting, "monodromy",
                        lambda *a, **k: exact(*a, **k) + 3e-4 * np.array([[1.0, -0.5], [0.7, 1.0]]))
    br = object.__new__(cont.ContinuationProblem)
    br.scale_vec, br.workers = np.array([1.0, 1.0]), 1
    br.flow = lambda speed, like=None: _DegenerateHopfFlow(speed)
    br.set_segments(1)
    t_ref, w_ref = 0.01, 10.0
    r_a = 0.1  # mu = 1e-4: radial multiplier exp(-4e-4)
    x_prev = np.array([r_a, 0.0, 1.0 / t_ref, (S_H + r_a ** 4 / K_DH) / w_ref])
    tangent = np.array([1.0, 0.0, 0.0, 4 * r_a ** 3 / K_DH / w_ref])
    tangent /= np.linalg.norm(tangent)
    ds = 0.2  # to r = 0.29 (the plain chord iteration with this monodromy diverges on this step)
    f_ref = cont._phase_normal(br, x_prev[:2], x_prev[3] * w_ref)
    z_prev = x_prev[:2] * br.scale()
    jac_prev = cont._jacobian(br, z_prev, 1.0, x_prev[3] * w_ref, br.scale(), t_ref, w_ref, np.array([0.6, 0.8]))[1]
    for jac, step in ((None, ds), (jac_prev, 0.05)):  # from r = 0.1 to 0.29 and to 0.15
        x, _ = cont._correct(br, x_prev + step * tangent, tangent, x_prev, step, 2, t_ref, w_ref, f_ref, x_prev[:2],
                             jac)
        r, period, speed = math.hypot(x[0], x[1]), x[2] * t_ref, x[3] * w_ref
        assert r ** 4 == pytest.approx(K_DH * (speed - S_H), rel=4e-2)  # r to 1e-2
        assert period == pytest.approx(2 * math.pi / OMEGA_DH, rel=1e-4)
        assert float(tangent @ (x - x_prev)) == pytest.approx(step, rel=1e-9)  # on the arclength plane (linear row)
        assert float(f_ref @ (x[:2] - x_prev[:2])) == pytest.approx(0.0, abs=1e-9)  # on the current phase plane


def test_inaccurate_monodromy_is_replaced_by_central_differences():
    """The trivial multiplier (1 exactly on a periodic orbit) checks a point's monodromy: one whose multiplier
    closest to 1 is off by more than MULTIPLIER_TOL is replaced by central differences of the flow; an accurate one
    is kept. On the closed-form degenerate Hopf cycle r = 0.3 (mu = r^4) the multipliers are 1 and exp(-4 mu T)
    (T = 1); central differences at the 1e-4 step are exact to ~1e-8 (truncation h^2 times the flow's curvature)."""
    from frbmodel.cycles import branch as cont

    br = object.__new__(cont.ContinuationProblem)
    br.scale_vec, br.workers = np.array([1.0, 1.0]), 1
    br.flow = lambda speed, like=None: _DegenerateHopfFlow(speed)
    br.set_segments(1)
    r, t_ref, w_ref = 0.3, 0.01, 10.0
    x = np.array([r, 0.0, 1.0 / t_ref, (S_H + r ** 4 / K_DH) / w_ref])
    expected = np.sort([1.0, math.exp(-4 * r ** 4)])
    wrong = np.array([[1.0, 0.1], [0.1, math.exp(-4 * r ** 4)]])  # the exact diagonal, coupled: multipliers moved
    assert cont.trivial_error(np.linalg.eigvals(wrong)) > 5e-3
    fixed = cont._checked_monodromy(br, x, 2, t_ref, w_ref, wrong, br.flow(x[3] * w_ref))
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(fixed).real), expected, atol=1e-6)
    good = fixed + 1e-4  # within the tolerance: kept as it is
    assert cont._checked_monodromy(br, x, 2, t_ref, w_ref, good, None) is good
    # three shooting segments: the monodromy is the product M2 M1 M0 of the segments' (in the reverse order the
    # multipliers here would be 0.984 +- 2.5e-5j instead of 1 and 0.968)
    br.set_segments(3)
    starts = np.concatenate([r * np.array([math.cos(a), math.sin(a)]) for a in 2 * math.pi * np.arange(3) / 3])
    x3 = np.concatenate([starts / br.scale(), x[2:]])
    fixed = cont._checked_monodromy(br, x3, 6, t_ref, w_ref, wrong, br.flow(x[3] * w_ref))
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(fixed).real), expected, atol=1e-6)


def test_cli_hopf_only_lists_both_crossing_directions(tmp_path, capsys):
    """`frb bifurcation --hopf-only` says for each Hopf point whether the mode loses or regains stability: at 36 um
    between 10 and 40 krpm the forward cylindrical mode loses it at 14.1 krpm and the forward conical mode regains
    it at 30.8 krpm (both checked against method J above)."""
    from frbmodel.cli import main

    assert main(["bifurcation", "--outer-clearance", "36e-6", "--speeds", "10000:40000", "--hopf-only",
                 "--out", str(tmp_path / "b")]) == 0
    lines = [ln.split() for ln in capsys.readouterr().out.splitlines() if ln.strip().endswith(("loses", "regains"))]
    assert [(round(float(ln[0]) / 1e3, 1), ln[-1]) for ln in lines] == [(14.1, "loses"), (30.8, "regains")]
