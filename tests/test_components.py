"""Co-simulation components (the physics behind the FMUs): ring integrator order, journal path extrapolation,
staggered coupling force model."""
import math

import numpy as np
import pytest
from _reference import quadrature_film_force
from scipy.integrate import solve_ivp

import frbmodel as frb
from frbmodel.nonlinear.components import BearingComponent, JournalHistory, RotorComponent, ramp_speed
from frbmodel.physics.bearing import ring_rhs_kernel


def _whirling_bearing(rpm=150e3):
    """The turbine bearing at its method-J equilibrium with the journal whirling on a 10 µm circle at 400 Hz
    (a developed whirl of the size seen in the run-ups)."""
    tc = frb.turbocharger(36e-6)
    b = tc.bearings[0]
    eq = frb.equilibrium(tc, "J", rpm).bearings[0]
    bc = BearingComponent(b, tc.film_model)
    bc.ring[:] = [eq.ring[0], eq.ring[1], 0.0, 0.0, eq.ring_speed]
    w = 2 * math.pi * 400.0
    r = 10e-6

    def journal(t):
        return np.array([eq.journal[0] + r * math.cos(w * t), eq.journal[1] + r * math.sin(w * t),
                         -r * w * math.sin(w * t), r * w * math.cos(w * t)])

    journal.centre = np.asarray(eq.journal)
    return bc, journal, w, rpm * math.pi / 30


def _reference_ring(bc, path, omega, H):
    """The ring over [0, H] on the quadratic journal path, by scipy's Radau at tight tolerances (an independent
    integrator of the same right-hand side)."""
    d = np.empty(5)

    def rhs(t, y):
        jx = path[0] + path[2] * t + 0.5 * path[4] * t * t
        jy = path[1] + path[3] * t + 0.5 * path[5] * t * t
        ring_rhs_kernel(*bc._args(), jx, jy, path[2] + path[4] * t, path[3] + path[5] * t, y, omega, 0.999, d)
        return d.copy()

    scale = np.array([1e-9, 1e-9, 1e-5, 1e-5, 1e-6])
    sol = solve_ivp(rhs, (0.0, H), bc.ring.copy(), method="Radau", rtol=1e-11, atol=scale)
    return sol.y[:, -1]


def test_ring_integrator_is_second_order_and_accurate_at_the_default_substep():
    bc, journal, w, omega = _whirling_bearing()
    H = 1e-4  # a long window so that the integration error is well above the reference's
    j0 = journal(0.0)
    a = -w * w * (j0[:2] - journal.centre)  # centripetal
    ring0 = bc.ring.copy()
    ref = _reference_ring(bc, np.concatenate([j0, a]), omega, H)
    errs = []
    for sub in (H / 4, H / 8, H / 16):
        bc.ring[:] = ring0
        bc.substep = sub
        bc.step(j0, omega, 0.0, H, accel=a)
        errs.append(np.abs(bc.ring[:2] - ref[:2]).max())
    # second order: halving the substep divides the error by ~4 (3 ... 5.5 allows for the Newton tolerance and
    # the reference's own error)
    for e1, e2 in zip(errs, errs[1:]):
        assert 3.0 < e1 / e2 < 5.5, errs
    bc.ring[:] = ring0
    bc.substep = 5e-6  # the FMU default
    bc.step(j0, omega, 0.0, H, accel=a)
    # ring position error after 100 µs at the default substep: < 0.1 % of the outer clearance
    assert np.abs(bc.ring[:2] - ref[:2]).max() < 1e-3 * bc.bearing.outer.clearance


