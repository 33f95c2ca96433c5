"""Figures of the main job as an engineer reads them (issue 24 item 8): composites whose labels, markers and legend
cover nothing, components below the colour range said so, coincident whirl curves both visible, a Campbell axis
that shows the unstable modes, damping colours that mark them, and interactive pages with the PNGs' content that
say so when they cannot load plotly.js."""
from types import SimpleNamespace

import numpy as np
import pytest
from plotly.colors import sample_colorscale, unlabel_rgb
from plotly.offline import get_plotlyjs
from test_html_offline import script_srcs
from test_plot_cli import figure_data, synthetic_run

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.plots.figures import (
    CAMPBELL_FMAX_FACTOR,
    HTML_FALLBACK,
    LABEL_OFFSETS,
    composite_figure,
    composite_plotly,
    full_fmax,
    html_plotlyjs,
    label_boxes,
    whirl_lines,
    write_html,
)
from frbmodel.plots.style import D_MAX, D_MIN, HTML_HEIGHT_PX, damping_cmap, damping_colorscale
from frbmodel.signals.tracking import NO_ONSET_PRESENT, Component

SPEEDS = np.linspace(20e3, 250e3, 116)


def _component(label, lo, hi, ratio, amp, onset=np.nan, end=np.nan):
    sel = (SPEEDS >= lo) & (SPEEDS <= hi)
    s = SPEEDS[sel]
    a = amp(s) if callable(amp) else np.full(s.size, amp)
    return Component(label, s, ratio * s / 60.0, a, "forward", onset_interp_rpm=onset, end_rpm=end,
                     onset_estimate="" if np.isfinite(onset) else NO_ONSET_PRESENT)


@pytest.fixture(scope="module")
def staged():
    """A spectrogram staged like the main job's defects: sub1 dominant from the start; sub2 vanishes at 100 krpm
    within the colour range; sub3 from the start fades below the range (at 70 krpm) before it vanishes (90 krpm);
    sub4 stays below the range (-30 dB); sub5's onset label would sit on sub2's cross."""
    comps = [_component("sub1", 20e3, 250e3, 0.5, 1e-4),
             _component("sub2", 60e3, 100e3, 0.3, 3e-5, onset=60e3, end=100e3),
             _component("sub3", 20e3, 90e3, 0.2, lambda s: 5e-5 * np.exp(-(s - 20e3) / 20e3), end=90e3),
             _component("sub4", 20e3, 250e3, 0.1, 10 ** (-30 / 20) * 1e-4),
             _component("sub5", 95e3, 250e3, 0.3 * 100 / 95, 2e-5, onset=95e3)]
    freqs = np.arange(0.0, 1500.0, 5.0)
    amp = np.full((freqs.size, SPEEDS.size), 1e-9)
    for c in comps:
        for s, f, a in zip(c.speeds_rpm, c.freqs_hz, c.amplitude_m):
            amp[np.abs(freqs - f) <= 10.0, np.searchsorted(SPEEDS, s)] = a
    sp = SimpleNamespace(node="compressor_wheel", db_range=25.0, run=None, speeds_rpm=SPEEDS, freqs_hz=freqs,
                         amplitude=amp, components=lambda: comps)
    sp.db = lambda: 20 * np.log10(amp / amp.max())
    return sp


def _markers(ax):
    return [ln for ln in ax.lines if ln.get_gid() == "component-marker"]


