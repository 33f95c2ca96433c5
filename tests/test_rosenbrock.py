"""The compiled Rosenbrock integrator (frbmodel.nonlinear.rosenbrock): linear algebra, Jacobian, and accuracy against
the matrix exponential of a linear model."""
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


def _spring_rotor_generator(tc, k_s, speed, n_r):
    """The generator of the linear rotor on springs k_s [N/m] at the bearings, at constant speed [rpm], with gravity
    as an extra constant state: d/dt (q, q̇, 1) = aug (q, q̇, 1) (its matrix exponential is the exact flow)."""
    M, K, G = tc.rotor.M, tc.rotor.K.copy(), tc.rotor.G
    for b in tc.bearings:
        K[4 * b.node, 4 * b.node] += k_s
        K[4 * b.node + 1, 4 * b.node + 1] += k_s
    aug = np.zeros((2 * n_r + 1, 2 * n_r + 1))
    aug[:n_r, n_r:2 * n_r] = np.eye(n_r)
    aug[n_r:2 * n_r, :n_r] = -np.linalg.solve(M, K)
    aug[n_r:2 * n_r, n_r:2 * n_r] = -speed * RPM * np.linalg.solve(M, G)
    aug[n_r:2 * n_r, -1] = np.linalg.solve(M, tc.rotor.gravity_load(tc.gravity))
    return aug

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


@pytest.mark.parametrize("films", [False, True], ids=["kernels", "films"])
@pytest.mark.parametrize("torque", [False, True], ids=["prescribed", "torque"])
def test_jacobian_rotor_block_exact_and_film_columns_by_differences(torque, films):
    """The rotor columns equal the operators of M q'' + (Omega G) q' + (K + Omega' G) q formed here from the rotor's
    M, K, G (q'' rows: -M^-1 (K + Omega' G), -Omega M^-1 G; q' rows: identity), to round-off; the film columns equal
    central differences with steps of 1e-4 of a nanometre-sized perturbation (truncation (h/c)^2 ~ 1e-8, round-off
    eps |f| / h <= 1e-5 of a column), within 1e-4 of each column's largest entry (the forward differences' own
    error ~ sqrt(eps)). The same for the columns of each film differenced alone in its own inputs (``films``, the
    fast RODAS variant; a torque-driven rotor keeps the bearing kernels' differences)."""
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
    jacobian(t, y, f0, jac, np.empty(n), np.empty(n), cols, scale, omega, omega_dot, p.args, films)
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
    aug = _spring_rotor_generator(tc, k_s, speed, n_r)
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


def _trees(order):
    """Every rooted tree with ``order`` vertices, as a sorted tuple of its root's subtrees (() is the single vertex)."""
    if order == 1:
        return [()]
    out = set()

    def forests(n, smallest):  # multisets of trees with n vertices in total, non-decreasing (by repr)
        if n == 0:
            yield ()
            return
        for k in range(1, n + 1):
            for t in _trees(k):
                if smallest is None or repr(t) >= repr(smallest):
                    for rest in forests(n - k, t):
                        yield (t,) + rest

    for f in forests(order - 1, None):
        out.add(tuple(sorted(f, key=repr)))
    return sorted(out, key=repr)


def _density(tree):
    """γ(t) of a rooted tree: its order times its subtrees' densities (Butcher); the exact solution's B-series
    coefficient of the tree is 1 / γ(t)."""
    n = 1 + sum(_order(s) for s in tree)
    return n * np.prod([_density(s) for s in tree]) if tree else 1.0


def _order(tree):
    return 1 + sum(_order(s) for s in tree)


def _weights(tree, alpha, beta):
    """Elementary weights Φ_j(t) of a Rosenbrock method, per stage (Hairer & Wanner II, Sect. IV.7): a vertex with
    one child takes Σ_k β_jk Φ_k (β = α + Γ with the diagonal γ: the Jacobian acts there), a vertex with several
    children the product over them of Σ_k α_jk Φ_k (the higher derivatives of f, at the stage points)."""
    if not tree:
        return np.ones(alpha.shape[0])
    if len(tree) == 1:
        return beta @ _weights(tree[0], alpha, beta)
    return np.prod([alpha @ _weights(s, alpha, beta) for s in tree], axis=0)


