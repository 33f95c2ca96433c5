"""The compiled Rosenbrock integrator (frbmodel.nonlinear.rosenbrock): linear algebra, Jacobian, and accuracy against
the
matrix exponential of a linear model."""
import numpy as np
import pytest
from scipy.linalg import expm

import frbmodel as frb
from frbmodel.core.linalg import lu_factor, lu_solve
from frbmodel.nonlinear.rosenbrock import FD_TYPICAL_M, NO_MODAL, film_columns, jacobian, rodas_chunk
from frbmodel.nonlinear.runup import (
    RPM,
    SpeedProfile,
    Unbalance,
    atol_vector,
    build_problem,
    initial_state,
    modal_error_basis,
    runup,
    typical_sizes,
)


def test_lu_solves_like_lapack():
    """Partial-pivoting LU of a random, badly scaled 43 x 43 matrix: the solution equals numpy's (LAPACK) to
    round-off (condition ~1e6 here: 1e-8 relative leaves room)."""
    rng = np.random.default_rng(3)
    a = rng.normal(size=(43, 43)) * np.logspace(-3, 3, 43)[None, :]
    b = rng.normal(size=43)
    lu, piv = a.copy(), np.zeros(43, dtype=np.int64)
    assert lu_factor(lu, piv)
    x = b.copy()
    lu_solve(lu, piv, x)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-8)


