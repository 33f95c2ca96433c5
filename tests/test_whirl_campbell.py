"""Film whirl (Lund vs Routh–Hurwitz vs eigenvalues), onset speeds, Campbell result object and exports."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import eig
from scipy.optimize import linear_sum_assignment

import frbmodel as frb
from frbmodel.linear.assembly import linear_system
from frbmodel.linear.whirl import film_whirl_ratio, lund_threshold, routh_hurwitz_stable
from frbmodel.physics.film import rt_coefficients

# docs/theory/whirl.md#film-whirl table: ε -> (γ, K̄_eq/γ²)
TABLE8 = [(0.01, 0.50003, 7.638), (0.1, 0.50294, 7.515), (0.3, 0.51942, 6.790), (0.5, 0.51464, 6.460),
          (0.6, 0.47396, 7.295), (0.7, 0.34457, 13.16), (0.75, 0.12668, 94.95)]


@pytest.mark.parametrize("eps,gamma,thr", TABLE8)
def test_whirl_ratio_table(eps, gamma, thr):
    g, t = film_whirl_ratio(eps)
    assert g == pytest.approx(gamma, abs=1e-5)  # table: 5 decimals
    assert t == pytest.approx(thr, rel=2e-3)  # table: 3-4 significant digits


def test_light_load_limits_and_stable_branch():
    g, t = film_whirl_ratio(0.0)
    assert g == pytest.approx(0.5, abs=1e-6) and t == pytest.approx(24 / math.pi, rel=1e-5)
    assert film_whirl_ratio(0.8)[1] == math.inf  # γ² <= 0 above ε = 0.75603: stable for any mass


@pytest.mark.parametrize("eps", [0.05, 0.3, 0.6])
def test_lund_threshold_equals_routh_hurwitz_and_eigenvalues(eps):
    # dimensional film: μ ω_s R L³/c³ = 1 N/m-scale units with W̄ from the static law
    K, C = rt_coefficients(eps)  # (K in ω_s units, C in 1/ω_s units with ω_s = 1)
    k_eq, g2 = lund_threshold(K, C)
    m_thr = k_eq / g2  # threshold mass (ω_s = 1)
    assert routh_hurwitz_stable(0.99 * m_thr, K, C)
    assert not routh_hurwitz_stable(1.01 * m_thr, K, C)
    # at the threshold the 2-DoF eigenproblem has Re λ = 0 and Im λ = γ ω_s
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K / m_thr, -C / m_thr]])
    lam = np.linalg.eigvals(A)
    crit = lam[np.argmin(np.abs(lam.real))]
    assert abs(crit.real) < 1e-8 * abs(crit)
    assert abs(crit.imag) == pytest.approx(math.sqrt(g2), rel=1e-8)


def test_onset_speeds_physics_11():
    ref = {36e-6: [11.1, 68.1, 11.8, 69.2], 40e-6: [11.0, 59.2, 11.7, 60.4], 42e-6: [10.9, 55.5, 11.6, 56.8],
           46e-6: [10.8, 49.4, 11.4, 50.6]}
    for co, krpm in ref.items():
        on = frb.film_onset_speeds(frb.turbocharger(co)) / 1e3
        np.testing.assert_allclose(on, krpm, atol=0.051)  # table rounded to 0.1 krpm


def test_whirl_frequencies_physics_11():
    # f_wI, f_wO of the J equilibrium: 36 µm turbine at 30k and 100k rpm (docs/theory/parameters.md#reference-numbers
    # table)
    cd = frb.campbell(frb.turbocharger(36e-6), "J", [30e3, 100e3, 200e3])
    np.testing.assert_allclose(cd.whirl_hz[:, 0], [306.0, 1002.0, 1999.8], atol=0.06)
    np.testing.assert_allclose(cd.whirl_hz[:, 1], [49.5, 166.5, 332.1], atol=0.06)
    np.testing.assert_allclose(cd.whirl_hz[1, 2:], [999.2, 165.9], atol=0.06)


SWEEP = np.linspace(10e3, 250e3, 40)
CHECKED = (0, 20, 39)  # sweep indices checked against an independent eigen-solution


@pytest.fixture(scope="module")
def cd_j():
    return frb.campbell(frb.turbocharger(36e-6), "J", SWEEP)


@pytest.fixture(scope="module")
def independent_eigenvalues():
    """Eigenvalues λ (Im λ > 0) of the method-J matrices at the checked speeds, from the generalized problem
    [[I, 0], [0, M]] ṡ = [[0, I], [−K, −C]] s (docs/theory/modal.md#modal-analysis) by scipy — no inverse of M, no mode
    selection or
    tracking of the library."""
    tc = frb.turbocharger(36e-6)
    out = {}
    for i in CHECKED:
        ls = linear_system(tc, "J", SWEEP[i])
        n = ls.M.shape[0]
        Z, I = np.zeros((n, n)), np.eye(n)
        lam = eig(np.block([[Z, I], [-ls.K, -ls.C]]), np.block([[I, Z], [Z, ls.M]]), right=False)
        out[i] = lam[lam.imag > 1e-7 * np.abs(lam)]  # under-damped modes, one of each conjugate pair
    return out


def test_campbell_frequency_and_damping_follow_the_eigenvalue_definitions(cd_j, independent_eigenvalues):
    """At the checked speeds the tracked columns must hold exactly the system's modes, each with
    f = Im λ / 2π and D = −Re λ / |λ| (docs/theory/modal.md#modal-analysis) of an independently solved eigenvalue."""
    n = SWEEP.size
    for a in (cd_j.frequencies_hz, cd_j.damping, cd_j.precession, cd_j.mode_kind, cd_j.eigenvalues):
        assert a.shape[0] == n and a.shape[1] == cd_j.n_modes
    assert cd_j.ring_speed_ratio.shape == (n, 2) and cd_j.whirl_hz.shape == (n, 4)
    for i, lam in independent_eigenvalues.items():
        ok = np.isfinite(cd_j.damping[i])  # tracked mode present at this speed
        f, d = cd_j.frequencies_hz[i, ok], cd_j.damping[i, ok]
        assert f.size == lam.size  # no mode lost or duplicated by the tracking
        f_ref, d_ref = lam.imag / (2 * np.pi), -lam.real / np.abs(lam)
        # λ rebuilt from (f, D): Im λ = 2πf, Re λ = −D |λ| with |λ| = 2πf / sqrt(1 − D²)
        lam_lib = 2 * np.pi * f * (1j - d / np.sqrt(1 - d * d))
        r, k = linear_sum_assignment(np.abs(lam_lib[:, None] - lam[None, :]))
        # two eigen-solvers on a non-normal matrix with film damping: ~1e-8 relative; 1e-6 leaves room for the
        # conditioning of the heavily damped ring modes (as test_methods.py's state-space check)
        np.testing.assert_allclose(f[r], f_ref[k], rtol=1e-6)
        np.testing.assert_allclose(d[r], d_ref[k], rtol=0, atol=1e-6)
        # the unstable count is the number of eigenvalues in the right half plane
        assert cd_j.n_unstable[i] == np.sum(lam.real > 0)
    # tracked low modes evolve smoothly: consecutive speed steps change them by far less than a mode spacing
    f = cd_j.frequencies_hz
    # (modes near critical damping are left out: their damped frequency sqrt(1-D²)|λ| moves steeply)
    low = [j for j in range(cd_j.n_modes) if np.isfinite(f[:, j]).all() and f[:, j].max() < 1500
           and np.abs(cd_j.damping[:, j]).max() < 0.8]
    assert low
    for j in low:
        assert np.max(np.abs(np.diff(f[:, j]))) < 60.0  # 6 krpm steps: 1X moves 100 Hz, these modes < 40 Hz


def test_whirl_onset_from_sweep_matches_exact(cd_j):
    # the result carries the exact onsets (docs/theory/parameters.md#reference-numbers table, rounded to 0.1 krpm), not
    # the grid interpolation
    np.testing.assert_allclose(cd_j.whirl_onset_rpm / 1e3, [11.1, 68.1, 11.8, 69.2], atol=0.051)
    assert "film_onset_speeds" in cd_j.meta["whirl_onset_source"]
    # the grid interpolation stays available; a sweep starting at 10 krpm resolves onsets above 10 krpm to its step
    # (6.2 krpm), linearly interpolated
    swept = cd_j.whirl_onset_on_grid()
    for k in (1, 3):
        assert swept[k] == pytest.approx(cd_j.whirl_onset_rpm[k], abs=1500)


def test_dataframe_and_exports(cd_j, tmp_path):
    df = cd_j.to_dataframe()
    assert {"speed [rpm]", "frequency [Hz]", "damping [-]", "precession"} <= set(df.columns)
    assert len(df) == np.isfinite(cd_j.frequencies_hz).sum()
    paths = cd_j.save(tmp_path, stem="cj")
    names = {p.name for p in paths}
    assert {"cj_modes.csv", "cj_films.csv", "cj_unstable.csv", "cj.json", "cj.png", "cj.html"} <= names
    back = pd.read_csv(tmp_path / "cj_modes.csv")
    np.testing.assert_allclose(back["frequency [Hz]"], df["frequency [Hz]"], rtol=1e-12)
    html = (tmp_path / "cj.html").read_text()
    assert "plotly" in html and "precession" in html
    assert (tmp_path / "cj.png").stat().st_size > 10_000


def test_absent_modes_are_nan_in_every_array(cd_j):
    """CampbellResult documents NaN for a mode absent at a speed (here an over-damped pair at 10 krpm)."""
    absent = ~np.isfinite(cd_j.damping)
    assert absent.any()
    assert np.all(np.isnan(cd_j.frequencies_hz[absent])) and np.all(np.isnan(cd_j.eigenvalues[absent]))


def test_unstable_ranges_are_the_forward_runs_of_negative_damping(cd_j, independent_eigenvalues):
    ur = cd_j.unstable_ranges()
    # an almost unloaded film is unstable above a very low speed (docs/theory/parameters.md#table-2-in-si-units; the
    # compressor films carry
    # 0.18 N): method J is unstable over the whole sweep, as the independent eigenvalues show at the checked speeds
    for lam in independent_eigenvalues.values():
        assert np.sum(lam.real > 0) >= 1
    assert np.all(cd_j.n_unstable >= 1) and len(ur) >= 1
    # the films' cross-coupled stiffness feeds whirl in the rotation sense only: every unstable mode is forward
    # (docs/theory/parameters.md#interpretation-choices, item 10)
    assert set(ur["precession"]) == {"forward"}
    for _, r in ur.iterrows():
        d = np.nan_to_num(cd_j.damping[:, r["mode"]], nan=1.0)
        a, b = np.searchsorted(cd_j.speeds_rpm, [r["from [rpm]"], r["to [rpm]"]])
        assert np.all(d[a:b + 1] < 0)  # unstable throughout the range ...
        assert (a == 0 or d[a - 1] >= 0) and (b == SWEEP.size - 1 or d[b + 1] >= 0)  # ... and maximal
        assert r["min damping [-]"] == pytest.approx(d[a:b + 1].min(), rel=1e-12)
    # every negative damping value lies in a listed range
    covered = np.zeros_like(cd_j.damping, dtype=bool)
    for _, r in ur.iterrows():
        covered[(cd_j.speeds_rpm >= r["from [rpm]"]) & (cd_j.speeds_rpm <= r["to [rpm]"]), r["mode"]] = True
    assert np.array_equal(covered, np.nan_to_num(cd_j.damping, nan=1.0) < 0)
