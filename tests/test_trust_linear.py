"""No silent wrong answers in the linear analysis and the API (issue #10): neutral vs unstable modes, speed grids
in any order, exact whirl onsets, absent modes, result files that record their inputs, and bad API arguments
refused with the argument, its value and the valid range."""
import json
import math
import warnings

import numpy as np
import pandas as pd
import pytest

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.linear.assembly import linear_system
from frbmodel.linear.campbell import campbell_from_modes
from frbmodel.linear.modal import modes
from frbmodel.physics.bearing import ring_torque
from frbmodel.physics.film import (
    Film,
    film_coefficients,
    film_force,
    film_torques,
    static_eccentricity,
    static_position,
)
from frbmodel.system.parameters import Turbocharger
from frbmodel.system.rotor import ShaftElement

SWEEP = np.linspace(10e3, 250e3, 100)
FILM = Film(radius=5.5e-3, length=6.5e-3, clearance=34e-6, viscosity=4.9e-3)
#: docs/theory/parameters.md#reference-numbers: film whirl onsets [krpm] of the Table 2 system at 36 µm (rounded to 0.1
# krpm)
ONSETS_36_KRPM = [11.1, 68.1, 11.8, 69.2]


# ------------------------------------------------------------------ 1. neutral modes of the undamped methods
@pytest.mark.parametrize("method", ["A", "B", "E"])
def test_undamped_methods_have_neutral_modes_only(method, tmp_path):
    """An undamped gyroscopic system with M, K positive definite has purely imaginary eigenvalues (conservative):
    D = 0 for every mode, whatever the round-off of the solver says about its sign. Method B goes through the
    general (non-Hermitian) eigen-solver, whose |D| ≈ 1e-13 of either sign used to be reported as 381 unstable
    rows with "max. simultaneously unstable modes: 11"."""
    cd = frb.campbell(frb.turbocharger(), method, SWEEP, whirl=False)
    present = np.isfinite(cd.damping)
    assert np.all(cd.stability[present] == "neutral")
    assert cd.n_unstable.max() == 0 and len(cd.unstable_ranges()) == 0
    paths = {p.name: p for p in cd.save(tmp_path, png=False, html=False)}
    modes_csv = pd.read_csv(paths[f"campbell_{method}_modes.csv"])
    assert set(modes_csv["stability"]) == {"neutral"}
    assert len(pd.read_csv(paths[f"campbell_{method}_unstable.csv"])) == 0
    meta = json.loads(paths[f"campbell_{method}.json"].read_text())
    assert meta["max_unstable_modes"] == 0 and meta["max_neutral_modes"] == cd.n_modes


def test_method_b_round_off_is_inside_the_bound_and_the_bound_is_tiny():
    cd = frb.campbell(frb.turbocharger(), "B", SWEEP, whirl=False)
    assert np.nanmax(np.abs(cd.damping)) > 0  # the general solver does leave round-off (else the test is vacuous)
    assert np.all(np.abs(cd.damping) <= cd.damping_tol)
    # the bound itself is round-off sized: far below any damping a film or a damper produces (>= 1e-5 here)
    assert np.nanmax(cd.damping_tol) < 1e-8


@pytest.mark.parametrize("delta, expected", [(1.0, "stable"), (-1.0, "unstable")])
def test_small_physical_damping_is_not_taken_for_round_off(delta, expected):
    """Mass-proportional damping C = δ M added to the undamped method-B system moves every eigenvalue of the
    gyroscopic system to Re λ = −δ m ω / (2 ω m + g) with the sign of δ (first-order perturbation; m, g > 0 for a
    positive-definite K): |D| ~ δ / (2ω) >= 1.5e-6 for the highest mode (52 kHz). The classification must see it;
    a threshold chosen too coarse (e.g. a fixed 1e-3) would call these modes neutral."""
    ls = linear_system(frb.turbocharger(), "B", 100e3)
    md = modes(ls.M, ls.C + delta * ls.M, ls.K)
    assert np.all(np.abs(md.damping) > 1e-6)
    assert set(md.stability) == {expected}