@pytest.mark.parametrize("torque", [False, True], ids=["prescribed", "torque"])
def test_jacobian_rotor_block_exact_and_film_columns_by_differences(torque):
    """The rotor columns equal the operators of M q'' + (Omega G) q' + (K + Omega' G) q formed here from the rotor's
    M, K, G (q'' rows: -M^-1 (K + Omega' G), -Omega M^-1 G; q' rows: identity), to round-off; the film columns equal
    central differences with steps of 1e-4 of a nanometre-sized perturbation (truncation (h/c)^2 ~ 1e-8, round-off
    eps |f| / h <= 1e-5 of a column), within 1e-4 of each column's largest entry (the forward differences' own
    error ~ sqrt(eps))."""
    tc = frb.turbocharger(36e-6)
    prof = SpeedProfile.torque(2e-3, 60e3, 0.1) if torque else SpeedProfile.ramp(20e3, 80e3, 0.1)
    p = build_problem(tc, prof, tc.film_model, [Unbalance("turbine_wheel", 1e-6, 0.2)])
    n, n_r, t = p.n_states, p.n_rotor, 0.03
    y = initial_state(p) * (1 + 1e-2 * np.cos(np.arange(n)))
    y[n_r:2 * n_r] += 1e-3 * np.sin(np.arange(n_r))  # moving rotor
    scale = typical_sizes(p, FD_TYPICAL_M)
    f0 = p.rhs(t, y, np.empty(n)).copy()
    omega = f0[2 * n_r + 10]
    omega_dot = f0[-1] if torque else float(np.interp(t, p.profile.t, p.profile.omega_dot))
    cols = film_columns(n_r, p.args[3], torque, True)
    jac = np.empty((n, n))
    jacobian(t, y, f0, jac, np.empty(n), np.empty(n), cols, scale, omega, omega_dot, p.args)
    M, K, G = tc.rotor.M, tc.rotor.K, tc.rotor.G
    stiff, gyro = -np.linalg.solve(M, K + omega_dot * G), -omega * np.linalg.solve(M, G)
    for k in set(range(2 * n_r)) - set(cols.tolist()):
        want = np.zeros(n)
        if k < n_r:
            want[n_r:2 * n_r] = stiff[:, k]
        else:
            want[k - n_r] = 1.0
            want[n_r:2 * n_r] = gyro[:, k - n_r]
        np.testing.assert_allclose(jac[:, k], want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    typical = atol_vector(p, 1e-5)[0]
    for k in cols:
        h = 1e-4 * typical[k]
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        ref = (p.rhs(t, yp, np.empty(n)).copy() - p.rhs(t, ym, np.empty(n))) / (2 * h)
        np.testing.assert_allclose(jac[:, k], ref, rtol=0, atol=1e-4 * np.abs(ref).max())


@pytest.mark.parametrize("modal", [False, True])
def test_linear_model_equals_matrix_exponential(modal):
    """With the journals on linear springs k_s at constant speed Omega the rotor is linear and time-invariant,
    z' = A z + b with A = [[0, I], [-M^-1 (K + K_s), -Omega M^-1 G]] and b the gravity load, formed here from the
    rotor's M, K, G: its exact solution is expm. RODAS at rtol 1e-8 must follow it at every output time (most between
    steps: the continuous output) within 1e-5 of the journal's motion (the undamped high modes, up to 52 kHz, are
    excited by the initial offset and resolved to the tolerance; measured 3e-7 over 3.7e4 steps), with the error
    norm per state and with the rotor's part in free-free modal coordinates (frb.runup's, modal_error_basis)."""
    tc = frb.turbocharger(36e-6)
    k_s, speed = 1e6, 30e3
    p = build_problem(tc, SpeedProfile.constant(speed, 0.01), tc.film_model, linear_springs=k_s)
    y0 = initial_state(p)
    n_r = p.n_rotor
    t = np.linspace(0.0, 0.01, 201)
    basis, atol = modal_error_basis(p, atol_vector(p, 1e-13)[0]) if modal else (NO_MODAL, atol_vector(p, 1e-13)[0])
    out, k, h, steps, rejected, status = rodas_chunk(
        y0, t, 1e-7, 1e-8, atol, typical_sizes(p, FD_TYPICAL_M),
        film_columns(n_r, p.args[3], False, False), 10**7, 1.0, p.args, basis)
    assert status == 0 and k == t.size
    M, K, G = tc.rotor.M, tc.rotor.K.copy(), tc.rotor.G
    for b in tc.bearings:
        K[4 * b.node, 4 * b.node] += k_s
        K[4 * b.node + 1, 4 * b.node + 1] += k_s
    aug = np.zeros((2 * n_r + 1, 2 * n_r + 1))
    aug[:n_r, n_r:2 * n_r] = np.eye(n_r)
    aug[n_r:2 * n_r, :n_r] = -np.linalg.solve(M, K)
    aug[n_r:2 * n_r, n_r:2 * n_r] = -speed * RPM * np.linalg.solve(M, G)
    aug[n_r:2 * n_r, -1] = np.linalg.solve(M, tc.rotor.gravity_load(tc.gravity))
    exact = np.array([(expm(aug * s) @ np.append(y0[:2 * n_r], 1.0))[:2 * n_r] for s in t])
    j = 4 * tc.bearings[0].node
    size = np.ptp(exact[:, j])
    assert size > 1e-7
    np.testing.assert_allclose(out[:, 2 * n_r + 10], speed * RPM * t, rtol=1e-9)  # rotation angle: exact
    if not modal:
        np.testing.assert_allclose(out[:, j], exact[:, j], rtol=0, atol=1e-5 * size)
        np.testing.assert_allclose(out[:, :2 * n_r], exact, rtol=0, atol=1e-5 * np.ptp(exact, axis=0).max())
        return
    # the modal norm holds every free-free mode to the same amplitude tolerance, so the error of each mode stays
    # below the sum of the local tolerances (steps x atol: errors of a non-growing linear mode add at most
    # linearly; measured 8.9e-11 m at the 28.6 kHz pair, 1.2e-9 m bound), and the modes below 15 kHz (the rigid
    # and the first bending modes, which carry the journal's motion) within 1e-5 of it (measured 2.5e-13 m)
    freq_hz = np.sort(np.sqrt(np.clip(np.linalg.eigvals(p.args[0][1]).real, 0, None))) / (2 * np.pi)  # basis order
    err = np.abs((out[:, :n_r] - exact[:, :n_r]) @ basis.T).max(axis=0)
    assert np.all(err <= steps * 1e-13), err
    assert np.all(err[freq_hz < 15e3] <= 1e-5 * size), (freq_hz, err)


def test_rodas_failure_keeps_the_results():
    """A step budget too small for the run stops the compiled Rosenbrock solver: status "stopped" with the time
    reached, the samples before it kept."""
    tc = frb.turbocharger(36e-6)
    with pytest.raises(frb.RunupStopped, match="step budget exhausted: more than nsteps = 1 solver steps") as exc:
        runup(tc, speed_rpm=(20e3, 25e3), duration=0.01, nsteps=1)
    assert exc.value.result.status == "stopped" and exc.value.result.time.size >= 1
