"""The compiled integration path (frbmodel.nonlinear.compiled, runup(integrator="radau")) against the scipy-LSODA
reference."""
import numpy as np
import pytest

import frbmodel as frb
from frbmodel.nonlinear.compiled import pack_problem, rhs_packed, solve_chunk
from frbmodel.nonlinear.runup import SpeedProfile, Unbalance, atol_vector, build_problem, initial_state, runup
from frbmodel.signals.spectral import spectrogram


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger(36e-6)


@pytest.mark.parametrize("profile", [SpeedProfile.ramp(20e3, 60e3, 0.1), SpeedProfile.torque(2e-3, 30e3, 0.1)],
                         ids=["prescribed", "torque"])
def test_packed_rhs_is_the_monolithic_rhs(tc, profile):
    """The callback's data travel through one flat array; unpacked, every argument must be the one the monolithic
    RHS gets from Python: the derivatives must agree to round-off, at a perturbed state with unbalance on both
    wheels so that every packed array enters the result. Round-off: the same code compiled for other array layouts
    may contract multiply-adds differently, and the rotor accelerations are sums of terms up to ~1e3 times larger
    than the result (measured differences <= 6e-11 relative); 1e-9 bounds that, while a wrongly packed array (a
    matrix, a node, an unbalance) changes the result by >= 1e-3."""
    unb = [Unbalance("turbine_wheel", 2e-6, 0.3), Unbalance("compressor_wheel", 1e-6, 1.1)]
    p = build_problem(tc, profile, "short_corrected", unb)
    y = initial_state(p) * (1 + 1e-3 * np.sin(np.arange(p.n_states)))
    for t in (0.0, 0.0371, 0.1):
        want = p.rhs(t, y, np.empty(p.n_states)).copy()
        got = rhs_packed(t, y, np.empty(p.n_states), pack_problem(p))
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.max(np.abs(want)))


def test_chunk_matches_lsoda_on_a_smooth_interval(tc):
    """Over 2 ms at a stable speed (2 krpm: the journals settle, no whirl to amplify differences) the compiled Radau
    solver and scipy's LSODA, both at rtol 1e-9, must give the same journal path to 1e-3 of its excursion
    (each is accurate to ~1e-9 relative; 1e-3 leaves room for the different error estimators)."""
    from scipy.integrate import solve_ivp

    p = build_problem(tc, SpeedProfile.constant(2e3, 0.002), "short_corrected")
    y0 = initial_state(p)
    atol, _ = atol_vector(p, 1e-12)
    t = np.linspace(0.0, 0.002, 21)
    y, steps, message = solve_chunk(pack_problem(p), y0, t, 1e-9, atol)
    ref = solve_ivp(lambda s, x: p.rhs(s, x, np.empty(p.n_states)).copy(), (0.0, 0.002), y0, method="LSODA",
                    t_eval=t, rtol=1e-9, atol=atol)
    j = 4 * tc.bearings[0].node
    excursion = np.ptp(ref.y[j])
    assert message == "" and steps > 0 and excursion > 0
    np.testing.assert_allclose(y[:, j], ref.y[j], rtol=0, atol=1e-3 * excursion)


@pytest.fixture(scope="module")
def lsoda_components(tc):
    r = runup(tc, speed_rpm=(20e3, 60e3), duration=0.25, output_rate_hz=10000, integrator="lsoda")
    return spectrogram(r, "turbine_wheel", segment_s=0.01).components()


@pytest.mark.parametrize("integrator", ["rodas", "radau"])
def test_compiled_and_lsoda_runups_have_the_same_onsets(tc, lsoda_components, integrator):
    """Acceptance (issue #13): each compiled path and the scipy-LSODA path give the same whirl onsets and onset
    frequencies (1 %) on a short run-up with two components, each at the default tolerances (converged to 1 %,
    README "Tolerance convergence")."""
    r = runup(tc, speed_rpm=(20e3, 60e3), duration=0.25, output_rate_hz=10000, integrator=integrator)
    assert r.status == "finished" and r.meta["integrator"] == integrator
    a, b = spectrogram(r, "turbine_wheel", segment_s=0.01).components(), lsoda_components
    assert len(a) == len(b) and len(a) >= 2
    for ca, cb in zip(a, b):
        assert ca.label == cb.label and ca.direction == cb.direction
        assert ca.onset_threshold_rpm == pytest.approx(cb.onset_threshold_rpm, rel=0.01, nan_ok=True)
        assert ca.onset_rpm == pytest.approx(cb.onset_rpm, rel=0.01, nan_ok=True)
        assert ca.onset_hz == pytest.approx(cb.onset_hz, rel=0.01, nan_ok=True)


def test_unknown_integrator_is_refused(tc):
    with pytest.raises(frb.ParameterError, match="integrator = 'rk4' is unknown; valid: 'rodas', 'radau', 'lsoda'"):
        runup(tc, duration=0.01, integrator="rk4")


def test_compiled_solver_failure_keeps_the_results(tc):
    """A step budget too small for the run makes the compiled solver stop: the run-up must say so (status
    "stopped", the time reached) and keep the samples before it, as the LSODA path does."""
    with pytest.raises(frb.RunupStopped, match="integrator failed after t = ") as exc:
        runup(tc, speed_rpm=(20e3, 25e3), duration=0.01, nsteps=2, integrator="radau")
    r = exc.value.result
    assert r.status == "stopped" and r.time.size >= 1 and np.all(np.isfinite(r.speed_rpm))