def test_neutral_modes_are_drawn_visibly_with_a_legend_entry():
    """The damping colour map is white at D = 0, on a white background: neutral modes get their own grey."""
    from matplotlib.colors import to_rgba

    from frbmodel.plots.figures import NEUTRAL_COLOR, NEUTRAL_COLOR_PLOTLY

    cd = frb.campbell(frb.turbocharger(), "B", SWEEP[::10], whirl=False)
    fig = cd.plot()
    ax = fig.axes[0]
    grey = np.array(to_rgba(NEUTRAL_COLOR))
    drawn = sum(len(c.get_offsets()) for c in ax.collections
                if len(c.get_offsets()) and np.allclose(c.get_facecolors()[0], grey))
    shown = np.isfinite(cd.frequencies_hz) & (cd.frequencies_hz <= ax.get_ylim()[1])
    assert drawn == shown.sum()  # every neutral mode in the frequency window, in grey
    assert any("neutral" in t.get_text() for t in ax.get_legend().get_texts())
    html = cd.plot_html()
    neutral = [t for t in html.data if "neutral" in (t.name or "")]
    assert len(neutral) == 1 and neutral[0].marker.color == NEUTRAL_COLOR_PLOTLY and neutral[0].showlegend is not False
    assert len(neutral[0].x) == shown.sum()


# ------------------------------------------------------------------ 2. speed grids in any order, exact onsets
def test_descending_grid_gives_the_ascending_result():
    tc = frb.turbocharger()
    grid = np.linspace(10e3, 250e3, 10)
    up = frb.campbell(tc, "J", grid)
    down = frb.campbell(tc, "J", grid[::-1])
    assert down.meta["speed_grid_order"] == "descending"
    np.testing.assert_array_equal(down.speeds_rpm, up.speeds_rpm)
    for name in ("frequencies_hz", "damping", "whirl_hz", "whirl_margin", "ring_speed_ratio", "whirl_onset_rpm"):
        np.testing.assert_array_equal(getattr(down, name), getattr(up, name))
    # docs/theory/parameters.md#reference-numbers onsets, not 250,000 rpm four times
    np.testing.assert_allclose(down.whirl_onset_rpm / 1e3, ONSETS_36_KRPM, atol=0.051)
    ur = down.unstable_ranges()
    assert len(ur) and np.all(ur["from [rpm]"] <= ur["to [rpm]"])


def test_result_built_from_a_descending_grid_is_sorted_consistently():
    """CampbellResult sorts at construction, whoever builds it (here the post-processing of the FMU path, fed the
    mode sets in descending order): every per-speed array moves with its speed."""
    from frbmodel.linear.modal import batch_modes

    tc = frb.turbocharger()
    speeds = np.linspace(250e3, 20e3, 8)
    systems = [linear_system(tc, "J", s) for s in speeds]
    margin = np.column_stack([speeds, -speeds, speeds, -speeds]) - 1e5  # rows tied to their speed
    cd = campbell_from_modes("J", speeds, batch_modes(systems), tc.rotor, systems[0].M, systems[0].ring_dofs,
                             np.column_stack([speeds, speeds]), np.zeros((8, 4)), np.zeros((8, 4)), margin, {})
    assert np.all(np.diff(cd.speeds_rpm) > 0)
    np.testing.assert_array_equal(cd.ring_speed_ratio[:, 0], cd.speeds_rpm)
    np.testing.assert_array_equal(cd.whirl_margin[:, 0], cd.speeds_rpm - 1e5)
    for i, s in enumerate(cd.speeds_rpm):  # the modes at each row are those of that speed's own eigen-solve
        ls = systems[list(speeds).index(s)]
        ref = np.sort(frb.modes(ls.M, ls.C, ls.K).frequencies_hz)
        got = np.sort(cd.frequencies_hz[i][np.isfinite(cd.frequencies_hz[i])])
        np.testing.assert_allclose(got, ref, rtol=1e-9)  # stacked vs single LAPACK call on the same matrices
    # the grid interpolation of an onset (margin 0 at 100 krpm for the films with rising margins)
    on = cd.whirl_onset_on_grid()
    assert on[0] == pytest.approx(1e5, rel=1e-12) and on[2] == pytest.approx(1e5, rel=1e-12)


