"""Spectral post-processing of run-ups: spectrogram vs rotor speed, tracking and labelling of components.

The orbit of a node, z = x + i y, is cut into overlapping Hann-windowed segments; the full (two-sided)
spectrum separates forward (f > 0) from backward (f < 0) whirl. Amplitudes are the orbit radius of each
component [m]; the figure shows them in dB relative to the largest, over a 25 dB range, as in the paper.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import ParameterError

#: |f/f_rot − 1| below this is the synchronous (1X) component
SYNC_TOL = 0.04
#: relative tolerance of the internal-resonance conditions (2:1 and combination with 1X)
RESONANCE_TOL = 0.03


@dataclass
class Component:
    """A tracked spectral component of a run-up."""

    label: str  # "1X", "sub1", "sub2", ...
    speeds_rpm: np.ndarray
    freqs_hz: np.ndarray
    amplitude_m: np.ndarray
    direction: str  # "forward" | "backward"

    onset_interp_rpm: float = math.nan
    onset_threshold_rpm: float = math.nan

    @property
    def onset_rpm(self) -> float:
        """Onset speed [rpm]: threshold crossing interpolated between segments (first detection if unknown)."""
        return self.onset_interp_rpm if math.isfinite(self.onset_interp_rpm) else float(self.speeds_rpm[0])

    @property
    def end_rpm(self) -> float:
        return float(self.speeds_rpm[-1])

    @property
    def onset_hz(self) -> float:
        """Frequency at the onset speed [Hz]: the median f/f_rot of the first three detections (robust to a
        one-segment shift of the first detection), times the onset speed (constant-ratio extrapolation)."""
        n = min(3, self.freqs_hz.size)
        return float(np.median(self.freqs_hz[:n] / self.speeds_rpm[:n]) * self.onset_rpm)

    @property
    def first_detection_hz(self) -> float:
        return float(self.freqs_hz[0])

    @property
    def ratio(self) -> np.ndarray:
        """Frequency / rotor frequency [-]."""
        return self.freqs_hz / (self.speeds_rpm / 60.0)


@dataclass
class SpectrogramResult:
    """Spectrogram of a node's orbit during a run-up.

    Attributes
    ----------
    times : (k,) segment centres [s];  speeds_rpm : (k,) rotor speed there
    freqs_hz : (f,) non-negative frequencies [Hz]
    forward, backward : (f, k) orbit amplitude [m] of forward and backward whirl components
    node : str
    """

    times: np.ndarray
    speeds_rpm: np.ndarray
    freqs_hz: np.ndarray
    forward: np.ndarray
    backward: np.ndarray
    node: str
    db_range: float = 25.0
    meta: dict = field(default_factory=dict)
    run: object = None

    @property
    def amplitude(self):
        """max(forward, backward) amplitude [m] (f, k)."""
        return np.maximum(self.forward, self.backward)

    def db(self):
        a = self.amplitude
        return 20 * np.log10(np.maximum(a, 1e-300) / a.max())

    # ---------------------------------------------------------------- components
    def components(self, min_segments=6, min_amplitude=None):
        """Tracked components with labels: "1X" and the sub-synchronous "sub1", "sub2", "sub3", ... in the
        order of their onset. A spectral peak counts when it lies within ``db_range`` of its segment's
        largest peak and above ``min_amplitude`` [m] (default: 5 % of the smallest film clearance of the run's
        system, else 1e-7 m) — so components well below the dominant one of the whole run are still found.

        Each component carries two onset estimates: ``onset_threshold_rpm`` (first detection, interpolated
        threshold crossing) and ``onset_rpm`` — the *turning point*: tracing the component backwards at constant
        f/f_rot, the speed where its amplitude is smallest (decay turns into growth, i.e. the growth rate
        crosses zero). In a run-up the threshold crossing lags the loss of stability (slow passage through the
        Hopf point), the turning point does not.
        """
        from scipy.signal import find_peaks

        if min_amplitude is None:
            min_amplitude = self.meta.get("min_amplitude_m", 1e-7)
        df = self.freqs_hz[1] - self.freqs_hz[0]
        # below one period per segment a "peak" cannot be told from the static deflection's drift and the
        # window's main lobe about 0 Hz (detrending leaves a residue there): not a component
        f_min = max(2 * df, 1.0 / self.meta.get("segment_s", 1.0 / (4 * df)))
        tracks = []  # each: dict(k=[], f=[], a=[], dir=[])
        active = []
        sync = {"k": [], "f": [], "a": [], "dir": [], "thr": []}
        for k in range(self.times.size):
            frot = self.speeds_rpm[k] / 60.0
            peaks = []
            thr = max(min_amplitude, max(self.forward[:, k].max(), self.backward[:, k].max()) *
                      10 ** (-self.db_range / 20))
            for sign, spec in ((1, self.forward[:, k]), (-1, self.backward[:, k])):
                idx, _ = find_peaks(spec, height=thr)
                peaks += [(self._peak_hz(spec, i), spec[i], sign) for i in idx]
            used = set()
            # harmonics (2x, 3x) of a stronger peak, and the mirror (−f) of a stronger peak (an elliptic orbit
            # whirls at +f and −f at once), are not components of their own
            for p, (f, a, sgn) in enumerate(peaks):
                for q, (f2, a2, sgn2) in enumerate(peaks):
                    tol = max(1.5 * df, 0.02 * f)
                    if a2 > a and ((f2 < f and any(abs(f - h * f2) < tol for h in (2, 3))) or
                                   (sgn2 != sgn and abs(f - f2) < tol)):
                        used.add(p)
                        break
            for p, (f, a, sgn) in enumerate(peaks):
                if p in used:
                    continue
                if abs(f / frot - 1.0) < SYNC_TOL + 0.5 * df / frot and sgn > 0:
                    sync["k"].append(k), sync["f"].append(f), sync["a"].append(a), sync["dir"].append(sgn)
                    sync["thr"].append(thr)
                    used.add(p)
            subs = [(f, a, sgn) for p, (f, a, sgn) in enumerate(peaks)
                    if p not in used and f < (1.0 - SYNC_TOL) * frot and f > f_min]
            new_active = []
            for tr in active:
                best, bd = None, np.inf
                for j, (f, a, sgn) in enumerate(subs):
                    d = abs(f - tr["f"][-1])
                    if sgn == tr["dir"][-1] and d < max(3 * df, 0.15 * tr["f"][-1]) and d < bd:
                        best, bd = j, d
                if best is not None:
                    f, a, sgn = subs.pop(best)
                    tr["k"].append(k), tr["f"].append(f), tr["a"].append(a), tr["dir"].append(sgn)
                    tr["thr"].append(thr)
                    tr["miss"] = 0
                    new_active.append(tr)
                else:
                    tr["miss"] += 1
                    (new_active if tr["miss"] <= 3 else tracks).append(tr)
            for f, a, sgn in subs:
                new_active.append({"k": [k], "f": [f], "a": [a], "dir": [sgn], "thr": [thr], "miss": 0})
            active = new_active
        tracks += active
        tracks = self._merge(tracks)
        tracks = [t for t in tracks if len(t["k"]) >= min_segments]
        tracks.sort(key=lambda t: (t["k"][0], t["f"][0]))
        out = []
        if len(sync["k"]) >= min_segments:
            out.append(self._component("1X", sync))
        for i, t in enumerate(tracks):
            out.append(self._component(f"sub{i + 1}", t))
        return out

    def _peak_hz(self, spec, i):
        """Frequency of the spectral peak at bin ``i`` [Hz], refined between bins by a parabola through the log
        magnitudes of the bin and its neighbours (Hann window: error well below 1 % of a bin)."""
        f = self.freqs_hz
        if 0 < i < f.size - 1 and spec[i - 1] > 0 and spec[i + 1] > 0:
            a, b, c = np.log(spec[i - 1]), np.log(spec[i]), np.log(spec[i + 1])
            den = a - 2 * b + c
            if den < 0:
                return float(f[i] + 0.5 * (a - c) / den * (f[1] - f[0]))
        return float(f[i])

    def _merge(self, tracks, max_gap=4, ratio_tol=0.2):
        """Join fragments of one component: same direction, the later starting at most ``max_gap`` segments
        after the earlier ends, with f/f_rot within ``ratio_tol``."""
        tracks = sorted(tracks, key=lambda t: t["k"][0])
        out = []
        for t in tracks:
            r0 = t["f"][0] / (self.speeds_rpm[t["k"][0]] / 60.0)
            host = None
            for o in out:
                gap = t["k"][0] - o["k"][-1]
                r1 = o["f"][-1] / (self.speeds_rpm[o["k"][-1]] / 60.0)
                if o["dir"][-1] == t["dir"][0] and 0 < gap <= max_gap and abs(r0 - r1) <= ratio_tol * r1:
                    host = o
            if host is None:
                out.append(t)
            else:
                for key in ("k", "f", "a", "dir", "thr"):
                    host[key] += t[key]
        return out

    def _component(self, label, t):
        k = np.array(t["k"])
        direction = "forward" if np.mean(t["dir"]) > 0 else "backward"
        comp = Component(label, self.speeds_rpm[k], np.array(t["f"]), np.array(t["a"]), direction)
        comp.onset_threshold_rpm = self._interpolated_onset(k[0], t["f"][0], direction, t["thr"][0])
        comp.onset_interp_rpm = self._turning_point(k[0], t["f"][0], direction) if label != "1X" else \
            comp.onset_threshold_rpm
        return comp

    def _turning_point(self, k0, f0, direction):
        """Trace the component backwards from segment ``k0`` at constant f/f_rot (peak within ±15 %) and
        return the speed of its smallest amplitude (parabolic interpolation in log amplitude)."""
        spec = self.forward if direction == "forward" else self.backward
        ratio = f0 / (self.speeds_rpm[k0] / 60.0)
        amps = []
        for k in range(k0, -1, -1):
            fc = ratio * self.speeds_rpm[k] / 60.0
            sel = np.flatnonzero(np.abs(self.freqs_hz - fc) <= 0.15 * fc + 1.5 * (self.freqs_hz[1] - self.freqs_hz[0]))
            if sel.size == 0:
                break
            amps.append(spec[sel, k].max())
        amps = np.log(np.maximum(np.array(amps[::-1]), 1e-300))
        ks = np.arange(k0 - amps.size + 1, k0 + 1)
        # walk back from the first detection while the (3-point median smoothed) amplitude keeps falling:
        # the first local minimum is where decay turned into growth
        sm = amps.copy()
        if amps.size >= 3:
            sm[1:-1] = np.median(np.stack([amps[:-2], amps[1:-1], amps[2:]]), axis=0)
        j = amps.size - 1
        while j > 0 and sm[j - 1] < sm[j]:
            j -= 1
        if j == 0 or j == amps.size - 1:
            return float(self.speeds_rpm[ks[j]])
        # vertex of a least-squares parabola through log amplitude vs speed over ±4 segments around the minimum:
        # a flat minimum at the noise floor is located by its surroundings, not by one segment's dip
        lo, hi = max(j - 4, 0), min(j + 5, amps.size)
        sp = self.speeds_rpm[ks[lo:hi]]
        s_ref = self.speeds_rpm[ks[j]]
        if hi - lo >= 5:
            c2, c1, _ = np.polyfit(sp - s_ref, amps[lo:hi], 2)
            if c2 > 0:
                vertex = s_ref - c1 / (2 * c2)
                if sp[0] <= vertex <= sp[-1]:
                    return float(vertex)
        return float(s_ref)

    def _interpolated_onset(self, k0, f0, direction, thr):
        """Speed where the component's amplitude crosses the detection threshold, interpolated in
        log-amplitude between the last segment without and the first segment with the component."""
        if k0 == 0:
            return float(self.speeds_rpm[0])
        spec = self.forward if direction == "forward" else self.backward
        i = int(np.argmin(np.abs(self.freqs_hz - f0)))
        lo = max(i - 2, 0)
        a_prev = spec[lo:i + 3, k0 - 1].max()
        a_now = spec[lo:i + 3, k0].max()
        if not (0 < a_prev < thr <= a_now):
            return float(self.speeds_rpm[k0])
        w = math.log(thr / a_prev) / math.log(a_now / a_prev)
        return float(self.speeds_rpm[k0 - 1] + w * (self.speeds_rpm[k0] - self.speeds_rpm[k0 - 1]))

    def internal_resonances(self, components=None):
        """Speed ranges where two sub-synchronous components satisfy f_b ≈ 2 f_a or f_a + f_b ≈ f_rot
        (within ``RESONANCE_TOL``): the signature of "total instability". List of dicts."""
        comps = [c for c in (components or self.components()) if c.label.startswith("sub")]
        found = []
        for i, a in enumerate(comps):
            for b in comps[i + 1:]:
                common = np.intersect1d(a.speeds_rpm, b.speeds_rpm)
                if common.size == 0:
                    continue
                fa = np.interp(common, a.speeds_rpm, a.freqs_hz)
                fb = np.interp(common, b.speeds_rpm, b.freqs_hz)
                lo, hi = np.minimum(fa, fb), np.maximum(fa, fb)
                frot = common / 60.0
                for kind, ok in (("2:1", np.abs(hi - 2 * lo) < RESONANCE_TOL * hi),
                                 ("f_a + f_b = 1X", np.abs(lo + hi - frot) < RESONANCE_TOL * frot)):
                    if ok.any():
                        found.append({"components": (a.label, b.label), "condition": kind,
                                      "from [rpm]": float(common[ok].min()), "to [rpm]": float(common[ok].max())})
        return found

    def components_table(self):
        """pandas DataFrame: label, direction, onset/end speed [rpm], onset frequency [Hz], ratio at onset."""
        import pandas as pd

        rows = [{"component": c.label, "direction": c.direction, "onset [rpm]": c.onset_rpm,
                 "first detection [rpm]": c.onset_threshold_rpm, "end [rpm]": c.end_rpm,
                 "f at onset [Hz]": c.onset_hz, "f at first detection [Hz]": c.first_detection_hz,
                 "f/f_rot at onset [-]": float(c.ratio[0]),
                 "max amplitude [m]": float(c.amplitude_m.max())} for c in self.components()]
        return pd.DataFrame(rows)

    # ---------------------------------------------------------------- figures
    def plot(self, campbell=None, whirl=True, rsr=True, fmax_hz=None, components=True, title=None, xscale="linear"):
        """Spectrogram vs speed; with ``campbell`` (a method-J :class:`CampbellResult`) its unstable-mode
        frequencies as solid lines and the film whirl curves dashed, and — with ``rsr`` — the run-up RSR vs the
        linear methods beside it (the paper's Figs. 12–14). Returns the matplotlib Figure."""
        from .plots import composite_figure

        return composite_figure(self, campbell=campbell, whirl=whirl, rsr=rsr, fmax_hz=fmax_hz,
                                components=components, title=title, xscale=xscale)

    def plot_html(self, path=None, campbell=None, fmax_hz=None):
        from .plots import composite_plotly

        fig = composite_plotly(self, campbell=campbell, fmax_hz=fmax_hz)
        if path is not None:
            fig.write_html(str(path))
        return fig


def spectrogram(run, node="turbine_wheel", segment_s=None, overlap=0.75, db_range=25.0, zero_pad=4):
    """Spectrogram of ``run.displacement[node]`` (orbit x + i y) against rotor speed.

    Parameters
    ----------
    run : RunupResult
    node : str
        "turbine_wheel", "compressor_wheel" (or any key of ``run.displacement``).
    segment_s : float, optional
        FFT segment length [s] (default: duration / 40, within 0.01 ... 0.05 s and at most duration / 4).
    overlap : float
        Segment overlap fraction (0.75).
    db_range : float
        Colour range [dB] (25, as in the paper).
    zero_pad : int
        FFT length = zero_pad × segment length (interpolates the spectrum for peak tracking).
    """
    if node not in run.displacement:
        raise ParameterError(f"node = {node!r} is unknown; valid: {sorted(run.displacement)}")
    t = run.time
    if t.size < 64:
        raise ParameterError(f"run has {t.size} samples; a spectrogram needs at least 64")
    dt = t[1] - t[0]
    fs = 1.0 / dt
    dur = t[-1] - t[0]
    seg = segment_s or min(max(dur / 40.0, 0.01), 0.05, dur / 4.0)
    nper = max(32, int(round(seg * fs)))
    if not 0.0 <= overlap < 1.0:
        raise ParameterError(f"overlap = {overlap!r} is invalid: valid range 0 <= overlap < 1")
    step = max(1, int(round(nper * (1 - overlap))))
    z = run.displacement[node][:, 0] + 1j * run.displacement[node][:, 1]
    win = np.hanning(nper)
    nfft = int(2 ** math.ceil(math.log2(nper * zero_pad)))
    starts = np.arange(0, z.size - nper + 1, step)
    segs = np.stack([z[s:s + nper] for s in starts])
    # static deflection and its slow drift with speed out (linear detrend per segment)
    from scipy.signal import detrend

    segs = detrend(segs.real, axis=1) + 1j * detrend(segs.imag, axis=1)
    spec = np.fft.fft(segs * win[None, :], n=nfft, axis=1) / win.sum()
    freqs = np.fft.fftfreq(nfft, dt)
    pos = freqs >= 0
    fpos = freqs[pos]
    order = np.argsort(fpos)
    fwd = np.abs(spec[:, pos])[:, order].T
    # backward: negative frequencies mapped to |f|
    neg_idx = np.array([np.argmin(np.abs(freqs + f)) for f in fpos[order]])
    bwd = np.abs(spec[:, neg_idx]).T
    bwd[0] = 0.0  # f = 0 counted once
    centres = t[starts + nper // 2]
    speeds = np.interp(centres, t, run.speed_rpm)
    meta = {"segment_s": nper * dt, "overlap": overlap, "nfft": nfft, "fs_hz": fs}
    sys_d = (run.meta or {}).get("system")
    if sys_d:
        meta["min_amplitude_m"] = 0.05 * min(f["clearance"] for b in sys_d["bearings"] for f in (b["inner"], b["outer"]))
    return SpectrogramResult(centres, speeds, fpos[order], fwd, bwd, node, db_range, meta, run)
