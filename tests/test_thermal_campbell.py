"""The thermal model in the Campbell diagram and the film whirl onsets (issue #25 stage 2): each speed at its own
thermal operating point against the constant-viscosity analyses of that operating point's system (an independent
path: the viscosities go into a plain Turbocharger), the onsets at the temperatures of their own speed, the closed
form of the outer film's onset ring speed, the direction with the supply temperature, and without an oil the stored
numbers of the code before this change bit for bit."""
import json
import math
from pathlib import Path

import numpy as np
import pytest
from _reference import with_viscosities_by_hand

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.core.errors import ParameterError
from frbmodel.linear.thermal import OilSupply, thermal_losses, thermal_system
from frbmodel.linear.whirl import film_whirl_ratio
from frbmodel.system.oil import OILS
from frbmodel.system.rotor import GRAVITY as G

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
REFERENCE = Path(__file__).parent / "reference" / "constant_viscosity_campbell.json"


@pytest.fixture(scope="module")
def onsets():
    """Exact film onsets with the thermal model at three supply temperatures [K] -> ndarray (4,) [rpm]."""
    return {t: frb.film_onset_speeds(TC, oil_supply=OilSupply(OIL, t)) for t in (333.15, 363.15, 393.15)}


def test_without_an_oil_the_campbell_diagram_is_the_stored_one_bit_for_bit():
    """tests/reference/make_constant_viscosity_campbell.py stored eigenvalues, whirl margins and frequencies, RSR and
    exact onsets computed by commit 3fb56f2 (before the thermal option existed): today's numbers, with
    ``oil_supply=None`` and without the argument, are equal to the last bit (no tolerance: the same operations)."""
    ref = json.loads(REFERENCE.read_text())
    for cd in (frb.campbell(TC, "J", np.array(ref["speeds_rpm"])),
               frb.campbell(TC, "J", np.array(ref["speeds_rpm"]), oil_supply=None)):
        np.testing.assert_array_equal(cd.eigenvalues.real, np.array(ref["eigenvalues_real"]))
        np.testing.assert_array_equal(cd.eigenvalues.imag, np.array(ref["eigenvalues_imag"]))
        for name in ("whirl_margin", "whirl_hz", "ring_speed_ratio", "whirl_onset_rpm"):
            np.testing.assert_array_equal(getattr(cd, name), np.array(ref[name]), err_msg=name)
        assert "oil_supply" not in cd.meta


def test_each_speed_of_the_thermal_campbell_is_the_constant_viscosity_campbell_of_its_operating_point():
    """campbell(oil_supply) at 60 and 180 krpm against campbell() of a Turbocharger whose film viscosities are
    copied by hand from the thermal_losses table at that speed: the eigenvalues (sorted by frequency: the mode
    tracking over a grid numbers the modes differently from a single speed) equal to 1e-12 relative (the same
    matrices; the stacked eigen-solve of two speeds against one speed alone may round differently)."""

    sup = OilSupply(OIL, 343.15, 2e5)
    cd = frb.campbell(TC, "J", np.array([60e3, 180e3]), oil_supply=sup)
    for i, rpm in enumerate((60e3, 180e3)):
        tab = thermal_losses(TC, rpm, OIL, 343.15, 2e5)
        ref = frb.campbell(with_viscosities_by_hand(TC, tab), "J", np.array([rpm]))
        lam, lam_ref = (x[np.isfinite(x)] for x in (cd.eigenvalues[i], ref.eigenvalues[0]))
        lam, lam_ref = lam[np.argsort(lam.imag)], lam_ref[np.argsort(lam_ref.imag)]
        assert lam.size == lam_ref.size > 10
        np.testing.assert_allclose(lam, lam_ref, rtol=1e-12)
        np.testing.assert_allclose(cd.whirl_margin[i], ref.whirl_margin[0], rtol=1e-12)
        np.testing.assert_allclose(cd.ring_speed_ratio[i], tab["RSR [-]"], rtol=1e-12)
        np.testing.assert_allclose(cd.meta["film_viscosities_Pa_s"][i],
                                   tab[["inner viscosity [Pa s]", "outer viscosity [Pa s]"]].to_numpy().ravel(),
                                   rtol=0)
    assert cd.meta["oil_supply"]["supply_temperature_K"] == 343.15