@pytest.mark.parametrize("n", [2, 5, 100])
def test_reported_onsets_are_exact_whatever_the_grid(n):
    """Interpolating the margin on a 5-speed grid gave 10,280 rpm for the turbine inner film (exact 11,073)."""
    cd = frb.campbell(frb.turbocharger(), "J", np.linspace(10e3, 250e3, n))
    np.testing.assert_allclose(cd.whirl_onset_rpm / 1e3, ONSETS_36_KRPM, atol=0.051)  #
    # docs/theory/parameters.md#reference-numbers, 0.1 krpm
    # and they are where the grid's own margins change sign (an independent consistency check)
    for k, on in enumerate(cd.whirl_onset_rpm):
        m = cd.whirl_margin[:, k]
        assert np.all(m[cd.speeds_rpm < on] <= 0) and np.all(m[cd.speeds_rpm > on] > 0)
    tab = cd.onsets_dataframe()
    assert list(tab["film"]) == ["turbine inner", "turbine outer", "compressor inner", "compressor outer"]
    assert tab["source"].str.contains("film_onset_speeds").all()


def test_onsets_are_nan_without_whirl():
    cd = frb.campbell(frb.turbocharger(), "A", [1e5], whirl=False)
    assert np.all(np.isnan(cd.whirl_onset_rpm)) and "whirl=False" in cd.meta["whirl_onset_source"]


# ------------------------------------------------------------------ 3. absent modes
def test_absent_modes_leave_no_phantom_rows(tmp_path):
    """J at 46 µm: over-damped pairs come and go; their tracks used to hold 0 Hz / NaN damping rows in the tables
    (108 of 2000 rows)."""
    cd = frb.campbell(frb.turbocharger(46e-6), "J", np.linspace(10e3, 250e3, 100), whirl=False)
    absent = ~np.isfinite(cd.eigenvalues)
    assert absent.any()  # the case exists
    for name in ("frequencies_hz", "damping", "damping_tol", "ring_fraction"):
        assert np.all(np.isnan(getattr(cd, name)[absent]))
    assert np.all(cd.precession[absent] == "") and np.all(cd.stability[absent] == "")
    cd.save(tmp_path, png=False, html=False)
    df = pd.read_csv(tmp_path / "campbell_J_modes.csv")
    assert len(df) == (~absent).sum()
    assert (df["frequency [Hz]"] > 0).all() and df["damping [-]"].notna().all()


# ------------------------------------------------------------------ 4. result files record their inputs
def test_campbell_json_records_system_method_options_and_grid(tmp_path):
    tc = frb.turbocharger(42e-6, film_model="short_corrected")
    speeds = [150e3, 30e3, 90e3]
    cd = frb.campbell(tc, "B", speeds, kx=3e6)
    paths = cd.save(tmp_path, png=False, html=False)
    meta = json.loads(next(p for p in paths if p.suffix == ".json").read_text())
    assert Turbocharger.from_dict(meta["system"]) == tc  # the full system, round-tripped
    assert meta["method"] == "B" and meta["method_options"] == {"kx": 3e6, "ky": 2e6}
    assert meta["film_model"] == "short_corrected"
    assert meta["speeds_rpm"] == sorted(speeds) and meta["speed_grid_order"] == "unsorted"
    assert meta["stability_rule"].startswith("|D| <= damping round-off bound")
    np.testing.assert_allclose(meta["whirl_onset_rpm"], cd.whirl_onset_rpm)


