"""Methods A–J: ROSS reference frequencies, registry, limits between methods, bad input."""
import numpy as np
import pytest
from scipy.linalg import eig

import frbmodel as frb
from frbmodel.linear import linear_system
from frbmodel.methods import METHODS

# physics.md §11: ROSS natural frequencies (Hz) and precession (F/B/C) of the same rotor
ROSS = {
    ("A", 0.0): [(113.9, None), (318.9, None), (1076.5, None), (2143.9, None)],
    ("A", 100e3): [(60.2, "B"), (192.5, "F"), (297.3, "B"), (349.6, "F"), (572.3, "B"), (1496.3, "B"), (2056.8, "F")],
    ("A", 200e3): [(36.9, "B"), (242.4, "F"), (265.0, "B"), (389.7, "B"), (396.7, "F"), (1177.5, "B")],
    ("B", 100e3): [(75.0, "B"), (216.8, "C"), (315.1, "B"), (417.3, "F"), (617.8, "C"), (1510.3, "C"), (2089.2, "F")],
}
LABEL = {"F": "forward", "B": "backward", "C": "mixed"}


@pytest.mark.parametrize("key", list(ROSS))
def test_methods_a_b_match_ross(key):
    method, rpm = key
    cd = frb.campbell(frb.turbocharger(), method, [rpm], whirl=False)
    f, p = cd.frequencies_hz[0], cd.precession[0]
    order = np.argsort(f)
    f, p = f[order], p[order]
    if rpm == 0.0:
        f = f[::2]  # degenerate pairs at standstill: one value per pair; precession undefined there
    for k, (fr, lab) in enumerate(ROSS[key]):
        # acceptance: within 0.1 %; the ROSS values are rounded to 0.1 Hz, so allow the rounding half-unit too
        assert abs(f[k] - fr) <= max(1e-3 * fr, 0.05)
        if lab:
            assert p[k] == LABEL[lab]


def test_registry_has_the_nine_methods_of_table1():
    assert list(METHODS) == list("ABCDEFGIJ")
    assert [m for m in METHODS if METHODS[m].ring_dofs] == list("EFGIJ")
    assert [m for m in METHODS if METHODS[m].needs_films] == list("CDFGIJ")


def test_state_space_equals_generalized_eigenproblem():
    ls = linear_system(frb.turbocharger(), "J", 120e3)
    n = ls.M.shape[0]
    Z, I = np.zeros((n, n)), np.eye(n)
    lam = eig(np.block([[Z, I], [-ls.K, -ls.C]]), np.block([[I, Z], [Z, ls.M]]), right=False)
    lam = np.sort_complex(lam[lam.imag > 1e-7 * np.abs(lam)])
    md = frb.modes(ls.M, ls.C, ls.K)
    # two different eigen-solvers on a non-normal matrix with film damping: agreement to ~1e-8 relative,
    # 1e-6 leaves room for the conditioning of the heavily damped ring modes
    np.testing.assert_allclose(np.sort_complex(md.eigenvalues), lam, rtol=1e-6)


def test_undamped_methods_have_zero_modal_damping():
    for m in "ABE":
        cd = frb.campbell(frb.turbocharger(), m, [50e3, 150e3], whirl=False)
        assert np.nanmax(np.abs(cd.damping)) < 1e-9  # conservative gyroscopic system: λ purely imaginary


def test_method_d_with_rigid_inner_film_approaches_c():
    from dataclasses import replace

    tc = frb.turbocharger(36e-6)
    # a very stiff inner film at the same operating point: clearance x s, viscosity and length x sqrt(s)
    # keep W c²/(μ R L³) (hence ε_I) and eq. (6) (μ L / c) unchanged while every coefficient scales with
    # μ L³/c³ = 1/s. C and D use the same modified system.
    s = 1e-6
    stiff = tc.with_(bearings=tuple(replace(b, inner=replace(b.inner, clearance=b.inner.clearance * s,
                                                             viscosity=b.inner.viscosity * s ** 0.5,
                                                             length=b.inner.length * s ** 0.5))
                                    for b in tc.bearings))
    assert frb.ring_speed_ratio(stiff.bearings[0]) == pytest.approx(frb.ring_speed_ratio(tc.bearings[0]), rel=1e-12)
    from scipy.optimize import linear_sum_assignment
    from frbmodel.modal import state_matrix

    for rpm in (50e3, 200e3):
        c, d = linear_system(stiff, "C", rpm), linear_system(stiff, "D", rpm)
        lc = np.linalg.eigvals(state_matrix(c.M, c.C, c.K))
        ld = np.linalg.eigvals(state_matrix(d.M, d.C, d.K))
        r, k = linear_sum_assignment(np.abs(lc[:, None] - ld[None, :]))
        # series k_O k_I/(k_I + k_O) = k_O (1 − k_O/k_I + ...): relative deviation O(1e-6); 1e-4 margin
        assert np.max(np.abs(lc[r] - ld[k]) / np.abs(lc[r])) < 1e-4
    # and the limit is not trivial: with the real inner film D and C differ clearly
    kd, kc = linear_system(tc, "D", 50e3).K, linear_system(tc, "C", 50e3).K
    assert np.abs(kd - kc).max() > 0.1 * np.abs(kc[4:6, 4:6] - tc.rotor.K[4:6, 4:6]).max()