def test_thermal_onsets_are_at_the_temperatures_of_their_own_speed(onsets):
    """Fixed-point consistency: the constant-viscosity onset of thermal_system(s*) (the films frozen at the thermal
    operating point of the onset s*) is s* itself. Both are Brent roots to 1e-6 rpm of margins that coincide at s*,
    so they agree to 2e-6 rpm (measured <= 1.6e-7 rpm over 313 ... 393 K)."""
    for t_s, on in onsets.items():
        for k, s in enumerate(on):
            frozen = frb.film_onset_speeds(thermal_system(TC, s, OIL, t_s))[k]
            assert abs(frozen - s) <= 2e-6, (t_s, k, frozen - s)


def test_outer_film_onset_is_at_the_ring_speed_of_lunds_threshold(onsets):
    """The outer film's wall-speed sum is the ring speed, so its onset is where c_O ω_FR² / g reaches Lund's
    threshold K̄/γ² of the short film: 6.47 ... 7.64 for ε in 0 ... 0.4 (film_whirl_ratio, a closed form of ε).
    The ring speed at the onset (from the thermal table there, an independent equilibrium) must lie in
    sqrt(thr g / c_O) over that band, whatever the supply temperature."""
    thr = [film_whirl_ratio(e, "short")[1] for e in np.linspace(1e-3, 0.4, 41)]
    c_o = TC.bearings[0].outer.clearance
    lo, hi = (math.sqrt(x * G / c_o) for x in (min(thr), max(thr)))
    for t_s, on in onsets.items():
        for k in (1, 3):  # turbine outer, compressor outer
            tab = thermal_losses(TC, on[k], OIL, t_s)
            ring = float(tab["ring speed [rad/s]"].iloc[k // 2])
            assert lo <= ring <= hi, (t_s, k, ring, lo, hi)
            assert float(tab["eps outer [-]"].iloc[k // 2]) < 0.4


def test_outer_film_onsets_fall_as_the_supply_temperature_rises(onsets):
    """Direction. Colder oil: higher viscosity, more friction power; the inner film (sheared at ω_R + ω_FR) heats far
    more than the outer one, so μ_I/μ_O and with it the RSR fall, and the ring reaches the outer film's threshold
    speed (test above) only at a higher rotor speed: the outer onsets rise as the supply temperature falls, and at
    every supply temperature lie above the constant-viscosity onsets (4.9 / 6.4 mPa s, RSR 0.196 there)."""
    const = frb.film_onset_speeds(TC)
    temps = sorted(onsets)
    for k in (1, 3):
        values = [onsets[t][k] for t in temps]
        assert all(a > b for a, b in zip(values, values[1:])), values
        assert values[-1] > const[k]


def test_oil_supply_is_used_or_refused():
    """An oil supply with a spring method (no films), or not an OilSupply, is refused with one line naming it."""
    sup = OilSupply(OIL)
    for letter in "ABE":
        with pytest.raises(ParameterError, match=f"method = '{letter}' cannot be combined with an oil supply: its "
                                                 "bearings are linear springs"):
            frb.campbell(TC, letter, [1e5], oil_supply=sup)
    with pytest.raises(ParameterError, match="oil_supply = 'SAE 5W-30' is a str; expected an OilSupply"):
        frb.campbell(TC, "J", [1e5], oil_supply="SAE 5W-30")
    with pytest.raises(ParameterError, match="supply_temperature_K = 90.0 K is invalid"):
        OilSupply(OIL, 90.0)
    with pytest.raises(ParameterError, match="supply_pressure_Pa = -1.0 Pa is invalid"):
        OilSupply(OIL, 363.15, -1.0)
    with pytest.raises(ParameterError, match="oil = 'SAE 5W-30' is a str; expected an Oil"):
        OilSupply("SAE 5W-30")


# ------------------------------------------------------------------ command line
def test_cli_campbell_with_an_oil_is_the_library_diagram(capsys, tmp_path):
    """frb campbell --oil: the saved onsets and viscosities equal campbell(oil_supply) at the same inputs (exactly:
    the same call); frb equilibrium --oil prints the viscosities of thermal_system."""
    out = tmp_path / "c"
    assert main(["campbell", "--oil", "SAE 5W-30", "--supply-temperature", "333.15", "--supply-pressure", "4e5",
                 "--speeds", "50000,150000", "--out", str(out)]) == 0
    assert "thermal model: SAE 5W-30, supply 333.15 K, 400000 Pa" in capsys.readouterr().out
    meta = json.loads((out / "campbell_J.json").read_text())
    ref = frb.campbell(TC, "J", [50e3, 150e3], oil_supply=OilSupply(OIL, 333.15, 4e5))
    np.testing.assert_array_equal(meta["whirl_onset_rpm"], ref.whirl_onset_rpm)
    np.testing.assert_array_equal(meta["film_viscosities_Pa_s"], ref.meta["film_viscosities_Pa_s"])
    assert main(["equilibrium", "--oil", "SAE 5W-30", "--speed-rpm", "150000"]) == 0
    mu = thermal_system(TC, 150e3, OIL, 363.15).bearings[0].inner.viscosity
    assert f"turbine inner {mu:.5g}" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["campbell", "--supply-temperature", "333.15"], "--supply-temperature needs an oil: give --oil NAME"),
    (["campbell", "--supply-pressure", "4e5"], "--supply-pressure needs an oil: give --oil NAME"),
    (["campbell", "--oil", "SAE 5W-30", "--method", "A"], "--method A cannot be combined with an oil"),
    (["campbell", "--oil", "SAE 5W-30", "--supply-temperature", "90"], "--supply-temperature = 90.0 K is invalid"),
    (["campbell", "--oil", "SAE 5W-30", "--supply-pressure=-1"], "--supply-pressure = -1.0 Pa is invalid"),
    (["campbell", "--oil", "SAE 99W"], "oil name = 'SAE 99W' is unknown"),
    (["campbell", "--oil", "SAE 5W-30", "--from-fmu", "x.ssp"], "--oil cannot apply with an SSP"),
    (["equilibrium", "--oil", "SAE 5W-30", "--method", "E"], "--method E cannot be combined with an oil"),
    (["equilibrium", "--oil", "SAE 5W-30", "--speed-rpm", "0"], "--speed-rpm = 0.0 rpm is invalid"),
])
def test_cli_refuses_bad_thermal_options_with_one_line_and_writes_nothing(capsys, tmp_path, argv, message):
    out = tmp_path / "out"
    code = main([*argv, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


# ------------------------------------------------------------------ onsets versus supply temperature
def _unstable_pairs(speed_rpm, t_s):
    """Eigenvalues with Re > 0 in the upper half plane of the first-order state matrix of the linearized system at
    the thermal operating point (numpy eigvals of [[0, I], [−M⁻¹K, −M⁻¹C]]: not the Campbell's solver path)."""
    from frbmodel.linear.assembly import linear_system

    ls = linear_system(thermal_system(TC, speed_rpm, OIL, t_s), "J", speed_rpm)
    n, m_inv = ls.M.shape[0], np.linalg.inv(ls.M)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ ls.K, -m_inv @ ls.C]])
    lam = np.linalg.eigvals(a)
    return int(np.sum((lam.real > 0) & (lam.imag > 0)))


