"""Nonlinear run-up: checks against the linear analysis, the static equilibrium, tolerance sensitivity,
contact handling, file output and bad input."""
import json
import math

import numpy as np
import pandas as pd
import pytest
from _reference import petroff, static_film_force, table2_bearing_loads

import frbmodel as frb
from frbmodel.nonlinear.runup import RunupResult, RunupStopped, SpeedProfile, Unbalance, runup
from frbmodel.physics.finite_length import correction_polynomials
from frbmodel.signals.spectral import spectrogram


@pytest.fixture(scope="module")
def tc():
    return frb.turbocharger(36e-6)


@pytest.mark.slow  # long (4-6 s); run with -m slow (README: the suite's slow checks)
def test_linear_springs_free_vibration_shows_campbell_frequencies(tc):
    """Journals on method-A springs (no films): the free vibration after the initial offset must contain the
    Campbell natural frequencies, each in its own whirl direction."""
    rpm, fs = 60e3, 10000.0
    # LSODA: this undamped free vibration keeps every mode ringing; the Rosenbrock default needs 2x the time here
    r = runup(tc, profile=SpeedProfile.constant(rpm, 0.4), duration=0.4, linear_springs=1e6, output_rate_hz=fs,
              progress=False, integrator="lsoda")
    z = r.displacement["turbine_wheel"] @ np.array([1.0, 1j])
    z = z - z.mean()
    w = np.hanning(z.size)
    nf = 2 ** 20
    Z = np.fft.fft(z * w, nf) / w.sum()
    f = np.fft.fftfreq(nf, 1 / fs)
    cd = frb.campbell(tc, "A", [rpm], whirl=False)
    checked = 0
    for fc, prec in zip(cd.frequencies_hz[0], cd.precession[0]):
        if fc > 0.4 * fs:
            continue
        sgn = 1 if prec == "forward" else -1
        sel = (sgn * f > 0.97 * fc) & (sgn * f < 1.03 * fc)
        amp = np.abs(Z[sel])
        if amp.max() < 1e-3 * np.abs(Z).max():
            continue  # mode not excited by the initial offset
        f_peak = abs(f[sel][np.argmax(amp)])
        # acceptance: within 1 %; the FFT of a 0.4 s record, zero-padded, resolves well below that
        assert f_peak == pytest.approx(fc, rel=0.01)
        checked += 1
    assert checked >= 6  # conical and cylindrical pairs plus bending modes are excited


def test_stable_constant_speed_settles_to_method_j_equilibrium(tc):
    rpm = 1500.0  # method J is stable below ~2.4 krpm (all modes D > 0)
    cd = frb.campbell(tc, "J", [rpm], whirl=False)
    assert np.nanmin(cd.damping) > 0
    r = runup(tc, profile=SpeedProfile.constant(rpm, 0.6), duration=0.6, output_rate_hz=2000, progress=False)
    eq = frb.equilibrium(tc, "J", rpm)
    for i, b in enumerate(eq.bearings):
        c = tc.bearings[i].outer.clearance
        # acceptance: within 1 % of the clearance (the slowest mode decays over ~0.2 s at this speed)
        assert np.abs(r.journal[b.name][-1] - b.journal).max() < 0.01 * c
        assert np.abs(r.ring[b.name][-1] - b.ring).max() < 0.01 * c
        assert r.ring_speed_ratio[-1, i] == pytest.approx(b.ring_speed_ratio, rel=0.01)


def test_tighter_tolerance_does_not_move_onsets(tc):
    res = []
    for rtol, atol in ((1e-7, 1e-10), (1e-8, 1e-11)):  # the defaults and both tightened tenfold
        r = runup(tc, speed_rpm=(20e3, 60e3), duration=0.25, output_rate_hz=10000, progress=False, rtol=rtol,
                  atol=atol)
        res.append(spectrogram(r, "turbine_wheel", segment_s=0.01).components())
    a, b = res
    assert len(a) == len(b) and len(a) >= 2
    for ca, cb in zip(a, b):
        assert ca.label == cb.label and ca.direction == cb.direction
        # acceptance: < 1 % change of the detected onset speeds
        assert cb.onset_threshold_rpm == pytest.approx(ca.onset_threshold_rpm, rel=0.01, nan_ok=True)
        assert cb.onset_rpm == pytest.approx(ca.onset_rpm, rel=0.01, nan_ok=True)  # NaN: present from the start
        assert cb.onset_hz == pytest.approx(ca.onset_hz, rel=0.01, nan_ok=True)


