"""Spectrogram (ShortTimeFFT), component tracking (frbmodel.signals.spectral, frbmodel.signals.tracking) and the
composite figures,
for run-ups and run-downs."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

import frbmodel as frb
import frbmodel.signals.tracking as tracking
from frbmodel.signals.spectral import spectrogram
from frbmodel.signals.tracking import BACKWARD, FORWARD, Peak, Track, assign


def _orbit_run(t, speed_rpm, z):
    """The fields of a run-up that :func:`spectrogram` reads, for a synthetic orbit z = x + i y."""
    return SimpleNamespace(time=t, speed_rpm=np.broadcast_to(speed_rpm, t.shape), meta={},
                           displacement={"turbine_wheel": np.column_stack([z.real, z.imag])})


def _reference_spectrogram(t, z, nper, step, nfft):
    """Straightforward STFT: each segment z[s : s + nper] (s = 0, step, ...) minus its least-squares line (real
    and imaginary parts, by numpy.polyfit), times the symmetric Hann window 0.5 − 0.5 cos(2πn/(nper − 1)),
    zero padded to nfft and transformed by numpy.fft; magnitudes divided by the window sum. Forward = bins of
    f >= 0, backward = the bins of −f (none for f = 0)."""
    n = np.arange(nper)
    win = 0.5 - 0.5 * np.cos(2 * np.pi * n / (nper - 1))
    starts = range(0, z.size - nper + 1, step)
    fwd, bwd = [], []
    for s in starts:
        seg = z[s:s + nper]
        line_re = np.polyval(np.polyfit(n, seg.real, 1), n)
        line_im = np.polyval(np.polyfit(n, seg.imag, 1), n)
        spec = np.abs(np.fft.fft((seg - line_re - 1j * line_im) * win, nfft)) / win.sum()
        fwd.append(spec[:nfft // 2])
        bwd.append(np.concatenate([[0.0], spec[:nfft // 2:-1]]))
    dt = t[1] - t[0]
    freqs = np.arange(nfft // 2) / (nfft * dt)
    return freqs, np.array(fwd).T, np.array(bwd).T, t[np.array(starts) + nper // 2]


@pytest.fixture(scope="module")
def short_run():
    # 0.1 s ramp of the co36 system: a few self-excited components on a static deflection (~1.4 s wall)
    return frb.runup(frb.turbocharger(36e-6), speed_rpm=(20e3, 60e3), duration=0.1, progress=False)


@pytest.mark.parametrize("kw", [dict(), dict(segment_s=0.02, overlap=0.5, zero_pad=2)])
@pytest.mark.parametrize("node", ["turbine_wheel", "compressor_wheel"])
def test_shorttimefft_matches_a_plain_segment_fft(short_run, node, kw):
    sp = spectrogram(short_run, node, **kw)
    nper = int(round(sp.meta["segment_s"] * sp.meta["fs_hz"]))
    step = max(1, int(round(nper * (1 - sp.meta["overlap"]))))
    z = short_run.displacement[node] @ np.array([1.0, 1j])
    freqs, fwd, bwd, times = _reference_spectrogram(short_run.time, z, nper, step, sp.meta["nfft"])
    assert fwd.shape == sp.forward.shape and bwd.shape == sp.backward.shape
    # frequencies and segment centres: same formula up to the last bit (k / (nfft dt) vs fftfreq)
    np.testing.assert_allclose(sp.freqs_hz, freqs, rtol=1e-15, atol=0)
    np.testing.assert_array_equal(sp.times, times)
    # amplitudes: both sides fit and subtract a line from samples of size up to max|z| in double precision, by
    # different algorithms (LAPACK least squares vs numpy.polyfit); the round-off left after the subtraction is a
    # few eps x max|z| per sample, and the FFT divided by the window sum averages it: the difference must stay
    # below 1e-14 max|z| (measured: <= 4e-16 max|z|). A wrong detrend (constant instead of linear), window
    # (periodic Hann), scaling or bin mapping changes the amplitudes by >= 1e-4 max|z| here.
    zmax = np.abs(z).max()
    np.testing.assert_allclose(sp.forward, fwd, rtol=0, atol=1e-14 * zmax)
    np.testing.assert_allclose(sp.backward, bwd, rtol=0, atol=1e-14 * zmax)
    # the comparison is not vacuous: both directions carry whirl of the order of the orbit itself (measured
    # forward max ~0.7 max|z|, backward max >= 0.1 max|z|)
    assert sp.forward.max() > 0.1 * zmax and sp.backward.max() > 0.01 * zmax


# ---------------------------------------------------------------------------------------------------- tracking
def _greedy(tracks, peaks, df_hz):
    """Greedy nearest neighbour with the same gate: each track in turn takes its nearest free admissible peak."""
    free, out = list(range(len(peaks))), []
    for i, tr in enumerate(tracks):
        ok = [j for j in free if peaks[j].direction == tr.direction
              and abs(peaks[j].freq_hz - tr.last_hz) < max(3 * df_hz, 0.15 * tr.last_hz)]
        if ok:
            j = min(ok, key=lambda j: abs(peaks[j].freq_hz - tr.last_hz))
            free.remove(j)
            out.append((i, j))
    return out


def _two_falling_chirps():
    """Two forward whirl components of equal amplitude, 120 Hz apart, both falling at 1400 Hz/s:
    f_lower = 1500 Hz − 1400 Hz/s t, f_upper = f_lower + 120 Hz, under a constant 120 krpm (2000 Hz) rotor.
    With 50 ms segments and no overlap each moves 70 Hz per segment — more than half their distance, so the
    lower track (the first one, found first) is nearer to the upper component's next peak than to its own."""
    fs, duration, f1, gap, rate = 10e3, 0.6, 1500.0, 120.0, 1400.0
    t = np.arange(0, duration, 1 / fs)
    z = sum(1e-6 * np.exp(2j * np.pi * (f0 * t - rate * t ** 2 / 2)) for f0 in (f1, f1 + gap))
    sp = spectrogram(_orbit_run(t, 120e3, z), segment_s=0.05, overlap=0.0)
    laws = (lambda s: f1 - rate * s, lambda s: f1 + gap - rate * s)
    return sp, laws


