"""The thermal model in the unbalance response (issue #25 stage 3): each speed at its own thermal operating point
against the constant-viscosity response of a system with that operating point's viscosities copied in by hand, the
refined 1X crossings and response peaks at the temperatures of their own speed, and without an oil the stored numbers
of the code before this change bit for bit."""
import json
from pathlib import Path

import numpy as np
import pytest
from _reference import with_viscosities_by_hand

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.core.errors import ParameterError
from frbmodel.linear.assembly import linear_system
from frbmodel.linear.thermal import OilSupply, thermal_losses, thermal_system
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
UNB = {"turbine_wheel": (1e-6, 0.0)}
SUPPLY = OilSupply(OIL, 343.15, 2e5)
REFERENCE = Path(__file__).parent / "reference" / "constant_viscosity_unbalance.json"


@pytest.fixture(scope="module")
def thermal_response():
    """Unbalance response with the thermal model, 20 ... 250 krpm in 24 speeds, with its critical-speed table."""
    return frb.unbalance_response(TC, "J", np.linspace(20e3, 250e3, 24), UNB, oil_supply=SUPPLY)


def _by_hand(speed_rpm):
    """Table 2 with the four film viscosities of thermal_losses at ``speed_rpm`` copied in by hand."""
    return with_viscosities_by_hand(TC, thermal_losses(TC, speed_rpm, OIL, SUPPLY.supply_temperature_K,
                                                        SUPPLY.supply_pressure_Pa))


def test_without_an_oil_the_unbalance_response_is_the_stored_one_bit_for_bit():
    """tests/reference/make_constant_viscosity_unbalance.py stored the complex amplitudes and the critical speeds
    computed by commit 8fe8a0b (before the option existed): today's, with and without ``oil_supply=None``, equal to
    the last bit (no tolerance: the same operations)."""
    ref = json.loads(REFERENCE.read_text())
    for ur in (frb.unbalance_response(TC, "J", ref["speeds_rpm"], UNB),
               frb.unbalance_response(TC, "J", ref["speeds_rpm"], UNB, oil_supply=None)):
        np.testing.assert_array_equal(ur.response.real, np.array(ref["response_real"]))
        np.testing.assert_array_equal(ur.response.imag, np.array(ref["response_imag"]))
        cs = ur.critical_speeds()
        np.testing.assert_array_equal(cs["speed [rpm]"], ref["critical_speed_rpm"])
        assert cs["source"].tolist() == ref["critical_source"] and "oil_supply" not in ur.meta


def test_each_speed_is_the_constant_viscosity_response_of_its_operating_point(thermal_response):
    """At 60 and 180 krpm the thermal response equals unbalance_response of the by-hand system at that one speed:
    the same matrices and one linear solve each, so equal to 1e-13 relative of the largest amplitude (measured:
    equal to the last bit)."""
    ur = frb.unbalance_response(TC, "J", [60e3, 180e3], UNB, critical=False, oil_supply=SUPPLY)
    for i, rpm in enumerate((60e3, 180e3)):
        ref = frb.unbalance_response(_by_hand(rpm), "J", [rpm], UNB, critical=False)
        scale = np.abs(ref.response[0]).max()
        np.testing.assert_allclose(ur.response[i], ref.response[0], rtol=0, atol=1e-13 * scale)
        mu = [f.viscosity for b in _by_hand(rpm).bearings for f in (b.inner, b.outer)]
        assert ur.meta["film_viscosities_Pa_s"][i] == mu
    assert ur.meta["oil_supply"]["supply_temperature_K"] == 343.15
    # the response differs from the constant viscosities' (the film viscosities are 2 ... 4 times Table 2's)
    const = frb.unbalance_response(TC, "J", [60e3, 180e3], UNB, critical=False)
    assert np.abs(const.response - ur.response).max() > 0.1 * np.abs(const.response).max()
    assert thermal_response.critical is not None


