"""Methods A–J: stored ROSS reference frequencies, registry, limits between methods, bad input."""
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eig

import frbmodel as frb
from frbmodel.linear.assembly import linear_system
from frbmodel.system.methods import METHODS

# Stored peer results: ROSS's natural frequencies and whirl directions of the same rotor on the same springs,
# written by tests/reference/make_ross_campbell.py (which records the ROSS and Python versions and the date)
ROSS = json.loads((Path(__file__).parent / "reference" / "ross_campbell_AB.json").read_text())
ROSS_CASES = [(m, s["speed [rpm]"]) for m, case in ROSS["methods"].items() for s in case["speeds"]]
LABEL = {"Forward": "forward", "Backward": "backward", "Mixed": "mixed"}


@pytest.mark.parametrize("method,rpm", ROSS_CASES)
def test_methods_a_b_match_ross(method, rpm):
    case = ROSS["methods"][method]
    ref = next(s["modes"] for s in case["speeds"] if s["speed [rpm]"] == rpm)
    springs = {"k": case["kx [N/m]"]} if method == "A" else {"kx": case["kx [N/m]"], "ky": case["ky [N/m]"]}
    cd = frb.campbell(frb.turbocharger(), method, [rpm], whirl=False, **springs)
    f, p = cd.frequencies_hz[0], cd.precession[0]
    order = np.argsort(f)
    f, p = f[order], p[order]
    f_ref = np.array([m["frequency [Hz]"] for m in ref])
    assert f.size == f_ref.size == 16  # every lateral mode of the 4-node rotor
    # Same discretisation in both codes (3 Euler-Bernoulli Hermite elements with consistent mass, rotary inertia
    # and gyroscopics, no shear; rigid discs; undamped springs): the frequencies may differ only by the round-off
    # of two eigen-solvers, bounded by eps·‖A‖/|λ| ≈ 2.2e-16 · (2π·52 kHz)² / (2π·30 Hz) ≈ 1.2e-7 relative for the
    # lowest mode. 1e-6 keeps a margin over that bound; a modelling difference is far larger (rotary inertia alone
    # changes the pinned-pinned shaft frequency by 0.34 %, test_rotor.py).
    np.testing.assert_allclose(f, f_ref, rtol=1e-6)
    if rpm > 0.0:  # at standstill the pairs are degenerate (planar for B): no whirl direction to compare
        assert list(p) == [LABEL[m["whirl"]] for m in ref]


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

    from frbmodel.linear.modal import state_matrix

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
    from frbmodel.linear.modal import precession_index

    # v = cos βt, w = sin βt (CCW orbit) -> v̄ = 1, w̄ = −i -> Ψ = +1 (docs/theory/modal.md#modal-analysis)
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
    from frbmodel.linear.modal import classify_precession, modes, precession_index, speed_modes

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
        np.testing.assert_allclose(fast[k].eigenvalues, ref.eigenvalues, rtol=1e-9,
                                   atol=1e-10 * abs(ref.eigenvalues).max())
        pf = classify_precession(*precession_index(fast[k].shapes, v, w))
        pr = classify_precession(*precession_index(ref.shapes, v, w))
        low = ref.frequencies_hz < 3000
        assert list(pf[low]) == list(pr[low])