def _follows(comp, law, times, tol):
    """``comp`` is detected in every segment, each time within ``tol`` [Hz] of ``law(segment centre)``."""
    return comp.freqs_hz.size == times.size and bool(np.all(np.abs(comp.freqs_hz - law(times)) < tol))


def test_assignment_keeps_close_chirps_on_their_own_laws(monkeypatch):
    sp, laws = _two_falling_chirps()
    df = sp.freqs_hz[1] - sp.freqs_hz[0]
    comps = sp.components()
    assert [c.label for c in comps] == ["sub1", "sub2"] and all(c.direction == "forward" for c in comps)
    # each track follows its law in every segment within one bin (4.9 Hz): the windowed spectrum of a linear
    # chirp is symmetric about its frequency at the segment centre and the other component is 24 bins away;
    # the two laws differ by 120 Hz, so a swapped segment fails
    for comp, law in zip(comps, laws):
        assert _follows(comp, law, sp.times, df)
    # the same peaks tracked greedily: the first track jumps onto the other component (the test discriminates)
    monkeypatch.setattr(tracking, "assign", _greedy)
    greedy = sp.components()
    assert not all(_follows(c, law, sp.times, df) for c, law in zip(greedy, laws))


def test_assignment_gate_and_direction():
    df = 5.0
    tracks = [Track(FORWARD, [0], [100.0]), Track(BACKWARD, [0], [300.0])]
    # gate max(3 df, 0.15 f): 15 Hz at 100 Hz, 45 Hz at 300 Hz; the backward track takes no forward peak
    peaks = [Peak(116.0, 1.0, FORWARD), Peak(301.0, 1.0, FORWARD), Peak(344.0, 1.0, BACKWARD)]
    assert assign(tracks, peaks, df) == [(1, 2)]
    assert assign(tracks, [Peak(114.0, 1.0, FORWARD), Peak(346.0, 1.0, BACKWARD)], df) == [(0, 0)]
    # one peak wanted by both forward tracks: it goes to the nearer one, whichever was opened first
    tracks = [Track(FORWARD, [0], [140.0]), Track(FORWARD, [0], [105.0])]
    assert assign(tracks, [Peak(106.0, 1.0, FORWARD)], 20.0) == [(1, 0)]
    assert _greedy(tracks, [Peak(106.0, 1.0, FORWARD)], 20.0) == [(0, 0)]


