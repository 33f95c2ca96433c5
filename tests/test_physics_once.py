"""The rotor equation of motion, written once (frbmodel.system.rotor / frbmodel.physics.dynamics), against matrices and
solutions
built independently here.

The reference matrices are not retyped from the code: they are integrated numerically (Gauss-Legendre) from the
Hermite-cubic shape functions and the energy expressions of an Euler-Bernoulli shaft with rotary inertia and
gyroscopic coupling, with docs/theory/conventions.md#conventions's conventions θx = −∂w/∂z, θy = +∂v/∂z and
equations-of-motion.md#euler-bernoulli-shaft-element's
rigid-disc rule
(I_d θ̈x + I_p Ω θ̇y = M_x, I_d θ̈y − I_p Ω θ̇x = M_y).
"""
import math

import numpy as np
import pytest
import scipy.linalg as sla

import frbmodel as frb
from frbmodel.core.units import rpm_to_rad_s
from frbmodel.linear.assembly import linear_system
from frbmodel.nonlinear.components import RotorComponent, ramp_speed, rotor_state_space
from frbmodel.physics.dynamics import add_unbalance_forces, monolithic_rhs, rotor_acceleration
from frbmodel.system.rotor import Disc, Rotor, ShaftElement, first_order_state_matrix

# --------------------------------------------------------------------------------------------------
# independent reference: element matrices by quadrature of the shaft's energy densities
# --------------------------------------------------------------------------------------------------


def _hermite(z, l):
    """Hermite cubics on [0, l] for (u1, u1', u2, u2') and their first and second z-derivatives."""
    x = z / l
    n = np.array([1 - 3 * x**2 + 2 * x**3, l * (x - 2 * x**2 + x**3), 3 * x**2 - 2 * x**3, l * (-x**2 + x**3)])
    d1 = np.array([(-6 * x + 6 * x**2) / l, 1 - 4 * x + 3 * x**2, (6 * x - 6 * x**2) / l, -2 * x + 3 * x**2])
    d2 = np.array([(-6 + 12 * x) / l**2, (-4 + 6 * x) / l, (6 - 12 * x) / l**2, (-2 + 6 * x) / l])
    return n, d1, d2


def _element_by_quadrature(l, d, rho, E):
    """(M, K, G) of one element in the DoF order [v1, w1, θx1, θy1, v2, w2, θx2, θy2] from
    T = ½∫ρA(v̇² + ẇ²) + ½∫ρI(θ̇x² + θ̇y²), U = ½∫EI(v''² + w''²) and the gyroscopic moment densities
    ρI_pΩ(θ̇y, −θ̇x) on (θx, θy), with v = Nv·q, w = Nw·q, θy = v', θx = −w'."""
    A, I = math.pi * d**2 / 4, math.pi * d**4 / 64
    M, K, G = np.zeros((8, 8)), np.zeros((8, 8)), np.zeros((8, 8))
    xg, wg = np.polynomial.legendre.leggauss(6)  # exact for the degree-6 products of cubics
    for xi, wi in zip(xg, wg):
        z, w = 0.5 * l * (xi + 1), 0.5 * l * wi
        n, d1, d2 = _hermite(z, l)
        nv, nw = np.zeros(8), np.zeros(8)  # v = nv·q, w = nw·q (w' = −θx at the nodes)
        nv[[0, 3, 4, 7]] = n
        nw[[1, 2, 5, 6]] = n * [1, -1, 1, -1]
        bv1, bw1, bv2, bw2 = np.zeros(8), np.zeros(8), np.zeros(8), np.zeros(8)
        bv1[[0, 3, 4, 7]], bw1[[1, 2, 5, 6]] = d1, d1 * [1, -1, 1, -1]
        bv2[[0, 3, 4, 7]], bw2[[1, 2, 5, 6]] = d2, d2 * [1, -1, 1, -1]
        th_y, th_x = bv1, -bw1
        M += w * rho * A * (np.outer(nv, nv) + np.outer(nw, nw))
        M += w * rho * I * (np.outer(th_x, th_x) + np.outer(th_y, th_y))
        K += w * E * I * (np.outer(bv2, bv2) + np.outer(bw2, bw2))
        G += w * rho * 2 * I * (np.outer(th_x, th_y) - np.outer(th_y, th_x))
    return M, K, G


