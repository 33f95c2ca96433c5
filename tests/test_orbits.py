"""Orbits of run-ups (frbmodel.signals.orbits), the µm / dB re 1 µm spectrogram scales, the content-limited frequency
axis,
order lines and the waterfall (frbmodel.plots.figures), on small synthetic runs (no integration)."""
import numpy as np
import pytest

from frbmodel.nonlinear.recorder import RunupResult
from frbmodel.plots.figures import composite_figure, content_fmax, spectrogram_colour, waterfall_figure, waterfall_lines
from frbmodel.signals.orbits import orbits, orbits_figure, window_indices
from frbmodel.signals.spectral import spectrogram

C_IN, C_OUT = {"front": 30e-6, "rear": 40e-6}, {"front": 50e-6, "rear": 60e-6}
R_J, R_R, R_W = {"front": 12e-6, "rear": 20e-6}, {"front": 5e-6, "rear": 15e-6}, 25e-6


def _circle(t, r, f_hz, phase=0.0):
    w = 2 * np.pi * f_hz * t + phase
    return r * np.column_stack([np.cos(w), np.sin(w)])


def _run(t, speed_rpm, disc_z=None):
    """A RunupResult with circular orbits: ring of radius R_R about the housing at 100 Hz, journal of radius R_J
    about the ring at 170 Hz (so journal = ring + circle), one wheel of radius R_W at 200 Hz (or ``disc_z``)."""
    ring = {b: _circle(t, R_R[b], 100.0) for b in C_IN}
    journal = {b: ring[b] + _circle(t, R_J[b], 170.0, 0.3) for b in C_IN}
    wheel = _circle(t, R_W, 200.0) if disc_z is None else np.column_stack([disc_z.real, disc_z.imag])
    sys_d = {"bearings": [{"name": b, "inner": {"clearance": C_IN[b]}, "outer": {"clearance": C_OUT[b]}}
                          for b in C_IN]}
    return RunupResult(t, np.asarray(speed_rpm, float), np.zeros((t.size, 2)), journal, ring,
                       np.zeros((t.size, 4)), {"wheel": wheel}, meta={"system": sys_d})


def test_orbits_equal_the_input_circles_in_um_and_eps():
    t = np.arange(0.0, 0.05, 1e-4)
    o = orbits(_run(t, np.full(t.size, 30e3)), time_s=(0.0, 0.05))
    for b in C_IN:
        # journal − ring subtracts the ring circle that was added: round-off of numbers ~ 3.5e-5 m, i.e. < 1e-19 m
        np.testing.assert_allclose(o.journal_in_ring[b], _circle(t, R_J[b], 170.0, 0.3), rtol=0, atol=1e-19)
        np.testing.assert_array_equal(o.ring[b], _circle(t, R_R[b], 100.0))
        # ε = r / C on the whole circle (closed form), to round-off
        np.testing.assert_allclose(np.hypot(*o.eps_inner(b).T), R_J[b] / C_IN[b], rtol=1e-12)
        np.testing.assert_allclose(np.hypot(*o.eps_outer(b).T), R_R[b] / C_OUT[b], rtol=1e-12)
    df = o.to_dataframe()
    np.testing.assert_allclose(df["rear ring in housing x [um]"], o.ring["rear"][:, 0] * 1e6, rtol=1e-15)
    np.testing.assert_allclose(df["wheel y [um]"], _circle(t, R_W, 200.0)[:, 1] * 1e6, rtol=1e-15)


def test_orbit_figure_plots_the_input_and_the_clearance_circles():
    import matplotlib.pyplot as plt

    t = np.arange(0.0, 0.02, 1e-4)
    o = orbits(_run(t, np.full(t.size, 30e3)), time_s=(0.0, 0.02))
    fig = o.plot()
    axs = fig.axes
    titles = [a.get_title() for a in axs]
    # top row µm: front journal-in-ring, front ring, rear journal-in-ring, rear ring, wheel; bottom row ε
    j = titles.index("rear: journal in ring")
    orbit, circle = axs[j].lines[0].get_xydata(), axs[j].lines[2].get_xydata()
    np.testing.assert_allclose(orbit, _circle(t, R_J["rear"], 170.0, 0.3) * 1e6, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*circle.T), C_IN["rear"] * 1e6, rtol=1e-12)
    e = titles.index("rear: ring in housing", j + 1 + 5)        # the ε row
    np.testing.assert_allclose(np.hypot(*axs[e].lines[0].get_xydata().T), R_R["rear"] / C_OUT["rear"], rtol=1e-12)
    np.testing.assert_allclose(np.hypot(*axs[e].lines[2].get_xydata().T), 1.0, rtol=1e-12)
    w = titles.index("wheel")
    np.testing.assert_allclose(np.hypot(*axs[w].lines[0].get_xydata().T), R_W * 1e6, rtol=1e-12)
    plt.close(fig)
    fig = orbits_figure([o, o])                                 # two windows: rows of ε panels + wheels in µm
    ax = fig.axes[2 * 5 - 3]                                    # second row, "rear: journal in ring, ε"
    assert ax.get_title() == "rear: journal in ring, ε"
    np.testing.assert_allclose(np.hypot(*ax.lines[0].get_xydata().T), R_J["rear"] / C_IN["rear"], rtol=1e-12)
    plt.close(fig)