def test_campbell_from_fmu_records_ssp_parameter_set_and_system(built, tmp_path):
    from frbmodel.cosim.linearize import campbell_from_fmu

    ssp = built / "turbocharger.ssp"
    cd = campbell_from_fmu(ssp, [150e3, 50e3], "J", "co46")
    assert cd.speeds_rpm.tolist() == [50e3, 150e3]
    meta = json.loads(next(p for p in cd.save(tmp_path, png=False, html=False) if p.suffix == ".json").read_text())
    assert meta["parameter_set"] == "co46" and meta["ssp"] == str(ssp.resolve())
    system = Turbocharger.from_dict(meta["system"])
    assert [b.outer.clearance for b in system.bearings] == [46e-6, 46e-6]
    # exact onsets of the 46 µm system (docs/theory/parameters.md#reference-numbers table: 10.8, 49.4, 11.4, 50.6 krpm)
    np.testing.assert_allclose(cd.whirl_onset_rpm / 1e3, [10.8, 49.4, 11.4, 50.6], atol=0.051)


# ------------------------------------------------------------------ 5. bad API arguments
TC = frb.turbocharger()
BAD_CALLS = [
    (lambda: frb.turbocharger(outer_clearance="36e-6"),
     "outer_clearance = '36e-6' is a str; expected a finite real number > 0 m"),
    (lambda: frb.turbocharger(inner_clearance=-1e-6), "inner_clearance = -1e-06 m is invalid: valid range is"),
    (lambda: film_force(FILM, [math.nan, 0.0], [0.0, 0.0], 1e3), r"e = \[nan, 0.0\] m is invalid"),
    (lambda: film_force(FILM, [0.0, 0.0], [0.0, math.inf], 1e3), r"e_dot = \[0.0, inf\] m/s is invalid"),
    (lambda: film_force(FILM, [0.0, 0.0], [0.0, 0.0], math.nan), "omega_sum = nan rad/s is invalid"),
    (lambda: film_force(FILM, [0.0, 0.0, 0.0], [0.0, 0.0], 1e3), r"e = \[0.0, 0.0, 0.0\] has shape \(3,\)"),
    (lambda: film_force(FILM, ["1e-6", 0.0], [0.0, 0.0], 1e3), "expected real numbers"),
    (lambda: film_force(FILM.to_dict(), [0.0, 0.0], [0.0, 0.0], 1e3), "film = .* is a dict; expected a Film"),
    (lambda: film_coefficients(FILM, [math.nan, 0.0], 1e3), r"e = \[nan, 0.0\] m is invalid"),
    (lambda: film_coefficients(FILM, [1e-6, 0.0], "3000"), "omega_sum = '3000' is a str"),
    (lambda: film_torques(FILM, [0.0, 0.0], [0.0, math.inf], 1e3, 0.0), r"force = \[0.0, inf\] N is invalid"),
    (lambda: static_position(FILM, (0.0, math.nan), 3e3), r"force = \(0.0, nan\) N is invalid"),
    (lambda: static_position(FILM, (0.0, 5.0), 0.0), "omega_sum = 0.0 rad/s is invalid: valid range"),
    (lambda: static_eccentricity(FILM, "5", 3e3), "load = '5' is a str"),
    (lambda: frb.equilibrium(TC, "J", "150000"), "speed_rpm = '150000' is a str"),
    (lambda: frb.equilibrium(36e-6, "J", 1e5), "system = 3.6e-05 is a float; expected a Turbocharger"),
    (lambda: frb.campbell(TC, "J", [1e5, math.nan]), r"speeds_rpm = \[100000.0, nan\] rpm is invalid"),
    (lambda: frb.campbell(TC, "A", [1e5], k="1e6"), "method A k = '1e6' is a str"),
    (lambda: frb.linear_system(TC, "J", math.inf), "speed_rpm = inf rpm is invalid"),
    (lambda: frb.modes(np.eye(2), np.zeros((2, 2)), [[1.0, math.nan], [0.0, 1.0]]), "K = .* is invalid"),
    (lambda: frb.modes(np.eye(2), np.zeros((3, 3)), np.eye(2)), "expected three square matrices"),
    (lambda: frb.ring_speed_ratio(TC.bearings[0], "0.1"), "eps_inner = '0.1' is a str"),
    (lambda: frb.ring_speed_ratio(TC.bearings[0], 1.0), "eps_inner = 1.0 is invalid: valid range 0 <= eps < 1"),
    (lambda: ring_torque(TC.bearings[0], [math.nan, 0], [0, 0], [0, 0], [0, 0], 1e3, 2e2), r"r_inner = \[nan, 0\]"),
    (lambda: frb.film_onset_speeds(TC, "A"), "method = 'A' has no film equilibrium"),
    (lambda: frb.film_onset_speeds(TC, speed_range_rpm=(0.0, 1e5)), r"speed_range_rpm\[0\] = 0.0 rpm is invalid"),
    (lambda: frb.film_onset_speeds(TC, speed_range_rpm=(2e5, 1e5)), r"speed_range_rpm\[1\] = 100000.0 rpm"),
    (lambda: Film(radius="5.5e-3", length=6.5e-3, clearance=34e-6, viscosity=4.9e-3),
     "film radius = '5.5e-3' is a str"),
    (lambda: ShaftElement("0.033", 0.011), "shaft element length = '0.033' is a str"),
]