def test_composite_png_labels_markers_and_legend_cover_nothing(staged):
    import matplotlib.pyplot as plt

    fig = composite_figure(staged, rsr=False)
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    assert not ax.get_legend().get_window_extent(renderer).overlaps(ax.bbox)  # not on the heatmap
    pts = np.vstack([ax.transData.transform(np.column_stack(ln.get_data())) for ln in _markers(ax)])
    labels = {t.get_text(): t.get_window_extent(renderer) for t in ax.texts}
    assert set(labels) == {"sub1 (from start)", "sub2", "sub3 (from start)", "sub5"}  # sub4: below the range
    for text, bb in labels.items():
        assert not any(bb.contains(*p) for p in pts), text
    assert ax.texts[-1].get_position() != LABEL_OFFSETS[0]  # sub5 moved off sub2's cross
    crosses = [ln for ln in _markers(ax) if ln.get_marker() == "x"]
    assert [float(ln.get_xdata()[0]) for ln in crosses] == [100.0]  # sub2 only: sub3 has faded by its end
    fades = [ln for ln in _markers(ax) if ln.get_marker() == "o"]
    assert len(fades) == 1 and 60.0 < fades[0].get_xdata()[0] < 80.0  # where sub3 leaves the colour range
    assert "sub4 (max -30.0 dB)" in ax.get_title() and "compressor wheel" in ax.get_title()
    plt.close(fig)


def test_composite_html_has_the_png_content(staged):
    fig = composite_plotly(staged, rsr=False)
    texts = [a.text for a in fig.layout.annotations]
    assert texts == ["<b>sub1 (from start)</b>", "<b>sub2</b>", "<b>sub3 (from start)</b>", "<b>sub5</b>"]
    by_name = {t.name: t for t in fig.data}
    assert list(by_name["component vanishes"].x) == [100e3]
    assert len(by_name["falls below the colour range"].x) == 1
    assert "sub4" in fig.layout.title.text and fig.layout.height <= HTML_HEIGHT_PX
    legend_top = fig.layout.legend.y  # below the plot, away from the colour bar's title and ticks
    assert fig.layout.legend.orientation == "h" and legend_top < 0


def test_html_label_boxes_avoid_markers(staged):
    from frbmodel.plots.figures import component_marks

    marks, _ = component_marks(staged)
    boxes = label_boxes(marks, (20e3, 250e3), (0.0, 1500.0))
    pts = [m[k] for m in marks for k in ("end", "fade") if m[k] is not None]
    for _, _, (x0, x1, y0, y1) in boxes:
        assert not any(x0 <= x <= x1 and y0 <= y <= y1 for x, y in pts)
    assert boxes[-1][:2] != ("left", "bottom")  # sub5 is not right-above its onset (sub2's cross is there)


def _whirl_cd(w_inner_2):
    s = np.linspace(20e3, 250e3, 20)
    w = np.column_stack([0.4 * s / 60, 0.1 * s / 60, w_inner_2 * s / 60, 0.12 * s / 60])
    return SimpleNamespace(speeds_rpm=s, whirl_hz=w, whirl_margin=np.ones_like(w), meta={},
                           film_labels=("turbine inner", "turbine outer", "compressor inner", "compressor outer"))


def test_coincident_whirl_curves_are_drawn_both_visible():
    lines = whirl_lines(_whirl_cd(0.401))  # the inner films of two bearings within 1 %: one on the other
    inner = [ln for ln in lines if "inner" in ln["name"]]
    assert inner[0]["ls"] != inner[1]["ls"] and inner[0]["dash"] != inner[1]["dash"]
    assert inner[0]["ls"][0] != inner[1]["ls"][0]  # interleaved: the dashes of one in the gaps of the other
    assert inner[1]["label"] == "whirl compressor inner (on turbine inner)"
    outer = [ln for ln in lines if "outer" in ln["name"]]  # 20 % apart: their own styles, plain labels
    assert outer[1]["label"] == "whirl compressor outer" and outer[1]["dash"] in ("dash", "dashdot")
    apart = whirl_lines(_whirl_cd(0.5))
    assert apart[2]["label"] == "whirl compressor inner"


@pytest.fixture(scope="module")
def campbell_j():
    return frb.campbell(frb.turbocharger(36e-6), "J", np.linspace(10e3, 250e3, 13), progress=False)