def test_contact_stop_names_bearing_film_time_speed_and_keeps_results(tc, tmp_path):
    with pytest.raises(RunupStopped) as ei:
        runup(tc, speed_rpm=(20e3, 40e3), duration=0.2, contact_eps=0.45, out_dir=tmp_path, progress=False,
              output_rate_hz=5000)
    msg = str(ei.value)
    assert "bearing" in msg and "film" in msg and "t = " in msg and "rpm" in msg and "eccentricity ratio" in msg
    part = ei.value.result
    assert part.status == "stopped" and 0 < part.time.size < 1001
    assert part.eccentricity.max() > 0.45
    meta = json.loads((tmp_path / "runup.json").read_text())
    assert meta["status"] == "stopped" and meta["message"] == msg
    on_disk = RunupResult.load(tmp_path)
    np.testing.assert_allclose(on_disk.time, part.time)
    np.testing.assert_allclose(on_disk.journal["turbine"], part.journal["turbine"], rtol=1e-8)


def test_results_file_is_self_describing(tc, tmp_path):
    r = runup(tc, speed_rpm=(30e3, 32e3), duration=0.02, out_dir=tmp_path, progress=False,
              unbalance=[Unbalance("turbine_wheel", 2e-6, 0.3)])
    df = pd.read_csv(tmp_path / "runup.csv")
    assert "turbine_wheel x [m]" in df.columns and "speed [rpm]" in df.columns and "RSR turbine [-]" in df.columns
    np.testing.assert_allclose(df["speed [rpm]"].iloc[[0, -1]], [30e3, 32e3], rtol=1e-9)
    np.testing.assert_allclose(df["turbine_wheel y [m]"], r.displacement["turbine_wheel"][:, 1], rtol=1e-8)
    meta = json.loads((tmp_path / "runup.json").read_text())
    assert meta["status"] == "finished" and meta["units"].startswith("SI")


def test_unbalance_response_equals_linear_frequency_response(tc):
    """Journals on springs, no films: the 1X forward orbit of the turbine wheel must equal the steady-state
    response (K − Ω²M + iΩ·ΩG) X = F̂ of the linear rotor to the rotating unbalance force."""
    rpm, me, fs = 30e3, 5e-6, 10000.0
    # LSODA: undamped springs keep every mode ringing, where it is faster than the default Rosenbrock (2.6 vs 6.4 s)
    r = runup(tc, profile=SpeedProfile.constant(rpm, 0.4), duration=0.4, linear_springs=1e6, perturbation=0.0,
              unbalance=[Unbalance("turbine_wheel", me)], output_rate_hz=fs, progress=False, integrator="lsoda")
    z = r.displacement["turbine_wheel"] @ np.array([1.0, 1j])
    z = z - z.mean()
    w = np.hanning(z.size)
    Z = np.fft.fft(z * w, 2 ** 18) / w.sum()
    f = np.fft.fftfreq(2 ** 18, 1 / fs)
    k = np.argmin(np.abs(f - rpm / 60))
    sim = np.abs(Z[k - 3:k + 4]).max()
    # independent linear solution
    Om = rpm * np.pi / 30
    rot = tc.rotor
    K = rot.K.copy()
    for b in tc.bearings:
        K[4 * b.node, 4 * b.node] += 1e6
        K[4 * b.node + 1, 4 * b.node + 1] += 1e6
    F = np.zeros(rot.n_dof, complex)
    F[0], F[1] = me * Om ** 2, -1j * me * Om ** 2  # (cos, sin) = Re((1, −i) e^{iΩt})
    X = np.linalg.solve(K - Om ** 2 * rot.M + 1j * Om * Om * rot.G, F)
    forward = abs(X[0] + 1j * X[1]) / 2
    # the free vibration started by switching the unbalance on never decays (undamped springs) but lies at
    # other frequencies; Hann leakage and the 2.5 Hz bin width leave a few per cent
    assert sim == pytest.approx(forward, rel=0.03)
    assert np.abs(Z[np.argmin(np.abs(f + rpm / 60))]) < 0.05 * sim  # no backward 1X