def _published_form(gamma, a, c_mat, m):
    """(α, Γ, b) from the transformed coefficients the code uses (a = α Γ⁻¹, C = diag(1/γ) − Γ⁻¹, m = b Γ⁻¹)."""
    g = np.linalg.inv(np.eye(len(m)) / gamma - c_mat)
    return a @ g, g, np.asarray(m) @ g


def _rodas_tables(five):
    """The full s x s transformed tables of RODAS or Rodas5P as :func:`rodas_chunk` runs them: the stages after the
    last explicit row at the previous stage's point plus its increment, y1 = the last one's plus its increment."""
    import frbmodel.nonlinear.rosenbrock as rb

    if five:
        s, gamma, rows, c_rows = 8, rb.GAMMA5, rb.A5, rb.C5
    else:
        s, gamma = 6, rb.GAMMA
        rows = np.array([[rb.A21, 0, 0, 0], [rb.A31, rb.A32, 0, 0], [rb.A41, rb.A42, rb.A43, 0],
                         [rb.A51, rb.A52, rb.A53, rb.A54]])
        c_rows = np.array([[rb.C21, 0, 0, 0, 0], [rb.C31, rb.C32, 0, 0, 0], [rb.C41, rb.C42, rb.C43, 0, 0],
                           [rb.C51, rb.C52, rb.C53, rb.C54, 0], [rb.C61, rb.C62, rb.C63, rb.C64, rb.C65]])
    a = np.zeros((s, s))
    a[1:rows.shape[0] + 1, :rows.shape[1]] = rows
    for i in range(rows.shape[0] + 1, s):
        a[i] = a[i - 1]
        a[i, i - 1] = 1.0
    c_mat = np.zeros((s, s))
    c_mat[1:, :s - 1] = c_rows
    m, m_hat = a[-1].copy(), a[-1].copy()
    m[-1] = 1.0
    return gamma, a, c_mat, m, m_hat


@pytest.mark.parametrize("five", [False, True], ids=["RODAS", "Rodas5P"])
def test_rosenbrock_coefficients_satisfy_the_order_conditions(five):
    """The coefficients as rodas_chunk runs them, taken back to the published form (α, Γ, b), satisfy every order
    condition Σ b_j Φ_j(t) = 1/γ(t) of the rooted trees t up to the method's order (RODAS 4: 8 trees, Rodas5P 5: 17),
    and the embedded solution those up to one order less; the nodes c_i = Σ_j α_ij and d_i = Σ_j γ_ij of the
    non-autonomous terms. Values typed to 16 digits: 1e-12 leaves room for the round-off of the sums of up to
    ~200 products of coefficients of size ~100 (measured worst residuals 2e-15 and 1.6e-14). The solution is not
    of one order more (the check has teeth: some tree of order p + 1 fails by > 1e-4)."""
    import frbmodel.nonlinear.rosenbrock as rb

    gamma, a, c_mat, m, m_hat = _rodas_tables(five)
    alpha, g, b = _published_form(gamma, a, c_mat, m)
    _, _, b_hat = _published_form(gamma, a, c_mat, m_hat)
    p = 5 if five else 4
    beta = alpha + g
    for order in range(1, p + 1):
        for t in _trees(order):
            assert abs(b @ _weights(t, alpha, beta) - 1 / _density(t)) < 1e-12, (order, t)
            if order < p:
                assert abs(b_hat @ _weights(t, alpha, beta) - 1 / _density(t)) < 1e-12, ("embedded", order, t)
    assert max(abs(b @ _weights(t, alpha, beta) - 1 / _density(t)) for t in _trees(p + 1)) > 1e-4
    assert max(abs(b_hat @ _weights(t, alpha, beta) - 1 / _density(t)) for t in _trees(p)) > 1e-4
    assert [len(_trees(k)) for k in range(1, 6)] == [1, 1, 2, 4, 9]  # the numbers of rooted trees (OEIS A000081)
    c_pub = (rb.CC5 if five else np.array([0, rb.CC2, rb.CC3, rb.CC4, 1.0, 1.0]))
    d_pub = (rb.D5 if five else np.array([rb.D1, rb.D2, rb.D3, rb.D4, 0.0, 0.0]))
    np.testing.assert_allclose(alpha.sum(axis=1), c_pub, rtol=0, atol=1e-12)
    np.testing.assert_allclose(g.sum(axis=1), d_pub, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.diag(g), gamma, rtol=1e-14)


