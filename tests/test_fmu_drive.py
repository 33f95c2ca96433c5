"""Driven rotor FMU and bearing-loss outputs (issue #11 items 1-2, FMU side).

The bearing FMU's ``journal_torque`` and ``power_loss`` against the Petroff closed form and the film moment
balance (docs/theory/rings.md#torques-on-the-ring, rings.md#friction-torque-and-power-loss); the rotor FMU's
``speed_source`` = "torque" co-simulated
through the SSP against
the monolithic torque-driven run-up; "input" against "ramp"; an invalid ``speed_source``; rollback in torque mode.
"""
import math

import numpy as np
import pytest

import frbmodel as frb

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from test_fmu_strict import ERROR, OK, Host, judge  # noqa: E402

from frbmodel.cosim.master import Master, cosimulate, operating_point_overrides  # noqa: E402
from frbmodel.nonlinear.runup import SpeedProfile  # noqa: E402

#: films and ring speed of the Petroff check (any valid geometry; not the presets, so nothing is shared with them)
INNER = dict(radius=5.0e-3, length=6.0e-3, clearance=30e-6, viscosity=5.0e-3)
OUTER = dict(radius=8.0e-3, length=7.0e-3, clearance=50e-6, viscosity=6.0e-3)
OMEGA_R, OMEGA_FR = 9000.0, 3100.0  # rotor and ring speed [rad/s]


def _bearing_at(built, tmp_path, name, journal):
    """A bearing FMU with the films above, ring centred at rest laterally and spinning at OMEGA_FR, journal at
    ``journal`` (x, y, vx, vy) and rotor speed OMEGA_R; returns (host, outputs by name)."""
    h = Host(built / "fmus" / "FloatingRingBearing.fmu", name, tmp_path)
    params = {f"{f}.{k}": v for f, d in (("inner", INNER), ("outer", OUTER)) for k, v in d.items()}
    params.update({"ring.x0": 0.0, "ring.y0": 0.0, "ring.speed0": OMEGA_FR})
    h.start(params)
    h.set("setReal", ("journal.x", "journal.y", "journal.vx", "journal.vy", "rotor_speed"), [*journal, OMEGA_R])
    names = ("journal_torque", "power_loss", "force.x", "force.y", "eps_inner", "eps_outer", "ring.speed")
    return h, dict(zip(names, h.real(names)))


def _petroff_coefficient(f):
    """A = 2π μ R³ L / c [N m s] of a centred film (docs/theory/rings.md#torques-on-the-ring, the Petroff torque per
    unit speed)."""
    return 2 * math.pi * f["viscosity"] * f["radius"] ** 3 * f["length"] / f["clearance"]


def test_bearing_losses_are_petroff_at_a_centred_journal_and_ring(built, tmp_path):
    """Acceptance (issue #11): centred journal and ring, T_J = −A_I (ω_R − ω_FR) and P = A_I (ω_R − ω_FR)² +
    A_O ω_FR² (docs/theory/rings.md#friction-torque-and-power-loss) to 1e-6 (the kernels evaluate the same integrals in
    closed form: round-off)."""
    h, out = _bearing_at(built, tmp_path, "petroff", (0.0, 0.0, 0.0, 0.0))
    a_i, a_o = _petroff_coefficient(INNER), _petroff_coefficient(OUTER)
    assert out["ring.speed"] == OMEGA_FR and out["eps_inner"] == 0.0 and out["eps_outer"] == 0.0
    assert out["journal_torque"] == pytest.approx(-a_i * (OMEGA_R - OMEGA_FR), rel=1e-6)
    assert out["power_loss"] == pytest.approx(a_i * (OMEGA_R - OMEGA_FR) ** 2 + a_o * OMEGA_FR ** 2, rel=1e-6)
    judge(h)


