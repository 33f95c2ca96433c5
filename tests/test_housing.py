"""Housing motion (base excitation) in the one monolithic model: the equations in the frame of a translating rigid
bearing housing (docs/theory/housing.md). Checks: a housing at rest is the former fixed-housing model to round-off
(stored output of the commit before the housing terms, tests/reference/make_fixed_housing.py); a housing accelerating
upwards by g without gravity is gravity with a fixed housing; the right-hand side's inertial load is −M T a_h on the
rotor and −m a_h on the rings, against an independent assembly with numpy."""
import json
from pathlib import Path

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.nonlinear.runup import SpeedProfile, Unbalance, build_problem, initial_state

REFERENCE = Path(__file__).resolve().parent / "reference" / "fixed_housing.json"


@pytest.mark.parametrize("case", ["ramp", "torque"])
def test_housing_at_rest_is_the_former_fixed_housing_model(case):
    """dy/dt at 9 states of the former model (commit 5fe3afe, tests/reference/make_fixed_housing.py) equals the
    present right-hand side with the housing at rest, to round-off. It was bit for bit until the compiled sums were
    allowed to be reordered (frbmodel.core.linalg.SUM_FLAGS) and the film force kernel computed cos α, sin α without
    atan2. The rotor's acceleration rows are held to 2 (n − 1) ε_mach Σ|terms| + 1e-12 |M⁻¹| |f| (a sum of n terms
    errs by at most (n − 1) ε Σ|terms| in any order, n = 48: 16 DoFs × 3 matrices; the film forces in f agree with
    their former arithmetic to 1e-12 over 20 000 random states); measured 0.61 ε Σ|terms|. Every other row is held to
    1e-11 of its largest value (the rings' rows are differences of two films' forces and torques); measured 3e-12.
    A housing term at rest, or any other change of the equations, would be far larger."""
    ref = json.loads(REFERENCE.read_text())["cases"][case]
    profile, unb = {"ramp": (SpeedProfile.ramp(30e3, 32e3, 4e-3), [Unbalance("turbine_wheel", 2e-6, 0.3)]),
                    "torque": (SpeedProfile.torque(0.05, 40e3, 4e-3), [])}[case]
    tc = frb.turbocharger(outer_clearance=36e-6)
    p = build_problem(tc, profile, "short", unb)
    assert not p.housing_acc.any()
    n_r = p.n_rotor
    _, mk, mg = tc.rotor.acceleration_matrices
    minv, minv_k, minv_g = (np.abs(a) for a in tc.rotor.acceleration_matrices)
    got = np.array([p.rhs(t, np.array(y), np.empty(len(y))).copy() for t, y in zip(ref["t"], ref["y"])])
    want = np.array(ref["dydt"])
    big = np.abs(want).max(axis=0)
    for y, g, w in zip(np.array(ref["y"]), got, want):
        q, qd, omega = y[:n_r], y[n_r:2 * n_r], w[2 * n_r + 10]
        omega_dot = w[-1] if case == "torque" else (32e3 - 30e3) * np.pi / 30 / 4e-3
        force = tc.rotor.M @ (w[n_r:2 * n_r] + mk @ q + mg @ (omega_dot * q + omega * qd))  # the nodal load
        loads = minv @ np.abs(force)
        terms = loads + minv_k @ np.abs(q) + minv_g @ (abs(omega_dot) * np.abs(q) + abs(omega) * np.abs(qd))
        bound = 2 * 47 * np.finfo(float).eps * terms + 1e-12 * loads
        np.testing.assert_array_less(np.abs(g[n_r:2 * n_r] - w[n_r:2 * n_r]), bound)
        rest = np.r_[0:n_r, 2 * n_r:w.size]
        np.testing.assert_array_less(np.abs(g[rest] - w[rest]), 1e-11 * big[rest] + 1e-300)


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


# ---------------------------------------------------------------------------------------------- through the FMU
def _slave(built, name, tmp, params):
    pytest.importorskip("fmpy")
    from _fmu import Slave

    return Slave(built / "fmus" / "FloatingRingTurbocharger.fmu", name, tmp, params)


def _constant(rpm, **kw):
    w = rpm * 2 * np.pi / 60
    return {"speed_start": w, "speed_end": w, **kw}


