"""Bearing losses (frbmodel.physics.losses): journal torque and friction power of both films, against the Petroff closed
form, the film's moment balance, an independent dissipation integral, and the steady torque balance."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import frbmodel as frb
from frbmodel.linear.losses import bearing_losses
from frbmodel.nonlinear.recorder import RunupResult, RunupSchema
from frbmodel.physics.bearing import ring_rhs_kernel
from frbmodel.physics.losses import bearing_loss, film_arrays


def _petroff(film):
    """A = 2π μ R³ L / c of a centred film [N m s] (docs/theory/rings.md#wall-torques-of-one-film), written out."""
    return 2 * math.pi * film.viscosity * film.radius ** 3 * film.length / film.clearance


@pytest.mark.parametrize("b", [0, 1])
@pytest.mark.parametrize("omega_r, omega_fr", [(2000.0, 400.0), (26180.0, 5210.0), (1000.0, 1500.0)])
def test_centred_power_loss_is_petroff(b, omega_r, omega_fr):
    """Centred journal and ring, no lateral motion: no pressure force, so T_J = −A_I (ω_R − ω_FR) and
    P = A_I (ω_R − ω_FR)² + A_O ω_FR² (docs/theory/rings.md#friction-torque-and-power-loss), for both bearings (their
    viscosities differ)."""
    bearing = frb.turbocharger(36e-6).bearings[b]
    a_i, a_o = _petroff(bearing.inner), _petroff(bearing.outer)
    t_j, p_i, p_o = bearing_loss(bearing, [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, omega_fr], omega_r)
    # acceptance 1e-6 relative; the kernel evaluates the same products, so agreement is at round-off
    assert t_j == pytest.approx(-a_i * (omega_r - omega_fr), rel=1e-6)
    assert p_i == pytest.approx(a_i * (omega_r - omega_fr) ** 2, rel=1e-6)
    assert p_o == pytest.approx(a_o * omega_fr ** 2, rel=1e-6)
    assert p_i + p_o == pytest.approx(a_i * (omega_r - omega_fr) ** 2 + a_o * omega_fr ** 2, rel=1e-6)


def _dissipation(film, r, rdot, omega_s, d_omega):
    """Viscous dissipation [W] of one short π-film, built from the pressure field (not from torques or forces):
    Couette shear μ (R Δω)² / h over the full circumference (the model's oil streamers,
    docs/theory/rings.md#wall-torques-of-one-film) plus the
    axial Poiseuille flow of the short-bearing pressure p = P(θ) (z² − L²/4) over its positive zone, whose
    dissipation ∫ h³/(12 μ) (∂p/∂z)² dz = h³ P² L³ / (36 μ) per unit circumferential length."""
    mu, radius, length, c = film.viscosity, film.radius, film.length, film.clearance

    def h(th):
        return c - r[0] * math.cos(th) - r[1] * math.sin(th)

    def prof(th):  # P(θ): ∂z(h³ ∂z p) = 6μω_s ∂θh + 12μ ∂t h with p = P (z² − L²/4)
        h_th = r[0] * math.sin(th) - r[1] * math.cos(th)
        h_t = -rdot[0] * math.cos(th) - rdot[1] * math.sin(th)
        return (6 * mu * omega_s * h_th + 12 * mu * h_t) / (2 * h(th) ** 3)

    couette = mu * radius ** 3 * length * d_omega ** 2 * quad(lambda th: 1.0 / h(th), 0, 2 * math.pi,
                                                              epsabs=0, epsrel=1e-13, limit=200)[0]
    grid = np.linspace(0.0, 2 * math.pi, 721)
    vals = [prof(t) for t in grid]
    pts = [0.0] + [brentq(prof, grid[k], grid[k + 1], xtol=1e-15) for k in range(720)
                   if vals[k] * vals[k + 1] < 0] + [2 * math.pi]
    poiseuille = 0.0
    for a, b in zip(pts[:-1], pts[1:]):
        if prof(0.5 * (a + b)) < 0:  # p > 0 where P < 0 (z² − L²/4 <= 0)
            poiseuille += quad(lambda th: h(th) ** 3 * prof(th) ** 2 * length ** 3 / (36 * mu) * radius, a, b,
                               epsabs=0, epsrel=1e-12, limit=200)[0]
    return couette + poiseuille


def test_power_loss_equals_the_dissipation_of_the_film_flow():
    """For random dynamic states (eccentric, moving journal and ring, any speeds), the friction power from the
    wall torques and forces equals the viscous dissipation integrated from the pressure field, film by film, and is
    therefore never negative."""
    bearing = frb.turbocharger(36e-6).bearings[0]
    ci, co = bearing.inner.clearance, bearing.outer.clearance
    rng = np.random.default_rng(3)
    for _ in range(12):
        ring_xy = rng.uniform(0.0, 0.85) * co * np.array([math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a)])
        rel = rng.uniform(0.0, 0.85) * ci * np.array([math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a)])
        ring_v = rng.normal(size=2) * 0.02
        journal_v = rng.normal(size=2) * 0.05
        w_r, w_fr = rng.uniform(-2e4, 3e4), rng.uniform(-5e3, 8e3)
        journal = np.r_[ring_xy + rel, journal_v]
        ring = np.r_[ring_xy, ring_v, w_fr]
        _, p_i, p_o = bearing_loss(bearing, journal, ring, w_r)
        want_i = _dissipation(bearing.inner, rel, journal_v - ring_v, w_r + w_fr, w_r - w_fr)
        want_o = _dissipation(bearing.outer, ring_xy, ring_v, w_fr, w_fr)
        # quadrature to ~1e-12 on smooth sub-intervals; 1e-9 relative leaves room for round-off in both
        assert p_i == pytest.approx(want_i, rel=1e-9)
        assert p_o == pytest.approx(want_o, rel=1e-9)
        assert p_i >= 0.0 and p_o >= 0.0


