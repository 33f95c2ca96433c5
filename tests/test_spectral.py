"""Spectrogram (ShortTimeFFT) and component tracking (frbmodel.spectral, frbmodel.tracking)."""
from types import SimpleNamespace

import numpy as np
import pytest

import frbmodel as frb
import frbmodel.tracking as tracking
from frbmodel.spectral import spectrogram
from frbmodel.tracking import BACKWARD, FORWARD, Peak, Track, assign


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
