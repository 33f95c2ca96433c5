"""Film forces, coefficients, static inverse and finite-length correction against independent references."""
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import frbmodel as frb
from frbmodel.physics.film import Film, attitude_angle, film_coefficients, film_force, static_load, static_position
from frbmodel.physics.finite_length import correction_polynomials, reynolds_force_ratio

TURB_INNER = Film(radius=5.5e-3, length=6.5e-3, clearance=34e-6, viscosity=4.9e-3)


def quadrature_force(film, r, rdot, omega_s):
    """Independent brute-force force: the short-bearing Reynolds pressure built from the raw inertial-frame
    gap h(θ, t) = c − r_x cos θ − r_y sin θ, clipped at p < 0 (half-Sommerfeld), integrated numerically in θ
    (adaptive quadrature) and z (3-point Gauss, exact for the parabolic profile)."""
    c, mu, R, L = film.clearance, film.viscosity, film.radius, film.length
    zg, wg = np.polynomial.legendre.leggauss(3)
    z = 0.5 * L * zg
    wz = 0.5 * L * wg

    def numerator(th):  # sign of the unclipped pressure profile (pressure > 0 where it is < 0 ... see below)
        h_th = r[0] * math.sin(th) - r[1] * math.cos(th)
        h_t = -rdot[0] * math.cos(th) - rdot[1] * math.sin(th)
        return 6 * mu * omega_s * h_th + 12 * mu * h_t

    def p(th):
        h = c - r[0] * math.cos(th) - r[1] * math.sin(th)
        prof = numerator(th) / (2 * h ** 3)
        return max(float(prof * (z ** 2 - L * L / 4) @ wz), 0.0)  # ∫ p dz, clipped (one sign along z)

    # cavitation boundaries: sign changes of the numerator on a fine grid, refined by Brent, so each
    # quadrature interval is smooth
    grid = np.linspace(0.0, 2 * math.pi, 721)
    vals = np.array([numerator(t) for t in grid])
    pts = [0.0] + [brentq(numerator, grid[k], grid[k + 1], xtol=1e-15) for k in range(720)
                   if vals[k] * vals[k + 1] < 0] + [2 * math.pi]
    fx = fy = 0.0
    for a, b in zip(pts[:-1], pts[1:]):
        fx -= quad(lambda th: p(th) * math.cos(th), a, b, limit=200, epsabs=0, epsrel=1e-12)[0] * R
        fy -= quad(lambda th: p(th) * math.sin(th), a, b, limit=200, epsabs=0, epsrel=1e-12)[0] * R
    return np.array([fx, fy])


def test_dynamic_force_matches_pressure_quadrature_at_random_states():
    rng = np.random.default_rng(7)
    f = TURB_INNER
    worst = 0.0
    for _ in range(120):
        eps = rng.uniform(0.0, 0.95)
        phi = rng.uniform(-math.pi, math.pi)
        r = eps * f.clearance * np.array([math.cos(phi), math.sin(phi)])
        rdot = rng.normal(0.0, 1.0, 2) * f.clearance * rng.uniform(10, 3000)  # up to several c per ms
        omega_s = rng.uniform(-500, 5000)  # either sign
        F = film_force(f, r, rdot, omega_s)
        Fq = quadrature_force(f, r, rdot, omega_s)
        scale = max(np.abs(Fq).max(), 1e-9)
        worst = max(worst, np.abs(F - Fq).max() / scale)
    # smooth sub-intervals integrated to 1e-12: 1e-9 relative leaves margin for round-off near ε = 0.95
    # (|F| ~ (1-ε²)^-2.5) while any formula or sign error is O(1)
    assert worst < 1e-9


def test_force_is_vectorized_consistently():
    rng = np.random.default_rng(1)
    r = rng.uniform(-0.6, 0.6, (50, 2)) * TURB_INNER.clearance
    v = rng.normal(0, 0.01, (50, 2))
    w = rng.uniform(100, 3000, 50)
    F = film_force(TURB_INNER, r, v, w)
    for k in range(0, 50, 7):
        np.testing.assert_allclose(F[k], film_force(TURB_INNER, r[k], v[k], w[k]), rtol=1e-14)