def test_method_e_ring_modes_at_spring_frequency():
    k = 1e6
    cd = frb.campbell(frb.turbocharger(), "E", [100e3], whirl=False, k=k)
    ring = cd.mode_kind[0] == "ring"
    assert ring.sum() == 4  # 2 rings x 2 directions
    # ring between two springs k (the heavy rotor barely moves): f ≈ sqrt(2k/m)/2π; rotor participation
    # shifts it by a few percent at most
    f_ring = np.sqrt(2 * k / 7.2e-3) / (2 * np.pi)
    np.testing.assert_allclose(cd.frequencies_hz[0, ring], f_ring, rtol=0.05)


def test_precession_sign_equals_frequency_slope_for_method_a():
    cd = frb.campbell(frb.turbocharger(), "A", np.linspace(90e3, 110e3, 11), whirl=False)
    f = cd.frequencies_hz
    slope = np.sign(f[-1] - f[0])
    for j in range(cd.n_modes):
        if np.isfinite(f[:, j]).all() and f[5, j] < 3000:
            expected = "forward" if slope[j] > 0 else "backward"
            assert cd.precession[5, j] == expected


def test_precession_indicator_hand_check():
    from frbmodel.modal import precession_index

    # v = cos βt, w = sin βt (CCW orbit) -> v̄ = 1, w̄ = −i -> Ψ = +1 (physics.md §9)
    psi, _ = precession_index(np.array([[1.0 + 0j], [-1j]]), [0], [1])
    assert psi[0, 0] == pytest.approx(1.0)
    psi, _ = precession_index(np.array([[1.0 + 0j], [1j]]), [0], [1])
    assert psi[0, 0] == pytest.approx(-1.0)


@pytest.mark.parametrize("method", ["C", "D", "F", "G", "I", "J"])
def test_film_methods_reject_non_positive_speed(method):
    with pytest.raises(frb.ParameterError, match="speed"):
        frb.campbell(frb.turbocharger(), method, [0.0, 1e5])


def test_bad_method_and_options():
    with pytest.raises(frb.ParameterError, match="method"):
        frb.campbell(frb.turbocharger(), "K", [1e5])
    with pytest.raises(frb.ParameterError, match="k"):
        frb.campbell(frb.turbocharger(), "A", [1e5], k=-1.0)
    with pytest.raises(frb.ParameterError, match="not used by method J"):
        frb.campbell(frb.turbocharger(), "J", [1e5], k=1e6)


@pytest.mark.parametrize("method", ["A", "E"])
def test_complex_coordinate_path_equals_state_space_path(method):
    """The half-size Hermitian solve used for undamped isotropic systems must reproduce the general
    state-space eigenvalues and precession at every speed."""
    from frbmodel.modal import classify_precession, modes, precession_index, speed_modes

    tc = frb.turbocharger()
    ls0 = linear_system(tc, method, 0.0)
    G = np.zeros_like(ls0.M)
    G[:16, :16] = tc.rotor.G
    speeds = np.array([1e3, 80e3, 240e3])
    fast = speed_modes(ls0.M, ls0.K, ls0.C, G, speeds * np.pi / 30, ls0.planes())
    v, w = np.arange(4) * 4, np.arange(4) * 4 + 1
    for k, s in enumerate(speeds):
        ref = modes(ls0.M, ls0.C + s * np.pi / 30 * G, ls0.K)
        # both are exact; eigenvalues to solver precision relative to the largest one
        np.testing.assert_allclose(fast[k].eigenvalues, ref.eigenvalues, rtol=1e-9, atol=1e-10 * abs(ref.eigenvalues).max())
        pf = classify_precession(*precession_index(fast[k].shapes, v, w))
        pr = classify_precession(*precession_index(ref.shapes, v, w))
        low = ref.frequencies_hz < 3000
        assert list(pf[low]) == list(pr[low])
