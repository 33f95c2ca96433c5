"""Housing motion (base excitation) in the one monolithic model: the equations in the frame of a translating rigid
bearing housing (docs/theory/housing.md). Checks: a housing at rest is the former fixed-housing model bit for bit
(stored output of the commit before the housing terms, tests/reference/make_fixed_housing.py); a housing accelerating
upwards by g without gravity is gravity with a fixed housing; the right-hand side's inertial load is −M T a_h on the
rotor and −m a_h on the rings, against an independent assembly with numpy."""
import json
from pathlib import Path

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.runup import SpeedProfile, Unbalance, build_problem, initial_state

REFERENCE = Path(__file__).resolve().parent / "reference" / "fixed_housing.json"


@pytest.mark.parametrize("case", ["ramp", "torque"])
def test_housing_at_rest_is_the_former_fixed_housing_model_bit_for_bit(case):
    """dy/dt at 9 states of the former model (commit 5fe3afe, tests/reference/make_fixed_housing.py) equals the
    present right-hand side with the housing at rest, exactly (the same floating-point operations)."""
    ref = json.loads(REFERENCE.read_text())["cases"][case]
    profile, unb = {"ramp": (SpeedProfile.ramp(30e3, 32e3, 4e-3), [Unbalance("turbine_wheel", 2e-6, 0.3)]),
                    "torque": (SpeedProfile.torque(0.05, 40e3, 4e-3), [])}[case]
    p = build_problem(frb.turbocharger(outer_clearance=36e-6), profile, "short", unb)
    assert not p.housing_acc.any()
    for t, y, want in zip(ref["t"], ref["y"], ref["dydt"]):
        y = np.array(y)
        np.testing.assert_array_equal(p.rhs(t, y, np.empty_like(y)), np.array(want))


def _rhs(problem, y, t=1e-3):
    out = np.empty_like(y)
    return problem.rhs(t, y, out).copy()


def _state(problem):
    """A state off equilibrium: the start state with random velocities (films loaded, rotor moving)."""
    y = initial_state(problem)
    rng = np.random.default_rng(3)
    n_r = problem.n_rotor
    y[n_r:2 * n_r] += rng.normal(size=n_r) * 1e-3
    return y


def test_inertial_load_of_the_housing_frame_against_numpy():
    """dy/dt with a_h minus dy/dt at rest = the rotor's −M⁻¹ M T a_h = −T a_h (every translational DoF accelerates
    by −a_h, rotations not at all) and −a_h on each ring's velocity rows; nothing else changes (the films see only
    relative kinematics)."""
    tc = frb.turbocharger()
    p = build_problem(tc, SpeedProfile.constant(30e3, 0.1), "short", [Unbalance("turbine_wheel", 1e-6)])
    y = _state(p)
    at_rest = _rhs(p, y)
    a_h = np.array([3.7, -12.5])
    p.housing_acc[:] = a_h
    moved = _rhs(p, y)
    d = moved - at_rest
    n_r = p.n_rotor
    want = np.zeros_like(d)
    want[n_r:2 * n_r:4], want[n_r + 1:2 * n_r:4] = -a_h[0], -a_h[1]  # M⁻¹ (−M T a_h) = −T a_h
    for b in range(2):
        r = p.ring_index(b)
        want[r + 2:r + 4] = -a_h
    np.testing.assert_allclose(d, want, rtol=0, atol=1e-9 * np.abs(a_h).max())  # M⁻¹M round-off (cond(M) ~ 1e7)


def test_upward_housing_acceleration_without_gravity_is_gravity_with_a_fixed_housing():
    """a_h = (0, +g) with gravity off loads every mass with −m g in y: the same equations as gravity on and a fixed
    housing (the same rounding is not expected: M T a_h is subtracted, M a_g was added)."""
    tc = frb.turbocharger()
    prof = SpeedProfile.constant(30e3, 0.1)
    with_gravity = build_problem(tc, prof, "short")
    weightless = build_problem(tc.with_(gravity=0.0), prof, "short")
    weightless.housing_acc[:] = [0.0, tc.gravity]
    y = _state(with_gravity)
    a, b = _rhs(with_gravity, y), _rhs(weightless, y)
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-9)  # round-off of M⁻¹ applied to the two loads
