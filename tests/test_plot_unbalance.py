"""``frb plot DIR`` on a folder of ``frb unbalance``: the Bode / polar / film-orbit figures redrawn from the saved
data are the figures ``frb unbalance`` drew (methods A and B: no equilibria, fast)."""
import numpy as np
import pandas as pd
from test_plot_cli import figure_data

from frbmodel.cli import main


def _traces(path):
    return [(t.get("name"), t.get("type"), {k: np.asarray(t[k]) for k in ("x", "y", "r", "theta") if k in t})
            for t in figure_data(path)]


def test_plot_redraws_an_unbalance_folder(tmp_path, capsys):
    out = tmp_path / "ub"
    assert main(["unbalance", "--method", "B,A", "--speeds", "3000:30000:10", "--out", str(out)]) == 0
    drawn = {m: _traces(out / f"unbalance_{m}.html") for m in "AB"}
    figures = ["unbalance_A.png", "unbalance_A.html", "unbalance_B.png", "unbalance_B.html", "unbalance_bode_BA.png"]
    for name in figures[:-1]:
        (out / name).unlink()
    bode = out / figures[-1]
    bode.write_bytes(b"")  # kept: its name holds the order of the methods (B, A), which no data file records
    capsys.readouterr()
    assert main(["plot", str(out)]) == 0
    assert bode.stat().st_size > 0
    assert sorted(p.name for p in out.glob("*.png")) + sorted(p.name for p in out.glob("*.html")) == \
        sorted(n for n in figures if n.endswith(".png")) + sorted(n for n in figures if n.endswith(".html"))
    for m in "AB":
        again = _traces(out / f"unbalance_{m}.html")
        assert [(n, t) for n, t, _ in again] == [(n, t) for n, t, _ in drawn[m]]
        for (_, _, a), (_, _, b) in zip(again, drawn[m]):
            for k in a:  # the same numbers: drawn from the in-memory result, then from the files
                if k == "theta":  # polar angle [deg]: the CSV keeps no sign of a zero imaginary part (+-180 deg)
                    np.testing.assert_allclose((a[k] - b[k] + 180.0) % 360.0 - 180.0, 0.0, atol=1e-9)
                else:
                    np.testing.assert_allclose(a[k], b[k], rtol=1e-12, atol=1e-12)
        # the Bode amplitude of the turbine wheel is the table's semi-major axis, in µm
        table = pd.read_csv(out / f"unbalance_{m}.csv")
        bode = next(d for n, t, d in again if n == "turbine wheel")  # (legend names read as words)
        np.testing.assert_allclose(bode["y"], table["turbine_wheel major semi-axis [m]"] * 1e6, rtol=1e-12)


def test_plot_unbalance_locations_and_bad_options(tmp_path, capsys):
    out = tmp_path / "ub"
    assert main(["unbalance", "--method", "A", "--speeds", "3000:30000:5", "--out", str(out)]) == 0
    assert main(["plot", str(out), "--locations", "node2,turbine_wheel"]) == 0
    names = {n for n, _, _ in _traces(out / "unbalance_A.html")}
    assert {"node2", "turbine wheel"} <= names and "compressor wheel" not in names
    capsys.readouterr()
    assert main(["plot", str(out), "--locations", "nowhere"]) == 2
    assert "--locations 'nowhere' is unknown" in capsys.readouterr().err
    assert main(["plot", str(out), "--orbits", "20000"]) == 2
    assert "need a run-up folder" in capsys.readouterr().err