def _assembled_by_hand(shaft, discs):
    """Global (M, K, G) of elements in series plus rigid discs (diag(m, m, I_d, I_d); ±I_p at (θx, θy))."""
    n = 4 * (len(shaft) + 1)
    M, K, G = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    for i, (l, d, rho, E) in enumerate(shaft):
        me, ke, ge = _element_by_quadrature(l, d, rho, E)
        s = slice(4 * i, 4 * i + 8)
        M[s, s] += me
        K[s, s] += ke
        G[s, s] += ge
    for node, m, ip, idia in discs:
        j = 4 * node
        M[j, j] += m
        M[j + 1, j + 1] += m
        M[j + 2, j + 2] += idia
        M[j + 3, j + 3] += idia
        G[j + 2, j + 3] += ip
        G[j + 3, j + 2] -= ip
    return M, K, G


TABLE2_SHAFT = [(33e-3, 11e-3, 7860.0, 2e11), (39e-3, 11e-3, 7860.0, 2e11), (33e-3, 11e-3, 7860.0, 2e11)]
TABLE2_DISCS = [(0, 0.326, 8.1e-5, 7.7e-5), (3, 0.118, 4.4e-5, 3.27e-5)]  #
# docs/theory/parameters.md#table-2-in-si-units


@pytest.fixture(scope="module")
def table2():
    """The preset rotor and the same rotor's matrices assembled here from
    docs/theory/parameters.md#table-2-in-si-units's numbers."""
    return frb.turbocharger().rotor, _assembled_by_hand(TABLE2_SHAFT, TABLE2_DISCS)


def _close(a, b, rel):
    """|a − b| <= rel · max|b| (entries of mixed units: the scale is the largest entry)."""
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * np.abs(b).max())


def test_eom_matrices_of_a_two_node_shaft_equal_the_energy_quadrature():
    rotor = Rotor([ShaftElement(0.05, 0.012, 0.004, 7800.0, 2.1e11)], [Disc(1, 0.2, 3e-5, 2e-5)])
    M, K, G = _assembled_by_hand([(0.05, 0.012, 7800.0, 2.1e11)], [(1, 0.2, 3e-5, 2e-5)])
    # hollow shaft: subtract the bore's share (A, I are linear in the section)
    Mb, Kb, Gb = _element_by_quadrature(0.05, 0.004, 7800.0, 2.1e11)
    M, K, G = M - Mb, K - Kb, G - Gb
    Om, Omd = 1.3e4, 2.0e4
    m_, c_, k_ = rotor.eom_matrices(Om, Omd)
    # Gauss quadrature is exact for these polynomials: agreement to a few ulps of the largest entry
    _close(m_, M, 1e-13)
    _close(c_, Om * G, 1e-13)
    _close(k_, K + Omd * G, 1e-13)
    # the forward/backward sense is in G's sign: +I_p at (θx, θy) of the disc node
    # (docs/theory/equations-of-motion.md#euler-bernoulli-shaft-element)
    assert c_[6, 7] > 0 > c_[7, 6]


def test_first_order_form_is_the_second_order_system(table2):
    rotor, (M, K, G) = table2
    n = rotor.n_dof
    Om, Omd = 9000.0, -3000.0
    A = rotor.state_matrix(Om, Omd)
    rng = np.random.default_rng(3)
    q, qd = rng.normal(size=n) * 1e-6, rng.normal(size=n) * 1e-3
    sdot = A @ np.concatenate([q, qd])
    np.testing.assert_array_equal(sdot[:n], qd)
    # M q̈ + ΩG q̇ + (K + Ω̇G) q = 0 for the free rotor; residual relative to the largest term
    res = M @ sdot[n:] + Om * G @ qd + (K + Omd * G) @ q
    scale = max(np.abs(K @ q).max(), np.abs(Om * G @ qd).max())
    assert np.abs(res).max() < 1e-9 * scale  # cond(M) ~ 1e7 times round-off
    assert first_order_state_matrix(np.ones((2, 2)), np.zeros((3, 1, 1, 2, 2))).shape == (3, 1, 1, 4, 4)