@pytest.mark.parametrize("kw,match", [
    (dict(duration=0.0), "duration"),
    (dict(duration=0.1, speed_rpm=(-1.0, 1e4)), "start speed"),
    (dict(duration=0.1, contact_eps=1.2), "contact_eps"),
    (dict(duration=0.1, unbalance=[Unbalance("no_such_wheel", 1e-6)]), "disc name"),
    # (a negative amount is refused by Unbalance itself: tests/test_trust.py; this one by the disc's bound)
    (dict(duration=0.1, unbalance=[Unbalance("turbine_wheel", 1.0)]), "unbalance of turbine_wheel = 1.0 kg m"),
    (dict(duration=0.1, film_model="long"), "film model"),
])
def test_bad_input(tc, kw, match):
    with pytest.raises(frb.ParameterError, match=match):
        runup(tc, progress=False, **kw)


def test_synthetic_spectrogram_components():
    """Spectral tracking on a synthetic orbit with known components: forward 0.4X starting at 30 % of the
    run, backward 0.1X throughout, 1X throughout."""
    fs, T = 10000.0, 1.0
    t = np.arange(0, T, 1 / fs)
    rpm = 30e3 + 30e3 * t / T
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / fs
    grow = np.where(t > 0.3, 1.0, 0.0)
    z = 2e-6 * np.exp(1j * phase) + 5e-6 * grow * np.exp(1j * 0.4 * phase) + 3e-6 * np.exp(-1j * 0.1 * phase)
    disp = {"turbine_wheel": np.column_stack([z.real, z.imag])}
    zeros2 = np.zeros((t.size, 2))
    run = RunupResult(t, rpm, np.zeros((t.size, 2)), {"turbine": zeros2, "compressor": zeros2},
                      {"turbine": zeros2, "compressor": zeros2}, np.zeros((t.size, 4)), disp)
    comps = {c.label: c for c in spectrogram(run, "turbine_wheel", segment_s=0.04).components(min_amplitude=5e-7)}
    assert set(comps) == {"1X", "sub1", "sub2"}
    back = [c for c in comps.values() if c.direction == "backward"]
    fwd_sub = [c for c in comps.values() if c.label != "1X" and c.direction == "forward"]
    assert len(back) == 1 and len(fwd_sub) == 1
    np.testing.assert_allclose(back[0].ratio, 0.1, atol=0.01)
    np.testing.assert_allclose(fwd_sub[0].ratio, 0.4, atol=0.01)
    # the forward component switches on at t = 0.3 s (39 krpm); segments of 0.04 s smear it by ~1.2 krpm
    assert fwd_sub[0].onset_threshold_rpm == pytest.approx(39e3, abs=1.5e3)


