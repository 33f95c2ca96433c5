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
    assert t.ring_mass == 7.2e-3  # 7.2 g, not the table's "7.2 kg" (docs/theory/parameters.md#table-2-in-si-units)
    assert t.ring_inertia == pytest.approx(33.641e-8)
    assert t.inner.viscosity == 4.9e-3 and c.inner.viscosity == 6.4e-3
    assert t.outer.clearance == 40e-6 and t.inner.clearance == 34e-6
    # ring mass consistent with its inertia: m (r_i² + r_o²)/2 within 1.3 %
    # (docs/theory/parameters.md#table-2-in-si-units)
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
    assert "RSR 0.22191" in out  # docs/theory/parameters.md#reference-numbers: 46 µm, turbine, 30k rpm, method J


def test_cli_bad_input_exits_with_message(tmp_path, capsys):
    assert main(["campbell", "--outer-clearance=-1e-6", "--out", str(tmp_path)]) == 2
    assert "clearance = -1e-06" in capsys.readouterr().err
    assert main(["equilibrium", "--method", "F", "--speed-rpm", "0"]) == 2
    assert "speed" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["campbell", "--method", "H"])


@pytest.mark.slow  # long (4-6 s); run with -m slow (README: the suite's slow checks)
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
    # F and G coincide (docs/theory/rings.md#coupled-static-equilibrium), I and J lie below eq. (6) in the turbine
    # bearing
    f = eq[eq["method"] == "F"]["RSR turbine [-]"].to_numpy()
    g = eq[eq["method"] == "G"]["RSR turbine [-]"].to_numpy()
    assert abs(f - g).max() < 1e-12
    assert (eq[eq["method"] == "J"]["RSR turbine [-]"] < f.max()).all()


# ----------------------------------------------------------------- broken system files: what the user sees
def _nth(text, old, new, n):
    """``text`` with the n-th (0-based) occurrence of ``old`` replaced."""
    parts = text.split(old)
    assert len(parts) > n + 1, (old, n)
    return old.join(parts[:n + 1]) + new + old.join(parts[n + 1:])