def test_campbell_default_axis_shows_the_unstable_modes(campbell_j):
    import matplotlib.pyplot as plt

    cd = campbell_j
    f_unstable = np.nanmax(np.where(cd.unstable, cd.frequencies_hz, np.nan))
    fig = cd.plot()
    ax = fig.axes[0]
    top = ax.get_ylim()[1]
    assert top == pytest.approx(CAMPBELL_FMAX_FACTOR * f_unstable) and top < 0.5 * full_fmax(cd)
    assert f"--fmax {full_fmax(cd):.0f}" in ax.get_title() and "36 µm" in ax.get_title()
    assert not ax.get_legend().get_window_extent(fig.canvas.get_renderer()).overlaps(ax.bbox)
    plt.close(fig)
    assert "full range" not in cd.plot(fmax_hz=4000.0).axes[0].get_title()  # the user's own range: no note
    plt.close("all")


def test_campbell_html_has_stars_unstable_entry_and_full_data(campbell_j, tmp_path):
    fig = campbell_j.plot_html(tmp_path / "c.html", shapes=False)
    by_name = {t.name: t for t in fig.data}
    unstable = by_name["unstable (D < -round-off bound)"]
    assert np.all(np.asarray(unstable.marker.color) < 0) and unstable.marker.line.width > 0
    stars = by_name["critical speeds (1X crossings)"]
    assert stars.marker.symbol == "star" and len(stars.x) >= 1
    assert fig.layout.yaxis.range[1] < full_fmax(campbell_j)  # opens on the unstable modes ...
    f_all = np.concatenate([np.asarray(t.y, dtype=float) for t in fig.data if t.mode == "markers"])
    assert f_all.max() > fig.layout.yaxis.range[1]  # ... with the points above it in the page (zoom out)
    assert fig.layout.height <= HTML_HEIGHT_PX


def _colour_at(scale, pos):
    """RGB (0..1) of a plotly colour scale at ``pos``, as plotly.js interpolates it (a repeated position is a
    jump)."""
    x = [float(p) for p, _ in scale]
    i = max(k for k in range(len(x) - 1) if x[k] <= pos < x[k + 1] or (k == len(x) - 2 and pos >= x[k]))
    lo, hi = (np.array(unlabel_rgb(scale[k][1]), dtype=float) / 255.0 for k in (i, i + 1))
    return lo + (hi - lo) * (pos - x[i]) / (x[i + 1] - x[i])


def _distance_from_white(rgb):
    return float(np.linalg.norm(1.0 - np.asarray(rgb[:3], dtype=float)))


def test_unstable_damping_is_clearly_coloured():
    pos = (-0.3 - D_MIN) / (D_MAX - D_MIN)
    rgb = _colour_at(damping_colorscale(), pos)
    assert _distance_from_white(rgb) > 0.6  # a diverging map centred at 0 (RdBu) gives ~0.3 here
    rdbu = np.array(unlabel_rgb(sample_colorscale("RdBu", [(-0.3 + 1.0) / 2.0])[0])) / 255.0  # cmid 0 (was)
    assert _distance_from_white(rdbu) < 0.45
    assert _distance_from_white(damping_cmap()(pos)) > 0.6  # the PNG: the same colours
    near = (-0.02 - D_MIN) / (D_MAX - D_MIN)  # even barely unstable is far from the stable side's colours
    assert _distance_from_white(damping_cmap()(near)) > 0.5


def test_pages_say_when_plotly_is_missing_and_embed_it_on_request(tmp_path):
    import plotly.graph_objects as go

    fig = go.Figure(go.Scatter(x=[0, 1], y=[1, 0]))
    page = write_html(fig, tmp_path / "a.html")
    text = page.read_text(encoding="utf-8")
    assert "<noscript>" in text and 'id="frb-no-plotly"' in text and HTML_FALLBACK.split(":")[0] in text
    assert text.index('id="frb-no-plotly"') < text.index("Plotly.newPlot(")  # shown before the figure runs
    with html_plotlyjs(True):
        (tmp_path / "alone").mkdir()
        alone = write_html(fig, tmp_path / "alone" / "b.html")
    assert script_srcs(alone) == [] and get_plotlyjs()[:40] in alone.read_text(encoding="utf-8")
    assert not (tmp_path / "alone" / "plotly.min.js").exists()