def test_acceleration_kernel_solves_the_equation_of_motion(table2):
    rotor, (M, K, G) = table2
    n = rotor.n_dof
    rng = np.random.default_rng(7)
    minv, mk, mg = rotor.acceleration_matrices
    ks, cs = np.zeros((n, n)), np.zeros((n, n))  # a linear support at node 1 (e.g. a bearing interface)
    ks[4:6, 4:6] = [[3e6, 1e6], [-2e6, 4e6]]
    cs[4:6, 4:6] = [[400.0, -50.0], [-50.0, 700.0]]
    for _ in range(5):
        f = rng.normal(size=n)
        q, qd = rng.normal(size=n) * 1e-5, rng.normal(size=n) * 1e-2
        Om, Omd = rng.uniform(1e3, 3e4), rng.uniform(-1e4, 1e4)
        want = np.linalg.solve(M, f - (K + Omd * G) @ q - Om * G @ qd)
        got = rotor_acceleration(minv, mk, mg, f, q, qd, Om, Omd)
        # relative to the largest acceleration: M⁻¹ (cond ~1e7) applied in two different orders
        _close(got, want, 1e-9)
        want_s = np.linalg.solve(M, f - (K + ks + Omd * G) @ q - (Om * G + cs) @ qd)
        got_s = rotor_acceleration(minv, mk + minv @ ks, mg, f, q, qd, Om, Omd, minv @ cs)
        _close(got_s, want_s, 1e-9)


def test_monolithic_rhs_rotor_rows_on_springs(table2):
    """The monolithic RHS with journals on linear springs (rings idle): its q̈ rows are M⁻¹(f_g − k x_J − ...)
    with the speed and acceleration interpolated from the profile."""
    rotor, (M, K, G) = table2
    tc = frb.turbocharger()
    n = rotor.n_dof
    jn = np.array([b.node for b in tc.bearings], dtype=np.int64)
    geom = np.ones((2, 2, 4))
    polys = np.zeros((2, 2, 2, 5))
    polys[..., -1] = 1.0
    tg, wg, wdg = np.array([0.0, 1.0]), np.array([2000.0, 6000.0]), np.array([4000.0, 4000.0])
    k_s, t = 2.5e6, 0.25
    rng = np.random.default_rng(11)
    y = np.zeros(2 * n + 11)
    y[:2 * n] = rng.normal(size=2 * n) * np.r_[np.full(n, 1e-5), np.full(n, 1e-2)]
    out = np.zeros_like(y)
    monolithic_rhs(t, y, out, rotor.acceleration_matrices, rotor.gravity_load(tc.gravity), n, jn, geom, polys,
                   np.ones(2), np.ones(2), tc.gravity, np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), tg, wg,
                   wdg, k_s, 0.999, np.zeros(4), np.zeros(2), np.zeros((2, n)))
    f = np.zeros(n)
    f[1::4] = -tc.gravity
    f = M @ f  # consistent gravity load (docs/theory/equations-of-motion.md#rotor)
    for node in jn:
        f[4 * node:4 * node + 2] -= k_s * y[4 * node:4 * node + 2]
    Om, Omd = 2000.0 + 4000.0 * t, 4000.0
    want = np.linalg.solve(M, f - (K + Omd * G) @ y[:n] - Om * G @ y[n:2 * n])
    np.testing.assert_array_equal(out[:n], y[n:2 * n])
    _close(out[n:2 * n], want, 1e-9)  # as above: two evaluation orders of M⁻¹ (cond ~1e7)
    assert out[2 * n + 10] == pytest.approx(Om, rel=1e-15)  # the rotation angle advances at Ω
    assert not np.any(out[2 * n:2 * n + 10])  # idle rings