@pytest.mark.parametrize("method, order", [(0, 4), (1, 5), (2, 4)], ids=["RODAS", "Rodas5P", "RODAS-fast"])
def test_fixed_steps_converge_at_the_method_order_to_the_matrix_exponential(method, order):
    """The compiled steps of RODAS (order 4, continuous output of order 3; also its fast variant, whose linear
    systems are solved by blocks) and Rodas5P (5, output of order 4) on the
    linear, time-invariant rotor on springs (closed form: expm, as above), with fixed steps h (the error test
    switched off, max_step = h) over 40 µs: halving h divides the error at the end by 2^p and that of the
    continuous output inside the first step (0.3 h; its local error, O(h^(q + 1)) for an output of order q) by at
    least 2^(q + 1). Measured observed orders 4.01 / 4.97 (RODAS) and 5.8 / 5.0 (Rodas5P); steps 8e-7 and 4e-7 s
    (ω_max h <= 0.26 for the 52 kHz mode: asymptotic, errors 1e-10 ... 2e-5, far above round-off); each bound is
    the theory's order less 0.2 for the pre-asymptotic rest."""
    tc = frb.turbocharger(36e-6)
    k_s, speed = 1e6, 30e3
    p = build_problem(tc, SpeedProfile.constant(speed, 0.01), tc.film_model, linear_springs=k_s)
    y0, n_r = initial_state(p), p.n_rotor
    aug = _spring_rotor_generator(tc, k_s, speed, n_r)
    err_end, err_dense = [], []
    for h in (8e-7, 4e-7):
        t = np.array([0.0, 0.3 * h, 4e-5])
        out, k, _, steps, _, status = rodas_chunk(y0, t, h, 1e-30, np.full(p.n_states, 1e30),
                                                  typical_sizes(p, FD_TYPICAL_M),
                                                  film_columns(n_r, p.args[3], False, False), 10**6, h, p.args,
                                                  NO_MODAL, method)
        assert status == 0 and steps == round(4e-5 / h)
        exact = [(expm(aug * s) @ np.append(y0[:2 * n_r], 1.0))[:2 * n_r] for s in t[1:]]
        err_dense.append(np.abs(out[1, :2 * n_r] - exact[0]).max())
        err_end.append(np.abs(out[2, :2 * n_r] - exact[1]).max())
    assert np.log2(err_end[0] / err_end[1]) > order - 0.2, err_end
    assert np.log2(err_dense[0] / err_dense[1]) > order - 0.2, err_dense


def _main_job_state(t_s=0.3):
    """(problem, t, y, f0, Ω, Ω̇) of the main job inside the whirl (RODAS at the defaults up to ``t_s``)."""
    tc = frb.turbocharger(36e-6)
    p = build_problem(tc, SpeedProfile.ramp(20e3, 250e3, 1.0), tc.film_model)
    modal, atol = modal_error_basis(p, atol_vector(p, 1e-11)[0])
    scale, cols = typical_sizes(p, FD_TYPICAL_M), film_columns(p.n_rotor, p.args[3], False, False)
    out, *_ = rodas_chunk(initial_state(p), np.array([0.0, t_s]), 1e-7, 1e-7, atol, scale, cols, 10**7, 1.0, p.args,
                          modal)
    y = out[1]
    f0 = p.rhs(t_s, y, np.empty(p.n_states)).copy()
    return p, t_s, y, f0, f0[2 * p.n_rotor + 10], float(np.interp(t_s, p.profile.t, p.profile.omega_dot))