def test_bearing_losses_belong_to_the_force_output(built, tmp_path):
    """Eccentric journal (ε_I = 0.6), centred ring, members at rest laterally: the journal torque is the
    eccentricity-corrected Petroff term plus the offset term of the FMU's own force output,
    T_J = −A_I Δω / sqrt(1 − ε²) − (r_x F_y − r_y F_x)/2, and with the inner film's moment balance
    T_J + M^I = −(r_x F_y − r_y F_x) the power the walls put in is P = −T_J Δω + (r_x F_y − r_y F_x) ω_FR +
    A_O ω_FR² (docs/theory/rings.md#torques-on-the-ring, rings.md#friction-torque-and-power-loss): outputs evaluated at
    one journal and ring state. 1e-9:
    round-off of
    sums of terms of similar size."""
    eps = 0.6
    r = eps * INNER["clearance"] * np.array([math.cos(1.1), math.sin(1.1)])
    h, out = _bearing_at(built, tmp_path, "offset", (r[0], r[1], 0.0, 0.0))
    assert out["eps_inner"] == pytest.approx(eps, rel=1e-12)
    moment = r[0] * out["force.y"] - r[1] * out["force.x"]  # e F_t of the film force on the journal
    dw = OMEGA_R - OMEGA_FR
    a_i, a_o = _petroff_coefficient(INNER), _petroff_coefficient(OUTER)
    assert abs(moment) > 0.1 * a_i * dw  # the offset term matters at this eccentricity
    assert out["journal_torque"] == pytest.approx(-a_i * dw / math.sqrt(1 - eps ** 2) - moment / 2, rel=1e-9)
    assert out["power_loss"] == pytest.approx(-out["journal_torque"] * dw + moment * OMEGA_FR + a_o * OMEGA_FR ** 2,
                                              rel=1e-9)
    judge(h)


@pytest.mark.parametrize("error", ["ConvergenceError", "IntegrationError"])
def test_numerical_failure_of_the_ring_integrator_is_a_discard_with_the_state_restored(built, tmp_path, monkeypatch,
                                                                                       error):
    """A ring integrator that does not converge (ConvergenceError) or blows up (IntegrationError) in a step after
    changing the ring state: fmi2Discard with the reason, the state of the start of the step kept (outputs as
    before), and the next step runs. The slave runs in this process on this frbmodel, so the failure is injected
    into the component's step."""
    from test_fmu_strict import DISCARD

    from frbmodel.nonlinear.components import BearingComponent

    h, before = _bearing_at(built, tmp_path, f"fail_{error}", (3e-6, -5e-6, 0.0, 0.0))
    real_step = BearingComponent.step

    def failing(self, *args, **kwargs):
        self.ring[:2] += 1e-6  # a half-done step
        raise getattr(frb, error)(f"injected {error}")

    monkeypatch.setattr(BearingComponent, "step", failing)
    _, text = h(DISCARD, "doStep", 0.0, 1e-5)
    assert f"injected {error}" in text and "discarded" in text
    after = dict(zip(before, h.real(list(before))))
    assert after == before
    monkeypatch.setattr(BearingComponent, "step", real_step)
    h(OK, "doStep", 0.0, 1e-5)
    judge(h)


# ---------------------------------------------------------------------------------------------------- torque mode
def _polar_inertia(rotor):
    """J_p [kg m²] written out from docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up: discs plus
    shaft elements ρ (π/32)(D_o⁴ − D_i⁴) l."""
    shaft = sum(e.density * math.pi / 32 * (e.outer_diameter ** 4 - e.inner_diameter ** 4) * e.length
                for e in rotor.shaft)
    return sum(d.polar_inertia for d in rotor.discs) + shaft


