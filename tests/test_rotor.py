"""FE rotor against closed-form beam results and hand statics."""
import math

import numpy as np
import pytest
from _reference import table2_bearing_loads
from scipy.linalg import eigh

import frbmodel as frb
from frbmodel.system.rotor import Disc, Rotor, ShaftElement


def test_matrices_symmetry_and_gyroscopic_skew():
    r = frb.turbocharger().rotor
    assert np.allclose(r.M, r.M.T) and np.allclose(r.K, r.K.T)
    assert np.allclose(r.G, -r.G.T)  # gyroscopic coupling does no work
    assert np.all(np.linalg.eigvalsh(r.M) > 0)


def test_free_free_rotor_has_four_rigid_body_modes_and_correct_mass():
    r = frb.turbocharger().rotor
    ev = np.linalg.eigvalsh(r.K)
    assert np.sum(np.abs(ev) < 1e-6 * ev.max()) == 4  # translation + tilt in each plane
    u = np.zeros(r.n_dof)
    u[0::4] = 1.0  # rigid x-translation (Hermite shape functions represent it exactly)
    # docs/theory/parameters.md#table-2-in-si-units: rotor total 0.522431 kg
    assert u @ r.M @ u == pytest.approx(0.522431, rel=1e-6)
    assert r.mass == pytest.approx(0.522431, rel=1e-6)


def test_static_reactions_equal_hand_statics():
    tc = frb.turbocharger()
    # moment and force balance of the rigid rotor (tests/_reference.py, docs/theory/parameters.md#table-2-in-si-units)
    np.testing.assert_allclose(tc.bearing_loads, table2_bearing_loads(tc.gravity), rtol=1e-10)
    np.testing.assert_allclose(tc.bearing_loads, [5.3093, -0.1843], atol=1e-4)  #
    # docs/theory/parameters.md#table-2-in-si-units (4 decimals)


def _pinned_pinned_frequencies_hz(n_el, plane, n_modes=3):
    """Lowest natural frequencies [Hz] of the project's FE model of a pinned-pinned 105 mm shaft (d = 11 mm,
    ``n_el`` equal elements) in one plane: ``plane`` = (displacement, rotation) DoF index within a node."""
    rot = Rotor([ShaftElement(0.105 / n_el, 0.011) for _ in range(n_el)])
    pinned = {plane[0], 4 * n_el + plane[0]}  # displacement of the two end nodes
    keep = [i for i in range(rot.n_dof) if i % 4 in plane and i not in pinned]
    w2 = eigh(rot.K[np.ix_(keep, keep)], rot.M[np.ix_(keep, keep)], eigvals_only=True)
    return np.sqrt(w2[:n_modes]) / (2 * math.pi)


def test_pinned_pinned_shaft_converges_to_the_rayleigh_beam():
    """The FE shaft (Euler-Bernoulli Hermite element with rotary inertia,
    docs/theory/equations-of-motion.md#euler-bernoulli-shaft-element) against the exact
    pinned-pinned Rayleigh beam, ω_n² = EI k⁴ / (ρA (1 + (I/A) k²)), k = nπ/L — 1969.76 Hz for n = 1, the
    docs/theory/equations-of-motion.md#euler-bernoulli-shaft-element value — in both planes (the y-z plane has θx =
    −w')."""
    E, rho, d, length = 2e11, 7860.0, 0.011, 0.105
    area, inertia = math.pi * d ** 2 / 4, math.pi * d ** 4 / 64
    k = np.arange(1, 4) * math.pi / length
    exact = np.sqrt(E * inertia * k ** 4 / (rho * area * (1 + inertia / area * k ** 2))) / (2 * math.pi)
    assert exact[0] == pytest.approx(1969.8, abs=0.05)  # the reference itself:
    # docs/theory/equations-of-motion.md#euler-bernoulli-shaft-element (0.1 Hz digits)
    errs = {}
    for n_el in (10, 20):
        fx = _pinned_pinned_frequencies_hz(n_el, (0, 3))  # x-z plane: v, θy
        fy = _pinned_pinned_frequencies_hz(n_el, (1, 2))  # y-z plane: w, θx
        # the y-z plane matrices are the x-z ones transformed by diag(1, −1): equal up to eigen-solver round-off
        np.testing.assert_allclose(fy, fx, rtol=1e-12)
        errs[n_el] = fx / exact - 1.0
        # conforming elements with consistent mass (Rayleigh-Ritz): the FE frequencies bound the exact ones above
        assert np.all(errs[n_el] > 0)
    # cubic Hermite elements: frequency error O(h⁴), so halving the element length divides it by 16
    # (14 ... 18 allows for the next term of the expansion; a lumped mass or a missing rotary inertia term
    # converges at O(h²) or to another limit)
    np.testing.assert_array_less(14.0, errs[10] / errs[20])
    np.testing.assert_array_less(errs[10] / errs[20], 18.0)


def test_invalid_rotor_parameters():
    with pytest.raises(frb.ParameterError, match="length"):
        ShaftElement(-0.01, 0.01)
    with pytest.raises(frb.ParameterError, match="inner_diameter"):
        ShaftElement(0.01, 0.01, 0.02)
    with pytest.raises(frb.ParameterError, match="mass"):
        Disc(0, 0.0, 1e-5, 1e-5, "w")
    with pytest.raises(frb.ParameterError, match="node"):
        Rotor([ShaftElement(0.01, 0.01)], [Disc(5, 1.0, 1e-5, 1e-5, "w")])