@pytest.mark.parametrize("direction", [1, -1])
def test_speed_window_picks_the_samples_about_the_speed(direction):
    t = np.arange(0.0, 1.0, 1e-4)
    # run-up 20 -> 60 krpm, or run-down 60 -> 20 krpm: 40 krpm is passed at t0 = 0.5 s
    speed = 40e3 + direction * 40e3 * (t - 0.5)
    run = _run(t, speed)
    idx = window_indices(run, 40e3, revolutions=10)
    # ±10 revolutions at 40 krpm = ±15 ms about t0; the grid holds t0 ± k × 0.1 ms (k ≤ 150), up to round-off
    expect = np.flatnonzero(np.abs(t - 0.5) <= 0.015 + 1e-9)
    np.testing.assert_array_equal(idx, expect)
    idx = window_indices(run, 40e3, span_rpm=2000.0)
    # ±1000 rpm at 40 krpm/s: ±25 ms about t0
    np.testing.assert_array_equal(idx, np.flatnonzero(np.abs(t - 0.5) <= 0.025 + 1e-9))
    o = orbits(run, speed_rpm=40e3, span_rpm=2000.0)
    assert o.speed_rpm.min() >= 39e3 - 1e-6 and o.speed_rpm.max() <= 41e3 + 1e-6
    np.testing.assert_array_equal(window_indices(run, time_s=(0.2, 0.3)), np.flatnonzero((t >= 0.2) & (t <= 0.3)))


def _whirl_run(top_hz=400.0):
    """Constant 60 krpm (1X = 1 kHz, absent from the orbit); forward whirl at 150 Hz (2 µm) and backward at
    ``top_hz`` (1 µm), sampled at 10 kHz."""
    t = np.arange(0.0, 0.5, 1e-4)
    z = 2e-6 * np.exp(2j * np.pi * 150.0 * t) + 1e-6 * np.exp(-2j * np.pi * top_hz * t)
    return _run(t, np.full(t.size, 60e3), disc_z=z)


def test_um_and_db_re_um_scales_are_the_amplitudes():
    sp = spectrogram(_whirl_run(), "wheel", segment_s=0.05)
    z, vmin, vmax, _ = spectrogram_colour(sp, "um")
    np.testing.assert_array_equal(z, np.maximum(sp.forward, sp.backward) * 1e6)
    fwd, bwd = sp.amplitude_um()
    np.testing.assert_array_equal(fwd, sp.forward * 1e6)
    np.testing.assert_array_equal(bwd, sp.backward * 1e6)
    # the spectrum of a 2 µm circle peaks at 2 µm: 150 Hz lies 0.7 Hz off the 4.9 Hz FFT grid (a Hann loss of
    # ~0.1 %) and the linear detrend of 7.5 periods takes a little more (measured −0.3 %): 1 % is the bound
    assert vmax == pytest.approx(2.0, rel=1e-2)
    z, vmin, vmax, _ = spectrogram_colour(sp, "db_um")
    np.testing.assert_allclose(z, 20 * np.log10(np.maximum(sp.forward, sp.backward) / 1e-6), rtol=1e-12)
    assert vmax - vmin == sp.db_range


def test_default_fmax_covers_the_content_and_not_much_more():
    for top in (400.0, 900.0):
        sp = spectrogram(_whirl_run(top), "wheel", segment_s=0.05)
        fmax = content_fmax(sp)
        # the Hann main lobe of a 50 ms segment is ±40 Hz; with the 1.2 margin the axis ends between the top
        # component and 1.2 × (top + 40 Hz) — far below the old default 1.1 × 1X = 1100 Hz / Nyquist 5 kHz
        assert top + 10.0 < fmax <= 1.2 * (top + 40.0)


def test_order_lines_and_waterfall():
    import matplotlib.pyplot as plt

    t = np.arange(0.0, 0.5, 1e-4)
    run = _run(t, 30e3 + 60e3 * t, disc_z=1e-6 * np.exp(2j * np.pi * 150.0 * t))
    sp = spectrogram(run, "wheel", segment_s=0.05)
    fig = composite_figure(sp, rsr=False, components=False, orders=(0.5, 1.0, 2.0), fmax_hz=4000.0)
    lines = {ln.get_label(): ln.get_xydata() for ln in fig.axes[0].lines}
    for k in (0.5, 1.0, 2.0):
        xy = lines[f"{k:g}X"]
        np.testing.assert_allclose(xy[:, 1], k * xy[:, 0] * 1e3 / 60.0, rtol=1e-12)   # k × f_rot, x in krpm
    plt.close(fig)
    f, s, z = waterfall_lines(sp, fmax_hz=1000.0, n_lines=5)
    assert s.size == 5 and np.all(np.diff(s) > 0) and f[-1] <= 1000.0
    np.testing.assert_allclose(z.max(axis=0), 1.0, rtol=2e-2)   # 1 µm circle; 150 Hz is off-bin by < 1/8 bin
    fig = waterfall_figure(sp, fmax_hz=1000.0, n_lines=5)
    plt.close(fig)


def test_cli_writers(tmp_path):
    from frbmodel.cli import build_parser
    from frbmodel.studies.run_outputs import orbit_windows, write_orbits, write_waterfalls

    t = np.arange(0.0, 0.2, 1e-4)
    run = _run(t, 30e3 + 100e3 * t)
    paths = write_orbits(orbit_windows(run, [35e3]), tmp_path) + write_waterfalls(run, tmp_path)
    assert sorted(p.name for p in paths) == ["orbits_35000.html", "orbits_35000.png", "waterfall_wheel.html",
                                             "waterfall_wheel.png"]
    assert all(p.stat().st_size > 0 for p in paths)
    args = build_parser().parse_args(["plot", "d", "--orbits", "60000,150000", "--waterfall"])
    assert args.orbits == "60000,150000" and args.waterfall