def test_torque_mode_cosimulation_equals_monolithic_runup(built):
    """Acceptance (issue #11): the SSP co-simulated by frbmodel's master with the rotor FMU in torque mode
    (constant drive torque, journal torques of the bearing FMUs braking) equals the monolithic torque-driven
    run-up through the first loss of stability (forward whirl, onset ~2 krpm): same components, onset within 2 %,
    frequency within 1 % (the acceptance tolerances); the speed trajectories within 0.1 % of the speed change, and
    the co-simulated speed equals Ω0 + ∫ (T_drive + Σ T_J) / J_p dt of its own recorded journal torques (0.1 % of
    the change; trapezoidal rule on the 5 kHz samples). A 0.13 N m drive takes the rotor from 1.5 to 4.4 krpm in
    0.3 s; macro step 20 µs, the upper end of the validated range (the onset from the equilibrium is insensitive
    to it)."""
    from frbmodel.signals.spectral import spectrogram

    tc = frb.turbocharger(36e-6)
    T, H, drive, rate = 0.3, 2e-5, 0.13, 5e3  # [s], [s], [N m], [Hz]: sub-synchronous whirl at 15-50 Hz
    m = frb.runup(tc, profile=SpeedProfile.torque(drive, 1.5e3, T), duration=T, output_rate_hz=rate,
                  perturbation=0.05, progress=False)
    ov = operating_point_overrides(tc, 1.5e3, perturbation=0.05)
    ov["rotor"].update(speed_source=("String", "torque"), drive_torque=("Real", drive))
    c = cosimulate(built / "turbocharger.ssp", "co36", stop_time=T, step_size=H, progress=False, overrides=ov,
                   output_rate_hz=rate)
    change = m.speed_rpm[-1] - m.speed_rpm[0]
    assert change > 2500  # through the onset region
    np.testing.assert_allclose(c.time, m.time, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.speed_rpm, m.speed_rpm, rtol=0, atol=1e-3 * change)
    w = c.speed_rpm * math.pi / 30
    torque = drive + sum(c.journal_torque[b.name] for b in tc.bearings)
    want = w[0] + np.r_[0.0, np.cumsum(0.5 * (torque[1:] + torque[:-1]) * np.diff(c.time))] / _polar_inertia(tc.rotor)
    np.testing.assert_allclose(w, want, rtol=0, atol=1e-3 * (w[-1] - w[0]))
    assert np.all(c.power_loss["turbine"] > 0) and np.all(c.power_loss["compressor"] > 0)
    cm = spectrogram(m, "turbine_wheel", segment_s=0.05).components()
    cc = spectrogram(c, "turbine_wheel", segment_s=0.05).components()
    assert [(x.label, x.direction) for x in cc] == [(x.label, x.direction) for x in cm]
    sub = [x for x in cm if x.label.startswith("sub")]
    assert sub and math.isfinite(sub[0].onset_rpm)  # a sub-synchronous onset inside the run
    for a, b in zip(cm, cc):
        assert b.onset_estimate == a.onset_estimate, a.label
        assert b.onset_rpm == pytest.approx(a.onset_rpm, rel=0.02, nan_ok=True), a.label
        assert b.onset_hz == pytest.approx(a.onset_hz, rel=0.01, nan_ok=True), a.label


def test_torque_mode_spin_and_rollback(built, tmp_path):
    """The rotor FMU alone in torque mode (bearing inputs: fixed springs and dampers, journal torques): each step
    Ω1 = Ω0 + H (T_drive + Σ T_J) / J_p (J_p from docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up)
    and φ1 = φ0 + H (Ω0 + Ω1) / 2 (the speed is
    linear over the step); getFMUstate / setFMUstate replays the same inputs bit for bit (rotor DoFs, speed,
    angle); a step with a non-finite journal torque is discarded and, after restoring, the rotor runs on as
    before. 1e-12: round-off of a few operations."""
    from test_fmu_strict import DISCARD

    tc = frb.turbocharger(36e-6)
    jp, H, tj = _polar_inertia(tc.rotor), 1e-5, (-1.5e-3, -2.0e-3)
    h = Host(built / "fmus" / "TurbochargerRotor.fmu", "spin", tmp_path)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set("setString", ["speed_source"], ["torque"])
    h.set("setReal", ["speed_start"], [2000.0])
    h(OK, "exitInitializationMode")
    springs = {f"{b.name}_bearing.{m}.{i}{i}": v for b in tc.bearings
               for m, v in (("stiffness", 2e6), ("damping", 300.0)) for i in "xy"}
    springs.update({f"{b.name}_bearing.torque": t for b, t in zip(tc.bearings, tj)})
    h.set("setReal", springs.keys(), springs.values())
    outs = ["rotor_speed", "rotor_angle", "turbine_bearing.journal.x", "turbine_bearing.journal.y",
            "compressor_wheel.y"]

    def run(k0, n):
        res = []
        for k in range(k0, k0 + n):
            drive = 0.01 * (1 + 0.3 * math.sin(k))  # [N m], changing every step
            h.set("setReal", ["drive_torque"], [drive])
            w0, phi0 = h.real(outs[:2])
            h(OK, "doStep", k * H, H)
            w1, phi1 = h.real(outs[:2])
            assert w1 == pytest.approx(w0 + H * (drive + sum(tj)) / jp, rel=1e-12)
            assert phi1 == pytest.approx(phi0 + H * (w0 + w1) / 2, rel=1e-12)
            res.append(h.real(outs))
        return np.array(res)

    run(0, 3)
    saved, _ = h(OK, "getFMUstate")
    first = run(3, 5)
    h(OK, "setFMUstate", saved)
    np.testing.assert_array_equal(run(3, 5), first)
    h.set("setReal", ["turbine_bearing.torque"], [math.nan])
    _, text = h(DISCARD, "doStep", 8 * H, H)
    assert "torque" in text
    h.set("setReal", ["turbine_bearing.torque"], [tj[0]])
    h(OK, "setFMUstate", saved)  # back to before the discarded step
    np.testing.assert_array_equal(run(3, 5), first)
    h(OK, "freeFMUstate", saved)
    judge(h)