def test_cli_writes_self_contained_pages_on_request(tmp_path):
    synthetic_run().save(tmp_path, nc=False)
    assert main(["plot", str(tmp_path), "--html", "self-contained"]) == 0
    pages = sorted(tmp_path.glob("composite_*.html"))
    assert len(pages) == 2 and not (tmp_path / "plotly.min.js").exists()
    import matplotlib.pyplot as plt

    fig = frb.spectrogram(synthetic_run(), "turbine_wheel").plot()  # the PNG's RSR panel: legend off the data too
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes[:2]:  # heatmap, RSR panel (then the colour bar)
        assert not ax.get_legend().get_window_extent(renderer).overlaps(ax.bbox)
    plt.close(fig)
    for page in pages:
        assert script_srcs(page) == []
        traces = figure_data(page)
        assert any(t.get("xaxis") == "x2" for t in traces)  # the RSR panel
        assert not any("_" in t.get("name", "") for t in traces)  # "turbine wheel", not "turbine_wheel"


def test_a_second_run_into_its_folder_keeps_the_shared_bundle(tmp_path):
    """A run into the folder of an earlier one removes the earlier run's files it did not write again (the
    manifest): the unchanged plotly.min.js its pages load is one of the files the new run uses."""
    for _ in range(2):
        assert main(["unbalance", "--method", "A", "--speeds", "20000:40000:3", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "plotly.min.js").read_text(encoding="utf-8") == get_plotlyjs()
    assert script_srcs(tmp_path / "unbalance_A.html") == ["plotly.min.js"]


@pytest.fixture(scope="module")
def responses():
    tc = frb.turbocharger(36e-6)
    speeds = np.linspace(3e3, 250e3, 8)
    return {m: frb.unbalance_response(tc, m, speeds, critical=False, progress=False) for m in "AJ"}


def _is_1_2_5_decade(v):
    k = np.floor(np.log10(v) + 1e-9)
    return any(np.isclose(v, m * 10.0 ** k) for m in (1, 2, 5))


def test_unbalance_pages_polar_units_log_ticks_height_names(responses):
    import matplotlib.pyplot as plt

    from frbmodel.plots.unbalance import response_figure, response_plotly

    undamped, damped = responses["A"], responses["J"]
    fig = response_plotly(undamped)
    assert not [t for t in fig.data if t.type == "scatterpolar"]  # not two lines along 0° and 180°
    assert "undamped" in fig.layout.title.text
    fig = response_plotly(damped)
    assert [t for t in fig.data if t.type == "scatterpolar"]
    assert any("[µm]" in a.text for a in fig.layout.annotations)  # the polar plot's radius has its unit
    for axis in (fig.layout.yaxis, fig.layout.yaxis3):
        assert axis.type == "log" and axis.tickmode == "array" and len(axis.tickvals) >= 2
        assert all(_is_1_2_5_decade(v) for v in axis.tickvals)
        assert all(not t.isdigit() or t in ("1", "2", "5", "10", "20", "50", "100") for t in axis.ticktext)
    assert fig.layout.height <= HTML_HEIGHT_PX
    assert not any("_" in (t.name or "") for t in fig.data) and "turbine wheel" in fig.layout.title.text
    png = response_figure(undamped)
    assert not [ax for ax in png.axes if ax.name == "polar"]
    assert any("undamped" in t.get_text() for ax in png.axes for t in ax.texts)
    plt.close(png)


def test_mode_shape_figure_title_clear_of_the_panels(campbell_j):
    import matplotlib.pyplot as plt

    from frbmodel.linear.modeshape import plot_mode_shapes

    fig = plot_mode_shapes([campbell_j.mode_shape(130e3, j) for j in range(16)],
                           title="method J, 130,000 rpm: mode shapes (x deflection at 8 phases; node orbits red "
                                 "forward, blue backward)")  # tall, as frb campbell --mode-shapes draws it
    renderer = fig.canvas.get_renderer()
    top = fig._suptitle.get_window_extent(renderer)
    assert not any(top.overlaps(ax.title.get_window_extent(renderer)) for ax in fig.axes)
    plt.close(fig)


def test_orbit_and_waterfall_pages_fit_a_screen_with_readable_names():
    from frbmodel.signals.orbits import orbits

    run = synthetic_run()
    page = orbits(run, time_s=(0.1, 0.12)).plot_html()
    assert page.layout.height <= HTML_HEIGHT_PX
    assert "turbine wheel" in [a.text for a in page.layout.annotations]  # panel titles, not "turbine_wheel"
    wf = frb.spectrogram(run, "turbine_wheel").waterfall_html()
    assert wf.layout.height <= HTML_HEIGHT_PX and "turbine wheel" in wf.layout.title.text


def test_html_option_refused_where_no_page_is_written(tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["runup", "--no-figure", "--html", "self-contained", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--html self-contained" in err[0] and "--no-figure" in err[0]
    assert not out.exists()  # refused before any work


def test_composite_page_rsr_legend_above_the_data():
    from frbmodel.plots.figures import HTML_LEGEND_ENTRY_PX, HTML_PANEL_PX

    fig = frb.spectrogram(synthetic_run(), "turbine_wheel").plot_html()
    rsr = [t for t in fig.data if t.legend == "legend2"]
    assert len(rsr) >= 4  # the run's and the linear methods' RSR, in the panel's own legend
    top = max(float(np.nanmax(t.y)) for t in rsr)
    lo, hi = fig.layout.yaxis2.range
    legend_fraction = len(rsr) * HTML_LEGEND_ENTRY_PX / HTML_PANEL_PX  # the legend hangs from the panel's top
    assert fig.layout.legend2.y == 1.0 and (hi - top) / (hi - lo) > legend_fraction


def test_polar_speed_labels_do_not_pile_up(responses):
    import matplotlib.pyplot as plt

    from frbmodel.plots.unbalance import POLAR_LABEL_GAP, response_figure

    fig = response_figure(responses["J"])
    polar = next(ax for ax in fig.axes if ax.name == "polar")
    pts = [t.xy[1] * np.exp(1j * t.xy[0]) for t in polar.texts]  # (angle, radius) -> x + iy
    rmax = polar.get_rmax()
    assert len(pts) >= 2
    assert all(abs(a - b) > POLAR_LABEL_GAP * rmax for i, a in enumerate(pts) for b in pts[:i])
    plt.close(fig)


def test_stability_map_legend_beside_the_plot_and_parameter_in_words():
    import matplotlib.pyplot as plt
    import pandas as pd

    from frbmodel.plots.studies import stability_map_figures

    kinds = [("linear", "J")] * 6 + [("runup", "run-up")] * 6  # twelve lines over the whole plot
    rows = [{"kind": k, "method": m, "item": f"item {i}", "outer_clearance [m]": c,
             "onset [rpm]": 1e3 * (i + 1) * c * 1e6, "f at onset [Hz]": 100.0}
            for i, (k, m) in enumerate(kinds) for c in (36e-6, 40e-6, 46e-6)]
    fig, page = stability_map_figures(pd.DataFrame(rows), "outer_clearance [m]")
    ax = fig.axes[0]
    assert not ax.get_legend().get_window_extent(fig.canvas.get_renderer()).overlaps(ax.bbox)
    assert ax.get_xlabel() == "outer clearance [µm]" and page.layout.xaxis.title.text == "outer clearance [µm]"
    assert page.layout.height <= HTML_HEIGHT_PX
    plt.close(fig)
