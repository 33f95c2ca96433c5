"""The interactive spectrogram file stays small (issue 12): at most about a screen of heatmap cells, each block of
cells keeping its largest value, single precision, plotly.js in a shared file beside it — and the peaks stay where
they are."""
import numpy as np
from test_plot_cli import figure_data

from frbmodel.signals.spectral import SpectrogramResult

LIMIT_BYTES = 1.5e6  # the bound for an interactive composite
SCREEN_COLUMNS, SCREEN_ROWS = 1000, 250  # a full-screen plot area: ~1000 px wide, rows of >= 2 px on ~500 px


def _spectrogram(n_seg, n_freq, df_hz, spike, order=1.0):
    """Forward whirl only: a noise floor of 1 nm, a ridge of 2 µm in the bin nearest ``order`` × f_rot in every
    segment (20 -> 250 krpm) and one isolated cell of 5 µm (the maximum) at ``spike`` = (frequency row, segment)."""
    speeds = np.linspace(20e3, 250e3, n_seg)
    freqs = np.arange(n_freq) * df_hz
    fwd = np.full((n_freq, n_seg), 1e-9)
    fwd[np.rint(order * speeds / 60.0 / df_hz).astype(int), np.arange(n_seg)] = 2e-6
    fwd[spike] = 5e-6
    times = np.linspace(0.0, 1.0, n_seg)
    return SpectrogramResult(times, speeds, freqs, fwd, np.zeros_like(fwd), "turbine_wheel")


def _heatmap(path):
    return next(t for t in figure_data(path) if t.get("type") == "heatmap")


def test_long_run_is_decimated_to_the_screen_and_keeps_its_peaks(tmp_path):
    spike = (800, 3001)  # 2000 Hz at segment 3001
    sp = _spectrogram(6000, 2048, 2.5, spike)  # 6000 x ~2000 visible cells: 96 MB as float64
    path = tmp_path / "long.html"
    sp.plot_html(path)
    assert path.stat().st_size < LIMIT_BYTES
    h = _heatmap(path)
    z, x, y = h["z"], h["x"], h["y"]
    assert z.dtype == np.float32 and z.shape == (y.size, x.size)
    assert x.size <= SCREEN_COLUMNS and y.size <= SCREEN_ROWS
    # the spike is the largest value: 0 dB re max, exactly (a block keeps its maximum); it lies within one
    # screen pixel (1/1000 of the speed span, 1/250 of the frequency span) of where it was
    i, j = np.unravel_index(np.argmax(z), z.shape)
    assert z[i, j] == 0.0
    assert abs(x[j] - sp.speeds_rpm[spike[1]]) <= np.ptp(sp.speeds_rpm) / SCREEN_COLUMNS
    assert abs(y[i] - sp.freqs_hz[spike[0]]) <= y.max() / SCREEN_ROWS
    # every other column holds the 1X ridge: 20 log10(2 µm / 5 µm) = -7.96 dB (float32: 1e-5 dB)
    others = np.delete(z, j, axis=1).max(axis=0)
    np.testing.assert_allclose(others, 20 * np.log10(2.0 / 5.0), atol=1e-5)


def test_main_job_sized_figure_is_kept_cell_for_cell(tmp_path):
    # the main job (co-simulation 20 -> 250 krpm in 1 s at 20 kHz): 157 segments x 1024 frequencies of 9.77 Hz,
    # content below ~1 kHz (its sub-synchronous whirl; here a 0.22X ridge)
    sp = _spectrogram(157, 1024, 20000.0 / 2048, (40, 80), order=0.22)
    path = tmp_path / "main.html"
    fig = sp.plot_html(path)
    assert path.stat().st_size < LIMIT_BYTES
    h = _heatmap(path)
    shown = sp.freqs_hz <= fig.layout.yaxis.range[1]
    assert h["z"].shape == (shown.sum(), 157)  # below the screen's resolution: nothing merged
    # the same cells in single precision (relative 6e-8; the noise floor is -74 dB: 1e-5 dB absolute)
    np.testing.assert_allclose(h["z"], sp.db()[shown], rtol=0, atol=1e-5)
    np.testing.assert_allclose(h["x"], sp.speeds_rpm, rtol=1e-7)


def test_plotly_js_beside_by_default_embedded_on_request(tmp_path):
    sp = _spectrogram(157, 1024, 20000.0 / 2048, (40, 80))
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    sp.plot_html(tmp_path / "a" / "offline.html", include_plotlyjs=True)
    sp.plot_html(tmp_path / "b" / "beside.html")
    offline, beside = (tmp_path / "a" / "offline.html").read_text(), (tmp_path / "b" / "beside.html").read_text()
    assert '<script charset="utf-8" src="plotly.min.js"></script>' in beside
    assert 'src="plotly.min.js"' not in offline and not (tmp_path / "a" / "plotly.min.js").exists()
    assert "cdn.plot.ly" not in beside
    assert len(offline) - len(beside) > 3e6  # plotly.js itself is several MB