def test_invalid_speed_source_is_an_error_listing_the_valid_values(built, tmp_path):
    h = Host(built / "fmus" / "TurbochargerRotor.fmu", "bad_source", tmp_path)
    h(OK, "setupExperiment", None, 0.0, None)
    h(OK, "enterInitializationMode")
    h.set("setString", ["speed_source"], ["turbine"])
    _, text = h(ERROR, "exitInitializationMode")
    assert "speed_source = 'turbine' is invalid" in text and "'ramp', 'input', 'torque'" in text
    judge(h)


# ---------------------------------------------------------------------------------------------------- input mode
def _ramp_or_input(ssp, source, tc, rpm, T, H, first):
    """Recorder rows of the SSP run by frbmodel's master stepping by ``first``, H − ``first``, then H, with the
    rotor speed from the ramp ``rpm`` = (start, end) over T, or, for ``source`` = "input", the same ramp fed into
    ``speed_in`` at the start of every step."""
    w0, w1 = (x * math.pi / 30 for x in rpm)
    ov = operating_point_overrides(tc, rpm[0], end_rpm=rpm[1], ramp_time=T, perturbation=0.05)
    ov["rotor"].update(speed_source=("String", source), speed_in=("Real", w0))
    rows = []
    with Master(ssp, "co36", stop_time=T, step_size=H, overrides=ov) as m:
        m.initialize()
        vr = m.rotor.vr(["speed_in"])
        t = 0.0
        for h in [first, H - first] + [H] * (int(round(T / H)) - 1):
            if source == "input":
                m.rotor.call("setReal", vr, [w0 + (w1 - w0) / T * t])
            t = m.step(t, h)
            rows.append(m.sample(t))
    return np.array(rows)


def test_speed_input_reproduces_the_ramp(built):
    """speed_source = "input" fed the ramp of "ramp" mode at every communication point gives the ramp mode's run.

    The input mode takes the angular acceleration from its last two inputs, so its first step (no history yet)
    runs at constant speed: a first step of 1 ns gives it the history (the effect of that step's missing rate is
    proportional to its length, far below the tolerances). Speeds then agree to round-off (1e-12 relative; measured
    2e-13), journals and rings to 1e-7 of the clearance: the ring integrator converges the ring speed to 1e-9 of
    itself per stage, so runs whose inputs differ by round-off differ at that level (measured 5e-9 of the clearance
    after 1000 steps). With a first step of 5 µs instead, its missing rate shows at 1e-5 of the clearance: the
    comparison resolves a one-step rate error."""
    tc = frb.turbocharger(36e-6)
    rpm, T, H = (1500.0, 1900.0), 0.01, 1e-5  # a stable ramp below the first whirl onset
    ssp = built / "turbocharger.ssp"
    ramp = _ramp_or_input(ssp, "ramp", tc, rpm, T, H, 1e-9)
    inp = _ramp_or_input(ssp, "input", tc, rpm, T, H, 1e-9)
    np.testing.assert_allclose(inp[1:, 1], ramp[1:, 1], rtol=1e-12)  # speed [rpm] after the first step
    clearance = tc.bearings[0].inner.clearance
    positions = slice(6, 14)  # journal and ring x, y of both bearings [m] (RunupSchema columns)
    assert np.abs(ramp[:, positions] - ramp[0, positions]).max() > 0.01 * clearance  # a transient to follow
    assert np.abs(inp[:, positions] - ramp[:, positions]).max() < 1e-7 * clearance
    # the same comparison with a first step of 5 µs (that step without the rate): measured 9e-6 of the clearance
    ramp, inp = (_ramp_or_input(ssp, source, tc, rpm, T, H, H / 2) for source in ("ramp", "input"))
    assert np.abs(inp[:, positions] - ramp[:, positions]).max() > 1e-6 * clearance