def test_internal_resonance_of_constructed_components():
    """Constant-ratio components (closed form): sub1 = 0.2 f_rot, sub3 = 0.8 f_rot, sub2 = 0.4 f_rot on
    60 ... 70 krpm and 0.5 f_rot elsewhere. Expected: sub1 + sub3 = f_rot everywhere; sub2 = 2 sub1 and
    sub3 = 2 sub2 on 60 ... 70 krpm; nothing else (0.5 : 0.2, 0.8 : 0.5, 0.2 + 0.5, 0.5 + 0.8 are no resonance)."""
    s = np.linspace(50e3, 90e3, 41)
    frot = s / 60.0
    sub2 = np.where((s >= 60e3) & (s <= 70e3), 0.4, 0.5) * frot
    comps = [tracking.Component(lab, s, f, np.ones_like(s), "forward")
             for lab, f in (("sub1", 0.2 * frot), ("sub2", sub2), ("sub3", 0.8 * frot), ("1X", frot))]
    found = {(r["components"], r["condition"]): (r["from [rpm]"], r["to [rpm]"])
             for r in tracking.internal_resonances(comps)}
    assert found == {(("sub1", "sub2"), "2:1"): (60e3, 70e3), (("sub2", "sub3"), "2:1"): (60e3, 70e3),
                     (("sub1", "sub3"), "f_a + f_b = 1X"): (50e3, 90e3)}


def test_internal_resonances_do_not_depend_on_the_speed_order():
    """The same constructed components with the speeds in falling order (a run-down) give the same ranges:
    resonances are found where both components are detected at once, never by interpolating over speed."""
    s = np.linspace(90e3, 50e3, 41)
    frot = s / 60.0
    sub2 = np.where((s >= 60e3) & (s <= 70e3), 0.4, 0.5) * frot
    comps = [tracking.Component(lab, s, f, np.ones_like(s), "forward")
             for lab, f in (("sub1", 0.2 * frot), ("sub2", sub2), ("sub3", 0.8 * frot))]
    found = {(r["components"], r["condition"]): (r["from [rpm]"], r["to [rpm]"])
             for r in tracking.internal_resonances(comps)}
    assert found == {(("sub1", "sub2"), "2:1"): (60e3, 70e3), (("sub2", "sub3"), "2:1"): (60e3, 70e3),
                     (("sub1", "sub3"), "f_a + f_b = 1X"): (50e3, 90e3)}


# ---------------------------------------------------------------------------------------------------- run-downs
FS, T_END = 10000.0, 1.0  # sampling rate [Hz], duration [s] of the synthetic runs
T_OFF, T_MIN = 0.3, 0.5025  # A switches off [s]; B's amplitude minimum [s] (0.4 hop off the segment grid)
THRESHOLD = 5e-7  # detection threshold [m] (min_amplitude; 25 dB below the largest peak is lower)


def _speed(direction, t):
    """Linear run-down 200 -> 100 krpm or run-up 100 -> 200 krpm in 1 s."""
    return 200e3 - 100e3 * t if direction == "down" else 100e3 + 100e3 * t


def _time(direction, rpm):
    """Inverse of :func:`_speed`."""
    return (200e3 - rpm) / 100e3 if direction == "down" else (rpm - 100e3) / 100e3


def _synthetic_run(direction, bearings=("turbine", "compressor"), disc="turbine_wheel", meta=None):
    """Closed-form orbit, as a function of time only (the same events in a run-up and a run-down):
    1X of 2 um throughout; A: forward 0.55X of 5 um switched off at T_OFF; B: forward 0.3X with
    log amplitude ln(3e-8 m) + 300/s² (t − T_MIN)² (capped at 3 um): above the threshold from the start, decays
    through it at T_MIN − 0.097 s, minimum at T_MIN, grows through it again at T_MIN + 0.097 s; C: backward 0.25X
    growing as 1e-7 m e^(t / 0.1 s) from the start (below the threshold until 0.161 s); a 1e-11 m noise floor."""
    t = np.arange(0, T_END, 1 / FS)
    rpm = _speed(direction, t)
    phase = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    amp_b = np.minimum(3e-8 * np.exp(300.0 * (t - T_MIN) ** 2), 3e-6)
    amp_c = np.minimum(1e-7 * np.exp(t / 0.1), 2e-6)
    z = (2e-6 * np.exp(1j * phase) + 5e-6 * (t < T_OFF) * np.exp(1j * 0.55 * phase)
         + amp_b * np.exp(1j * 0.3 * phase) + amp_c * np.exp(-1j * 0.25 * phase))
    rng = np.random.default_rng(3)
    z = z + 1e-11 * (rng.standard_normal(t.size) + 1j * rng.standard_normal(t.size))
    zeros2 = np.zeros((t.size, 2))
    return frb.RunupResult(t, rpm, np.zeros((t.size, len(bearings))), {b: zeros2 for b in bearings},
                           {b: zeros2 for b in bearings}, np.zeros((t.size, 2 * len(bearings))),
                           {disc: np.column_stack([z.real, z.imag])}, meta=meta or {})