def test_a_campbell_mode_onset_is_the_bisected_eigenvalue_crossing():
    """The ring mode (~118 Hz) that loses stability near the outer films' onset at 333.15 K: its grid-interpolated
    onset on a 10 krpm grid against a bisection (24 halvings, 6e-4 rpm) of the speed where the number of unstable
    eigenvalues of the state matrix rises. Tolerance 1e-3 relative: the modal damping is interpolated linearly over
    10 krpm (measured 7.7e-5; 1.3e-5 on a 2.4 krpm grid)."""
    from frbmodel.studies.thermal import onsets_vs_supply

    grid = np.linspace(60e3, 160e3, 11)
    films, modes = onsets_vs_supply(TC, OIL, [333.15], speeds_rpm=grid)
    inside = modes[~modes["unstable at grid start"]]
    assert len(inside) == 1 and 110 < inside["frequency at onset [Hz]"].iloc[0] < 125
    s = float(inside["onset [rpm]"].iloc[0])
    i = int(np.searchsorted(grid, s))
    a, b = grid[i - 1], grid[i]
    n_a = _unstable_pairs(a, 333.15)
    assert _unstable_pairs(b, 333.15) == n_a + 1
    for _ in range(24):
        c = 0.5 * (a + b)
        a, b = (a, c) if _unstable_pairs(c, 333.15) > n_a else (c, b)
    assert s == pytest.approx(0.5 * (a + b), rel=1e-3)