@pytest.mark.parametrize("h", [1e-7, 1e-5, 1e-3])
def test_block_solve_of_the_iteration_matrix_equals_lapack(h):
    """W x = b with W = I/(h γ) − J at a state of the main job inside the whirl: the reduced solve by ring blocks
    (fast RODAS) and the whole reduced LU (RODAS) both equal numpy's (LAPACK) dense solve of the full 43 x 43 W, to
    1e-9 of the solution's largest entry, over steps from far below to far above the run's (1e-5 s): cond(W) is
    3e9 ... 2e14 there, so the worst-case bound cond · eps says little; measured 4.9e-13, 1.1e-12 and 3e-16 for
    both (the bound leaves a factor 1000 for another state; a wrong block or a missed coupling gives O(1))."""
    from frbmodel.nonlinear.rosenbrock import GAMMA, _factor, _solve, block_workspace

    p, t, y, f0, omega, omega_dot = _main_job_state()
    n, n_r = p.n_states, p.n_rotor
    jac = np.empty((n, n))
    jacobian(t, y, f0, jac, np.empty(n), np.empty(n), film_columns(n_r, p.args[3], False, False),
             typical_sizes(p, FD_TYPICAL_M), omega, omega_dot, p.args)
    b = np.random.default_rng(5).normal(size=n) * np.abs(y).clip(1e-9)
    ref = np.linalg.solve(np.eye(n) / (h * GAMMA) - jac, b)
    for blocks in (False, True):
        w, piv, blk = np.empty((n - n_r, n - n_r)), np.empty(n - n_r, dtype=np.int64), block_workspace(n, n_r, blocks)
        assert _factor(jac, h * GAMMA, n_r, w, piv, blk)
        assert blk[0][1] == blocks  # the blocks were used (no fallback to the whole LU)
        x = b.copy()
        _solve(w, piv, jac, h * GAMMA, n_r, x, blk)
        np.testing.assert_allclose(x, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_fast_rodas_follows_rodas():
    """The fast variant is RODAS with a Jacobian that differs by the differences' own error (~3e-7 of a column) and
    linear systems solved by blocks: on the main job's first 0.1 s (20 -> 43 krpm, through the onset of the first
    whirl at 34.9 krpm) it takes the same number of steps within 1 % and gives the same journal orbit within
    1e-9 m = 100 atol (measured: 1889 steps both, 2.0e-11 m; both integrate to atol 1e-11 m per step, and the
    difference of two such runs grows through the onset)."""
    from frbmodel.nonlinear.rosenbrock import RODAS4_FAST

    tc = frb.turbocharger(36e-6)
    p = build_problem(tc, SpeedProfile.ramp(20e3, 250e3, 1.0), tc.film_model)
    modal, atol = modal_error_basis(p, atol_vector(p, 1e-11)[0])
    scale, cols = typical_sizes(p, FD_TYPICAL_M), film_columns(p.n_rotor, p.args[3], False, False)
    t = np.arange(4001) / 40e3
    runs = [rodas_chunk(initial_state(p), t, 1e-7, 1e-7, atol, scale, cols, 10**7, 1.0, p.args, modal, m)
            for m in (0, RODAS4_FAST)]
    assert all(r[5] == 0 and r[1] == t.size for r in runs)
    assert abs(runs[1][3] / runs[0][3] - 1) < 0.01
    j = 4 * tc.bearings[0].node
    assert np.abs(runs[1][0][:, j:j + 2] - runs[0][0][:, j:j + 2]).max() < 1e-9
