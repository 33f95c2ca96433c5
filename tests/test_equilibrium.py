"""Equilibria of methods C, D, F, G, I, J: docs/theory/parameters.md#reference-numbers reference values and consistency
between methods."""

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.physics.film import film_force

# docs/theory/parameters.md#reference-numbers (turbine bearing unless noted): c_o [µm], rpm, method -> RSR, ε_I, ε_O
REF = [
    (36, 30e3, "F", 0.19903, 0.2436, 0.3613), (36, 30e3, "I", 0.19240, 0.2446, 0.3686),
    (36, 30e3, "J", 0.18894, 0.2452, 0.3725), (36, 100e3, "F", 0.19903, 0.0828, 0.1422),
    (36, 100e3, "I", 0.19794, 0.0828, 0.1429), (36, 100e3, "J", 0.19753, 0.0829, 0.1432),
    (36, 200e3, "J", 0.19863, 0.0419, 0.0737), (46, 30e3, "F", 0.24100, 0.2371, 0.4257),
    (46, 30e3, "I", 0.22715, 0.2392, 0.4384), (46, 30e3, "J", 0.22191, 0.2400, 0.4434),
    (46, 100e3, "J", 0.23763, 0.0803, 0.1877),
]


@pytest.mark.parametrize("co,rpm,method,rsr,ei,eo", REF)
def test_reference_equilibria(co, rpm, method, rsr, ei, eo):
    b = frb.equilibrium(frb.turbocharger(co * 1e-6), method, rpm).bearings[0]
    # the table is rounded to 5 (RSR) and 4 (ε) decimals
    assert b.ring_speed_ratio == pytest.approx(rsr, abs=6e-6)
    assert b.eps_inner == pytest.approx(ei, abs=6e-5)
    assert b.eps_outer == pytest.approx(eo, abs=6e-5)


def test_compressor_reference_and_positions():
    eq = frb.equilibrium(frb.turbocharger(36e-6), "J", 100e3)
    c = eq.bearings[1]
    assert c.ring_speed_ratio == pytest.approx(0.19903, abs=6e-6)
    assert c.eps_inner == pytest.approx(0.0022, abs=6e-5) and c.eps_outer == pytest.approx(0.0024, abs=6e-5)
    f = frb.equilibrium(frb.turbocharger(36e-6), "F", 100e3).bearings[0]
    # docs/theory/parameters.md#reference-numbers: journal rel. ring (2.7985, −0.2959) µm, ring (5.0354, −0.9210) µm at
    # RSR (6)
    np.testing.assert_allclose(f.r_inner * 1e6, [2.7985, -0.2959], atol=2e-4)
    np.testing.assert_allclose(f.ring * 1e6, [5.0354, -0.9210], atol=2e-4)


@pytest.mark.parametrize("method", ["F", "G", "I", "J", "D"])
def test_equilibrium_satisfies_force_balance(method):
    tc = frb.turbocharger(40e-6)
    eq = frb.equilibrium(tc, method, 80e3)
    for b, e, w in zip(tc.bearings, eq.bearings, tc.bearing_loads):
        fi = film_force(b.inner, e.r_inner, [0, 0], e.omega_inner)
        fo = film_force(b.outer, e.ring, [0, 0], e.omega_outer)
        np.testing.assert_allclose(fi, [0, w], atol=1e-9 * max(abs(w), 1))  # (28)-(29)
        np.testing.assert_allclose(fo - fi, [0, b.ring_mass * 9.81], atol=1e-9)  # (30)-(31)


def test_f_and_g_coincide():
    tc = frb.turbocharger(36e-6)
    for rpm in (10e3, 60e3, 250e3):
        f, g = frb.equilibrium(tc, "F", rpm), frb.equilibrium(tc, "G", rpm)
        for a, b in zip(f.bearings, g.bearings):
            # G solves the coupled system by Newton to 1e-13 in scaled unknowns; F is closed form
            np.testing.assert_allclose(a.journal, b.journal, atol=1e-12 * 36e-6)
            np.testing.assert_allclose(a.ring, b.ring, atol=1e-12 * 36e-6)
        assert g.evaluations > f.evaluations  # the coupled solve needs more work (Fig. 11)


def test_i_and_j_ring_speeds_below_eq6_rising_more_in_turbine():
    for co in (36e-6, 46e-6):
        tc = frb.turbocharger(co)
        rsr6 = frb.ring_speed_ratio(tc.bearings[0])
        speeds = np.linspace(20e3, 250e3, 8)
        for m in "IJ":
            r = np.array([[b.ring_speed_ratio for b in frb.equilibrium(tc, m, s).bearings] for s in speeds])
            assert np.all(r < rsr6 + 1e-12)
            assert np.all(np.diff(r[:, 0]) > 0)  # rises with speed
            rise = r[-1] - r[0]
            assert rise[0] > rise[1]  # more so in the more heavily loaded turbine bearing
        rj = frb.equilibrium(tc, "J", 30e3).bearings[0].ring_speed_ratio
        ri = frb.equilibrium(tc, "I", 30e3).bearings[0].ring_speed_ratio
        assert rj < ri  # offset torques brake the ring further


def test_corrected_model_equilibrium_balances_forces():
    tc = frb.turbocharger(36e-6, film_model="short_corrected")
    eq = frb.equilibrium(tc, "J", 60e3)
    short = frb.equilibrium(frb.turbocharger(36e-6), "J", 60e3)
    b, e = tc.bearings[0], eq.bearings[0]
    fi = film_force(b.inner, e.r_inner, [0, 0], e.omega_inner, "short_corrected")
    np.testing.assert_allclose(fi, [0, tc.bearing_loads[0]], atol=1e-9)
    assert e.eps_inner > short.bearings[0].eps_inner  # weaker finite film -> more eccentric


@pytest.mark.parametrize("method", ["A", "B", "E"])
def test_methods_without_films_have_no_equilibrium(method):
    with pytest.raises(frb.ParameterError, match="no film equilibrium"):
        frb.equilibrium(frb.turbocharger(), method, 1e5)


@pytest.mark.parametrize("speed", [0.0, -100.0])
def test_non_positive_speed_is_rejected(speed):
    with pytest.raises(frb.ParameterError, match="speed"):
        frb.equilibrium(frb.turbocharger(), "J", speed)


def test_unknown_method_letter():
    with pytest.raises(frb.ParameterError, match="'H'.*valid methods are A, B, C, D, E, F, G, I, J"):
        frb.equilibrium(frb.turbocharger(), "H", 1e5)