def test_turning_point_finds_the_loss_of_stability_under_a_noise_floor():
    """A component that decays, passes its amplitude minimum at t0 (growth rate zero: the loss of stability) and
    then grows, log A = a (t − t0)², on top of a random noise floor: the turning-point onset must find the speed
    at t0, where the threshold crossing comes much later."""
    rng = np.random.default_rng(1)
    fs, T = 20000.0, 1.0
    t = np.arange(0, T, 1 / fs)
    rpm = 20e3 + 230e3 * t / T
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / fs
    t0 = 0.3  # 89 krpm
    # log-amplitude quadratic on both sides (growth rate linear in speed, zero at t0): slow decay from 3e-7 m
    # (below detection) to 1e-8 m at t0, then faster growth (x5000 in 0.17 s, as in the co36 run-up)
    a = np.where(t < t0, math.log(30.0) / t0 ** 2, 300.0)
    amp = np.minimum(1e-8 * np.exp(a * (t - t0) ** 2), 2e-5)
    z = 1e-5 * np.exp(1j * 0.5 * phase) + amp * np.exp(1j * 0.12 * phase)
    z += 1e-11 * (rng.standard_normal(t.size) + 1j * rng.standard_normal(t.size))
    disp = {"turbine_wheel": np.column_stack([z.real, z.imag])}
    zeros2 = np.zeros((t.size, 2))
    run = RunupResult(t, rpm, np.zeros((t.size, 2)), {"turbine": zeros2, "compressor": zeros2},
                      {"turbine": zeros2, "compressor": zeros2}, np.zeros((t.size, 4)), disp)
    seg, hop = 0.025, 0.025 / 4  # segment length [s]; the spectrogram's default overlap is 75 %
    comps = spectrogram(run, "turbine_wheel", segment_s=seg).components(min_amplitude=1e-7)
    grown = [c for c in comps if abs(np.median(c.ratio) - 0.12) < 0.02]
    assert len(grown) == 1
    c = grown[0]
    ramp = 230e3 / T  # [rpm/s]
    true = 20e3 + ramp * t0
    # Bound: a segment centred more than half a segment from t0 sees only the decaying (or only the growing) side,
    # where the amplitude is monotonic, so its windowed amplitude is monotonic too: the minimum of the windowed
    # amplitude lies within ± seg/2 of t0, i.e. ± 2.875 krpm.
    assert c.onset_rpm == pytest.approx(true, abs=ramp * seg / 2)
    # The threshold crossing lags: detection needs the peak within 25 dB of the segment's largest (the 0.5X line
    # of 1e-5 m) and above min_amplitude, i.e. A = 1e-5 · 10^(−25/20) = 5.6e-7 m, reached at t_x = t0 +
    # sqrt(ln(A/1e-8) / 300). The Hann-weighted mean of the convex growing amplitude exceeds its centre value
    # (Jensen) and stays below A while the whole segment lies before t_x: the crossing lies in [t_x − seg/2, t_x].
    # The log-linear interpolation between segments moves it earlier by at most a hop. Frequency drift across a
    # segment and bin scalloping (Hann, 4x zero padding: < 0.1 dB) lower either peak by < 5 %, which shifts the
    # crossing by < 0.05 / (600 (t_x − t0)) s (the log-amplitude slope at t_x) either way.
    threshold = max(1e-7, 1e-5 * 10 ** (-25 / 20))
    t_x = t0 + math.sqrt(math.log(threshold / 1e-8) / 300.0)
    shift = 0.05 / (600.0 * (t_x - t0))
    assert 20e3 + ramp * (t_x - seg / 2 - hop - shift) <= c.onset_threshold_rpm <= 20e3 + ramp * (t_x + shift)


def test_cli_runup_and_compare_pipeline(tmp_path, capsys):
    from frbmodel.cli import main
    from frbmodel.studies.compare import compare

    assert main(["runup", "--speeds", "20000:30000", "--duration", "0.05", "--rate", "10000",
                 "--out", str(tmp_path / "r")]) == 0
    for name in ("runup.csv", "runup.json", "composite_turbine_wheel.png", "composite_turbine_wheel.html",
                 "components_compressor_wheel.csv"):
        assert (tmp_path / "r" / name).exists()
    assert "results in" in capsys.readouterr().out
    table, paths = compare(frb.turbocharger(), clearances=(40e-6,), speed_rpm=(20e3, 40e3), duration=0.08,
                           profile="ramp", out_dir=tmp_path / "c", n_speeds=20, progress=lambda m: None,
                           runup_kw={"progress": False, "output_rate_hz": 10000})
    out = tmp_path / "c"
    assert (out / "linear_vs_nonlinear.md").exists() and (out / "co40um" / "composite.png").exists()
    assert all(p.exists() for p in paths)
    # 20 krpm lies above the inner films' whirl onsets (11.0 / 11.7 krpm at c_O = 40 µm,
    # docs/theory/parameters.md#reference-numbers), so the
    # run starts from an unstable equilibrium and must show sub-synchronous whirl: the table cannot be empty
    sub = table[table["component"].str.startswith("sub")]
    assert len(sub) >= 1 and set(table["c_o [um]"]) == {40.0} and set(table["run-up"]) == {"finished"}
    # oil whirl runs in the rotation sense (docs/theory/whirl.md#film-whirl) and is sub-synchronous; a component already
    # growing at
    # the start has no onset in this run (NaN), the others start inside the run's speed range
    assert set(sub["direction"]) == {"forward"}
    onset = sub["nonlinear onset [rpm]"]
    has = onset.notna()
    assert np.all(sub["f at onset [Hz]"][has] < onset[has] / 60.0)
    assert np.all((onset[has] >= 20e3) & (onset[has] <= 40e3))
    # the method-J modes they are paired with are unstable, hence forward
    # (docs/theory/parameters.md#interpretation-choices, item 10)
    paired = sub["J mode"].dropna() if "J mode" in sub else pd.Series(dtype=object)
    assert paired.str.startswith("forward").all()
    # the written table is the returned one
    on_disk = pd.read_csv(out / "linear_vs_nonlinear.csv")
    np.testing.assert_allclose(on_disk["nonlinear onset [rpm]"], table["nonlinear onset [rpm]"], rtol=1e-12,
                               equal_nan=True)


