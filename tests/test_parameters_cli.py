"""System description (validation, TOML/JSON round trip) and the command line."""
import json
from dataclasses import replace

import numpy as np
import pytest

import frbmodel as frb
from frbmodel.cli import main


def test_table2_values():
    tc = frb.turbocharger(40e-6)
    t, c = tc.bearings
    assert (t.name, c.name) == ("turbine", "compressor")
    assert t.ring_mass == 7.2e-3  # 7.2 g, not the table's "7.2 kg" (physics.md §10)
    assert t.ring_inertia == pytest.approx(33.641e-8)
    assert t.inner.viscosity == 4.9e-3 and c.inner.viscosity == 6.4e-3
    assert t.outer.clearance == 40e-6 and t.inner.clearance == 34e-6
    # ring mass consistent with its inertia: m (r_i² + r_o²)/2 within 1.3 % (physics.md §10)
    ri, ro = t.inner.radius + t.inner.clearance, t.outer.radius
    assert t.ring_mass * (ri ** 2 + ro ** 2) / 2 == pytest.approx(t.ring_inertia, rel=0.015)


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_round_trip(tmp_path, suffix):
    tc = frb.turbocharger(42e-6, film_model="short_corrected")
    p = tc.save(tmp_path / f"sys{suffix}")
    back = frb.load_system(p)
    assert back.to_dict() == tc.to_dict()
    np.testing.assert_array_equal(back.rotor.M, tc.rotor.M)


def test_toml_file_keeps_its_layout_and_takes_numpy_scalars(tmp_path):
    ref = frb.turbocharger(42e-6)
    # a bearing node given as a numpy integer (e.g. from np.argmin) must be written as a TOML integer
    b0 = replace(ref.bearings[0], node=np.int64(ref.bearings[0].node))
    text = ref.with_(bearings=(b0, ref.bearings[1])).save(tmp_path / "sys.toml").read_text()
    # what users edit by hand: top-level scalars with the units note, one [[rotor.shaft]] table per shaft
    # element, one [[bearings]] table per bearing with its [bearings.inner] / [bearings.outer] films
    assert 'units = "SI: m, kg, s, Pa, Pa s, kg m^2"' in text.splitlines()
    assert text.count("[[rotor.shaft]]\n") == len(ref.rotor.shaft)
    assert text.count("[[bearings]]\n") == 2 and text.count("[bearings.outer]\n") == 2
    assert f"node = {ref.bearings[0].node}" in text.splitlines()
    assert "clearance = 4.2e-05" in text.splitlines()  # floats as their shortest repr: exact round trip
    assert frb.load_system(tmp_path / "sys.toml").to_dict() == ref.to_dict()


def test_bad_file_content_names_the_quantity(tmp_path):
    d = frb.turbocharger().to_dict()
    d["bearings"][0]["outer"]["clearance"] = -3e-6
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d))
    with pytest.raises(frb.ParameterError, match=r"film clearance = -3e-06"):
        frb.load_system(p)
    d = frb.turbocharger().to_dict()
    d["bearings"][1]["inner"]["viscosity"] = 0
    p.write_text(json.dumps(d))
    with pytest.raises(frb.ParameterError, match="viscosity"):
        frb.load_system(p)
    with pytest.raises(frb.ParameterError, match="does not exist"):
        frb.load_system(tmp_path / "missing.toml")
    (tmp_path / "broken.toml").write_text("gravity = \n")
    with pytest.raises(frb.ParameterError, match="broken.toml.*not valid TOML"):
        frb.load_system(tmp_path / "broken.toml")
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(frb.ParameterError, match="broken.json.*not valid JSON"):
        frb.load_system(tmp_path / "broken.json")


def test_invalid_system_parameters():
    with pytest.raises(frb.ParameterError, match="clearance"):
        frb.turbocharger(outer_clearance=0.0)
    with pytest.raises(frb.ParameterError, match="clearance"):
        frb.turbocharger(outer_clearance=-36e-6)
    with pytest.raises(frb.ParameterError, match="viscosity"):
        frb.turbocharger(viscosity_turbine=0.0)
    with pytest.raises(frb.ParameterError, match="film model"):
        frb.turbocharger(film_model="long")


def test_cli_campbell_writes_results(tmp_path, capsys):
    rc = main(["campbell", "--method", "F", "--outer-clearance", "40e-6", "--speeds", "20000:200000:10",
               "--out", str(tmp_path)])
    assert rc == 0
    out = capsys.readouterr().out
    assert "results in" in out and "unstable" in out
    for name in ("campbell_F_modes.csv", "campbell_F.png", "campbell_F.html", "campbell_F.json"):
        assert (tmp_path / name).exists()
    meta = json.loads((tmp_path / "campbell_F.json").read_text())
    assert meta["outer_clearance_m"] == [40e-6, 40e-6]


def test_cli_equilibrium_and_system_file(tmp_path, capsys):
    sysfile = tmp_path / "my.toml"
    assert main(["system", "--outer-clearance", "46e-6", "--out", str(sysfile)]) == 0
    assert main(["equilibrium", "--method", "J", "--speed-rpm", "30000", "--system", str(sysfile)]) == 0
    out = capsys.readouterr().out
    assert "RSR 0.22191" in out  # physics.md §11: 46 µm, turbine, 30k rpm, method J


def test_cli_bad_input_exits_with_message(tmp_path, capsys):
    assert main(["campbell", "--outer-clearance=-1e-6", "--out", str(tmp_path)]) == 2
    assert "clearance = -1e-06" in capsys.readouterr().err
    assert main(["equilibrium", "--method", "F", "--speed-rpm", "0"]) == 2
    assert "speed" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["campbell", "--method", "H"])


def test_cli_paper_figures(tmp_path, capsys):
    assert main(["paper-figures", "--out", str(tmp_path), "--n-speeds", "8"]) == 0
    for n in (4, 5, 6, 7, 8, 9):
        assert list(tmp_path.glob(f"fig{n:02d}_campbell_*.png"))
    for name in ("fig09_campbell_F_zoom500Hz.png", "fig10_rsr.png", "fig11_equilibrium_cost.png",
                 "fig10_11_equilibria.csv", "fig09_campbell_F_unstable.md"):
        assert (tmp_path / name).exists()
    import pandas as pd

    eq = pd.read_csv(tmp_path / "fig10_11_equilibria.csv")
    assert set(eq["method"]) == set("FGIJ")
    # F and G coincide (physics.md 6.4), I and J lie below eq. (6) in the turbine bearing
    f = eq[eq["method"] == "F"]["RSR turbine [-]"].to_numpy()
    g = eq[eq["method"] == "G"]["RSR turbine [-]"].to_numpy()
    assert abs(f - g).max() < 1e-12
    assert (eq[eq["method"] == "J"]["RSR turbine [-]"] < f.max()).all()
