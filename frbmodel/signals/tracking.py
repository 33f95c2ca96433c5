"""Spectral components of a run-up or run-down: peaks per spectrogram segment, tracks through the segments,
onsets and ends, labels.

The input is a spectrogram as :func:`frbmodel.signals.spectral.spectrogram` computes it: the orbit amplitude [m] of
forward and backward whirl, ``(n_freqs, n_segments)`` each, on non-negative frequencies [Hz], with the rotor
speed [rpm] of every segment. Segments are in time order; the speed may rise (run-up), fall (run-down) or stay
constant — nothing here assumes that it increases. In each segment the spectral peaks within ``db_range`` of the
segment's largest one are found; harmonics and mirror images of stronger peaks are dropped; forward peaks at the
rotor frequency form the synchronous component "1X"; the sub-synchronous peaks are assigned to the tracks of the
previous segments by :func:`scipy.optimize.linear_sum_assignment` (gate: same direction and
|Δf| < max(3 df, 0.15 f)). Fragments of one component are joined, short tracks dropped, and each component gets
its onset (turning point, or none if it is there from the start of the run), the speeds where it crosses the
detection threshold on appearing and on vanishing, and a label.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: |f/f_rot − 1| below this is the synchronous (1X) component
SYNC_TOL = 0.04
#: relative tolerance of the internal-resonance conditions (2:1 and combination with 1X)
RESONANCE_TOL = 0.03
#: +1 forward whirl (f > 0 in the spectrum of x + i y), −1 backward
FORWARD, BACKWARD = 1, -1


@dataclass(frozen=True)
class Peak:
    """A spectral peak of one segment.

    Parameters
    ----------
    freq_hz : float
        Peak frequency [Hz], refined between bins (:func:`peak_frequency_hz`).
    amplitude_m : float
        Orbit amplitude at the peak bin [m].
    direction : int
        ``FORWARD`` (+1) or ``BACKWARD`` (−1) whirl.

    Examples
    --------
    >>> Peak(400.0, 2e-6, BACKWARD).direction == BACKWARD
    True
    """

    freq_hz: float
    amplitude_m: float
    direction: int


@dataclass
class Track:
    """A sequence of peaks of one component through the spectrogram segments.

    Parameters
    ----------
    direction : int
        ``FORWARD`` (+1) or ``BACKWARD`` (−1); all peaks of a track whirl in this direction.
    segments : list of int
        Segment index of every peak.
    freqs_hz : list of float
        Peak frequencies [Hz].
    amplitudes_m : list of float
        Peak orbit amplitudes [m].
    thresholds_m : list of float
        Detection threshold [m] of the segment of every peak.
    misses : int
        Consecutive segments without a peak for this track (while tracking).

    Examples
    --------
    >>> tr = Track(FORWARD)
    >>> tr.add(3, Peak(120.0, 2e-6, FORWARD), 1e-7)
    >>> tr.segments, tr.last_hz, tr.direction_name
    ([3], 120.0, 'forward')
    """

    direction: int
    segments: list = field(default_factory=list)
    freqs_hz: list = field(default_factory=list)
    amplitudes_m: list = field(default_factory=list)
    thresholds_m: list = field(default_factory=list)
    misses: int = 0

    def add(self, k, peak, threshold_m):
        """Append a peak found in a segment; resets :attr:`misses`.

        Parameters
        ----------
        k : int
            Segment index.
        peak : Peak
            The peak.
        threshold_m : float
            Detection threshold of segment ``k`` [m].
        """
        self.segments.append(k)
        self.freqs_hz.append(peak.freq_hz)
        self.amplitudes_m.append(peak.amplitude_m)
        self.thresholds_m.append(threshold_m)
        self.misses = 0

    def extend(self, other):
        """Append all peaks of a later fragment of the same component.

        Parameters
        ----------
        other : Track
            The later fragment.

        Examples
        --------
        >>> a, b = Track(FORWARD, [0, 1], [100.0, 101.0]), Track(FORWARD, [3], [103.0])
        >>> a.extend(b)
        >>> a.segments, len(a)
        ([0, 1, 3], 3)
        """
        self.segments += other.segments
        self.freqs_hz += other.freqs_hz
        self.amplitudes_m += other.amplitudes_m
        self.thresholds_m += other.thresholds_m

    def __len__(self):
        return len(self.segments)

    @property
    def last_hz(self) -> float:
        """Frequency of the latest peak [Hz]."""
        return self.freqs_hz[-1]

    @property
    def direction_name(self) -> str:
        """Whirl direction, "forward" or "backward"."""
        return "forward" if self.direction > 0 else "backward"


#: what :attr:`Component.onset_rpm` is (:attr:`Component.onset_estimate`)
ONSET_TURNING_POINT = "turning point"
ONSET_THRESHOLD = "threshold crossing"
NO_ONSET_PRESENT = "none: present from the start"
NO_ONSET_GROWING = "none: growing from the start"


@dataclass
class Component:
    """A tracked and labelled spectral component of a run-up or run-down.

    Parameters
    ----------
    label : str
        "1X" (synchronous) or "sub1", "sub2", ... (sub-synchronous, in the order of their first detection).
    speeds_rpm : ndarray
        Rotor speed [rpm] of each detection, in time order (falling in a run-down).
    freqs_hz : ndarray
        Component frequency [Hz] of each detection.
    amplitude_m : ndarray
        Orbit amplitude [m] of each detection.
    direction : str
        "forward" or "backward" whirl.
    onset_interp_rpm : float
        Onset speed [rpm]: the turning point for sub-synchronous components, the threshold crossing for 1X; NaN
        if the component is there from the start of the run (see ``onset_estimate``).
    onset_threshold_rpm : float
        Speed [rpm] where the amplitude rises through the detection threshold (interpolated between the last
        segment without and the first with the component); NaN if it is detected in the first segment.
    end_rpm : float
        Speed [rpm] where the component vanishes: the amplitude falls through the detection threshold
        (interpolated between the last segment with and the next without it); NaN if it lasts to the last segment.
    onset_estimate : str
        What ``onset_interp_rpm`` is: :data:`ONSET_TURNING_POINT`, :data:`ONSET_THRESHOLD`,
        :data:`NO_ONSET_PRESENT` (detected in the first segment) or :data:`NO_ONSET_GROWING` (its amplitude,
        traced back in time, falls all the way to the first segment: it grew from the start of the run).
    segments : ndarray of int, optional
        Spectrogram segment of each detection.

    Examples
    --------
    A component seen in every segment of a run-down from 200 to 150 krpm has neither onset nor end:

    >>> c = Component("sub1", np.array([200e3, 175e3, 150e3]), np.array([800.0, 700.0, 600.0]), np.ones(3),
    ...               "forward", onset_estimate=NO_ONSET_PRESENT)
    >>> c.onset_rpm, c.end_rpm, c.detected_from_rpm, float(c.ratio[0])
    (nan, nan, 200000.0, 0.24)
    """

    label: str
    speeds_rpm: np.ndarray
    freqs_hz: np.ndarray
    amplitude_m: np.ndarray
    direction: str

    onset_interp_rpm: float = math.nan
    onset_threshold_rpm: float = math.nan
    end_rpm: float = math.nan
    onset_estimate: str = ""
    segments: np.ndarray = None

    @property
    def onset_rpm(self) -> float:
        """Onset speed [rpm] (``onset_interp_rpm``): NaN where the component has no onset in this run."""
        return float(self.onset_interp_rpm)

    @property
    def from_start(self) -> bool:
        """True if the component is there from the start of the run (present or growing): it has no onset."""
        return self.onset_estimate in (NO_ONSET_PRESENT, NO_ONSET_GROWING)

    @property
    def detected_from_rpm(self) -> float:
        """Speed of the first detection [rpm] (segment centre)."""
        return float(self.speeds_rpm[0])

    @property
    def detected_to_rpm(self) -> float:
        """Speed of the last detection [rpm] (segment centre)."""
        return float(self.speeds_rpm[-1])

    def _ratio_times(self, ends, speed_rpm):
        n = min(3, self.freqs_hz.size)
        sel = slice(0, n) if ends == "first" else slice(-n, None)
        return float(np.median(self.freqs_hz[sel] / self.speeds_rpm[sel]) * speed_rpm)

    @property
    def onset_hz(self) -> float:
        """Frequency at the onset speed [Hz]: the median f/f_rot of the first three detections (robust to a
        one-segment shift of the first detection), times the onset speed (constant-ratio extrapolation); NaN
        without an onset."""
        return self._ratio_times("first", self.onset_rpm)

    @property
    def end_hz(self) -> float:
        """Frequency where the component vanishes [Hz]: the median f/f_rot of the last three detections times
        :attr:`end_rpm`; NaN if it lasts to the end of the run."""
        return self._ratio_times("last", self.end_rpm)

    @property
    def first_detection_hz(self) -> float:
        """Frequency of the first detection [Hz]."""
        return float(self.freqs_hz[0])

    @property
    def ratio(self) -> np.ndarray:
        """Frequency / rotor frequency [-] of each detection."""
        return self.freqs_hz / (self.speeds_rpm / 60.0)


# ---------------------------------------------------------------------------------------------------- peaks
def peak_frequency_hz(freqs_hz, spec, i):
    """Frequency [Hz] of the spectral peak at bin ``i``, refined between bins by the vertex of a parabola through
    the log magnitudes of the bin and its neighbours (Hann window: error well below 1 % of a bin).

    Parameters
    ----------
    freqs_hz : (f,) ndarray
        Equally spaced bin frequencies [Hz].
    spec : (f,) ndarray
        Magnitudes (any unit).
    i : int
        Bin index of the peak.

    Returns
    -------
    float
        Peak frequency [Hz]; the bin frequency at the ends or where the parabola opens upwards.

    Examples
    --------
    A Gaussian is a parabola in log magnitude, so its centre is found exactly:

    >>> f = np.arange(10.0)
    >>> float(round(peak_frequency_hz(f, np.exp(-(f - 4.3) ** 2), 4), 12))
    4.3
    """
    f = freqs_hz
    if 0 < i < f.size - 1 and spec[i - 1] > 0 and spec[i + 1] > 0:
        a, b, c = np.log(spec[i - 1]), np.log(spec[i]), np.log(spec[i + 1])
        den = a - 2 * b + c
        if den < 0:
            return float(f[i] + 0.5 * (a - c) / den * (f[1] - f[0]))
    return float(f[i])


def segment_peaks(freqs_hz, forward, backward, threshold_m):
    """Peaks above ``threshold_m`` of one segment's forward and backward spectra.

    Parameters
    ----------
    freqs_hz : (f,) ndarray
        Non-negative bin frequencies [Hz].
    forward, backward : (f,) ndarray
        Orbit amplitude [m] of forward and backward whirl.
    threshold_m : float
        Minimum peak height [m].

    Returns
    -------
    list of Peak
        Forward peaks by increasing frequency, then backward ones.

    Examples
    --------
    >>> f = np.arange(8.0) * 10.0
    >>> fwd = np.array([0, 1, 5, 1, 0, 2, 0, 0]) * 1e-6
    >>> bwd = np.array([0, 0, 0, 0, 0, 0, 3, 0]) * 1e-6
    >>> [(p.direction, round(p.freq_hz, 6)) for p in segment_peaks(f, fwd, bwd, 1.5e-6)]
    [(1, 20.0), (1, 50.0), (-1, 60.0)]
    """
    from scipy.signal import find_peaks

    peaks = []
    for sign, spec in ((FORWARD, forward), (BACKWARD, backward)):
        idx, _ = find_peaks(spec, height=threshold_m)
        peaks += [Peak(peak_frequency_hz(freqs_hz, spec, i), spec[i], sign) for i in idx]
    return peaks


def secondary_peaks(peaks, df_hz):
    """Indices of peaks that are not components of their own: harmonics (2×, 3×) of a stronger lower peak, and
    the mirror (−f) of a stronger peak (an elliptic orbit whirls at +f and −f at once).

    Parameters
    ----------
    peaks : list of Peak
        The peaks of one segment (:func:`segment_peaks`).
    df_hz : float
        Bin spacing [Hz]; peaks closer than max(1.5 df, 2 % of f) to a harmonic or mirror count as one.

    Returns
    -------
    set of int
        Indices into ``peaks``.

    Examples
    --------
    >>> secondary_peaks([Peak(100.0, 5.0, FORWARD), Peak(200.5, 1.0, FORWARD), Peak(100.2, 2.0, BACKWARD)], 1.0)
    {1, 2}
    """
    out = set()
    for p, pk in enumerate(peaks):
        tol = max(1.5 * df_hz, 0.02 * pk.freq_hz)
        for q in peaks:
            if q.amplitude_m > pk.amplitude_m and (
                    (q.freq_hz < pk.freq_hz and any(abs(pk.freq_hz - h * q.freq_hz) < tol for h in (2, 3))) or
                    (q.direction != pk.direction and abs(pk.freq_hz - q.freq_hz) < tol)):
                out.add(p)
                break
    return out


# ---------------------------------------------------------------------------------------------------- tracks
def assign(tracks, peaks, df_hz):
    """Assign peaks of the current segment to existing tracks.

    A peak may continue a track if it whirls in the track's direction and lies within
    |Δf| < max(3 df, 0.15 f_last) of the track's latest frequency. Among these pairs the assignment with the
    most matches and, among those, the smallest total |Δf| is taken (:func:`scipy.optimize.linear_sum_assignment`).
    Where every track's nearest admissible peak is a different one, this is each track's nearest peak.

    Parameters
    ----------
    tracks : list of Track
        The active tracks.
    peaks : list of Peak
        The sub-synchronous peaks of the current segment.
    df_hz : float
        Bin spacing [Hz].

    Returns
    -------
    list of (int, int)
        (track index, peak index) pairs, by increasing track index.

    Examples
    --------
    Track 0 (at 100 Hz) is nearer to the peak at 102 Hz than to its own at 97 Hz; a greedy nearest-neighbour
    search starting with track 0 would swap the two tracks:

    >>> tracks = [Track(FORWARD, [0], [100.0]), Track(FORWARD, [0], [104.0])]
    >>> assign(tracks, [Peak(97.0, 1.0, FORWARD), Peak(102.0, 1.0, FORWARD)], 1.0)
    [(0, 0), (1, 1)]
    """
    from scipy.optimize import linear_sum_assignment

    if not tracks or not peaks:
        return []
    f_tr = np.array([t.last_hz for t in tracks])
    d = np.abs(np.array([p.freq_hz for p in peaks])[None, :] - f_tr[:, None])
    ok = (np.array([t.direction for t in tracks])[:, None] == np.array([p.direction for p in peaks])[None, :]) & \
        (d < np.maximum(3 * df_hz, 0.15 * f_tr)[:, None])
    if not ok.any():
        return []
    cost = np.where(ok, d, np.inf)
    best = cost.argmin(axis=1)
    has = ok.any(axis=1)
    if np.unique(best[has]).size == has.sum():  # every track's nearest peak is distinct: that is the optimum
        return [(int(i), int(best[i])) for i in np.flatnonzero(has)]
    # a forbidden pair costs more than any admissible assignment, so the optimum has the most admissible pairs
    big = 1.0 + d[ok].sum()
    r, c = linear_sum_assignment(np.where(ok, d, big))
    return [(int(i), int(j)) for i, j in zip(r, c) if ok[i, j]]


def split_segment(peaks, speed_rpm, df_hz, f_min_hz):
    """Split one segment's independent peaks into synchronous (1X) and sub-synchronous ones.

    Parameters
    ----------
    peaks : list of Peak
        Peaks without harmonics and mirrors (:func:`secondary_peaks` removed).
    speed_rpm : float
        Rotor speed of the segment [rpm].
    df_hz : float
        Bin spacing [Hz].
    f_min_hz : float
        Lowest frequency of a sub-synchronous component [Hz].

    Returns
    -------
    sync, subs : list of Peak
        Forward peaks within ``SYNC_TOL`` (plus half a bin) of the rotor frequency; peaks below
        (1 − ``SYNC_TOL``) f_rot and above ``f_min_hz``.

    Examples
    --------
    At 60 krpm (f_rot = 1000 Hz): a forward peak at 1000 Hz is 1X, one at 400 Hz is sub-synchronous, a backward
    peak at 1000 Hz is neither, and a peak at 1500 Hz is super-synchronous:

    >>> peaks = [Peak(400.0, 1.0, FORWARD), Peak(1000.0, 1.0, FORWARD), Peak(1000.0, 1.0, BACKWARD),
    ...          Peak(1500.0, 1.0, FORWARD)]
    >>> sync, subs = split_segment(peaks, 60e3, 10.0, 0.0)
    >>> [p.freq_hz for p in sync], [p.freq_hz for p in subs]
    ([1000.0], [400.0])
    """
    frot = speed_rpm / 60.0
    is_sync = [p.direction > 0 and abs(p.freq_hz / frot - 1.0) < SYNC_TOL + 0.5 * df_hz / frot for p in peaks]
    sync = [p for p, s in zip(peaks, is_sync) if s]
    subs = [p for p, s in zip(peaks, is_sync) if not s and f_min_hz < p.freq_hz < (1.0 - SYNC_TOL) * frot]
    return sync, subs


def track_peaks(freqs_hz, speeds_rpm, forward, backward, db_range=25.0, min_amplitude_m=1e-7, f_min_hz=0.0,
                max_misses=3):
    """Follow the spectral peaks through the segments of a spectrogram.

    Parameters
    ----------
    freqs_hz : (f,) ndarray
        Non-negative, equally spaced frequencies [Hz].
    speeds_rpm : (k,) ndarray
        Rotor speed of every segment [rpm].
    forward, backward : (f, k) ndarray
        Orbit amplitude [m] of forward and backward whirl.
    db_range : float
        A peak counts when it lies within this range [dB] of its segment's largest one ...
    min_amplitude_m : float
        ... and above this amplitude [m].
    f_min_hz : float
        Lowest frequency of a sub-synchronous component [Hz].
    max_misses : int
        A track ends after this many consecutive segments without a peak.

    Returns
    -------
    sync : Track
        The synchronous (1X) peaks.
    tracks : list of Track
        Sub-synchronous tracks, unmerged, by the segment of their end.

    Examples
    --------
    A run-up from 30 to 39.5 krpm, one segment per 500 rpm: a 1X line, and a forward whirl at 0.4 f_rot whose
    amplitude is smallest in segment 5 and rises above the detection threshold in segment 12:

    >>> f_hz = np.arange(0.0, 1000.0, 10.0)
    >>> speeds = 30e3 + 500.0 * np.arange(20)
    >>> def line(f0_hz):
    ...     return np.exp(-((f_hz[:, None] - f0_hz) / 15.0) ** 2)
    >>> fwd = 1e-9 + 1e-5 * line(speeds / 60) + 1e-9 * 2.0 ** np.abs(np.arange(20) - 5) * line(0.4 * speeds / 60)
    >>> bwd = np.full_like(fwd, 1e-9)
    >>> sync, tracks = track_peaks(f_hz, speeds, fwd, bwd, db_range=40.0)
    >>> len(sync), [(t.segments[0], len(t)) for t in tracks]
    (20, [(12, 8)])
    """
    df = freqs_hz[1] - freqs_hz[0]
    sync, done, active = Track(FORWARD), [], []
    for k in range(forward.shape[1]):
        thr = max(min_amplitude_m, max(forward[:, k].max(), backward[:, k].max()) * 10 ** (-db_range / 20))
        peaks = segment_peaks(freqs_hz, forward[:, k], backward[:, k], thr)
        skip = secondary_peaks(peaks, df)
        s_peaks, subs = split_segment([p for i, p in enumerate(peaks) if i not in skip], speeds_rpm[k], df, f_min_hz)
        for p in s_peaks:
            sync.add(k, p, thr)
        pairs = dict(assign(active, subs, df))
        kept = []
        for i, tr in enumerate(active):
            if i in pairs:
                tr.add(k, subs[pairs[i]], thr)
            else:
                tr.misses += 1
            (kept if tr.misses <= max_misses else done).append(tr)
        taken = set(pairs.values())
        for j, p in enumerate(subs):
            if j not in taken:
                kept.append(Track(p.direction))
                kept[-1].add(k, p, thr)
        active = kept
    return sync, done + active


def merge_fragments(tracks, speeds_rpm, max_gap=4, ratio_tol=0.2):
    """Join fragments of one component: same direction, the later starting at most ``max_gap`` segments after
    the earlier ends, with f/f_rot within ``ratio_tol`` (relative).

    Parameters
    ----------
    tracks : list of Track
        Sub-synchronous tracks (:func:`track_peaks`).
    speeds_rpm : (k,) ndarray
        Rotor speed of every segment [rpm].
    max_gap : int
        Largest gap [segments] between the end of one fragment and the start of the next.
    ratio_tol : float
        Relative tolerance [-] on f/f_rot between the end of one fragment and the start of the next.

    Returns
    -------
    list of Track
        The joined tracks, by their first segment (the inputs are modified in place).

    Examples
    --------
    At a constant 60 krpm, a 400 Hz fragment resumes after a gap of 2 segments; a 700 Hz track stays apart:

    >>> speeds = np.full(10, 60e3)
    >>> parts = [Track(FORWARD, [0, 1, 2], [400.0] * 3), Track(FORWARD, [5, 6], [405.0] * 2),
    ...          Track(FORWARD, [4, 5], [700.0] * 2)]
    >>> [t.segments for t in merge_fragments(parts, speeds)]
    [[0, 1, 2, 5, 6], [4, 5]]
    """
    out = []
    for t in sorted(tracks, key=lambda t: t.segments[0]):
        r0 = t.freqs_hz[0] / (speeds_rpm[t.segments[0]] / 60.0)
        host = None
        for o in out:
            gap = t.segments[0] - o.segments[-1]
            r1 = o.freqs_hz[-1] / (speeds_rpm[o.segments[-1]] / 60.0)
            if o.direction == t.direction and 0 < gap <= max_gap and abs(r0 - r1) <= ratio_tol * r1:
                host = o
        if host is None:
            out.append(t)
        else:
            host.extend(t)
    return out


# ---------------------------------------------------------------------------------------------------- onsets
def _traced_log_amplitudes(spec, freqs_hz, speeds_rpm, k0, f0_hz):
    """Log amplitude of a component traced backwards in time from segment ``k0`` (at ``f0_hz``) at constant
    f/f_rot — the largest amplitude within ±15 % + 1.5 bins of the traced frequency — and the segments traced,
    both in time order."""
    ratio = f0_hz / (speeds_rpm[k0] / 60.0)
    df = freqs_hz[1] - freqs_hz[0]
    amps = []
    for k in range(k0, -1, -1):  # backwards in time: towards lower speed in a run-up, higher in a run-down
        fc = ratio * speeds_rpm[k] / 60.0
        sel = np.flatnonzero(np.abs(freqs_hz - fc) <= 0.15 * fc + 1.5 * df)
        if sel.size == 0:
            break
        amps.append(spec[sel, k].max())
    amps = np.log(np.maximum(np.array(amps[::-1]), 1e-300))
    return amps, np.arange(k0 - amps.size + 1, k0 + 1)


def turning_point_rpm(spec, freqs_hz, speeds_rpm, k0, f0_hz):
    """Onset at the turning point: trace a component backwards in time from its first detection (segment ``k0``,
    at ``f0_hz``) at constant f/f_rot and return the speed [rpm] of its smallest amplitude, where decay turned into
    growth (the growth rate crosses zero).

    In a run-up the threshold crossing lags the loss of stability (slow passage through the Hopf point); the
    turning point does not. The trace runs over segments in time order, so it works alike for run-ups (back in
    time = towards lower speed), run-downs (towards higher speed) and constant speed.

    Parameters
    ----------
    spec : (f, k) ndarray
        Orbit amplitude [m] in the component's whirl direction.
    freqs_hz : (f,) ndarray
        Frequencies [Hz].
    speeds_rpm : (k,) ndarray
        Rotor speed of every segment [rpm], in time order.
    k0 : int
        Segment of the first detection.
    f0_hz : float
        Frequency of the first detection [Hz].

    Returns
    -------
    float
        Speed [rpm]: vertex of a least-squares parabola in log amplitude over ±4 segments (in time) about the
        (3-point median smoothed) first local minimum, mapped to speed by linear interpolation between the
        segments; else the speed of that segment. NaN if the amplitude keeps falling back to the first segment of
        the run (the component grew from the start: no onset in this run).

    Examples
    --------
    An amplitude that falls back in time all the way to segment 0 has no turning point in the run:

    >>> spec = np.array([[1e-9, 1e-8, 1e-7, 1e-6]] * 8)
    >>> turning_point_rpm(spec, np.arange(8.0) * 100.0, np.array([4e4, 3e4, 2e4, 1e4]), 3, 200.0)
    nan
    """
    amps, ks = _traced_log_amplitudes(spec, freqs_hz, speeds_rpm, k0, f0_hz)
    # walk back from the first detection while the smoothed amplitude keeps falling: the first local minimum
    sm = amps.copy()
    if amps.size >= 3:
        sm[1:-1] = np.median(np.stack([amps[:-2], amps[1:-1], amps[2:]]), axis=0)
    j = amps.size - 1
    while j > 0 and sm[j - 1] < sm[j]:
        j -= 1
    if j == 0 and ks[0] == 0:
        return math.nan  # still falling at the first segment of the run: growing from (before) the start
    if j == 0 or j == amps.size - 1:
        return float(speeds_rpm[ks[j]])
    # a flat minimum at the noise floor is located by its surroundings, not by one segment's dip; the parabola is
    # fitted in time (segment index) — speed need not be monotonic — and its vertex mapped to speed
    lo, hi = max(j - 4, 0), min(j + 5, amps.size)
    if hi - lo >= 5:
        c2, c1, _ = np.polyfit(np.arange(lo - j, hi - j, dtype=float), amps[lo:hi], 2)
        if c2 > 0:
            vertex = -c1 / (2 * c2)
            if lo - j <= vertex <= hi - 1 - j:
                return float(np.interp(ks[j] + vertex, ks, speeds_rpm[ks]))
    return float(speeds_rpm[ks[j]])


def _crossing_rpm(spec, freqs_hz, speeds_rpm, k_out, k_in, f_hz, threshold_m):
    """Speed [rpm] between segment ``k_in`` (component detected, at ``f_hz``) and its time neighbour ``k_out``
    (not detected) where the amplitude crosses ``threshold_m``, interpolated in log amplitude; the speed of
    ``k_in`` if the amplitudes do not straddle the threshold."""
    i = int(np.argmin(np.abs(freqs_hz - f_hz)))
    lo = max(i - 2, 0)
    a_out = spec[lo:i + 3, k_out].max()
    a_in = spec[lo:i + 3, k_in].max()
    if not (0 < a_out < threshold_m <= a_in):
        return float(speeds_rpm[k_in])
    w = math.log(threshold_m / a_out) / math.log(a_in / a_out)
    return float(speeds_rpm[k_out] + w * (speeds_rpm[k_in] - speeds_rpm[k_out]))


def threshold_crossing_rpm(spec, freqs_hz, speeds_rpm, k0, f0_hz, threshold_m):
    """Speed [rpm] where a component's amplitude rises through the detection threshold, interpolated in log
    amplitude between the last segment without (``k0 − 1``) and the first with the component (``k0``, at
    ``f0_hz``).

    Parameters
    ----------
    spec : (f, k) ndarray
        Orbit amplitude [m] in the component's whirl direction.
    freqs_hz : (f,) ndarray
        Frequencies [Hz].
    speeds_rpm : (k,) ndarray
        Rotor speed of every segment [rpm], in time order (rising, falling or constant).
    k0 : int
        Segment of the first detection.
    f0_hz : float
        Frequency of the first detection [Hz].
    threshold_m : float
        Detection threshold of segment ``k0`` [m].

    Returns
    -------
    float
        The interpolated speed; the speed of segment ``k0`` if the amplitude does not cross there; NaN if
        ``k0 == 0`` (present from the start of the run: nothing crossed).

    Examples
    --------
    Amplitude ×10 from one segment to the next, threshold ×√10 above the first: half way — in a run-up and in a
    run-down alike.

    >>> spec = np.array([[1e-8, 1e-7]] * 5)
    >>> threshold_crossing_rpm(spec, np.arange(5.0), np.array([1000.0, 2000.0]), 1, 2.0, 10 ** -7.5)
    1500.0
    >>> threshold_crossing_rpm(spec, np.arange(5.0), np.array([3000.0, 2000.0]), 1, 2.0, 10 ** -7.5)
    2500.0
    """
    if k0 == 0:
        return math.nan
    return _crossing_rpm(spec, freqs_hz, speeds_rpm, k0 - 1, k0, f0_hz, threshold_m)


def vanishing_rpm(spec, freqs_hz, speeds_rpm, k1, f1_hz, threshold_m):
    """Speed [rpm] where a component's amplitude falls through the detection threshold, interpolated in log
    amplitude between its last segment (``k1``, at ``f1_hz``) and the next one (``k1 + 1``).

    Parameters
    ----------
    spec, freqs_hz, speeds_rpm
        As for :func:`threshold_crossing_rpm`.
    k1 : int
        Segment of the last detection.
    f1_hz : float
        Frequency of the last detection [Hz].
    threshold_m : float
        Detection threshold of segment ``k1`` [m].

    Returns
    -------
    float
        The interpolated speed; the speed of segment ``k1`` if the amplitude does not cross there; NaN if ``k1``
        is the last segment (the component lasts to the end of the run).

    Examples
    --------
    A run-down whose component drops ×10 from 2000 to 1000 rpm, threshold ×√10 below the last detection:

    >>> spec = np.array([[1e-7, 1e-8]] * 5)
    >>> vanishing_rpm(spec, np.arange(5.0), np.array([2000.0, 1000.0]), 0, 2.0, 10 ** -7.5)
    1500.0
    """
    if k1 >= speeds_rpm.size - 1:
        return math.nan
    return _crossing_rpm(spec, freqs_hz, speeds_rpm, k1 + 1, k1, f1_hz, threshold_m)


# ---------------------------------------------------------------------------------------------------- components
def to_component(label, track, freqs_hz, speeds_rpm, forward, backward):
    """The :class:`Component` ``label`` of ``track``, with its onset (turning point for sub-synchronous
    components, threshold crossing for 1X; none if it is there from the start of the run), the threshold
    crossings where it appears (``onset_threshold_rpm``) and vanishes (``end_rpm``).

    Parameters
    ----------
    label : str
        "1X" or "sub1", "sub2", ...; "1X" takes the threshold crossing as its onset.
    track : Track
        The component's peaks.
    freqs_hz : (f,) ndarray
        Frequencies [Hz].
    speeds_rpm : (k,) ndarray
        Rotor speed of every segment [rpm], in time order.
    forward, backward : (f, k) ndarray
        Orbit amplitude [m] of forward and backward whirl (the track's direction selects one).

    Returns
    -------
    Component

    Examples
    --------
    See :func:`find_components`, which calls it for every track.
    """
    k = np.array(track.segments)
    spec = forward if track.direction > 0 else backward
    comp = Component(label, speeds_rpm[k], np.array(track.freqs_hz), np.array(track.amplitudes_m),
                     track.direction_name, segments=k)
    k0, f0, k1 = int(k[0]), track.freqs_hz[0], int(k[-1])
    comp.onset_threshold_rpm = threshold_crossing_rpm(spec, freqs_hz, speeds_rpm, k0, f0, track.thresholds_m[0])
    comp.end_rpm = vanishing_rpm(spec, freqs_hz, speeds_rpm, k1, track.freqs_hz[-1], track.thresholds_m[-1])
    if k0 == 0:
        comp.onset_estimate = NO_ONSET_PRESENT
    elif label == "1X":
        comp.onset_interp_rpm, comp.onset_estimate = comp.onset_threshold_rpm, ONSET_THRESHOLD
    else:
        comp.onset_interp_rpm = turning_point_rpm(spec, freqs_hz, speeds_rpm, k0, f0)
        comp.onset_estimate = ONSET_TURNING_POINT if math.isfinite(comp.onset_interp_rpm) else NO_ONSET_GROWING
    return comp


def find_components(freqs_hz, speeds_rpm, forward, backward, db_range=25.0, min_amplitude_m=1e-7, f_min_hz=0.0,
                    min_segments=6):
    """Tracked, labelled components of a spectrogram: "1X" and the sub-synchronous "sub1", "sub2", ... in the
    order of their first detection (ties by frequency).

    Parameters
    ----------
    freqs_hz, speeds_rpm, forward, backward, db_range, min_amplitude_m, f_min_hz
        As for :func:`track_peaks`.
    min_segments : int
        Tracks (after joining fragments) with fewer detections are dropped.

    Returns
    -------
    list of Component

    Examples
    --------
    The spectrogram of :func:`track_peaks`: the sub-synchronous whirl is first detected at 36 krpm, and crosses
    the detection threshold at about 35.8 krpm, but its onset (where its decay turned into growth) is at 32.5 krpm:

    >>> f_hz = np.arange(0.0, 1000.0, 10.0)
    >>> speeds = 30e3 + 500.0 * np.arange(20)
    >>> def line(f0_hz):
    ...     return np.exp(-((f_hz[:, None] - f0_hz) / 15.0) ** 2)
    >>> fwd = 1e-9 + 1e-5 * line(speeds / 60) + 1e-9 * 2.0 ** np.abs(np.arange(20) - 5) * line(0.4 * speeds / 60)
    >>> comps = find_components(f_hz, speeds, fwd, np.full_like(fwd, 1e-9), db_range=40.0)
    >>> [(c.label, c.onset_estimate, round(c.onset_rpm, -2)) for c in comps]
    [('1X', 'none: present from the start', nan), ('sub1', 'turning point', 32500.0)]
    >>> c = comps[1]
    >>> c.detected_from_rpm, round(c.onset_threshold_rpm, -2), round(float(c.ratio[0]), 6)
    (36000.0, 35800.0, 0.4)
    """
    sync, tracks = track_peaks(freqs_hz, speeds_rpm, forward, backward, db_range, min_amplitude_m, f_min_hz)
    tracks = [t for t in merge_fragments(tracks, speeds_rpm) if len(t) >= min_segments]
    tracks.sort(key=lambda t: (t.segments[0], t.freqs_hz[0]))
    labelled = ([("1X", sync)] if len(sync) >= min_segments else []) + \
        [(f"sub{i + 1}", t) for i, t in enumerate(tracks)]
    return [to_component(lab, t, freqs_hz, speeds_rpm, forward, backward) for lab, t in labelled]


def _simultaneous(a, b):
    """Speeds [rpm] and the two components' frequencies [Hz] where both are detected: matched by segment (by speed
    for components built without segments) — no interpolation, so the order of the speeds does not matter."""
    if a.segments is not None and b.segments is not None:
        _, ia, ib = np.intersect1d(a.segments, b.segments, return_indices=True)
    else:
        _, ia, ib = np.intersect1d(a.speeds_rpm, b.speeds_rpm, return_indices=True)
    return a.speeds_rpm[ia], a.freqs_hz[ia], b.freqs_hz[ib]


def internal_resonances(components):
    """Speed ranges where two sub-synchronous components satisfy f_b ≈ 2 f_a or f_a + f_b ≈ f_rot (within
    ``RESONANCE_TOL``) at the same time: the signature of "total instability".

    Parameters
    ----------
    components : list of Component
        Components of one run; only the sub-synchronous ones are compared.

    Returns
    -------
    list of dict
        Keys "components" (two labels), "condition" ("2:1" or "f_a + f_b = 1X"), "from [rpm]", "to [rpm]" (the
        lowest and highest speed where the condition holds, in a run-up and a run-down alike).

    Examples
    --------
    >>> s = np.array([60e3, 90e3])
    >>> a = Component("sub1", s, np.array([200.0, 300.0]), np.ones(2), "forward")
    >>> b = Component("sub2", s, np.array([400.0, 1000.0]), np.ones(2), "forward")
    >>> internal_resonances([a, b])
    [{'components': ('sub1', 'sub2'), 'condition': '2:1', 'from [rpm]': 60000.0, 'to [rpm]': 60000.0}]
    """
    comps = [c for c in components if c.label.startswith("sub")]
    found = []
    for i, a in enumerate(comps):
        for b in comps[i + 1:]:
            common, fa, fb = _simultaneous(a, b)
            if common.size == 0:
                continue
            lo, hi = np.minimum(fa, fb), np.maximum(fa, fb)
            frot = common / 60.0
            for kind, ok in (("2:1", np.abs(hi - 2 * lo) < RESONANCE_TOL * hi),
                             ("f_a + f_b = 1X", np.abs(lo + hi - frot) < RESONANCE_TOL * frot)):
                if ok.any():
                    found.append({"components": (a.label, b.label), "condition": kind,
                                  "from [rpm]": float(common[ok].min()), "to [rpm]": float(common[ok].max())})
    return found


#: columns of :func:`components_table`, with what each holds
COMPONENT_COLUMNS = {
    "component": '"1X" or "sub1", "sub2", ... in the order of their first detection',
    "whirl direction": '"forward" or "backward"',
    "onset [rpm]": "onset speed: see 'onset estimate'; empty if the component is there from the start",
    "onset estimate": f"{ONSET_TURNING_POINT!r} (sub-synchronous), {ONSET_THRESHOLD!r} (1X), "
                      f"{NO_ONSET_PRESENT!r} or {NO_ONSET_GROWING!r}",
    "f at onset [Hz]": "frequency at the onset speed",
    "first detection [rpm]": "speed where the amplitude rises through the detection threshold (empty if present "
                             "from the start)",
    "f at first detection [Hz]": "frequency of the first detection",
    "vanishes at [rpm]": "speed where the amplitude falls through the detection threshold (empty if the "
                         "component lasts to the end of the run)",
    "f at vanishing [Hz]": "frequency where it vanishes",
    "detected from [rpm]": "speed of the first segment with the component",
    "detected to [rpm]": "speed of the last segment with the component",
    "f/f_rot at first detection [-]": "frequency ratio of the first detection",
    "max amplitude [m]": "largest orbit amplitude of the component",
}


def components_table(components):
    """pandas DataFrame, one row per component; the columns are the keys of :data:`COMPONENT_COLUMNS` (which says
    what each holds). Speeds are in the run's time order: in a run-down "vanishes at" is below "detected from".

    Parameters
    ----------
    components : list of Component
        Components of one run (:func:`find_components`).

    Returns
    -------
    pandas.DataFrame

    Examples
    --------
    >>> c = Component("sub1", np.array([60e3, 90e3]), np.array([400.0, 600.0]), np.array([1e-6, 3e-6]), "forward",
    ...               onset_interp_rpm=55e3, onset_estimate=ONSET_TURNING_POINT)
    >>> row = components_table([c]).iloc[0]
    >>> [round(float(row[k]), 6) for k in ("onset [rpm]", "f at onset [Hz]", "max amplitude [m]")]
    [55000.0, 366.666667, 3e-06]
    """
    import pandas as pd

    rows = [{"component": c.label, "whirl direction": c.direction, "onset [rpm]": c.onset_rpm,
             "onset estimate": c.onset_estimate, "f at onset [Hz]": c.onset_hz,
             "first detection [rpm]": c.onset_threshold_rpm, "f at first detection [Hz]": c.first_detection_hz,
             "vanishes at [rpm]": c.end_rpm, "f at vanishing [Hz]": c.end_hz,
             "detected from [rpm]": c.detected_from_rpm, "detected to [rpm]": c.detected_to_rpm,
             "f/f_rot at first detection [-]": float(c.ratio[0]),
             "max amplitude [m]": float(c.amplitude_m.max())} for c in components]
    return pd.DataFrame(rows, columns=list(COMPONENT_COLUMNS))


__all__ = ["SYNC_TOL", "RESONANCE_TOL", "FORWARD", "BACKWARD", "ONSET_TURNING_POINT", "ONSET_THRESHOLD",
           "NO_ONSET_PRESENT", "NO_ONSET_GROWING", "COMPONENT_COLUMNS", "Peak", "Track", "Component",
           "peak_frequency_hz", "segment_peaks", "secondary_peaks", "assign", "split_segment", "track_peaks",
           "merge_fragments", "turning_point_rpm", "threshold_crossing_rpm", "vanishing_rpm", "to_component",
           "find_components", "internal_resonances", "components_table"]