@pytest.mark.parametrize("call, message", BAD_CALLS, ids=[m.split(" ")[0] + f"-{i}" for i, (_, m) in
                                                          enumerate(BAD_CALLS)])
def test_bad_api_arguments_are_refused_naming_the_argument_and_value(call, message):
    with pytest.raises(ParameterError, match=message) as exc:
        call()
    assert "touches its wall" not in str(exc.value)  # a non-finite input is not a wall contact


def test_wall_contact_is_still_a_contact_error():
    with pytest.raises(frb.FilmContactError, match="eps = 1.5"):
        film_force(FILM, [1.5 * FILM.clearance, 0.0], [0.0, 0.0], 1e3)


# ------------------------------------------------------------------ 6. one keyword name
@pytest.mark.parametrize("func, args", [
    (film_force, (FILM, [1e-5, 0.0], [0.0, 0.0], 1e3)),
    (film_coefficients, (FILM, [1e-5, 0.0], 1e3)),
    (static_position, (FILM, (0.0, 5.0), 3e3)),
    (static_eccentricity, (FILM, 5.0, 3e3)),
    (frb.ring_speed_ratio, (TC.bearings[0], 0.3, 0.2, "full")),
])
def test_old_model_keyword_warns_and_gives_the_film_model_result(func, args):
    def first(result):  # the force, matrix, position or ratio (the first element of a tuple result)
        return np.asarray(result[0] if isinstance(result, tuple) else result)

    new = func(*args, film_model="short_corrected")
    with pytest.warns(DeprecationWarning, match="use film_model="):
        old = func(*args, model="short_corrected")
    np.testing.assert_array_equal(first(old), first(new))
    assert not np.array_equal(first(func(*args)), first(new))  # the keyword did act
    with pytest.raises(ParameterError, match="both model="):
        func(*args, model="short", film_model="short")


# ------------------------------------------------------------------ 8. progress protocol
def test_campbell_progress_is_a_bool_and_silent_by_default(capsys):
    frb.campbell(TC, "J", [5e4, 1e5], whirl=False)
    assert capsys.readouterr().err == ""
    frb.campbell(TC, "J", [5e4, 1e5], whirl=False, progress=True)
    assert "campbell J" in capsys.readouterr().err
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        frb.campbell(TC, "J", [5e4], whirl=False, progress=lambda i, n: None)
    assert any(issubclass(x.category, DeprecationWarning) for x in w)
