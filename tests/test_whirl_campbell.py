"""Film whirl (Lund vs Routh–Hurwitz vs eigenvalues), onset speeds, Campbell result object and exports."""
import math

import numpy as np
import pandas as pd
import pytest

import frbmodel as frb
from frbmodel.film import rt_coefficients
from frbmodel.whirl import film_whirl_ratio, lund_threshold, routh_hurwitz_stable

# physics.md §8 table: ε -> (γ, K̄_eq/γ²)
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
    # f_wI, f_wO of the J equilibrium: 36 µm turbine at 30k and 100k rpm (physics.md §11 table)
    cd = frb.campbell(frb.turbocharger(36e-6), "J", [30e3, 100e3, 200e3])
    np.testing.assert_allclose(cd.whirl_hz[:, 0], [306.0, 1002.0, 1999.8], atol=0.06)
    np.testing.assert_allclose(cd.whirl_hz[:, 1], [49.5, 166.5, 332.1], atol=0.06)
    np.testing.assert_allclose(cd.whirl_hz[1, 2:], [999.2, 165.9], atol=0.06)


@pytest.fixture(scope="module")
def cd_j():
    return frb.campbell(frb.turbocharger(36e-6), "J", np.linspace(10e3, 250e3, 40))


def test_campbell_arrays_and_tracking(cd_j):
    n = 40
    for a in (cd_j.frequencies_hz, cd_j.damping, cd_j.precession, cd_j.mode_kind, cd_j.eigenvalues):
        assert a.shape[0] == n and a.shape[1] == cd_j.n_modes
    assert cd_j.ring_speed_ratio.shape == (n, 2) and cd_j.whirl_hz.shape == (n, 4)
    d = cd_j.damping[np.isfinite(cd_j.damping)]
    assert np.all((d > -1) & (d < 1))
    # tracked low modes evolve smoothly: consecutive speed steps change them by far less than a mode spacing
    f = cd_j.frequencies_hz
    # (modes near critical damping are left out: their damped frequency sqrt(1-D²)|λ| moves steeply)
    low = [j for j in range(cd_j.n_modes) if np.isfinite(f[:, j]).all() and f[:, j].max() < 1500
           and np.abs(cd_j.damping[:, j]).max() < 0.8]
    assert low
    for j in low:
        assert np.max(np.abs(np.diff(f[:, j]))) < 60.0  # 6 krpm steps: 1X moves 100 Hz, these modes < 40 Hz


def test_whirl_onset_from_sweep_matches_exact(cd_j):
    exact = frb.film_onset_speeds(frb.turbocharger(36e-6))
    swept = cd_j.whirl_onset_rpm
    # a sweep starting at 10 krpm resolves onsets above 10 krpm to its step (6.2 krpm), linearly interpolated
    for k in (1, 3):
        assert swept[k] == pytest.approx(exact[k], abs=1500)


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


def test_unstable_ranges_consistent_with_damping(cd_j):
    ur = cd_j.unstable_ranges()
    for _, r in ur.iterrows():
        sel = (cd_j.speeds_rpm >= r["from [rpm]"]) & (cd_j.speeds_rpm <= r["to [rpm]"])
        assert np.all(cd_j.damping[sel, r["mode"]] < 0)
    assert int(cd_j.n_unstable.max()) >= (1 if len(ur) else 0)
