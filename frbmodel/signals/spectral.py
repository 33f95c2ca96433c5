"""Spectral post-processing of run-ups and run-downs: spectrogram of a node's orbit against rotor speed.

The orbit of a node, z = x + i y, is cut into overlapping segments; each is linearly detrended (the static
deflection and its slow drift with speed), Hann-windowed and Fourier transformed
(:class:`scipy.signal.ShortTimeFFT`). The two-sided spectrum separates forward (f > 0) from backward (f < 0)
whirl. Amplitudes are the orbit radius of each component [m]; the figure shows them in dB relative to the
largest, over a 25 dB range, as in the paper. Components are tracked and labelled by :mod:`frbmodel.signals.tracking`.
Segments stay in time order, so the speed of a run-down falls from segment to segment.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ParameterError, check_real
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..linear.equilibrium import linear_rsr
from ..plots.figures import composite_figure, composite_plotly, waterfall_figure, waterfall_plotly, write_html
from ..system.parameters import Turbocharger
from .tracking import RESONANCE_TOL, SYNC_TOL, Component, components_table, find_components, internal_resonances


@dataclass
class SpectrogramResult(Result):
    """Spectrogram of a node's orbit during a run-up or run-down.

    Parameters
    ----------
    times : (k,) ndarray
        Segment centres [s].
    speeds_rpm : (k,) ndarray
        Rotor speed at the segment centres [rpm] (time order: falling in a run-down).
    freqs_hz : (f,) ndarray
        Non-negative frequencies [Hz].
    forward, backward : (f, k) ndarray
        Orbit amplitude [m] of forward and backward whirl components.
    node : str
        Name of the node (a key of ``RunupResult.displacement``).
    db_range : float
        Colour range of the figures and detection range of the components [dB].
    meta : dict
        ``segment_s`` [s], ``overlap`` [-], ``nfft``, ``fs_hz`` [Hz] and, with a system in the run's metadata,
        ``min_amplitude_m`` [m] (5 % of the smallest film clearance).
    run : RunupResult, optional
        The run-up (for the RSR panel of :meth:`plot`).
    """

    NC_GLOB = "spectrogram*.nc"  # (Result.load of a folder)
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
    def direction(self) -> str:
        """``"up"`` (run-up), ``"down"`` (run-down) or ``"constant"``: the sign of the last minus the first
        segment's speed (as :attr:`frbmodel.nonlinear.runup.SpeedProfile.direction`)."""
        d = float(self.speeds_rpm[-1] - self.speeds_rpm[0])
        return "up" if d > 0 else "down" if d < 0 else "constant"

    @property
    def amplitude(self):
        """max(forward, backward) orbit amplitude [m], (f, k)."""
        return np.maximum(self.forward, self.backward)

    def db(self):
        """:attr:`amplitude` in dB relative to its maximum, (f, k)."""
        a = self.amplitude
        return 20 * np.log10(np.maximum(a, 1e-300) / a.max())

    def amplitude_um(self):
        """Forward and backward orbit amplitudes in µm, ((f, k), (f, k))."""
        return self.forward * 1e6, self.backward * 1e6

    def db_re_um(self):
        """:attr:`amplitude` in dB re 1 µm, (f, k)."""
        return 20 * np.log10(np.maximum(self.amplitude, 1e-300) / 1e-6)

    def to_xarray(self):
        """The spectrogram as an :class:`xarray.Dataset` with dimensions frequency × time.

        Returns
        -------
        xarray.Dataset
            Coordinates ``frequency`` [Hz], ``time`` [s] (segment centres) and ``speed`` [rpm] along ``time``;
            variables ``forward`` and ``backward`` (frequency, time): orbit amplitude [m] of forward / backward
            whirl, each with ``units`` and ``long_name``; attributes ``node``, ``direction``, ``db_range_dB`` and
            :attr:`meta` (segment length [s], overlap, FFT length, sampling rate [Hz], ...).

        Examples
        --------
        >>> sp = SpectrogramResult(np.array([0.1, 0.2]), np.array([3e4, 3.1e4]), np.array([0.0, 100.0, 200.0]),
        ...                        np.zeros((3, 2)), np.zeros((3, 2)), "turbine_wheel", meta={"segment_s": 0.05})
        >>> ds = sp.to_xarray()
        >>> dict(ds["forward"].sizes), ds["forward"].attrs["units"], ds["speed"].dims, ds.attrs["direction"]
        ({'frequency': 3, 'time': 2}, 'm', ('time',), 'up')
        """
        import xarray as xr

        ft = ("frequency", "time")
        data = {"forward": variable(ft, self.forward, "m", "orbit amplitude of forward whirl (+f)"),
                "backward": variable(ft, self.backward, "m", "orbit amplitude of backward whirl (-f)")}
        coords = {"frequency": variable(("frequency",), self.freqs_hz, "Hz", "whirl frequency"),
                  "time": variable(("time",), self.times, "s", "segment centre time"),
                  "speed": variable(("time",), self.speeds_rpm, "rpm", "rotor speed at the segment centre")}
        attrs = {"title": f"spectrogram of the {self.node} orbit x + iy", "node": self.node,
                 "direction": self.direction, "db_range_dB": float(self.db_range), **self.meta}
        return xr.Dataset(data, coords, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The spectrogram from a dataset of :meth:`to_xarray` (e.g. ``spectrogram_<node>.nc`` of :meth:`save`);
        without the run (no RSR panel in its figures).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        SpectrogramResult
        """
        meta = {k: decode_attr(v) for k, v in ds.attrs.items() if k not in ("title", "direction")}
        node, db_range = str(meta.pop("node")), float(meta.pop("db_range_dB"))
        return cls(ds["time"].values, ds["speed"].values, ds["frequency"].values,
                   ds["forward"].transpose("frequency", "time").values,
                   ds["backward"].transpose("frequency", "time").values, node, db_range, meta)

    def to_dataframe(self):
        """The spectrogram as a long table: one row per segment and frequency, ``time [s]``, ``speed [rpm]``,
        ``frequency [Hz]``, ``forward [m]``, ``backward [m]`` (orbit amplitudes of forward / backward whirl)."""
        import pandas as pd

        k, f = self.times.size, self.freqs_hz.size
        return pd.DataFrame({"time [s]": np.repeat(self.times, f), "speed [rpm]": np.repeat(self.speeds_rpm, f),
                             "frequency [Hz]": np.tile(self.freqs_hz, k), "forward [m]": self.forward.T.ravel(),
                             "backward [m]": self.backward.T.ravel()})

    # ---------------------------------------------------------------- components
    def components(self, min_segments=6, min_amplitude=None):
        """Tracked components with labels: "1X" and the sub-synchronous "sub1", "sub2", ... in the order of their
        onset (:func:`frbmodel.signals.tracking.find_components`).

        A spectral peak counts when it lies within ``db_range`` of its segment's largest peak and above
        ``min_amplitude`` — so components well below the dominant one of the whole run are still found.
        Each component carries ``onset_rpm`` — the turning point, where the amplitude traced backwards in time at
        constant f/f_rot is smallest (:func:`frbmodel.signals.tracking.turning_point_rpm`) — and the interpolated
        threshold crossings where it appears (``onset_threshold_rpm``) and vanishes (``end_rpm``). A component that
        is there from the start of the run (detected in the first segment, or growing since then) has no onset
        (NaN), in a run-up and a run-down alike; one that lasts to the end has no ``end_rpm``.

        Parameters
        ----------
        min_segments : int
            Components detected in fewer segments are dropped.
        min_amplitude : float, optional
            Minimum peak amplitude [m] (default: ``meta["min_amplitude_m"]``, else 1e-7 m).

        Returns
        -------
        list of Component
        """
        if min_amplitude is None:
            min_amplitude = self.meta.get("min_amplitude_m", 1e-7)
        df = self.freqs_hz[1] - self.freqs_hz[0]
        # below one period per segment a "peak" cannot be told from the static deflection's drift and the
        # window's main lobe about 0 Hz (detrending leaves a residue there): not a component
        f_min = max(2 * df, 1.0 / self.meta.get("segment_s", 1.0 / (4 * df)))
        return find_components(self.freqs_hz, self.speeds_rpm, self.forward, self.backward, db_range=self.db_range,
                               min_amplitude_m=min_amplitude, f_min_hz=f_min, min_segments=min_segments)

    def internal_resonances(self, components=None):
        """Speed ranges where two sub-synchronous components satisfy f_b ≈ 2 f_a or f_a + f_b ≈ f_rot (within
        ``RESONANCE_TOL``): the signature of "total instability".

        Parameters
        ----------
        components : list of Component, optional
            Default: :meth:`components`.

        Returns
        -------
        list of dict
            See :func:`frbmodel.signals.tracking.internal_resonances`.
        """
        return internal_resonances(components or self.components())

    def components_table(self):
        """pandas DataFrame of :meth:`components`: label, whirl direction, onset and what it is, threshold crossings
        on appearing and vanishing [rpm], frequencies [Hz] (columns:
        :data:`frbmodel.signals.tracking.COMPONENT_COLUMNS`)."""
        return components_table(self.components())

    # ---------------------------------------------------------------- figures
    def plot(self, campbell=None, whirl=True, rsr=True, fmax_hz=None, components=True, title=None, xscale="linear",
             amplitude="db_max", orders=(1.0,), linear_rsr=None):
        """Spectrogram vs speed; with ``campbell`` (a method-J :class:`CampbellResult`) its unstable-mode
        frequencies as solid lines and the film whirl curves dashed, and — with ``rsr`` — the run-up RSR vs the
        linear methods beside it (the paper's Figs. 12–14).

        ``amplitude`` is the colour scale: ``"db_max"`` (dB re the largest, default), ``"um"`` (µm) or
        ``"db_um"`` (dB re 1 µm); ``orders`` the order lines k × f_rot (1X by default); the frequency axis ends
        by default a little above the highest component within the colour range
        (:func:`frbmodel.plots.figures.content_fmax`); ``linear_rsr`` the linear methods' RSR of the RSR panel
        (default: :func:`frbmodel.linear.equilibrium.linear_rsr` over the run's speeds, when the run carries its
        system). See :func:`frbmodel.plots.figures.composite_figure`.

        Parameters
        ----------
        campbell : CampbellResult, optional
            Method-J Campbell diagram whose unstable modes are drawn over the spectrogram.
        whirl : bool
            Draw the films' whirl curves (dashed) with ``campbell``.
        rsr : bool
            Add the RSR panel (run-up vs the linear methods).
        fmax_hz : float, optional
            Upper end of the frequency axis [Hz] (default: from the content).
        components : bool
            Label the tracked sub-synchronous components and mark where they vanish.
        title : str, optional
            Figure title.
        xscale : {"linear", "log"}
            Speed axis scale.
        amplitude : {"db_max", "um", "db_um"}
            Colour scale.
        orders : sequence of float
            Order lines k × f_rot drawn.
        linear_rsr : dict, optional
            The linear methods' RSR for the RSR panel.

        Returns
        -------
        matplotlib.figure.Figure
        """

        return composite_figure(self, campbell=campbell, whirl=whirl, rsr=rsr, fmax_hz=fmax_hz,
                                components=components, title=title, xscale=xscale, amplitude=amplitude,
                                orders=orders, linear_rsr=linear_rsr if linear_rsr is not None or not rsr
                                else self._linear_rsr())

    def _linear_rsr(self):
        """The linear methods' RSR over the run's speeds (:func:`frbmodel.linear.equilibrium.linear_rsr`) for the
        composites' RSR panel, when the run carries its system; else None."""
        sys_d = (getattr(self.run, "meta", None) or {}).get("system") if self.run is not None else None
        if not sys_d:
            return None

        speed = self.run.speed_rpm
        return linear_rsr(Turbocharger.from_dict(sys_d), np.linspace(max(speed.min(), 1e3), speed.max(), 25))

    def plot_html(self, path=None, campbell=None, fmax_hz=None, amplitude="db_max", orders=(1.0,), compact=True,
                  include_plotlyjs=None, rsr=True, linear_rsr=None):
        """Interactive composite (plotly): spectrogram with the overlays and component marks of :meth:`plot` and
        the RSR panel; written to ``path`` (HTML) if given (options as :meth:`plot`).

        Parameters
        ----------
        path : str or Path, optional
            The HTML file.
        campbell, fmax_hz, amplitude, orders, rsr
            As for :meth:`plot`.
        linear_rsr : tuple, optional
            The linear methods' RSR of the RSR panel (default: computed as :meth:`plot` does, when the run carries
            its system).
        compact : bool
            Keep the file small (:func:`frbmodel.plots.figures.composite_plotly`): at most about a screen of heatmap
            cells, every peak kept, single precision.
        include_plotlyjs : {"directory", True}, optional
            How the file gets plotly.js (:func:`frbmodel.plots.figures.write_html`): ``"directory"`` (as every
            interactive figure of a results folder: ``plotly.min.js`` beside the file, one copy per folder; small
            files, shown offline) or ``True`` (embedded: a self-contained file, 4.8 MB larger). Default:
            ``"directory"``, or what :func:`frbmodel.plots.figures.html_plotlyjs` set.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        if rsr and linear_rsr is None:
            linear_rsr = self._linear_rsr()
        fig = composite_plotly(self, campbell=campbell, fmax_hz=fmax_hz, amplitude=amplitude, orders=orders,
                               compact=compact, rsr=rsr, linear_rsr=linear_rsr)
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def save(self, out_dir, campbell=None, xscale="linear", title=None, orders=(1.0,), png=True, html=True, nc=True):
        """Write the composite figure and the component table of this spectrogram into ``out_dir``.

        Parameters
        ----------
        out_dir : str or Path
            Folder (created if missing).
        campbell : CampbellResult, optional
            Method-J Campbell diagram for the overlay (unstable modes, whirl curves).
        xscale : {"linear", "log"}
            Speed axis scale of the PNG.
        title : str, optional
            Figure title (default: the kind of run and the node).
        orders : sequence of float
            Order lines k × f_rot.
        png, html : bool
            Write ``composite_<node>.png`` / ``.html``.
        nc : bool
            Write ``spectrogram_<node>.nc`` (:meth:`to_xarray`; :meth:`load` reads it back).

        Returns
        -------
        list of Path
            The figures written, ``components_<node>.csv`` (:meth:`components_table`) and the ``.nc``.
        """
        from pathlib import Path

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = out / f"composite_{self.node}"
        paths, lin = [], self._linear_rsr()
        if png:
            import matplotlib.pyplot as plt

            fig = self.plot(campbell=campbell, xscale=xscale, title=title, orders=orders, linear_rsr=lin)
            paths.append(stem.with_suffix(".png"))
            fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
            plt.close(fig)
        if html:
            paths.append(stem.with_suffix(".html"))
            self.plot_html(paths[-1], campbell=campbell, orders=orders, linear_rsr=lin)
        paths.append(out / f"components_{self.node}.csv")
        self.components_table().to_csv(paths[-1], index=False)
        if nc:
            paths.append(self.to_netcdf(out / f"spectrogram_{self.node}.nc"))
        return paths

    def waterfall(self, fmax_hz=None, amplitude="um", orders=(1.0,), n_lines=40, title=None):
        """3-D waterfall (speed × frequency × amplitude in µm, or ``amplitude="db_um"``) with order lines
        (:func:`frbmodel.plots.figures.waterfall_figure`).

        Parameters
        ----------
        fmax_hz : float, optional
            Upper end of the frequency axis [Hz] (default: from the content).
        amplitude : {"um", "db_um"}
            Amplitude axis: µm, or dB re 1 µm.
        orders : sequence of float
            Order lines k × f_rot drawn.
        n_lines : int
            Number of spectra (speeds) drawn.
        title : str, optional
            Figure title.

        Returns
        -------
        matplotlib.figure.Figure
        """

        return waterfall_figure(self, fmax_hz, amplitude, orders, n_lines, title)

    def waterfall_html(self, path=None, fmax_hz=None, amplitude="um", orders=(1.0,), n_lines=40,
                       include_plotlyjs=None):
        """Interactive 3-D waterfall (plotly); written to ``path`` (HTML) if given.

        Parameters
        ----------
        path : str or Path, optional
            The HTML file (not written if None).
        fmax_hz : float, optional
            Upper end of the frequency axis [Hz] (default: from the content).
        amplitude : {"um", "db_um"}
            Amplitude axis: µm, or dB re 1 µm.
        orders : sequence of float
            Order lines k × f_rot drawn.
        n_lines : int
            Number of spectra (speeds) drawn.
        include_plotlyjs : {"directory", True}, optional
            As for :func:`frbmodel.plots.figures.write_html`: plotly.js beside the page, or embedded in it.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        fig = waterfall_plotly(self, fmax_hz, amplitude, orders, n_lines)
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig


def _detrend_complex(seg):
    """Linear detrend of the real and imaginary parts of one segment."""
    from scipy.signal import detrend

    return detrend(seg.real) + 1j * detrend(seg.imag)


def orbit_spectra(z, fs_hz, nperseg, hop, nfft):
    """Forward and backward whirl spectra of consecutive segments of a complex orbit.

    Segment ``p`` is ``z[p * hop : p * hop + nperseg]`` (segments that fit entirely into ``z``); it is linearly
    detrended (real and imaginary parts), multiplied by a symmetric Hann window, zero padded to ``nfft`` and
    transformed; the magnitude is divided by the window sum, so a circular orbit of radius r gives a peak of r.

    Parameters
    ----------
    z : (n,) complex ndarray
        Orbit x + i y [m], equally sampled.
    fs_hz : float
        Sampling rate [Hz].
    nperseg, hop, nfft : int
        Segment length, segment step and FFT length (even, ≥ ``nperseg``) in samples.

    Returns
    -------
    freqs_hz : (nfft // 2,) ndarray
        Non-negative frequencies [Hz].
    forward, backward : (nfft // 2, k) ndarray
        Amplitude [m] at +f and −f (backward at f = 0 is set to 0: f = 0 counted once).
    starts : (k,) ndarray of int
        First sample of each segment.

    Examples
    --------
    A circular forward orbit of radius 2 at 100 Hz (an exact bin):

    >>> fs = 1000.0
    >>> z = 2.0 * np.exp(2j * np.pi * 100.0 * np.arange(400) / fs)
    >>> f, fwd, bwd, starts = orbit_spectra(z, fs, 100, 50, 200)
    >>> i = fwd[:, 0].argmax()
    >>> float(f[i]), round(float(fwd[i, 0]), 3), round(float(bwd[i, 0]), 3), starts[:3].tolist()
    (100.0, 2.0, 0.0, [0, 50, 100])
    """
    from scipy.signal import ShortTimeFFT

    win = np.hanning(nperseg)
    sft = ShortTimeFFT(win, hop=hop, fs=fs_hz, fft_mode="twosided", mfft=nfft, phase_shift=None)
    n_seg = (z.size - nperseg) // hop + 1
    # k_offset = m_num_mid puts the first slice at z[0:nperseg] (ShortTimeFFT centres slice p at p * hop)
    spec = sft.stft_detrend(z, _detrend_complex, p0=0, p1=n_seg, k_offset=sft.m_num_mid) / win.sum()
    half = nfft // 2
    forward = np.abs(spec[:half])
    backward = np.abs(spec[-np.arange(half) % nfft])
    backward[0] = 0.0
    return sft.f[:half], forward, backward, np.arange(n_seg) * hop


def spectrogram(run, node=None, segment_s=None, overlap=0.75, db_range=25.0, zero_pad=4):
    """Spectrogram of ``run.displacement[node]`` (orbit x + i y) against rotor speed.

    Parameters
    ----------
    run : RunupResult
    node : str, optional
        A disc of the run (a key of ``run.displacement``); default: the first disc of the system.
    segment_s : float, optional
        FFT segment length [s] (default: duration / 40, within 0.01 ... 0.05 s and at most duration / 4).
    overlap : float
        Segment overlap fraction (0.75).
    db_range : float
        Colour range [dB] (25, as in the paper).
    zero_pad : int
        FFT length = zero_pad × segment length, rounded up to a power of 2 (interpolates the spectrum for peak
        tracking).

    Returns
    -------
    SpectrogramResult

    Examples
    --------
    Any object with ``time``, ``speed_rpm``, ``displacement`` and ``meta`` as a :class:`RunupResult` has them
    will do; here a forward whirl at 200 Hz of radius 1 um at a constant 30 krpm, present from the start (so it
    has no onset):

    >>> from types import SimpleNamespace
    >>> t = np.arange(0, 0.5, 1e-4)
    >>> z = 1e-6 * np.exp(2j * np.pi * 200.0 * t)
    >>> run = SimpleNamespace(time=t, speed_rpm=np.full(t.size, 30e3), meta={},
    ...                       displacement={"turbine_wheel": np.column_stack([z.real, z.imag])})
    >>> sp = spectrogram(run, segment_s=0.05)
    >>> tab = sp.components_table()
    >>> round(float(sp.forward.max()) * 1e6, 2), tab["f at first detection [Hz]"].round(1).tolist()
    (1.0, [200.0])
    >>> tab["onset [rpm]"].tolist(), tab["onset estimate"].tolist()
    ([nan], ['none: present from the start'])
    """
    if node is None:
        node = next(iter(run.displacement))
    if node not in run.displacement:
        raise ParameterError(f"node = {node!r} is unknown; valid: {sorted(run.displacement)}")
    t = run.time
    if t.size < 64:
        raise ParameterError(f"run has {t.size} samples; a spectrogram needs at least 64")
    if not 0.0 <= overlap < 1.0:
        raise ParameterError(f"overlap = {overlap!r} is invalid: valid range 0 <= overlap < 1")
    dt = t[1] - t[0]
    fs = 1.0 / dt
    dur = t[-1] - t[0]
    if segment_s is not None:  # (a negative or zero segment was taken as the default)
        check_real("segment_s", segment_s, "s", minimum=0.0)
    if not (np.isfinite(db_range) and db_range > 0):
        raise ParameterError(f"db_range = {db_range!r} dB is invalid: valid range is finite and > 0 dB")
    if not (isinstance(zero_pad, (int, np.integer)) and zero_pad >= 1):
        raise ParameterError(f"zero_pad = {zero_pad!r} is invalid: valid range integer >= 1")
    seg = segment_s or min(max(dur / 40.0, 0.01), 0.05, dur / 4.0)
    nper = max(32, int(round(seg * fs)))
    if nper > t.size:
        raise ParameterError(f"segment_s = {seg!r} s is invalid: valid range up to the run's duration {dur:g} s")
    step = max(1, int(round(nper * (1 - overlap))))
    nfft = int(2 ** math.ceil(math.log2(nper * zero_pad)))
    z = run.displacement[node][:, 0] + 1j * run.displacement[node][:, 1]
    freqs, fwd, bwd, starts = orbit_spectra(z, fs, nper, step, nfft)
    centres = t[starts + nper // 2]
    speeds = np.interp(centres, t, run.speed_rpm)
    meta = {"segment_s": nper * dt, "overlap": overlap, "nfft": nfft, "fs_hz": fs}
    sys_d = (run.meta or {}).get("system")
    if sys_d:
        films = [f for b in sys_d["bearings"] for f in (b["inner"], b["outer"])]
        meta["min_amplitude_m"] = 0.05 * min(f["clearance"] for f in films)
    return SpectrogramResult(centres, speeds, freqs, fwd, bwd, node, db_range, meta, run)


__all__ = ["SYNC_TOL", "RESONANCE_TOL", "Component", "SpectrogramResult", "orbit_spectra", "spectrogram"]
