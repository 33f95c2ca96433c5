"""The thermal model in the Hopf points and the limit cycles at a constant speed (issue #25 stage 3): a Hopf point
with an oil supply is where the method-J linear system of its own thermal operating point loses stability, and the
Hopf point of the system frozen at that operating point; a limit cycle with an oil supply is the limit cycle of the
system whose viscosities are copied in by hand; a continuation with an oil supply integrates at every speed the
by-hand system of that speed and starts at the thermal Hopf point."""
import math

import numpy as np
import pytest
from _reference import with_viscosities_by_hand
from scipy.optimize import brentq

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.cycles.branch import ContinuationProblem, equilibrium_jacobian
from frbmodel.cycles.continuation import BifurcationDiagram, continuation, hopf_points
from frbmodel.cycles.flow import SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS, ConstantSpeedFlow
from frbmodel.cycles.limitcycle import LimitCycle
from frbmodel.linear.modal import state_matrix
from frbmodel.linear.thermal import OilSupply, thermal_losses, thermal_system
from frbmodel.nonlinear.runup import SpeedProfile, build_problem
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
SUPPLY = OilSupply(OIL, 363.15)


def _by_hand(speed_rpm):
    """Table 2 with the four film viscosities of thermal_losses at ``speed_rpm`` copied in by hand."""
    return with_viscosities_by_hand(TC, thermal_losses(TC, speed_rpm, OIL, SUPPLY.supply_temperature_K,
                                                        SUPPLY.supply_pressure_Pa))


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


def test_continuation_flows_are_those_of_each_speeds_own_operating_point():
    """The flows of a continuation with an oil supply at 80 and 84 krpm are the flows of the by-hand systems of
    those speeds (the same viscosities, the same integrator: equal to 1e-12 relative, round-off of identical
    operations), and the frozen system of 80 krpm flown at 84 krpm differs from them by far more than the flows'
    tolerance: a branch (and its speed column, differences of flows at two speeds) follows the temperatures."""
    br = ContinuationProblem(TC, TC.film_model, SHOOT_RTOL, SHOOT_ATOL_M, SCALE_M, WORKERS, 80e3, 1, SUPPLY)
    z = equilibrium_jacobian(TC, 80e3, oil_supply=SUPPLY)[0] + 1e-7  # 0.1 µm (and 1e-7 SI) off the equilibrium
    ends = {}
    for s in (80e3, 84e3):
        ends[s], fl = br.ends(z, 2e-3, s)
        by_hand = ConstantSpeedFlow(build_problem(_by_hand(s), SpeedProfile.constant(s, 1.0), TC.film_model),
                                    SHOOT_RTOL, SHOOT_ATOL_M, fl.method)
        np.testing.assert_allclose(ends[s], by_hand(z, 2e-3), rtol=1e-12, atol=1e-18)
    frozen = ConstantSpeedFlow(build_problem(_by_hand(80e3), SpeedProfile.constant(84e3, 1.0), TC.film_model),
                               SHOOT_RTOL, SHOOT_ATOL_M, fl.method)(z, 2e-3)
    moved = np.abs(frozen - ends[84e3])[:TC.rotor.n_dof]  # rotor displacements [m]
    assert moved.max() > 100 * SHOOT_ATOL_M


def test_continuation_with_an_oil_supply_starts_at_the_thermal_hopf_point(tmp_path):
    """The branch of the first Hopf point with the oil at 363.15 K: its Hopf record is hopf_points(oil_supply=)'s
    point (1995 rpm; 2012 rpm at Table 2's viscosities, 0.85 % away), its first points lie within 0.1 % of it (a
    branch integrated at constant viscosities would have to reach the 2012 rpm point), the diagram records the
    supply and reads it back; a LimitCycle start of another supply is refused."""
    hp = hopf_points(TC, (1e3, 6e3), oil_supply=SUPPLY)[0]
    assert abs(hp.speed_rpm / hopf_points(TC, (1e3, 6e3))[0].speed_rpm - 1) > 5e-3
    bd = continuation(TC, (1e3, 6e3), "hopf", max_points=3, oil_supply=SUPPLY)
    rec = [b for b in bd.bifurcations if b["type"] == "Hopf"]
    assert len(rec) == 1 and rec[0]["speed_rpm"] == pytest.approx(hp.speed_rpm, rel=1e-9)
    assert all(p.speed_rpm == pytest.approx(hp.speed_rpm, rel=1e-3) for p in bd.points) and len(bd.points) == 3
    assert all(p.period == pytest.approx(1 / hp.frequency_hz, rel=1e-3) for p in bd.points)
    bd.save(tmp_path)
    assert BifurcationDiagram.load(tmp_path).meta["oil_supply"] == SUPPLY.to_dict()
    other = LimitCycle(3e3, 0.05, None, np.ones(3), True, np.zeros(3), True, {}, None)  # (refused before use)
    with pytest.raises(ParameterError, match="computed with oil_supply = None, the continuation has"):
        continuation(TC, (1e3, 6e3), other, oil_supply=SUPPLY)


def test_refusals_name_the_option():
    with pytest.raises(ParameterError, match="guess = a RunupResult cannot be combined with oil_supply"):
        run = frb.runup(TC, profile=frb.SpeedProfile.constant(60e3, 1e-3), duration=1e-3)
        frb.limit_cycle(TC, 60e3, guess=run, oil_supply=SUPPLY)
    with pytest.raises(ParameterError, match="oil_supply = 'SAE 5W-30' is a str"):
        hopf_points(TC, (70e3, 90e3), oil_supply="SAE 5W-30")


def test_cli_bifurcation_with_an_oil_lists_the_thermal_hopf_points(tmp_path, capsys):
    """`frb bifurcation --oil … --hopf-only` writes the Hopf points of hopf_points(oil_supply=) (called here: the
    same values to the printed 0.1 rpm and in the CSV exactly) and says which supply it used."""
    from frbmodel.cli import main

    out = tmp_path / "h"
    assert main(["bifurcation", "--oil", "SAE 5W-30", "--supply-temperature", "363.15", "--speeds", "5000:120000",
                 "--hopf-only", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "thermal model: SAE 5W-30, supply 363.15 K, 300000 Pa" in text
    ref = hopf_points(TC, (5e3, 120e3), restabilizing=True, oil_supply=SUPPLY)
    import pandas as pd

    csv = pd.read_csv(out / "hopf_points.csv")
    assert csv.iloc[:, 0].tolist() == [h.speed_rpm for h in ref] and len(ref) == 2
    assert all(f"{h.speed_rpm:10.1f} rpm" in text for h in ref)