def test_centred_limit_is_pure_squeeze_damping():
    f = TURB_INNER
    v = np.array([1e-3, -2e-3])
    F = film_force(f, np.zeros(2), v, 3000.0)
    expected = -math.pi * f.viscosity * f.radius * f.length ** 3 / (2 * f.clearance ** 3) * v  #
    # docs/theory/films.md#limits-and-validity
    np.testing.assert_allclose(F, expected, rtol=1e-12)


def test_circular_whirl_at_half_speed_carries_no_load():
    f = TURB_INNER
    omega_s = 2000.0
    r = np.array([0.3, 0.4]) * f.clearance
    rdot = 0.5 * omega_s * np.array([-r[1], r[0]])  # φ̇ = ω_s / 2
    assert np.abs(film_force(f, r, rdot, omega_s)).max() < 1e-9


def test_contact_raises_clear_error():
    with pytest.raises(frb.FilmContactError, match="eps"):
        film_force(TURB_INNER, [TURB_INNER.clearance, 0.0], [0, 0], 1000.0)


# docs/theory/films.md#static-equilibrium-of-one-film reference table: ε -> (W̄, β [deg])
STATIC_TABLE = [(0.05, 0.039498, 86.353), (0.3, 0.292375, 68.178), (0.6, 1.27263, 46.321), (0.9, 24.0061, 20.826)]


@pytest.mark.parametrize("eps,wbar,beta", STATIC_TABLE)
def test_static_load_and_attitude_table(eps, wbar, beta):
    # table values have 5-6 significant digits
    assert static_load(eps) == pytest.approx(wbar, rel=2e-5)
    assert math.degrees(attitude_angle(eps)) == pytest.approx(beta, abs=1e-3)


@pytest.mark.parametrize("eps", [1e-4, 0.05, 0.3, 0.6, 0.9, 0.99])
def test_static_inverse_round_trip(eps):
    f = TURB_INNER
    ws = 3000.0
    W = static_load(eps) * f.viscosity * ws * f.radius * f.length ** 3 / f.clearance ** 2
    e, eps2, _ = static_position(f, (0.0, W), ws)
    assert eps2 == pytest.approx(eps, rel=1e-10)  # quartic solved to machine precision
    F = film_force(f, e, [0, 0], ws)  # the dynamic force at that position must give the load back
    np.testing.assert_allclose(F, [0.0, W], atol=1e-10 * W)


def test_worked_example_physics_4_3():
    f = TURB_INNER
    ws = 3000.0
    # ε = 0.3 and 0.6: W, journal position, K, C (docs/theory/films.md#worked-numbers; given to 5-6 digits)
    cases = [
        (5.61568, (9.4691, -3.7916), [[3.98474e5, 4.33498e5], [-7.40361e5, 2.96452e5]],
         [[333.701, -133.619], [-133.619, 448.872]]),
        (24.44359, (14.7536, -14.0887), [[1.503801e6, 2.20762e5], [-2.974712e6, 2.840641e6]],
         [[536.533, -512.351], [-512.351, 1593.783]]),
    ]
    for W, pos, K_ref, C_ref in cases:
        e, _, _ = static_position(f, (0.0, W), ws)
        np.testing.assert_allclose(e * 1e6, pos, atol=2e-4)
        K, C = film_coefficients(f, e, ws)
        np.testing.assert_allclose(K, K_ref, rtol=1e-4, atol=1.0)
        np.testing.assert_allclose(C, C_ref, rtol=1e-4, atol=1e-3)