# ---------------------------------------------------------------------------------------------------- SSP
def test_ssp_for_a_rotor_with_other_bearing_and_disc_names(tmp_path):
    """write_ssp(system=...) for a rotor FMU built for a system whose bearings and discs have other names: the
    bearing components carry the system's bearing names, every connection (journal torque included) joins
    variables the FMUs have, and frbmodel's master runs the SSP in torque mode."""
    import shutil
    from dataclasses import replace
    from pathlib import Path

    from fmpy import read_model_description

    from frbmodel.cosim.build import build_fmus
    from frbmodel.cosim.ssp import read_ssp, write_ssp

    tc = frb.turbocharger(36e-6)
    names = {"turbine": "hot", "compressor": "cold"}
    system = tc.with_(bearings=tuple(replace(b, name=names[b.name]) for b in tc.bearings),
                      rotor=replace(tc.rotor, discs=tuple(replace(d, name=f"wheel_{i}")
                                                          for i, d in enumerate(tc.rotor.discs))))
    build = tmp_path / "build"
    build_fmus(build, Path(__file__).resolve().parents[1], progress=lambda m: None,
               rotor_file=system.save(tmp_path / "renamed.toml"))
    ssp = tmp_path / "ssp"
    write_ssp(ssp, clearances=(36e-6,), start_rpm=1500, end_rpm=1500, stop_time=0.002, system=system)
    for f in ("FloatingRingBearing", "TurbochargerRotor"):
        shutil.copy(build / "fmus" / f"{f}.fmu", ssp / "resources")
    with read_ssp(ssp) as s:
        assert set(s.components) == {"rotor", "hot", "cold"}
        variables = {c: {v.name for v in read_model_description(str(path)).modelVariables}
                     for c, path in s.components.items()}
        assert all(sc in variables[se] and ec in variables[ee] for se, sc, ee, ec in s.connections)
        assert ("hot", "journal_torque", "rotor", "hot_bearing.torque") in s.connections
        assert ("cold", "journal_torque", "rotor", "cold_bearing.torque") in s.connections
    ov = {"rotor": {"speed_source": ("String", "torque"), "drive_torque": ("Real", 0.05)}}
    run = cosimulate(ssp, "co36", progress=False, overrides=ov)
    assert run.status == "finished" and run.speed_rpm[-1] > run.speed_rpm[0]
    assert np.all(run.power_loss["hot"] > 0) and np.all(run.journal_torque["cold"] < 0)
    # the whole-turbocharger FMU of the same build carries the system's names, and so does the engine example
    tc_fmu = build / "fmus" / "FloatingRingTurbocharger.fmu"
    tc_vars = {v.name for v in read_model_description(str(tc_fmu)).modelVariables}
    assert {"hot_bearing.housing_force.y", "cold_bearing.outer.clearance", "wheel_0.x", "wheel_1.unbalance"} <= tc_vars
    assert not any(n.startswith(("turbine", "compressor")) for n in tc_vars)
    with read_ssp(build / "engine_turbocharger.ssp") as s:
        params = s.parameters()["turbocharger"]
        assert "hot_bearing.outer.clearance" in params and "turbine_bearing.outer.clearance" not in params
