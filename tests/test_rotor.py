"""FE rotor against closed-form beam results and hand statics."""
import math

import numpy as np
import pytest
from scipy.linalg import eigh

import frbmodel as frb
from frbmodel.rotor import Disc, Rotor, ShaftElement


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
    # physics.md §10: rotor total 0.522431 kg
    assert u @ r.M @ u == pytest.approx(0.522431, rel=1e-6)
    assert r.mass == pytest.approx(0.522431, rel=1e-6)


def test_static_reactions_equal_hand_statics():
    tc = frb.turbocharger()
    g = 9.81
    rho_a = 7860 * math.pi / 4 * 0.011 ** 2
    # moments about node 1 (z = 33 mm) and force balance, physics.md §10
    pieces = [(0.326, 0.0), (0.118, 0.105), (rho_a * 0.033, 0.0165), (rho_a * 0.039, 0.0525), (rho_a * 0.033, 0.0885)]
    total = sum(m for m, _ in pieces) * g
    moment = sum(m * g * (z - 0.033) for m, z in pieces)  # weight moment about node 1 (downward loads)
    w2 = moment / 0.039  # compressor reaction (upward positive) from moment balance
    w1 = total - w2
    np.testing.assert_allclose(tc.bearing_loads, [w1, w2], rtol=1e-10)
    np.testing.assert_allclose(tc.bearing_loads, [5.3093, -0.1843], atol=1e-4)


def test_pinned_pinned_shaft_first_frequency():
    # physics.md §7.4: a pinned-pinned 105 mm shaft (d = 11 mm) gives 1969.8 Hz with rotary inertia
    # (1976.4 Hz Euler-Bernoulli without); 30 elements make the FE discretisation error negligible
    n_el = 30
    rot = Rotor([ShaftElement(0.105 / n_el, 0.011) for _ in range(n_el)])
    keep = [i for i in range(rot.n_dof) if i % 4 in (0, 3)]  # x-z plane: v, θy
    pinned = [0, 4 * n_el]
    keep = [i for i in keep if i not in pinned]
    w2 = eigh(rot.K[np.ix_(keep, keep)], rot.M[np.ix_(keep, keep)], eigvals_only=True)
    f1 = math.sqrt(w2[0]) / (2 * math.pi)
    assert f1 == pytest.approx(1969.8, abs=0.5)
    # closed form without rotary inertia: (π/L)² sqrt(EI/ρA)/(2π)
    ei = 2e11 * math.pi * 0.011 ** 4 / 64
    ra = 7860 * math.pi * 0.011 ** 2 / 4
    f_eb = (math.pi / 0.105) ** 2 * math.sqrt(ei / ra) / (2 * math.pi)
    assert f_eb == pytest.approx(1976.4, abs=0.1)
    assert f1 < f_eb  # rotary inertia lowers the frequency


def test_invalid_rotor_parameters():
    with pytest.raises(frb.ParameterError, match="length"):
        ShaftElement(-0.01, 0.01)
    with pytest.raises(frb.ParameterError, match="inner_diameter"):
        ShaftElement(0.01, 0.01, 0.02)
    with pytest.raises(frb.ParameterError, match="mass"):
        Disc(0, 0.0, 1e-5, 1e-5, "w")
    with pytest.raises(frb.ParameterError, match="node"):
        Rotor([ShaftElement(0.01, 0.01)], [Disc(5, 1.0, 1e-5, 1e-5, "w")])
