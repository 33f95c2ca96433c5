"""The thermal model in the Hopf points and the limit cycles at a constant speed (issue #25 stage 3): a Hopf point
with an oil supply is where the method-J linear system of its own thermal operating point loses stability, and the
Hopf point of the system frozen at that operating point; a limit cycle with an oil supply is the limit cycle of the
system whose viscosities are copied in by hand; continuation refuses an oil supply."""
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.cycles.continuation import continuation, hopf_points
from frbmodel.linear.modal import state_matrix
from frbmodel.linear.thermal import OilSupply, thermal_losses, thermal_system
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
SUPPLY = OilSupply(OIL, 363.15)


def _by_hand(speed_rpm):
    """Table 2 with the four film viscosities of thermal_losses at ``speed_rpm`` copied in by hand."""
    tab = thermal_losses(TC, speed_rpm, OIL, SUPPLY.supply_temperature_K, SUPPLY.supply_pressure_Pa)
    bearings = tuple(replace(b, inner=replace(b.inner, viscosity=r["inner viscosity [Pa s]"]),
                             outer=replace(b.outer, viscosity=r["outer viscosity [Pa s]"]))
                     for b, (_, r) in zip(TC.bearings, tab.iterrows()))
    return replace(TC, bearings=bearings)


@pytest.fixture(scope="module")
def hopf():
    """The thermal Hopf point of the ring mode near 118 Hz, 70 ... 90 krpm, 363.15 K supply."""
    hps = hopf_points(TC, (70e3, 90e3), n_grid=4, oil_supply=SUPPLY)
    assert len(hps) == 1
    return hps[0]


def test_a_thermal_hopf_point_is_where_the_thermal_method_j_system_loses_stability(hopf):
    """Brent's root of the real part of the method-J eigenvalue (numpy eigvals of the state matrix of
    linear_system(thermal_system(s)), each trial speed at its own operating point: the thermal Campbell's rule, not
    the full model's Jacobian) equals the Hopf speed and frequency to 0.5 % (the tolerance of
    tests/test_continuation.py: the full model also has the rings' spin, which method J fixes by the torque balance;
    measured there <= 0.03 % at constant viscosities)."""
    def lam(s):
        ls = frb.linear_system(thermal_system(TC, s, OIL, 363.15), "J", s)
        ev = np.linalg.eigvals(state_matrix(ls.M, ls.C, ls.K))
        ev = ev[ev.imag > 0]
        return ev[np.argmin(np.abs(ev.imag / (2 * math.pi) - hopf.frequency_hz))]
    s = brentq(lambda x: lam(x).real, 0.95 * hopf.speed_rpm, 1.05 * hopf.speed_rpm, xtol=1e-3)
    assert hopf.speed_rpm == pytest.approx(s, rel=0.005)
    assert hopf.frequency_hz == pytest.approx(lam(s).imag / (2 * math.pi), rel=0.005)
    # not the constant-viscosity Hopf points (58.5 and 95.9 krpm at Table 2's viscosities)
    assert all(abs(h.speed_rpm - hopf.speed_rpm) > 5e3 for h in hopf_points(TC, (50e3, 100e3), n_grid=5))


def test_a_thermal_hopf_point_is_the_hopf_point_of_its_own_operating_point(hopf):
    """Fixed-point consistency: the Hopf point of the system frozen at the thermal operating point of s_h (by-hand
    viscosities) is s_h; both are Brent roots to 1e-6 relative of real parts that coincide at s_h, so 3e-6."""
    frozen = hopf_points(_by_hand(hopf.speed_rpm), (0.98 * hopf.speed_rpm, 1.02 * hopf.speed_rpm), n_grid=3)
    assert len(frozen) == 1
    assert frozen[0].speed_rpm == pytest.approx(hopf.speed_rpm, rel=3e-6)
    assert frozen[0].frequency_hz == pytest.approx(hopf.frequency_hz, rel=1e-5)


@pytest.mark.slow
def test_a_thermal_limit_cycle_is_the_limit_cycle_of_its_operating_point():
    """limit_cycle(oil_supply) at 100 krpm against limit_cycle of the by-hand system: the same computation on the
    same system, so period, multipliers and orbit equal to 1e-9 relative (settling, shooting and sampling are
    deterministic). Slow: two limit cycles of ~6.5 s each (39 s measured for the test under load)."""
    lc = frb.limit_cycle(TC, 100e3, oil_supply=SUPPLY)
    ref = frb.limit_cycle(_by_hand(100e3), 100e3)
    assert lc.period == pytest.approx(ref.period, rel=1e-9)
    np.testing.assert_allclose(lc.multipliers, ref.multipliers, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(lc.max_eps, ref.max_eps, rtol=1e-9)
    assert lc.meta["oil_supply"]["supply_temperature_K"] == 363.15


def test_refusals_name_the_option():
    with pytest.raises(ParameterError, match="oil_supply cannot be combined with continuation"):
        continuation(TC, (70e3, 90e3), oil_supply=SUPPLY)
    with pytest.raises(ParameterError, match="guess = a RunupResult cannot be combined with oil_supply"):
        run = frb.runup(TC, profile=frb.SpeedProfile.constant(60e3, 1e-3), duration=1e-3)
        frb.limit_cycle(TC, 60e3, guess=run, oil_supply=SUPPLY)
    with pytest.raises(ParameterError, match="oil_supply = 'SAE 5W-30' is a str"):
        hopf_points(TC, (70e3, 90e3), oil_supply="SAE 5W-30")