FILM_KEYS = "valid keys: clearance, length, radius, viscosity"
TOP_KEYS = "valid keys: bearings, film_model, gravity, name, oil, rotor, units"
# (what goes wrong, edit of the saved Table 2 system (old, new, which occurrence), what the message must say);
# the saved file has 3 [[rotor.shaft]], 2 [[rotor.discs]] and 2 [[bearings]] tables with [bearings.inner] and
# [bearings.outer] each, in this order
BAD_FILES = [
    ("misspelt film key", ("viscosity", "viscosty", 0),
     f"unknown key 'viscosty' in bearings[0].inner (film), did you mean 'viscosity'? {FILM_KEYS}"),
    ("misspelt key, second bearing's outer film", ("viscosity", "viscosty", 3),
     f"unknown key 'viscosty' in bearings[1].outer (film), did you mean 'viscosity'? {FILM_KEYS}"),
    ("misspelt bearing key", ("ring_mass", "ring_mas", 1),
     "unknown key 'ring_mas' in bearings[1] (bearing), did you mean 'ring_mass'? valid keys: inner, name, node, "
     "outer, ring_inertia, ring_mass"),
    ("misspelt shaft element key", ("density", "densty", 2),
     "unknown key 'densty' in rotor.shaft[2] (shaft element), did you mean 'density'? valid keys: density, "
     "inner_diameter, length, outer_diameter, youngs_modulus"),
    ("misspelt disc key", ("polar_inertia", "polar_inerta", 1),
     "unknown key 'polar_inerta' in rotor.discs[1] (disc), did you mean 'polar_inertia'? valid keys: "
     "diametral_inertia, mass, name, node, polar_inertia"),
    ("misspelt top-level key", ("gravity = ", "gravty = ", 0),
     f"unknown key 'gravty' at the top level, did you mean 'gravity'? {TOP_KEYS}"),
    ("unknown top-level key", ("gravity = 9.81", "gravity = 9.81\ncolour = 1", 0),
     f"unknown key 'colour' at the top level; {TOP_KEYS}"),
    ("number as a string", ("clearance = 3.6e-05", 'clearance = "36e-6"', 0),
     "bearings[0].outer.clearance = '36e-6' is a string; expected a real number [m] (write numbers without quotes)"),
    ("list for a number", ("gravity = 9.81", "gravity = [9.81]", 0),
     "gravity = [9.81] is a list; expected a real number [m/s^2]"),
    ("boolean for a number", ("ring_mass = 0.0072", "ring_mass = true", 0),
     "bearings[0].ring_mass = True is a boolean; expected a real number [kg]"),
    ("fraction for a node", ("node = 1\n", "node = 1.0\n", 0),
     "bearings[0].node = 1.0 is a real number; expected an integer"),
    ("missing key", ("viscosity = 0.0049\n", "", 0),
     "bearings[0].inner (film) lacks the required key 'viscosity'; required: radius, length, clearance, viscosity"),
    ("value out of range", ("clearance = 3.6e-05", "clearance = -3.6e-05", 1),
     "bearings[1].outer: film clearance = -3.6e-05 m is invalid: valid range is a finite real number > 0 m"),
    ("shaft value out of range", ("length = 0.039", "length = 0.0", 0),
     "rotor.shaft[1]: shaft element length = 0.0 m is invalid"),
    # trust5: accepted before (repeated names collided in unbalances, results and FMU variables; a units note of
    # "mm" was read as SI; gravity 1e9 ran where the FMUs refuse 1e3)
    ("repeated disc name", ('name = "compressor_wheel"', 'name = "turbine_wheel"', 0),
     "disc names = ['turbine_wheel', 'turbine_wheel'] are invalid: 'turbine_wheel' is used more than once"),
    ("repeated bearing name", ('name = "compressor"', 'name = "turbine"', 0),
     "bearing names = ['turbine', 'turbine'] are invalid: 'turbine' is used more than once"),
    ("empty disc name", ('name = "compressor_wheel"', 'name = ""', 0),
     "disc name = '' is invalid: give each disc a non-empty name"),
    ("empty bearing name", ('name = "turbine"', 'name = " "', 0),
     "bearing name = ' ' is invalid: give each bearing a non-empty name"),
    ("units other than SI", ('units = "SI: m, kg, s, Pa, Pa s, kg m^2"', 'units = "mm"', 0),
     "units = 'mm' is invalid: a system file is in SI units"),
    ("gravity above 100 g", ("gravity = 9.81", "gravity = 1e9", 0),
     "gravity = 1000000000.0 m/s^2 is invalid: valid range 0 ... 1000 m/s^2"),
    # a disc's inertias swapped or in the wrong unit: 2 I_d >= I_p holds for every rigid body of revolution (the
    # principal moments' triangle inequality), so I_d = 2e-5 with I_p = 4.4e-5 kg m^2 is no body at all
    ("diametral inertia below half the polar", ("diametral_inertia = 3.27e-05", "diametral_inertia = 2e-05", 0),
     "rotor.discs[1]: disc 'compressor_wheel' diametral_inertia = 2e-05 kg m^2 is invalid with polar_inertia = "
     "4.4e-05 kg m^2: no rigid body of revolution has I_d < I_p / 2; valid range >= 2.2e-05 kg m^2"),
]