def test_corrected_films_and_user_profile_start_from_their_equilibrium():
    """Sample 0 of a run-up without perturbation must be the static equilibrium of the corrected films with the
    ring speed of the full torque balance (method J). Checked by an independent residual: the static film forces
    written out from docs/theory/films.md#static-and-quasi-static-case times the film model's finite-length factors
    (docs/theory/films.md#finite-length-correction; checked against the finite-volume solver in test_film.py), the
    hand-statics bearing loads (docs/theory/parameters.md#table-2-in-si-units) and the ring torques of
    docs/theory/rings.md#torques-on-the-ring — not by recomputing the equilibrium the run-up starts from."""
    tc = frb.turbocharger(36e-6, film_model="short_corrected")
    r = runup(tc, profile=lambda t: 30e3 + 1e5 * t * t, duration=0.01, perturbation=0.0, progress=False)
    np.testing.assert_allclose(r.speed_rpm[[0, -1]], [30e3, 30e3 + 1e5 * 1e-4], rtol=1e-6)
    omega = r.speed_rpm[0] * math.pi / 30
    loads = table2_bearing_loads(tc.gravity)

    def cross(e, f):
        return e[0] * f[1] - e[1] * f[0]

    for i, b in enumerate(tc.bearings):
        journal, ring = r.journal[b.name][0], r.ring[b.name][0]
        w_fr = r.ring_speed_ratio[0, i] * omega
        e_in, e_out = journal - ring, ring
        f_in = static_film_force(b.inner, e_in, omega + w_fr, *correction_polynomials(b.inner.length_to_diameter))
        f_out = static_film_force(b.outer, e_out, w_fr, *correction_polynomials(b.outer.length_to_diameter))
        # The equilibrium is closed form up to a 1-D root to 1e-15, so the residuals are round-off (~1e-15 N);
        # 1e-9 of the turbine load leaves margin, while the plain short film in place of the corrected one leaves
        # 14-20 % of the load and a ring speed off by 1e-6 leaves a torque residual of ~1e-6 of the drive torque.
        tol = 1e-9 * loads[0]
        # (28)-(31): the inner film carries the bearing reaction, the outer film that plus the ring weight
        np.testing.assert_allclose(f_in, [0.0, loads[i]], rtol=0, atol=tol)
        np.testing.assert_allclose(f_out - f_in, [0.0, b.ring_mass * tc.gravity], rtol=0, atol=tol)
        # (32): the ring torques balance, M^I + M^O = 0
        drive = petroff(b.inner, math.hypot(*e_in) / b.inner.clearance) * (omega - w_fr)
        brake = petroff(b.outer, math.hypot(*e_out) / b.outer.clearance) * w_fr
        torque = drive - 0.5 * cross(e_in, f_in) - brake - 0.5 * cross(e_out, f_out)
        assert abs(torque) < 1e-9 * drive