def test_refined_1x_crossings_are_at_the_temperatures_of_their_own_speed(thermal_response):
    """Each refined 1X crossing s* of the thermal response: the state matrix [[0, I], [-M^-1 K, -M^-1 C]] of the
    linear system of thermal_system(s*) (numpy eigvals: not the Campbell's solver path) has an eigenvalue with
    Im/2π = s*/60 to 1e-6 relative (the refinement keeps a root only where |f - n/60| <= 1e-6 n/60; Brent's own
    tolerance leaves ~1e-9)."""
    cs = thermal_response.critical_speeds()
    cross = cs[(cs["source"] == "1X crossing") & cs["refined"]]
    assert len(cross) >= 2
    for s in cross["speed [rpm]"]:
        ls = linear_system(thermal_system(TC, s, OIL, 343.15, 2e5), "J", s)
        n, m_inv = ls.M.shape[0], np.linalg.inv(ls.M)
        lam = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ ls.K, -m_inv @ ls.C]]))
        f = lam.imag[lam.imag > 0] / (2 * np.pi)
        assert np.min(np.abs(f - s / 60.0)) <= 1e-6 * s / 60.0, s


def test_refined_response_peaks_are_maxima_of_the_operating_points_response(thermal_response):
    """Each refined response peak s*: its amplitude equals the constant-viscosity response of the by-hand system at
    s* (1e-12: the same solve), and it is not below the thermal response 0.1 % of s* either side (a maximum of the
    thermal curve, each side at its own operating point)."""
    cs = thermal_response.critical_speeds()
    peaks = cs[(cs["source"] == "response peak") & cs["refined"]]
    assert len(peaks) >= 2
    for _, r in peaks.iterrows():
        s, name = r["speed [rpm]"], r["location"]
        ref = frb.unbalance_response(_by_hand(s), "J", [s], UNB, critical=False)
        assert abs(ref.major_axis(name)[0] - r["amplitude [m]"]) <= 1e-12 * r["amplitude [m]"]
        side = frb.unbalance_response(TC, "J", [0.999 * s, 1.001 * s], UNB, critical=False, oil_supply=SUPPLY)
        assert np.all(side.major_axis(name) <= r["amplitude [m]"] * (1 + 1e-12))


def test_cli_unbalance_with_an_oil_saves_the_library_result(tmp_path):
    """frb unbalance --oil: the saved amplitudes equal unbalance_response(oil_supply) at the same inputs (exactly:
    the same call)."""
    out = tmp_path / "u"
    assert main(["unbalance", "--oil", "SAE 5W-30", "--supply-temperature", "343.15", "--supply-pressure", "2e5",
                 "--speeds", "60000,180000", "--out", str(out)]) == 0
    saved = frb.UnbalanceResponse.load(out)
    ref = frb.unbalance_response(TC, "J", [60e3, 180e3], UNB, oil_supply=SUPPLY)
    np.testing.assert_array_equal(saved.response, ref.response)
    assert saved.meta["oil_supply"]["supply_pressure_Pa"] == 2e5


def test_library_refuses_an_oil_with_a_spring_method():
    with pytest.raises(ParameterError, match="method = 'A' cannot be combined with an oil supply"):
        frb.unbalance_response(TC, "A", [60e3], oil_supply=SUPPLY)


@pytest.mark.parametrize("argv, message", [
    (["--supply-temperature", "333.15"], "--supply-temperature needs an oil: give --oil NAME"),
    (["--oil", "SAE 5W-30", "--method", "A,J"], "--method A,J cannot be combined with an oil"),
    (["--oil", "SAE 5W-30", "--supply-temperature", "90"], "--supply-temperature = 90.0 K is invalid"),
    (["--oil", "SAE 5W-30", "--supply-pressure=-1"], "--supply-pressure = -1.0 Pa is invalid"),
])
def test_cli_refuses_bad_thermal_options_with_one_line_and_writes_nothing(capsys, tmp_path, argv, message):
    out = tmp_path / "out"
    code = main(["unbalance", *argv, "--speeds", "60000,180000", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()
