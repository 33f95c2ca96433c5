"""The rings' temperatures as states (issue #25 item 3, docs/theory/thermal.md#run-ups): the limits of the ring's
heat capacity (no capacity: the quasi-static operating points of thermal_losses; a huge one: the ring frozen at its
start temperature), the ring's energy balance (heat into it integrated over the run = m_R c_R ΔT_R), the direction of
the lag on a run-up, and the run-up's lagged viscosity table."""
import numpy as np
import pytest

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.linear.thermal import OilSupply, ring_lag, thermal_losses
from frbmodel.nonlinear.runup import SpeedProfile, lagged_viscosity_table, viscosity_table
from frbmodel.physics.thermal import ThermalModel

TC = frb.turbocharger()
OIL = frb.OILS["SAE 5W-30"]
T_S = 363.15
T = np.linspace(0.0, 1.0, 49)
RPM = 20e3 + 230e3 * T  # the main job's 1 s ramp


def _supply(capacity):
    return OilSupply(OIL, T_S, model=ThermalModel(ring_heat_capacity_J_K=capacity))


def test_without_capacity_the_ring_is_quasi_static():
    """m_R c_R = 1e-3 J/K: τ_R = C / (G_RI + G_RO) ≈ 0.2 ms (G ≈ 5 W/K, docs/theory/thermal.md), so the ring lags
    the steady temperature by τ_R · dT/dt ≈ 0.2 ms · 21 K/s ≈ 4 mK: temperatures within 0.02 K of thermal_losses,
    viscosities within 0.05 % (≈ 2.3 %/K of SAE 5W-30 at 380 K times 0.02 K)."""
    _, ring, inner, outer, mu, _ = ring_lag(TC, T, RPM, _supply(1e-3))
    qs = thermal_losses(TC, RPM[::12], OIL, T_S)
    for b, bearing in enumerate(TC.bearings):
        q = qs[qs["bearing"] == bearing.name]
        np.testing.assert_allclose(ring[b, ::12], q["ring temperature [K]"], atol=0.02)
        np.testing.assert_allclose(inner[b, ::12], q["inner film temperature [K]"], atol=0.02)
        np.testing.assert_allclose(outer[b, ::12], q["outer film temperature [K]"], atol=0.02)
        np.testing.assert_allclose(mu[2 * b, ::12], q["inner viscosity [Pa s]"], rtol=5e-4)


def test_a_huge_capacity_freezes_the_ring_and_a_real_one_lags_on_a_run_up():
    """1e4 J/K: τ_R ≈ 2000 s; the heat into a ring is at most (G_RI + G_RO) ≈ 5 W/K times the films' rise over the
    ring, ≤ 40 K here, so ≤ 200 W, and the ring moves by ≤ 200 W · 1 s / 1e4 J/K = 0.02 K in the 1 s ramp; 2.736 J/K
    (7.2 g of bronze): the ring, heated by the films, lags below its steady temperature and above the frozen one,
    so the films run cooler than quasi-static (the ring takes up heat) — a direction, not a number."""
    _, frozen, *_ = ring_lag(TC, T, RPM, _supply(1e4))
    assert np.abs(frozen - frozen[:, :1]).max() < 0.02
    _, ring, inner, *_ = ring_lag(TC, T, RPM, _supply(2.736))
    qs = thermal_losses(TC, [RPM[-1]], OIL, T_S)
    steady = qs["ring temperature [K]"].to_numpy()
    assert np.all(frozen[:, -1] < ring[:, -1]) and np.all(ring[:, -1] < steady)
    assert np.all(inner[:, -1] < qs["inner film temperature [K]"].to_numpy())


def test_the_heat_into_the_ring_is_what_it_stores():
    """Energy conservation of the ring: ∫ Q_ring dt = m_R c_R (T_R(end) − T_R(0)). The trapezoidal integral of the
    49 samples has a relative error ~ (Δt)² T''/12 ≈ 1e-4 (Q varies smoothly on the 0.55 s time scale); LSODA's
    rtol is 1e-8: 1e-3 relative."""
    cap = 2.736
    t, ring, *_, heat = ring_lag(TC, T, RPM, _supply(cap))
    stored = cap * (ring[:, -1] - ring[:, 0])
    np.testing.assert_allclose(np.trapezoid(heat, t, axis=1), stored, rtol=1e-3)
    assert np.all(stored > 1.0)  # (the ring heats by several K: the check is not 0 = 0)


def test_the_run_up_table_takes_the_lag_and_refuses_what_it_cannot_serve():
    """The lagged table of a ramp is ring_lag's viscosities at the table's speeds (interpolated in time: within the
    LSODA tolerance, 1e-6 relative); with a negligible capacity it is the quasi-static table (5e-4, as above); a
    torque-driven or a non-monotonic profile is refused."""
    prof = SpeedProfile.ramp(20e3, 250e3, 1.0)
    speeds, table = lagged_viscosity_table(TC, prof, _supply(2.736))
    rpm = speeds / (2 * np.pi / 60)
    _, *_, mu, _ = ring_lag(TC, (rpm - 20e3) / 230e3, rpm, _supply(2.736))
    np.testing.assert_allclose(table, mu, rtol=1e-6)
    qs_speeds, qs_table = viscosity_table(TC, prof.omega / (2 * np.pi / 60), _supply(None))
    np.testing.assert_allclose(lagged_viscosity_table(TC, prof, _supply(1e-3))[1], qs_table, rtol=5e-4)
    assert not np.allclose(table, qs_table, rtol=5e-3)  # the real ring's lag moves the viscosities by 1-5 %
    with pytest.raises(ParameterError, match="cannot take ring_heat_capacity_J_K: the rings' temperatures as states"):
        frb.runup(TC, profile=SpeedProfile.torque(0.05, 20e3, 0.01), oil_supply=_supply(2.736))
    with pytest.raises(ParameterError, match="ring_heat_capacity_J_K = -1.0 J/K is invalid"):
        ThermalModel(ring_heat_capacity_J_K=-1.0)