@pytest.mark.parametrize("direction", ["down", "up"])
def test_components_of_a_synthetic_run_down_and_run_up(direction):
    seg = 0.025  # [s]
    hop = seg / 4  # the default 75 % overlap
    sp = spectrogram(_synthetic_run(direction), segment_s=seg)
    assert sp.direction == direction
    comps = sp.components(min_amplitude=THRESHOLD)

    def pick(ratio, whirl, from_start):
        found = [c for c in comps if abs(np.median(c.ratio) - ratio) < 0.02 and c.direction == whirl
                 and c.from_start == from_start]
        assert len(found) == 1, [(c.label, np.median(c.ratio), c.direction, c.onset_estimate) for c in comps]
        return found[0]

    one_x, a, b1 = pick(1.0, "forward", True), pick(0.55, "forward", True), pick(0.3, "forward", True)
    c, b2 = pick(0.25, "backward", True), pick(0.3, "forward", False)
    assert len(comps) == 5
    # present in the first segment: no onset and no threshold crossing on appearing — not the start speed
    for comp in (one_x, a, b1):
        assert comp.onset_estimate == tracking.NO_ONSET_PRESENT
        assert np.isnan(comp.onset_rpm) and np.isnan(comp.onset_threshold_rpm) and np.isnan(comp.onset_hz)
    # C grows from the start (first detected at 0.16 s): traced back in time it falls to the first segment
    assert c.onset_estimate == tracking.NO_ONSET_GROWING and np.isnan(c.onset_rpm)
    assert np.isfinite(c.onset_threshold_rpm)
    # 1X, C and B2 last to the end: no "vanishes at"
    assert all(np.isnan(comp.end_rpm) for comp in (one_x, c, b2))
    # A vanishes: switched off at T_OFF, a segment centred at t_c holds the Hann-weighted fraction
    # F(u) = u − sin(2πu)/(2π) of it, u = (T_OFF − t_c)/seg + 1/2; F = THRESHOLD / 5 um = 0.1 at u = 0.259, so the
    # windowed amplitude crosses the threshold at t_c = T_OFF + 0.241 seg. The log-linear interpolation between
    # the two segment centres that straddle the crossing errs by less than their distance (one hop).
    assert _time(direction, a.end_rpm) == pytest.approx(T_OFF + 0.241 * seg, abs=hop)
    # B1 decays through the threshold at t_v = T_MIN − sqrt(ln(THRESHOLD / 3e-8) / 300): the Hann-weighted mean of
    # the convex amplitude exceeds its centre value (Jensen) until the window lies after t_v: crossing in
    # [t_v, t_v + seg/2], ± one hop of interpolation
    t_v = T_MIN - math.sqrt(math.log(THRESHOLD / 3e-8) / 300.0)
    assert t_v - hop <= _time(direction, b1.end_rpm) <= t_v + seg / 2 + hop
    # B2 appears at t_x = T_MIN + sqrt(...) by the same argument mirrored: crossing in [t_x − seg/2, t_x] ± a hop
    t_x = T_MIN + math.sqrt(math.log(THRESHOLD / 3e-8) / 300.0)
    assert b2.onset_estimate == tracking.ONSET_TURNING_POINT
    assert t_x - seg / 2 - hop <= _time(direction, b2.onset_threshold_rpm) <= t_x + hop
    # B2's turning point: the amplitude law is even about T_MIN and so is the Hann window, so the windowed log
    # amplitude is even about T_MIN up to the noise floor (1e-11 m vs 3e-8 m) and the drift of B's frequency
    # (< 0.3 bin per segment); the least-squares parabola over ±4 segments of this even, nearly parabolic curve
    # has its vertex within a small fraction of a hop of T_MIN (measured <= 0.014 hop for segments of 20, 25 and
    # 40 ms in both directions). The nearest segment centre is 0.4 hop away, so a tolerance of 0.1 hop fails an
    # estimate that stops at the segment grid (as a bounds check assuming rising speeds did in a run-down).
    assert _time(direction, b2.onset_rpm) == pytest.approx(T_MIN, abs=0.1 * hop)
    # traced back in time: in a run-down the turning point lies at a higher speed than the first detection
    assert (b2.onset_rpm > b2.onset_threshold_rpm) == (direction == "down")


