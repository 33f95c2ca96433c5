"""Interactive figures open offline and stay small (issue 12): every HTML the package writes loads plotly.js from one
``plotly.min.js`` in its own folder (written once per folder, whatever the figure), never from a CDN; a
self-contained file on request."""
from html.parser import HTMLParser

import numpy as np
import pytest
from plotly.offline import get_plotlyjs
from test_plot_cli import FS, figure_data, synthetic_run

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.linear.modeshape import save_mode_shapes
from frbmodel.plots.figures import write_html
from frbmodel.signals.orbits import orbits

LIMIT_BYTES = 1.5e6  # the bound for an interactive composite
PLOTLY_JS = "plotly.min.js"  # the name plotly's include_plotlyjs="directory" writes and refers to


class _Scripts(HTMLParser):
    """The src attributes of the <script> tags of a page (html.parser, not the package's own writer)."""

    def __init__(self):
        super().__init__()
        self.srcs = []
        self.tags = 0

    def handle_starttag(self, tag, attrs):
        if tag == "script":
            self.tags += 1
            src = dict(attrs).get("src")
            if src is not None:
                self.srcs.append(src)


def script_srcs(path):
    parser = _Scripts()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser.srcs


def assert_offline_folder(folder, n_html):
    """``n_html`` HTML files, each loading plotly.js only from the folder's one plotly.min.js (the installed
    plotly.js, byte for byte), none embedding it or naming a CDN."""
    pages = sorted(folder.glob("*.html"))
    assert len(pages) == n_html
    assert [p.name for p in folder.glob("*.js")] == [PLOTLY_JS]  # one bundle, whatever wrote the figures
    assert (folder / PLOTLY_JS).read_text(encoding="utf-8") == get_plotlyjs()
    header = get_plotlyjs()[:40]  # "/**\n* plotly.js v<version>": only an embedded bundle has it
    for page in pages:
        text = page.read_text(encoding="utf-8")
        assert script_srcs(page) == [PLOTLY_JS], page.name  # relative: found next to the page, offline
        assert "cdn.plot.ly" not in text and header not in text, page.name
    return pages


@pytest.fixture(scope="module")
def main_job_dir(tmp_path_factory):
    """A synthetic run like the main job's co-simulation (20 -> 250 krpm in 1 s; sampled at 10 kHz instead of
    20 kHz, which halves the segments, so the spectrogram is decimated less), redrawn by ``frb plot`` with
    waterfalls and an orbit window: five HTML figures of three kinds in one folder."""
    out = tmp_path_factory.mktemp("main_job")
    synthetic_run((20e3, 250e3), duration=1.0).save(out, nc=False)
    assert main(["plot", str(out), "--waterfall", "--orbits", "100000"]) == 0
    return out


def test_run_folder_figures_share_one_bundle_and_stay_small(main_job_dir):
    pages = assert_offline_folder(main_job_dir, 5)  # 2 composites, 2 waterfalls, 1 orbit window
    composites = [p for p in pages if p.name.startswith("composite_")]
    assert len(composites) == 2
    for p in composites:
        assert p.stat().st_size < LIMIT_BYTES
        traces = figure_data(p)  # the figure's data are in the page: a heatmap over the whole run
        x = next(t for t in traces if t.get("type") == "heatmap")["x"]
        assert x.min() < 25e3 and x.max() > 245e3
    # the bundle exists once: the figures together are far smaller than one figure with plotly.js embedded
    assert sum(p.stat().st_size for p in pages) < len(get_plotlyjs())


def test_linear_results_write_into_the_same_bundle(tmp_path):
    tc = frb.turbocharger(36e-6)
    cd = frb.campbell(tc, "A", np.linspace(20e3, 100e3, 9))
    cd.plot_html(tmp_path / "campbell_A.html")
    ur = frb.unbalance_response(tc, "A", np.linspace(20e3, 100e3, 9), {"turbine_wheel": (1e-6, 0.0)})
    ur.plot_html(tmp_path / "unbalance_A.html")
    save_mode_shapes(cd, 60e3, tmp_path, fmax_hz=1500.0)  # several 3-D figures in one page: plotly.js once
    pages = assert_offline_folder(tmp_path, 3)
    shapes = next(p for p in pages if p.name.startswith("mode_shapes_"))
    assert shapes.read_text(encoding="utf-8").count("Plotly.newPlot(") >= 2


def test_two_figures_two_small_files_one_bundle(tmp_path):
    run = synthetic_run((20e3, 250e3), duration=1.0)
    for node in run.displacement:
        frb.spectrogram(run, node).plot_html(tmp_path / f"composite_{node}.html")
    for page in assert_offline_folder(tmp_path, 2):
        assert page.stat().st_size < LIMIT_BYTES


def test_stale_bundle_replaced_current_one_kept(tmp_path):
    import plotly.graph_objects as go

    fig = go.Figure(go.Scatter(x=[0, 1], y=[1, 0]))
    (tmp_path / PLOTLY_JS).write_text("/**\n* plotly.js v0.0.1\n*/\n", encoding="utf-8")  # another version
    write_html(fig, tmp_path / "a.html")
    assert (tmp_path / PLOTLY_JS).read_text(encoding="utf-8") == get_plotlyjs()
    # the installed version with something appended: same header, so left as it is (one write per folder)
    (tmp_path / PLOTLY_JS).write_text(get_plotlyjs() + "\n// kept\n", encoding="utf-8")
    write_html(fig, tmp_path / "b.html")
    assert (tmp_path / PLOTLY_JS).read_text(encoding="utf-8").endswith("// kept\n")
    assert not list(tmp_path.glob(".*.tmp"))  # no temporary file left behind


@pytest.mark.parametrize("kind", ["composite", "campbell", "orbits"])
def test_self_contained_file_on_request(tmp_path, kind):
    if kind == "composite":
        frb.spectrogram(synthetic_run(), "turbine_wheel").plot_html(tmp_path / "f.html", include_plotlyjs=True)
    elif kind == "campbell":
        cd = frb.campbell(frb.turbocharger(36e-6), "A", np.linspace(20e3, 100e3, 5))
        cd.plot_html(tmp_path / "f.html", include_plotlyjs=True)
    else:
        run = synthetic_run()
        orbits(run, time_s=(0.1, 0.1 + 20 / FS)).plot_html(tmp_path / "f.html", include_plotlyjs=True)
    page = tmp_path / "f.html"
    assert script_srcs(page) == [] and not (tmp_path / PLOTLY_JS).exists()
    assert get_plotlyjs()[:40] in page.read_text(encoding="utf-8")  # plotly.js inside the page