def test_unbalance_force_is_minus_mass_times_acceleration_of_the_unbalance():
    """m e at angle θ(t) = φ0 + Ωt + Ω̇t²/2 on a rotor: the force on the rotor is −m d²r/dt², here by central
    differences of the unbalance position."""
    me, phase, phi0, Om, Omd = 2e-6, 0.4, 1.1, 3000.0, 5e4
    f = np.zeros(8)
    add_unbalance_forces(f, phi0, Om, Omd, np.array([1], dtype=np.int64), np.array([me]), np.array([phase]))

    def r(t):
        th = phase + phi0 + Om * t + 0.5 * Omd * t * t
        return np.array([math.cos(th), math.sin(th)]) * me  # m·e·(cos, sin): the mass factor is inside me

    h = 1e-6
    want = -(r(h) - 2 * r(0.0) + r(-h)) / h**2
    # central-difference truncation (hΩ)²/12 ~ 1e-6 relative; round-off e·eps/h² ~ 1e-10 relative
    np.testing.assert_allclose(f[4:6], want, rtol=1e-5)
    assert not np.any(f[:4]) and not np.any(f[6:])


def test_rotor_state_space_eigenvalues_with_pinned_journals(table2):
    """Eigenvalues of the rotor component's (A, B, C) with the journal accelerations constrained to zero by the
    bearing-force inputs equal those of the pinned rotor's quadratic eigenproblem built here."""
    rotor, (M, K, G) = table2
    tc = frb.turbocharger()
    n = rotor.n_dof
    rpm, rpm_dot = 90e3, 40e3  # ramp: Ω and Ω̇ both enter
    rc = RotorComponent(tc, ramp_speed(rpm, rpm + rpm_dot, 1.0))
    ss = rotor_state_space(rc)
    A, B, C = ss["A"], ss["B"], ss["C"]
    jd = [4 * b.node + k for b in tc.bearings for k in (0, 1)]
    # journal accelerations = rows n + jd of ṡ = A s + B F: choose F so they vanish (reaction forces)
    Ca = np.zeros((len(jd), 2 * n))
    Ca[np.arange(len(jd)), n + np.array(jd)] = 1.0
    assert np.array_equal(C[[0, 1, 4, 5]][:, :n], Ca[:, n:])  # C outputs the journal positions
    # inputs: (Fx, Fy) per bearing act at the journal DoFs; outputs: journal (x, y, vx, vy) per bearing
    for k, dof in enumerate(jd):
        e = np.zeros(n)
        e[dof] = 1.0
        _close(B[n:, k], np.linalg.solve(M, e), 1e-9)  # cond(M) ~1e7 times round-off
        assert not np.any(B[:n, k])
    s = np.random.default_rng(2).normal(size=2 * n)
    np.testing.assert_array_equal(C @ s, np.concatenate([[s[d], s[d + 1], s[n + d], s[n + d + 1]] for d in jd[::2]]))
    P = np.eye(2 * n) - B @ np.linalg.solve(Ca @ B, Ca)
    lam_c = np.linalg.eigvals(P @ A)
    lam_c = lam_c[np.abs(lam_c) > 1.0]  # drop the constrained directions (0, defective: |λ| ~ sqrt(eps)·|A|)
    Om, Omd = rpm_to_rad_s(rpm), rpm_to_rad_s(rpm_dot)
    free = np.setdiff1d(np.arange(n), jd)
    Mf, Cf, Kf = M[np.ix_(free, free)], Om * G[np.ix_(free, free)], (K + Omd * G)[np.ix_(free, free)]
    m = free.size
    lam_q = sla.eig(np.block([[np.zeros((m, m)), np.eye(m)], [-Kf, -Cf]]),
                    np.block([[np.eye(m), np.zeros((m, m))], [np.zeros((m, m)), Mf]]), right=False)
    assert lam_c.size == lam_q.size == 2 * m
    for lq in lam_q:  # each pinned eigenvalue is found; 1e-7: eig of two differently conditioned forms
        assert np.min(np.abs(lam_c - lq)) < 1e-7 * abs(lq)
    assert np.max(lam_q.real) < 1e-6 * np.abs(lam_q).max()  # conservative + gyroscopic: no damping