def test_onsets_vs_supply_tables_are_the_thermal_onsets_with_their_states(onsets):
    """The film table's onsets are film_onset_speeds with the thermal model (the fixture's, computed directly:
    equal to the last bit, the same search), the constant-viscosity column that of the system's own viscosities;
    at every onset the film runs above the supply temperature (it dissipates: conservation) and the RSR is the ring
    speed over the rotor speed (1e-12)."""
    from frbmodel.studies.thermal import onsets_vs_supply

    films, _ = onsets_vs_supply(TC, OIL, [333.15, 393.15], speeds_rpm=[50e3, 150e3])
    const = frb.film_onset_speeds(TC)
    for t_s in (333.15, 393.15):
        grp = films[films["supply temperature [K]"] == t_s]
        np.testing.assert_array_equal(grp["onset [rpm]"], onsets[t_s])
        np.testing.assert_array_equal(grp["constant-viscosity onset [rpm]"], const)
        assert (grp["film temperature at onset [K]"] > t_s).all()
        np.testing.assert_allclose(grp["RSR at onset [-]"],
                                   grp["ring speed at onset [rad/s]"] / (grp["onset [rpm]"] * 2 * math.pi / 60),
                                   rtol=1e-12)
    with pytest.raises(ParameterError, match="supply_temperature_K = 90.0 K is invalid"):
        onsets_vs_supply(TC, OIL, [333.15, 90.0])


def test_cli_losses_onsets_writes_the_library_tables_and_the_figure(capsys, tmp_path):
    """frb losses --oil --onsets: whirl_onsets.csv equals onsets_vs_supply at the same inputs (to the CSV's
    round trip, 1e-15), and the figure is written; without an oil --onsets is refused (exit 2, nothing written)."""
    import pandas as pd

    from frbmodel.studies.thermal import onsets_vs_supply

    out = tmp_path / "on"
    assert main(["losses", "--oil", "SAE 5W-30", "--supply-temperature", "363.15", "--speeds", "50000,150000",
                 "--onsets", "--out", str(out)]) == 0
    assert "film whirl onsets (exact" in capsys.readouterr().out
    ref, _ = onsets_vs_supply(TC, OIL, [363.15], speeds_rpm=[50e3, 150e3])
    csv = pd.read_csv(out / "whirl_onsets.csv")
    np.testing.assert_allclose(csv["onset [rpm]"], ref["onset [rpm]"], rtol=1e-15)
    assert (out / "whirl_onsets_modes.csv").exists() and (out / "whirl_onsets.png").stat().st_size > 10_000
    bad = tmp_path / "bad"
    assert main(["losses", "--onsets", "--out", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "--onsets needs an oil" in err and len(err.strip().splitlines()) == 1 and not bad.exists()


def test_onsets_figure_takes_the_tables_with_units():
    """plot_onsets_vs_supply: K on the axis, °C on the top, krpm, a line per film, constant-viscosity references."""
    import matplotlib

    matplotlib.use("Agg")
    import pandas as pd

    from frbmodel.plots.thermal import plot_onsets_vs_supply

    films = pd.DataFrame({"supply temperature [K]": [333.15, 393.15] * 2, "film": ["a inner"] * 2 + ["a outer"] * 2,
                          "onset [rpm]": [1e4, 1.1e4, 1e5, 7e4], "oil": ["X"] * 4,
                          "constant-viscosity onset [rpm]": [1e4] * 2 + [6e4] * 2})
    modes = pd.DataFrame({"supply temperature [K]": [333.15], "onset [rpm]": [9e4], "unstable at grid start": [False]})
    fig = plot_onsets_vs_supply(films, modes)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "oil supply temperature [K]" and ax.get_ylabel() == "whirl onset speed [krpm]"
    assert [c.get_xlabel() for c in ax.child_axes] == ["[°C]"]
    labels = ax.get_legend_handles_labels()[1]
    assert "a outer film (thermal model)" in labels and "constant viscosities (system file)" in labels