def test_components_table_says_what_each_column_is():
    tab = spectrogram(_synthetic_run("down"), segment_s=0.025).components_table()
    assert list(tab.columns) == list(tracking.COMPONENT_COLUMNS)
    assert {"onset [rpm]", "onset estimate", "first detection [rpm]", "vanishes at [rpm]"} <= set(tab.columns)
    one_x = tab[tab["component"] == "1X"].iloc[0]
    assert np.isnan(one_x["onset [rpm]"]) and one_x["onset estimate"] == "none: present from the start"
    # the range detected is in time order: from near the start speed down to near the end speed
    assert one_x["detected from [rpm]"] > 195e3 and one_x["detected to [rpm]"] < 105e3


def test_turning_point_rpm_fits_in_time_for_falling_speeds():
    """log amplitude = (k − 5.3)² over segments k (a parabola: the least-squares fit is exact) on a falling speed
    law s_k = 100 krpm − 2 krpm k: the vertex maps to s(5.3) = 89.4 krpm; traced back from segment 9."""
    k = np.arange(10)
    spec = np.exp((k - 5.3) ** 2)[None, :] * np.ones((16, 1)) * 1e-9
    freqs = np.arange(16) * 50.0
    speeds = 100e3 - 2e3 * k
    f0 = 0.3 * speeds[9] / 60.0
    # tolerance: the fit is exact up to round-off (log amplitudes of order 30, 9 points)
    assert tracking.turning_point_rpm(spec, freqs, speeds, 9, f0) == pytest.approx(100e3 - 2e3 * 5.3, abs=1e-6)
    # the same amplitudes on a rising speed law 80 krpm + 2 krpm k: s(5.3) = 90.6 krpm
    assert tracking.turning_point_rpm(spec, freqs, 80e3 + 2e3 * k, 9, f0) == pytest.approx(80e3 + 2e3 * 5.3, abs=1e-6)


# ---------------------------------------------------------------------------------------------------- figures
def test_composite_figures_of_a_run_down_with_renamed_bearings():
    import matplotlib.pyplot as plt
    from matplotlib.collections import QuadMesh

    from frbmodel.plots.figures import composite_figure, composite_plotly

    run = _synthetic_run("down", bearings=("front", "rear"), disc="impeller")
    sp = spectrogram(run, segment_s=0.025)  # default node: the run's first (here only) disc
    assert sp.node == "impeller"
    fig = composite_figure(sp, rsr=True)
    ax, ax_rsr = fig.axes[0], fig.axes[1]  # then the colour bar
    try:
        assert "Run-down" in ax.get_title() and "run-down" in ax.get_xlabel()
        lo, hi = ax.get_xlim()
        assert lo < hi
        assert (lo, hi) == pytest.approx((sp.speeds_rpm.min() / 1e3, sp.speeds_rpm.max() / 1e3))
        # the image runs along an increasing speed axis: its first column is the run-down's last segment
        mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
        x = mesh.get_coordinates()[0, :, 0]
        assert np.all(np.diff(x) > 0)
        sel = sp.freqs_hz <= ax.get_ylim()[1]
        np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(sel.sum(), -1), sp.db()[sel][:, ::-1])
        texts = [t.get_text() for t in ax.texts]
        assert "1X (from start)" in texts and any(t.startswith("sub") and "(from start)" not in t for t in texts)
        labels = [line.get_label() for line in ax_rsr.get_lines()]
        assert labels == ["run-down, front", "run-down, rear"]
    finally:
        plt.close(fig)
    pfig = composite_plotly(sp)
    heat = pfig.data[0]
    assert np.all(np.diff(heat.x) > 0) and "Run-down" in pfig.layout.title.text
    np.testing.assert_array_equal(np.asarray(heat.z), sp.db()[sp.freqs_hz <= pfig.layout.yaxis.range[1]][:, ::-1])