@pytest.mark.parametrize("what, edit, message", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_system_file_is_refused_naming_file_key_and_place(tmp_path, what, edit, message):
    text = frb.turbocharger().save(tmp_path / "ok.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(_nth(text, *edit))
    with pytest.raises(frb.ParameterError) as e:
        frb.load_system(bad)
    assert str(e.value).startswith(f"system file {str(bad)!r}: ") and message in str(e.value), str(e.value)


def test_misspelt_key_in_json_and_in_from_dict():
    d = frb.turbocharger().to_dict()
    d["bearings"][0]["outer"]["viscosty"] = d["bearings"][0]["outer"].pop("viscosity")
    with pytest.raises(frb.ParameterError, match=r"unknown key 'viscosty' in bearings\[0\].outer \(film\), did "
                                                 r"you mean 'viscosity'\?"):
        frb.Turbocharger.from_dict(d)
    b = frb.turbocharger().bearings[0].to_dict()
    b["ring_mas"] = b.pop("ring_mass")
    with pytest.raises(frb.ParameterError, match="unknown key 'ring_mas' in bearing .*did you mean 'ring_mass'"):
        frb.FloatingRingBearing.from_dict(b)
    with pytest.raises(frb.ParameterError, match="the system description = 'x' is a string; expected a table"):
        frb.Turbocharger.from_dict("x")


def test_schema_lists_exactly_the_fields_of_the_classes():
    """The file schema and the dataclasses it builds must not drift apart: the keys of each table are the
    fields of its class, the required keys the fields without a default."""
    from dataclasses import MISSING, fields

    from frbmodel.system.parameters import BEARING, DISC, FILM, ROTOR, SHAFT_ELEMENT, SYSTEM

    for section, cls in ((FILM, frb.Film), (SHAFT_ELEMENT, frb.ShaftElement), (DISC, frb.Disc),
                         (BEARING, frb.FloatingRingBearing), (ROTOR, frb.Rotor), (SYSTEM, frb.Turbocharger)):
        names = {f.name for f in fields(cls)}
        assert set(section.keys) == names | ({"units"} if cls is frb.Turbocharger else set()), cls
        assert set(section.required) == {f.name for f in fields(cls)
                                         if f.default is MISSING and f.default_factory is MISSING}, cls


def test_syntax_errors_name_file_line_and_column(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text("gravity = 9.81\nfilm_model = short\n")  # an unquoted string: line 2, column 14 ('s')
    with pytest.raises(frb.ParameterError) as e:
        frb.load_system(p)
    assert str(e.value) == (f"system file {str(p)!r}, line 2, column 14: not valid TOML: Invalid value\n"
                            "    film_model = short\n" + " " * 17 + "^")
    p = tmp_path / "s.json"
    p.write_text('{\n  "gravity": 9.81,\n  "rotor": ,\n}')  # a missing value: line 3, column 12 (',')
    with pytest.raises(frb.ParameterError, match=r"s.json', line 3, column 12: not valid JSON: Expecting value"):
        frb.load_system(p)
    # a file cut off inside a string: TOML reports the end of the document, the message its line and column
    text = frb.turbocharger().save(tmp_path / "ok.toml").read_text()
    cut = text[:text.index('name = "turbine"') + len('name = "turb')]
    p = tmp_path / "cut.toml"
    p.write_text(cut)
    with pytest.raises(frb.ParameterError) as e:
        frb.load_system(p)
    line = cut.count("\n") + 1
    assert f"cut.toml', line {line}, column 13: not valid TOML: Unterminated string\n" in str(e.value)
    # cut off at a line boundary the file parses, and its content is incomplete
    p.write_text(text[:text.index("[[bearings]]")])
    with pytest.raises(frb.ParameterError, match="the system description lacks the required key 'bearings'"):
        frb.load_system(p)


def test_cli_bad_system_file_exits_2_without_traceback(tmp_path, capsys):
    p = tmp_path / "my.toml"
    p.write_text(frb.turbocharger().save(tmp_path / "ok.toml").read_text().replace("gravity", "gravty"))
    assert main(["equilibrium", "--method", "J", "--speed-rpm", "30000", "--system", str(p)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "my.toml" in err and "unknown key 'gravty' at the top level" in err


@pytest.mark.parametrize("argv, words", [
    (["campbell", "--speeds", "1000:2e6:3"], ["contains 2000000.0 rpm", "valid range |speed| <= 1e+06 rpm"]),
    (["equilibrium", "--speed-rpm", "1e300"], ["--speed-rpm = 1e+300 rpm", "valid range 0 < speed <= 1e+06 rpm"]),
    (["unbalance", "--speeds", "1000:2e6:3"], ["valid range |speed| <= 1e+06 rpm"]),
    (["losses", "--speeds", "10000:2e6:2"], ["contains 2000000.0 rpm", "<= 1e+06 rpm"]),
    (["system", "--out", "nodir/x.toml"], ["'nodir/x.toml' cannot be written: No such file or directory"]),
    (["system", "--out", "adir.toml"], ["'adir.toml' cannot be written: it is a folder"]),
    (["build-fmus", "--out", "afile"], ["--out = 'afile' is not a writable folder: it is a file"]),
    (["runup", "--speeds", "20000:21000", "--duration", "0.01", "--rate", "1e12", "--no-figure"],
     ["output_rate_hz = 1e+12 Hz", "valid range <= 1e+07 samples"]),
    (["campbell", "--parameter-set", "co40", "--speeds", "1000:2000:2"], ["applies only with --from-fmu"]),
    (["compare", "--fmax", "nan", "--duration", "0.01"], ["--fmax = nan Hz is invalid"]),
    (["compare", "--duration", "0"], ["--duration = 0.0 s is invalid"]),
    (["bifurcation", "--speeds", "1000:3000", "--max-points", "2", "--runs", "nope"], ["nope: no run-up result there"]),
])
def test_cli_refuses_out_of_range_speeds_bad_outputs_and_late_checked_options(tmp_path, monkeypatch, capsys, argv,
                                                                              words):
    """Cases found by trying the CLI as a new user (2026-11-28): speeds above 1e6 rpm were accepted by the linear
    analyses (exit 0 with results at 2 Mrpm); an --out that cannot be written was a traceback; a sample count that
    cannot fit in memory was a MemoryError; --parameter-set without --from-fmu was ignored; --fmax, --duration and
    --runs were checked only after the computation. Each is refused with exit 2 before any work and nothing is
    written (no output folder)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("")
    (tmp_path / "adir.toml").mkdir()
    out = tmp_path / "out"
    if argv[0] not in ("system", "build-fmus", "equilibrium", "losses"):
        argv = argv + ["--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and all(w in err for w in words), err
    assert not out.exists()


def test_api_refuses_speeds_above_the_model_limit():
    """The same limit as the run-ups' (1e6 rpm) in the linear analyses' API: campbell, equilibrium (and through it
    the losses), before any eigenvalue is computed."""
    tc = frb.turbocharger()
    with pytest.raises(frb.ParameterError, match=r"2000000.0 rpm: valid range \|speed\| <= 1e\+06 rpm"):
        frb.campbell(tc, "A", [1e3, 2e6])
    with pytest.raises(frb.ParameterError, match=r"valid range 0 < speed <= 1e\+06 rpm"):
        frb.equilibrium(tc, "J", 2e6)
    assert frb.equilibrium(tc, "J", 250e3).bearings[0].ring_speed > 0  # the verified range still works


def test_a_key_given_twice_in_a_json_system_file_is_refused(tmp_path):
    """trust5: json keeps the last of two equal keys without a word ({"gravity": 9.81, "gravity": 0.0} ran without
    gravity); TOML refuses a repeated key itself."""
    path = frb.turbocharger().save(tmp_path / "tc.json")
    text = path.read_text()
    assert '"gravity": 9.81' in text
    path.write_text(text.replace('"gravity": 9.81', '"gravity": 9.81, "gravity": 0.0', 1))
    with pytest.raises(frb.ParameterError, match=r"system file '.*tc.json': key 'gravity' is given twice in one "
                                                 r"table \(values 9.81 and 0.0\); give it once"):
        frb.load_system(path)