def test_journal_torque_is_the_reaction_of_the_ring_torque():
    """The film is massless: the torques on journal and ring about the origin cancel,
    T_J + q_J × F + M^I − q_FR × F = 0, i.e. T_J + M^I = −(q_J − q_FR) × F^I
    (docs/theory/rings.md#wall-torques-of-one-film). M^I is taken from the
    ring's equation of motion (:func:`frbmodel.physics.bearing.ring_rhs_kernel`, I_FR ω̇_FR = M^I + M^O) with a centred,
    resting ring, whose outer film then adds M^O = −A_O ω_FR (closed form)."""
    tc = frb.turbocharger(36e-6)
    rng = np.random.default_rng(5)
    for bearing in tc.bearings:
        geom, polys = film_arrays(bearing, tc.film_model)
        for _ in range(10):
            rel = rng.uniform(0.0, 0.9) * bearing.inner.clearance * np.array([math.cos(a := rng.uniform(0, 6.3)),
                                                                               math.sin(a)])
            jv = rng.normal(size=2) * 0.05
            w_r, w_fr = rng.uniform(1e3, 3e4), rng.uniform(0.0, 6e3)
            ring = np.array([0.0, 0.0, 0.0, 0.0, w_fr])
            d = np.empty(5)
            fx, fy, _, _ = ring_rhs_kernel(geom, polys, bearing.ring_mass, bearing.ring_inertia, tc.gravity, rel[0],
                                           rel[1], jv[0], jv[1], ring, w_r, math.inf, d)
            m_inner = bearing.ring_inertia * d[4] + _petroff(bearing.outer) * w_fr
            t_j, _, _ = bearing_loss(bearing, np.r_[rel, jv], ring, w_r, tc.film_model)
            cross = rel[0] * fy - rel[1] * fx
            # the Petroff parts cancel and both offset parts are −(e × F)/2; round-off relative to the Petroff part
            assert t_j + m_inner == pytest.approx(-cross, abs=1e-10 * abs(t_j))
        t_j, _, _ = bearing_loss(bearing, np.zeros(4), [0.0, 0.0, 0.0, 0.0, 900.0], 5000.0)
        assert t_j < 0  # a centred journal spinning faster than its ring is braked


def test_steady_power_loss_is_journal_torque_times_speed():
    """At the method-J equilibrium the ring torque is balanced and nothing moves laterally, so the power the films
    dissipate is all taken from the journal: P = −T_J ω_R (docs/theory/rings.md#friction-torque-and-power-loss)."""
    tc = frb.turbocharger(36e-6)
    df = bearing_losses(tc, [20e3, 100e3, 250e3])
    w = df["speed [rpm]"].to_numpy() * math.pi / 30
    # the equilibrium's torque residual is solved to round-off; 1e-9 relative allows for its tolerance
    np.testing.assert_allclose(df["power loss [W]"], -df["journal torque [N m]"] * w, rtol=1e-9)
    assert (df["power loss inner [W]"] > 0).all() and (df["power loss outer [W]"] > 0).all()
    assert list(df["bearing"]) == ["turbine", "compressor"] * 3


def test_bearing_loss_is_vectorised_and_refuses_bad_states():
    bearing = frb.turbocharger(36e-6).bearings[1]
    rng = np.random.default_rng(1)
    journal = np.c_[rng.normal(size=(4, 2)) * 5e-6, rng.normal(size=(4, 2)) * 1e-3]
    ring = np.c_[rng.normal(size=(4, 2)) * 5e-6, np.zeros((4, 2)), rng.uniform(1e3, 2e3, 4)]
    t, p_i, p_o = bearing_loss(bearing, journal, ring, 8000.0)
    for k in range(4):
        assert (t[k], p_i[k], p_o[k]) == bearing_loss(bearing, journal[k], ring[k], 8000.0)
    with pytest.raises(frb.ParameterError, match="finite"):
        bearing_loss(bearing, [math.nan, 0, 0, 0], [0, 0, 0, 0, 1.0], 100.0)
    with pytest.raises(frb.ParameterError, match="eps"):
        bearing_loss(bearing, [0, 0, 0, 0], [bearing.outer.clearance, 0, 0, 0, 1.0], 100.0)


def test_recorder_loss_columns_and_old_files(tmp_path):
    """The loss columns round-trip; a results file written before they existed still loads (NaN there)."""
    schema = RunupSchema(("a", "b"), ("d",))
    assert schema.columns[-4:] == ["journal torque a [N m]", "power loss a [W]", "journal torque b [N m]",
                                   "power loss b [W]"]
    row = schema.row(0.1, 1000.0, [10.0, 20.0], np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2)),
                     [[1e-6, 2e-6]], journal_torque=[-1e-3, -2e-3], power_loss=[0.5, 0.25])
    res = RunupResult.from_rows(schema, row[None, :])
    assert res.journal_torque["b"][0] == -2e-3 and res.power_loss["a"][0] == 0.5
    df = res.to_dataframe()
    back = RunupResult.from_dataframe(df)
    np.testing.assert_array_equal(back.to_dataframe().to_numpy(), df.to_numpy())
    old = df.drop(columns=[c for c in df.columns if c.startswith(("journal torque", "power loss"))])
    old.to_csv(tmp_path / "runup.csv", index=False)
    loaded = RunupResult.load(tmp_path)
    assert np.isnan(loaded.power_loss["a"]).all() and np.isnan(loaded.journal_torque["b"]).all()
    np.testing.assert_array_equal(loaded.displacement["d"], [[1e-6, 2e-6]])
    assert isinstance(loaded.to_dataframe(), pd.DataFrame)
