"""Ring torques and ring-speed ratios: closed forms (6), (7), torque balance, wall-shear integration."""
import math

import numpy as np
import pytest
from _reference import short_pressure_theta
from scipy.optimize import brentq

import frbmodel as frb
from frbmodel.physics.bearing import ring_torque
from frbmodel.physics.film import film_force, film_torques


def eq6(b):
    """Paper eq. (6), written independently from its geometric form."""
    ratio = (b.outer.viscosity / b.inner.viscosity) * (b.outer.length / b.inner.length) * \
        (b.inner.clearance / b.outer.clearance) * (b.outer.radius / b.inner.radius) ** 3
    return 1.0 / (1.0 + ratio)


def eq7(b, ei, eo):
    ratio = (b.outer.viscosity * b.outer.length * b.outer.radius ** 3 * b.inner.clearance * math.sqrt(1 - ei ** 2)) / \
        (b.inner.viscosity * b.inner.length * b.inner.radius ** 3 * b.outer.clearance * math.sqrt(1 - eo ** 2))
    return 1.0 / (1.0 + ratio)


@pytest.mark.parametrize("co,rsr", [(36e-6, 0.19903), (40e-6, 0.21636), (42e-6, 0.22475), (46e-6, 0.24100)])
def test_rsr_eq6_reference_values(co, rsr):
    for b in frb.turbocharger(co).bearings:
        assert frb.ring_speed_ratio(b) == pytest.approx(rsr, abs=5e-6)  # table has 5 decimals
        assert frb.ring_speed_ratio(b) == pytest.approx(eq6(b), rel=1e-14)


def _balance(b, ei, eo, offset, wr=10000.0):
    """Solve total ring torque = 0 for the ring speed with the *dynamic* film force and torque functions."""
    def torque(wfr):
        ri = np.array([0.0, -ei * b.inner.clearance])  # journal below the ring centre
        ro = np.array([eo * b.outer.clearance, 0.0])
        fi = film_force(b.inner, ri, [0, 0], wr + wfr) if offset else np.zeros(2)
        fo = film_force(b.outer, ro, [0, 0], wfr) if offset else np.zeros(2)
        return ring_torque(b, ri, fi, ro, fo, wr, wfr)
    return brentq(torque, 1e-6 * wr, wr, xtol=1e-14 * wr, rtol=1e-15) / wr


def test_torque_balance_reproduces_eq6_and_eq7():
    b = frb.turbocharger(36e-6).bearings[0]
    # ε = 0: offset terms vanish, full balance = (6)
    assert _balance(b, 0.0, 0.0, True) == pytest.approx(eq6(b), rel=1e-12)
    # Petroff terms only at nonzero ε = (7)
    for ei, eo in [(0.2, 0.4), (0.6, 0.1), (0.05, 0.8)]:
        assert _balance(b, ei, eo, False) == pytest.approx(eq7(b, ei, eo), rel=1e-12)
        assert frb.ring_speed_ratio(b, ei, eo) == pytest.approx(eq7(b, ei, eo), rel=1e-13)
        # the full balance brakes the ring further (offset torques brake, docs/theory/rings.md#torques-on-the-ring)
        assert _balance(b, ei, eo, True) < eq7(b, ei, eo)


def test_explicit_full_rsr_equals_dynamic_torque_root():
    b = frb.turbocharger(36e-6).bearings[0]
    for ei, eo in [(0.3, 0.4), (0.7, 0.2)]:
        # the explicit formula puts the inner film on the −y side for any direction: torques are invariant
        assert frb.ring_speed_ratio(b, ei, eo, torque="full") == pytest.approx(_balance(b, ei, eo, True), rel=1e-9)


def test_wall_torques_equal_numerical_wall_shear():
    """Integrate the wall shear of u(y) = p_x (y² − y h)/(2μ) + U1 (1 − y/h) + U2 y/h numerically."""
    rng = np.random.default_rng(11)
    f = frb.turbocharger().bearings[0].inner
    th = np.linspace(0, 2 * np.pi, 200001)[:-1]
    dth = th[1] - th[0]
    for _ in range(10):
        eps = rng.uniform(0.05, 0.8)
        ang = rng.uniform(0, 2 * np.pi)
        r = eps * f.clearance * np.array([math.cos(ang), math.sin(ang)])
        rdot = rng.normal(0, 1, 2) * f.clearance * 300
        w1, w2 = rng.uniform(500, 3000), rng.uniform(0, 600)
        P, h = short_pressure_theta(f, r, rdot, w1 + w2, th)
        dP = (np.roll(P, -1) - np.roll(P, 1)) / (2 * dth)
        R, mu, L = f.radius, f.viscosity, f.length
        dU = (w2 - w1) * R
        # inner wall: τ = −h p_x/2 + μ ΔU/h ; outer wall: τ = −h p_x/2 − μ ΔU/h ; torque arm R, area R dθ dz
        t_in = R * R * np.sum(-h * dP / (2 * R) + mu * dU * L / h) * dth
        t_out = R * R * np.sum(-h * dP / (2 * R) - mu * dU * L / h) * dth
        F = film_force(f, r, rdot, w1 + w2)
        ti, to = film_torques(f, r, F, w1, w2)
        # 2e5-point periodic rule with central differences: ~1e-7 relative, the kink of the clipped
        # pressure at the cavitation boundary limits it to ~1e-5
        assert ti == pytest.approx(t_in, rel=2e-4)
        assert to == pytest.approx(t_out, rel=2e-4)
        # moment balance of the film (docs/theory/rings.md#wall-torques-of-one-film)
        assert ti + to == pytest.approx(-(r[0] * F[1] - r[1] * F[0]), rel=1e-12)