def test_cosim_rotor_step_is_the_trapezoidal_rule_of_the_supported_rotor(table2):
    """One RotorComponent step with bearing forces F0 − K_b (x − x_ref) − C_b (v − v_ref), F0 = −K_b x_ref −
    C_b v_ref (a linear support about the origin) equals the closed-form trapezoidal (Cayley) step of the
    first-order system with K + K_b and ΩG + C_b, built here from the hand-assembled matrices."""
    rotor, (M, K, G) = table2
    tc = frb.turbocharger()
    n = rotor.n_dof
    rpm = 60e3
    Om = rpm_to_rad_s(rpm)
    rc = RotorComponent(tc, ramp_speed(rpm, rpm, 1.0), substep=2e-6)
    rng = np.random.default_rng(5)
    rc.y[:] = np.r_[rng.normal(size=n) * 1e-6, rng.normal(size=n) * 1e-3]
    kb = np.array([[[4e6, 1.5e6], [-2.5e6, 3e6]], [[2e6, 5e5], [-7e5, 2.2e6]]])
    cb = np.array([[[300.0, -40.0], [90.0, 500.0]], [[150.0, -20.0], [60.0, 260.0]]])  # FD Jacobians: unsymmetric
    refs = np.array([rc.journal(b) for b in range(2)])
    f0 = np.array([-kb[b] @ refs[b, :2] - cb[b] @ refs[b, 2:] for b in range(2)])
    s = rc.y.copy()
    H, n_sub = 1e-5, 5
    rc.step(H, f0, kb, cb, refs)
    Kt, Ct = K.copy(), Om * G
    for b, bear in enumerate(tc.bearings):
        j = slice(4 * bear.node, 4 * bear.node + 2)
        Kt[j, j] += kb[b]
        Ct[j, j] += cb[b]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kt, -Minv @ Ct]])
    g = np.r_[np.zeros(n), Minv @ rotor.gravity_load(tc.gravity)]
    h = H / n_sub
    I = np.eye(2 * n)
    for _ in range(n_sub):  # (I − hA/2) s1 = (I + hA/2) s0 + h g  (constant forcing)
        s = np.linalg.solve(I - 0.5 * h * A, (I + 0.5 * h * A) @ s + h * g)
    _close(rc.y[:n], s[:n], 1e-9)  # two algebraically equal forms of the same step; cond(M) ~1e7
    _close(rc.y[n:], s[n:], 1e-9)


def test_linear_system_rotor_part_is_the_equation_of_motion(table2):
    rotor, (M, K, G) = table2
    tc = frb.turbocharger()
    ls = linear_system(tc, "A", 120e3, k=3e6)  # journals on isotropic springs: no equilibrium involved
    Kw = K.copy()
    for b in tc.bearings:
        Kw[4 * b.node, 4 * b.node] += 3e6
        Kw[4 * b.node + 1, 4 * b.node + 1] += 3e6
    _close(ls.M, M, 1e-13)
    _close(ls.C, rpm_to_rad_s(120e3) * G, 1e-13)
    _close(ls.K, Kw, 1e-13)


def test_static_deflection_holds_the_journals_and_its_reactions_do_not_depend_on_them():
    """Two supports: statically determinate, so K q − f_g at the supports (the reactions) is the same for any
    prescribed journal positions, and equals Rotor.static_reactions."""
    tc = frb.turbocharger()
    r = tc.rotor
    nodes = [b.node for b in tc.bearings]
    f = r.gravity_load(tc.gravity)
    w0 = r.static_reactions(nodes, tc.gravity)
    for pos in ([(0.0, 0.0), (0.0, 0.0)], [(3e-6, -1e-5), (-2e-6, 4e-6)]):
        q = r.static_deflection(nodes, pos, tc.gravity)
        np.testing.assert_array_equal(q[[4 * nodes[0], 4 * nodes[0] + 1, 4 * nodes[1], 4 * nodes[1] + 1]],
                                      np.ravel(pos))
        react = r.K @ q - f
        free = np.setdiff1d(np.arange(r.n_dof), [4 * k + i for k in nodes for i in (0, 1)])
        assert np.abs(react[free]).max() < 1e-9 * np.abs(f).max()  # equilibrium off the supports
        # the reactions carry the weight and do not depend on the prescribed positions (1e-9: round-off of K q)
        np.testing.assert_allclose(react[[4 * k + 1 for k in nodes]], w0, rtol=0, atol=1e-9 * np.abs(w0).max())
        np.testing.assert_allclose(react[[4 * k for k in nodes]], 0.0, atol=1e-9 * np.abs(w0).max())