def test_stepped_upward_housing_acceleration_is_gravity():
    """The stepped turbocharger (the FMU's component) with gravity off and a housing acceleration of +g upwards
    equals it with gravity on and the housing at rest, from the same state (30 krpm, 20 ms at 1 ms steps): within
    1e-9 of the clearance (M T g and M a_g are added in another order: round-off, grown by the unstable modes)."""
    from frbmodel.nonlinear.turbocharger_component import TurbochargerComponent

    tc = frb.turbocharger()
    w = 30e3 * np.pi / 30
    a = TurbochargerComponent(tc, "ramp", w, w, 1.0)
    b = TurbochargerComponent(tc.with_(gravity=0.0), "ramp", w, w, 1.0)
    b.y[:] = a.y
    out_a, out_b = [], []
    for _ in range(20):
        a.step(1e-3)
        b.step(1e-3, housing_acc=(0.0, tc.gravity))
        out_a.append(a.outputs().copy())
        out_b.append(b.outputs().copy())
    np.testing.assert_allclose(b.y[:2 * tc.rotor.n_dof], a.y[:2 * tc.rotor.n_dof], rtol=0,
                               atol=1e-9 * 36e-6 * 3e4)  # displacements and velocities (x 30 000 rad/s)
    # (from the second step on: the first step's smallest film thickness includes b's own start, replaced above)
    np.testing.assert_allclose(np.array(out_b)[1:], np.array(out_a)[1:], rtol=1e-7, atol=1e-9 * 36e-6)
    assert abs(a.y[1] - a.y[1 + 4]) > 0 and np.abs(np.array(out_a)[:, 5]).max() > 1.0  # loaded: forces of Newtons


def test_fmu_settled_housing_forces_carry_the_weights(built, tmp_path):
    """Below the first Hopf point (1500 rpm, every mode damped: slowest decay time 0.23 s) the FMU settles from the
    run-up's 5 % offset onto the equilibrium: after 1 s each bearing's housing force is (0, -(R_b + m_ring g)) with
    R_b the static reaction (tc.bearing_loads), and both together carry rotor and rings: -(m_rotor + Σ m_ring) g.
    Tolerance 1e-4 of the weight: the offset's force, decayed by e^-(1 s / 0.23 s), is below it (measured 2.5e-7)."""
    tc = frb.turbocharger()
    s = _slave(built, "settle", tmp_path, _constant(1500))
    names = [f"{b.name}_bearing.housing_force.{q}" for b in tc.bearings for q in "xy"]
    _, f = s.run(1e-2, 1.0, names)
    s.close()
    end = f[-1].reshape(2, 2)
    weight = (tc.rotor.mass + sum(b.ring_mass for b in tc.bearings)) * tc.gravity
    want = [-(r + b.ring_mass * tc.gravity) for r, b in zip(tc.bearing_loads, tc.bearings)]
    np.testing.assert_allclose(end[:, 1], want, rtol=0, atol=1e-4 * weight)
    np.testing.assert_allclose(end[:, 0], 0.0, rtol=0, atol=1e-4 * weight)
    assert end[:, 1].sum() == pytest.approx(-weight, abs=1e-4 * weight)
    assert np.abs(f[:, 1::2] - want).max() > 2e-4 * weight  # it did have to settle (5 % offset: 1.9e-3 N after 10 ms)


def test_fmu_harmonic_housing_acceleration_gives_the_linear_response(built, tmp_path):
    """A small harmonic housing acceleration a_y = A sin(Ωt) (A = 0.2 m/s², 120 Hz) at 1500 rpm: the journals' steady
    response equals that of the linearized system of method J at that speed, (K − Ω²M + iΩC) X = −M T A (the
    project's linear machinery, frb.linear_system), within 2 % in amplitude (the acceptance bound) and 0.02 rad in
    phase. The input is set to its value at each step's midpoint (a zero-order hold without the half-step lag);
    the response is fitted over 0.25 ... 0.45 s with a linear drift for what is left of the start transient."""
    tc = frb.turbocharger()
    A, f_hz, h = 0.2, 120.0, 5e-5
    Om = 2 * np.pi * f_hz
    s = _slave(built, "harmonic", tmp_path, _constant(1500, perturbation=0.0))
    names = [f"{b.name}_bearing.journal.{q}" for b in tc.bearings for q in "xy"]
    ts, q = s.run(h, 0.45, names, inputs=lambda t: {"housing_acceleration.y": A * np.sin(Om * (t + h / 2))},
                  every=2.5e-4)
    s.close()
    keep = ts >= 0.25
    basis = np.column_stack([np.ones(keep.sum()), ts[keep], np.cos(Om * ts[keep]), np.sin(Om * ts[keep])])
    coef = np.linalg.lstsq(basis, q[keep], rcond=None)[0]
    got = coef[3] + 1j * coef[2]  # q = Im(X e^{iΩt}) = Re X sin + Im X cos
    ls = frb.linear_system(tc, "J", 1500)
    n = ls.M.shape[0]
    T = np.zeros(n)
    T[1:tc.rotor.n_dof:4] = 1.0  # every w DoF
    T[tc.rotor.n_dof + 1::2] = 1.0  # the rings' y
    X = np.linalg.solve(ls.K - Om ** 2 * ls.M + 1j * Om * ls.C, -ls.M @ T * A)
    want = np.array([X[4 * b.node + k] for b in tc.bearings for k in (0, 1)])
    big = np.abs(want) > 0.1 * np.abs(want).max()  # amplitude and phase where the response is not ~0
    np.testing.assert_allclose(np.abs(got[big]), np.abs(want[big]), rtol=0.02)
    assert np.abs(np.angle(got[big] / want[big])).max() < 0.02