def test_force_end_is_the_film_force_at_the_end_of_the_path():
    """``force_end`` must be the inner-film force on the journal at the end of the quadratic journal path, with the
    ring where the step left it. Reference: the short-bearing Reynolds pressure of that end state integrated by
    brute-force quadrature (tests/_reference.py), not the force kernel the component uses."""
    bc, journal, w, omega = _whirling_bearing()
    assert bc.film_model == "short"  # the quadrature reference is the plain short π-film
    H = 1e-5
    j0 = journal(0.0)
    a = np.array([3.0, -2.0])
    bc.step(j0, omega, 0.0, H, accel=a)
    j1 = np.array([j0[0] + j0[2] * H + 0.5 * a[0] * H * H, j0[1] + j0[3] * H + 0.5 * a[1] * H * H,
                   j0[2] + a[0] * H, j0[3] + a[1] * H])
    ring = bc.ring  # x, y, vx, vy, ω_FR after the step
    expected = quadrature_film_force(bc.bearing.inner, j1[:2] - ring[:2], j1[2:] - ring[2:4], omega + ring[4])
    # quadrature to 1e-12 relative on smooth sub-intervals; 1e-9 leaves room for round-off, while any error in
    # the path end point (O(a H²) = 1e-10 m against e ~ 1e-5 m) or in the ring state shifts the force by > 1e-6
    np.testing.assert_allclose(bc.force_end, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
    np.testing.assert_array_equal(bc.path_accel, a)


def test_journal_history_path_is_third_order_on_a_whirl_orbit():
    """Quadratic path with the backward-difference acceleration: end-of-step position error O(H³) (linear
    path: O(H²))."""
    _, journal, w, _ = _whirling_bearing()
    errs_q, errs_l = [], []
    for H in (2e-5, 1e-5, 5e-6):
        hist = JournalHistory()
        t0 = 1e-3
        hist.update(t0 - H, journal(t0 - H))
        j0 = journal(t0)
        a = hist.acceleration(t0, j0, H)
        exact = journal(t0 + H)[:2]
        errs_q.append(np.abs(j0[:2] + j0[2:] * H + 0.5 * a * H * H - exact).max())
        errs_l.append(np.abs(j0[:2] + j0[2:] * H - exact).max())
    for e1, e2 in zip(errs_q, errs_q[1:]):
        assert 6.0 < e1 / e2 < 10.0  # third order: ratio 8
    for e1, e2 in zip(errs_l, errs_l[1:]):
        assert 3.0 < e1 / e2 < 5.0  # second order: ratio 4
    assert errs_q[0] < 0.2 * errs_l[0]


def test_journal_history_falls_back_to_a_linear_path():
    hist = JournalHistory()
    j = np.array([0.0, 0.0, 1.0, 2.0])
    np.testing.assert_array_equal(hist.acceleration(0.0, j, 1e-5), 0.0)  # first call
    hist.update(0.0, j)
    np.testing.assert_array_equal(hist.acceleration(1e-3, j, 1e-5), 0.0)  # gap of 100 steps
    np.testing.assert_array_equal(hist.acceleration(0.0, j, 1e-5), 0.0)  # time not increasing (a retried step)
    np.testing.assert_allclose(hist.acceleration(1e-5, j + [0, 0, 1e-3, 0], 1e-5), [100.0, 0.0])
    st = hist.state()
    h2 = JournalHistory()
    h2.set_state(st)  # FMU state round trip
    np.testing.assert_allclose(h2.acceleration(1e-5, j + [0, 0, 1e-3, 0], 1e-5), [100.0, 0.0])


def test_rotor_path_force_model_is_exact_for_a_force_linear_in_the_journal_state():
    """If the bearing force is exactly F = F0 − K (x − x_r) − C (v − v_r) (a linear spring-damper), the bearing
    reports F1 = F(x_p(H)) and the rotor's path model F0 + (F1 − F0) τ/H − K (x − x_p) − C (v − v_p) must reduce to
    that same linear law for any path acceleration: the rotor motion must not depend on ``a``."""
    tc = frb.turbocharger(36e-6)
    k, c = 2e6, 300.0
    K = [np.array([[k, 0.1 * k], [-0.1 * k, k]])] * 2
    C = [np.array([[c, 0.0], [0.0, c]])] * 2
    out = []
    for a in (np.zeros(2), np.array([50.0, -80.0])):
        rot = RotorComponent(tc, ramp_speed(50e3, 50e3, 1.0))
        rot.y[:rot.n] = 1e-6 * np.sin(np.arange(rot.n))
        rot.y[rot.n:] = 1e-3 * np.cos(np.arange(rot.n))
        refs = [rot.journal(b) for b in range(2)]
        F0 = [np.array([0.1, -3.0]), np.array([0.2, -4.0])]
        H = 1e-5
        F1 = []
        for b in range(2):
            xr, vr = refs[b][:2], refs[b][2:]
            xp = xr + vr * H + 0.5 * a * H * H
            vp = vr + a * H
            F1.append(F0[b] - K[b] @ (xp - xr) - C[b] @ (vp - vr))
        rot.step(H, F0, K, C, refs, path=(F1, [a, a]))
        out.append(rot.y.copy())
    # the τ² term of the path and the C·a term cancel exactly; only round-off remains
    np.testing.assert_allclose(out[1], out[0], rtol=1e-9, atol=1e-18)


def test_bad_acceleration_is_refused():
    bc, journal, _, omega = _whirling_bearing()
    with pytest.raises(frb.ParameterError, match="acceleration"):
        bc.step(journal(0.0), omega, 0.0, 1e-5, accel=(math.nan, 0.0))


def test_ring_newton_non_convergence_is_reported():
    """Issue #10: the ring integrator's Newton loop must not return unconverged silently. A 2 ms macro step drives
    the extrapolated journal path of a 400 Hz whirl far through the film (a τ²/2 ≈ 0.13 mm), where the stage
    equations have no nearby solution; a single allowed iteration cannot converge either. Both raise
    ConvergenceError naming the bearing, time and speed, and leave the ring state untouched."""
    bc, journal, w, omega = _whirling_bearing()
    j0 = journal(0.0)
    ring0 = bc.ring.copy()
    with pytest.raises(frb.ConvergenceError, match=r"turbine bearing: .*did not converge in 12 iterations at t = .* "
                                                   r"150000 rpm .*last correction"):
        bc.step(j0, omega, 0.0, 2e-3, t=0.0, accel=-w * w * (j0[:2] - journal.centre))
    np.testing.assert_array_equal(bc.ring, ring0)
    bc.newton_max_iter = 1
    with pytest.raises(frb.ConvergenceError, match="did not converge in 1 iterations"):
        bc.step(j0, omega, 0.0, 1e-5)
    np.testing.assert_array_equal(bc.ring, ring0)
    bc.newton_max_iter = 12  # the default converges on the same step
    bc.step(j0, omega, 0.0, 1e-5)


def test_rotor_blow_up_is_an_integration_error():
    """A numerical blow-up (here a linearly unstable negative support stiffness whose growth overflows) is an
    IntegrationError (an ArithmeticError), not a ParameterError: the input was valid, the integration failed."""
    from frbmodel.core.errors import IntegrationError

    tc = frb.turbocharger(36e-6)
    rot = RotorComponent(tc, ramp_speed(50e3, 50e3, 1.0))
    rot.y[0] = 1e-6
    K, C, F = [np.eye(2) * -1e9] * 2, [np.zeros((2, 2))] * 2, [np.zeros(2)] * 2
    with pytest.raises(IntegrationError, match="non-finite") as info:
        for _ in range(2000):
            rot.step(1e-5, F, K, C)
    assert isinstance(info.value, ArithmeticError) and not isinstance(info.value, frb.ParameterError)
    assert np.isfinite(rot.y).all()  # the state is left at the start of the failed step