def test_dimensionless_standard_frame_table():
    # docs/theory/films.md#worked-numbers: k̄ = K c / W, c̄ = C c ω_s / W for the standard frame (load on inner member
    # along −y)
    ref = {0.3: [2.412553, 2.624601, -4.482499, 1.794861, 6.061152, -2.426978, 8.153048],
           0.6: [2.091723, 0.307070, -4.137699, 3.951212, 2.238884, -2.137977, 6.650655]}
    f, ws = TURB_INNER, 3000.0
    for eps, (kxx, kxy, kyx, kyy, cxx, cxy, cyy) in ref.items():
        W = static_load(eps) * f.viscosity * ws * f.radius * f.length ** 3 / f.clearance ** 2
        e, _, _ = static_position(f, (0.0, W), ws)
        K, C = film_coefficients(f, e, ws)
        kb = K * f.clearance / W
        cb = C * f.clearance * ws / W
        np.testing.assert_allclose(kb, [[kxx, kxy], [kyx, kyy]], rtol=2e-6, atol=1e-6)
        np.testing.assert_allclose(cb, [[cxx, cxy], [cxy, cyy]], rtol=2e-6, atol=1e-6)


@pytest.mark.parametrize("model", ["short", "short_corrected"])
def test_coefficients_equal_central_differences(model):
    rng = np.random.default_rng(3)
    f = TURB_INNER
    for _ in range(20):
        eps = rng.uniform(0.0, 0.9)
        phi = rng.uniform(-math.pi, math.pi)
        ws = rng.uniform(200, 4000)
        e = eps * f.clearance * np.array([math.cos(phi), math.sin(phi)])
        K, C = film_coefficients(f, e, ws, model)
        Kfd, Cfd = np.zeros((2, 2)), np.zeros((2, 2))
        h, hv = 1e-6 * f.clearance, 1e-6 * f.clearance * ws
        for j in range(2):
            d = np.zeros(2)
            d[j] = h
            Kfd[:, j] = -(film_force(f, e + d, [0, 0], ws, model) - film_force(f, e - d, [0, 0], ws, model)) / (2 * h)
            d[j] = hv
            Cfd[:, j] = -(film_force(f, e, d, ws, model) - film_force(f, e, -d, ws, model)) / (2 * hv)
        # central differences with step 1e-6 c: truncation ~1e-12 relative, round-off ~1e-10; the
        # moving cavitation boundary adds no kink at zero velocity (G = 0 on the boundary)
        scale_k, scale_c = np.abs(K).max(), np.abs(C).max()
        np.testing.assert_allclose(K, Kfd, atol=1e-7 * scale_k)
        np.testing.assert_allclose(C, Cfd, atol=1e-7 * scale_c)


def test_coefficients_at_zero_eccentricity():
    f, ws = TURB_INNER, 2500.0
    K, C = film_coefficients(f, [0.0, 0.0], ws)
    base = f.viscosity * f.radius * f.length ** 3 / f.clearance ** 3
    np.testing.assert_allclose(K, math.pi * ws * base / 4 * np.array([[0, 1], [-1, 0]]), atol=1e-9 * base * ws)
    np.testing.assert_allclose(C, math.pi * base / 2 * np.eye(2), rtol=1e-13)


def test_compressor_film_coefficients_physics_11():
    # docs/theory/parameters.md#reference-numbers: compressor inner film at 100 krpm, RSR 0.19903, ε = 0.00223 — stays
    # finite, matches
    tc = frb.turbocharger(36e-6)
    b = tc.bearings[1]
    wr = 100e3 * math.pi / 30
    ws = wr * (1 + 0.19903)
    e, eps, _ = static_position(b.inner, (0.0, tc.bearing_loads[1]), ws)
    assert eps == pytest.approx(0.00223, abs=1e-5)
    K, C = film_coefficients(b.inner, e, ws)
    np.testing.assert_allclose(K[0, 1], 2.42546e6, rtol=1e-4)
    np.testing.assert_allclose(K[1, 0], -2.42554e6, rtol=1e-4)
    np.testing.assert_allclose(np.diag(C), [386.3, 386.3], rtol=1e-3)


def test_reynolds_ratios_match_physics_5_table():
    # docs/theory/films.md#finite-length-correction table (λ = 0.5909 inner); its grid is converged to about 1e-3, ours
    # is an independent
    # finite-volume discretisation of the same problem, so agreement within 2e-3 is expected
    ref = {0.02: (0.7209, 0.8772), 0.3: (0.6918, 0.8476), 0.6: (0.5851, 0.7361), 0.9: (0.2822, 0.3909)}
    for eps, (fr, ft) in ref.items():
        r = reynolds_force_ratio(eps, 0.5909)
        assert r[0] == pytest.approx(fr, abs=2e-3)
        assert r[1] == pytest.approx(ft, abs=2e-3)


def test_reynolds_ratio_tends_to_one_for_short_bearings():
    fr, ft = reynolds_force_ratio(0.3, 0.05)
    assert fr == pytest.approx(1.0, abs=5e-3) and ft == pytest.approx(1.0, abs=5e-3)  # docs/theory/films.md:
    # 0.996/0.998


def test_correction_polynomial_close_to_physics_fit():
    # the quartic fit of docs/theory/films.md#finite-length-correction for λ = 0.5625 (outer) has max fit error
    # 0.003-0.004: compare the evaluated fits
    pr_ref = [-1.2544, 1.4466, -0.9242, 0.0906, 0.7367]
    pt_ref = [-1.6862, 2.0149, -1.1721, 0.1279, 0.8840]
    pr, pt = correction_polynomials(0.5625)
    eps = np.linspace(0.02, 0.9, 30)
    assert np.abs(np.polyval(pr, eps) - np.polyval(pr_ref, eps)).max() < 6e-3
    assert np.abs(np.polyval(pt, eps) - np.polyval(pt_ref, eps)).max() < 6e-3


def test_corrected_film_static_inverse_round_trip():
    f, ws = TURB_INNER, 3000.0
    e, eps, _ = static_position(f, (1.0, 4.0), ws, "short_corrected")
    F = film_force(f, e, [0, 0], ws, "short_corrected")
    np.testing.assert_allclose(F, [1.0, 4.0], atol=1e-10)
    e_short, eps_short, _ = static_position(f, (1.0, 4.0), ws, "short")
    assert eps > eps_short  # the finite-length film carries less, so it runs more eccentric


@pytest.mark.parametrize("field,value", [("clearance", -1e-6), ("clearance", 0.0), ("viscosity", 0.0),
                                         ("radius", float("nan")), ("length", -1.0)])
def test_invalid_film_parameters(field, value):
    kw = dict(radius=5.5e-3, length=6.5e-3, clearance=34e-6, viscosity=4.9e-3)
    kw[field] = value
    with pytest.raises(frb.ParameterError, match=field) as ei:
        Film(**kw)
    assert "valid range" in str(ei.value) or "finite" in str(ei.value)


def test_unknown_film_model():
    with pytest.raises(frb.ParameterError, match="film model"):
        film_force(TURB_INNER, [0, 0], [0, 0], 1.0, film_model="long")


def test_turbine_film_coefficients_physics_11():
    """docs/theory/parameters.md#reference-numbers: turbine inner and outer film at 100 krpm with RSR (6) (method F
    equilibrium)."""
    tc = frb.turbocharger(36e-6)
    eq = frb.equilibrium(tc, "F", 100e3).bearings[0]
    b = tc.bearings[0]
    Ki, Ci = film_coefficients(b.inner, eq.r_inner, eq.omega_inner)
    Ko, Co = film_coefficients(b.outer, eq.ring, eq.omega_outer)
    # reference values are given to 4-6 significant digits
    np.testing.assert_allclose(Ki, [[3.9597e5, 1.85535e6], [-1.93596e6, 2.0472e5]], rtol=2e-4)
    np.testing.assert_allclose(Ci, [[298.36, -31.55], [-31.55, 305.53]], rtol=5e-4)
    np.testing.assert_allclose(Ko, [[3.7584e5, 9.9967e5], [-1.13199e6, 2.0705e5]], rtol=2e-4)
    np.testing.assert_allclose(Co, [[987.25, -180.57], [-180.57, 1058.26]], rtol=5e-4)
