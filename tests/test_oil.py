"""The oil (frbmodel.system.oil): the ASTM D341 (Walther) law through two datasheet points, against published
viscosities at a third temperature; density and dynamic viscosity from their definitions; bad values refused with
the quantity, value and valid range; the [oil] table of a system file."""
import math

import pytest

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.system.oil import OILS, Oil, oil_from_dict, walther_coefficients

#: Stachowiak & Batchelor, Engineering Tribology (Butterworth-Heinemann), Table 2.3 "Dynamic viscosity and
#: pressure-viscosity coefficients of some commonly used lubricants": dynamic viscosity [mPa s] of twelve oils at
#: 30, 60 and 100 °C, in the table's order
STACHOWIAK_TABLE_2_3 = [
    ("light machine oil", 38.0, 12.1, 5.3), ("heavy machine oil", 153.0, 34.0, 9.1),
    ("heavy machine oil", 250.0, 50.5, 12.6), ("cylinder oil", 810.0, 135.0, 26.8), ("spindle oil", 18.6, 6.3, 2.4),
    ("light machine oil", 45.0, 12.0, 3.9), ("medicinal white oil", 107.0, 23.3, 6.4),
    ("heavy machine oil", 122.0, 26.3, 7.3), ("heavy machine oil", 171.0, 31.0, 7.5), ("spindle oil", 30.7, 8.6, 3.1),
    ("heavy machine oil", 165.0, 30.0, 6.8), ("heavy machine oil", 310.0, 44.2, 9.4),
]


@pytest.mark.parametrize("name", list(OILS))
def test_walther_returns_both_datasheet_points(name):
    """ν(40 °C) and ν(100 °C) are the datasheet values: the fit passes through them exactly (1e-12 relative: the
    round trip through two logarithms and two powers of ten costs a few ulps of the double log)."""
    oil = OILS[name]
    assert oil.kinematic_viscosity(313.15) == pytest.approx(oil.nu40_m2_s, rel=1e-12)
    assert oil.kinematic_viscosity(373.15) == pytest.approx(oil.nu100_m2_s, rel=1e-12)


def test_walther_law_is_the_d341_form():
    """log10 log10(ν + 0.7) is linear in log10 T with slope −B at three arbitrary temperatures (1e-12: rounding)."""
    oil = OILS["SAE 10W-40"]
    a, b = oil.walther
    for t in (280.0, 350.0, 420.0):
        w = math.log10(math.log10(oil.kinematic_viscosity(t) * 1e6 + 0.7))
        assert w == pytest.approx(a - b * math.log10(t), rel=1e-12)


def test_walther_predicts_a_third_published_point():
    """Fitted through a published oil's viscosities at 30 and 100 °C, the law predicts its viscosity at 60 °C.

    The table gives dynamic viscosities, so they are made kinematic with a density of 880 kg/m³ at 15 °C and
    6.5e-4 1/K (the table gives none; ±3 % in the density moves the prediction by < 1 %). Tolerance 6 %: the table's
    two- to three-digit values (34 mPa s is ±1.5 %), the assumed density, and the interpolation error of the
    two-constant law for mineral oils (a few percent) together. The first row (a light machine oil, 38 / 12.1 /
    5.3 mPa s) is 12 % off: that oil does not follow D341 between these points, or the row is misprinted; it is
    asserted to be off so that the exclusion is visible. The median error is asserted separately (< 2 %)."""
    errors = []
    for _, mu30, mu60, mu100 in STACHOWIAK_TABLE_2_3:
        def nu(mu_mpas, t):
            return mu_mpas * 1e-3 / (880.0 * (1.0 - 6.5e-4 * (t - 288.15))) * 1e6  # [mm²/s]

        a, b = walther_coefficients(303.15, nu(mu30, 303.15), 373.15, nu(mu100, 373.15))
        predicted = 10.0 ** (10.0 ** (a - b * math.log10(333.15))) - 0.7
        errors.append(predicted / nu(mu60, 333.15) - 1.0)
    assert abs(errors[0]) > 0.10
    assert max(abs(e) for e in errors[1:]) < 0.06, errors
    assert sorted(abs(e) for e in errors)[len(errors) // 2] < 0.02


def test_named_oils_are_in_their_published_grade_ranges():
    """SAE J300: ν(100 °C) of 0W-20 in 6.9 ... <9.3, 5W-30 in 9.3 ... <12.5, 10W-40 and 15W-40 in 12.5 ... <16.3 mm²/s;
    ISO 3448: VG 46 is 41.4 ... 50.6 mm²/s at 40 °C."""
    ranges = {"SAE 0W-20": (6.9, 9.3), "SAE 5W-30": (9.3, 12.5), "SAE 10W-40": (12.5, 16.3),
              "SAE 15W-40": (12.5, 16.3)}
    for name, (lo, hi) in ranges.items():
        assert lo <= OILS[name].nu100_m2_s * 1e6 < hi
    assert 41.4 <= OILS["ISO VG 46"].nu40_m2_s * 1e6 <= 50.6


def test_density_and_dynamic_viscosity_from_their_definitions():
    """ρ(T) = ρ15 (1 − α (T − 288.15)) and μ = ρ ν (1e-14 relative: rounding)."""
    oil = Oil(46e-6, 6.8e-6, 870.0, 6.5e-4, 2000.0)
    assert oil.density(288.15) == 870.0
    assert oil.density(373.15) == pytest.approx(870.0 * (1.0 - 6.5e-4 * 85.0), rel=1e-14)
    assert oil.dynamic_viscosity(350.0) == pytest.approx(oil.density(350.0) * oil.kinematic_viscosity(350.0),
                                                         rel=1e-14)


def test_colder_oil_is_more_viscous():
    oil = OILS["SAE 5W-30"]
    mus = [oil.dynamic_viscosity(t) for t in (253.15, 293.15, 333.15, 373.15, 413.15)]
    assert all(a > b for a, b in zip(mus, mus[1:]))


@pytest.mark.parametrize("kwargs, message", [
    (dict(nu40_m2_s=6.8e-6, nu100_m2_s=46e-6), "valid range 2e-6 <= nu100 < nu40"),
    (dict(nu40_m2_s=46.0, nu100_m2_s=6.8), "valid range 2e-6 <= nu100 < nu40 <= 1e-2"),  # mm²/s given as m²/s
    (dict(nu100_m2_s=-1e-6), "oil nu100_m2_s = -1e-06 m^2/s is invalid"),
    (dict(density15_kg_m3=0.87), "oil density15_kg_m3 = 0.87 kg/m^3 is invalid: valid range 600 ... 1200"),
    (dict(specific_heat_J_kgK=2.0), "oil specific_heat_J_kgK = 2 J/(kg K) is invalid: valid range 1000 ... 3000"),
    (dict(density_coefficient_1_K="6.5e-4"), "is a str"),
])
def test_bad_oil_values_are_refused_with_value_and_range(kwargs, message):
    base = dict(nu40_m2_s=46e-6, nu100_m2_s=6.8e-6, density15_kg_m3=870.0)
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")
                       .replace(".", r"\.").replace("^", r"\^")):
        Oil(**{**base, **kwargs})


@pytest.mark.parametrize("t, message", [
    (90.0, "= 90.0 K is invalid: valid range 243.15 ... 473.15 K (-30 ... 200 °C); temperatures are in K"),
    (float("nan"), "is invalid"),
    (460.0, "valid range 243.15 ... 452.1"),  # ISO VG 46 falls below 2 mm²/s at 452 K: D341's two-constant limit
])
def test_temperatures_outside_the_law_are_refused(t, message):
    oil = OILS["SAE 5W-30"] if t != 460.0 else OILS["ISO VG 46"]
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        oil.dynamic_viscosity(t)


def test_oil_table_by_name_or_numbers_and_round_trip(tmp_path):
    assert oil_from_dict({"name": "ISO VG 46"}) is OILS["ISO VG 46"]
    oil = Oil(50e-6, 8e-6, 860.0, 7e-4, 2100.0, "my oil")
    assert Oil.from_dict(oil.to_dict()) == oil
    tc = frb.turbocharger().with_(oil=oil)
    assert frb.load_system(tc.save(tmp_path / "tc.toml")) == tc
    assert frb.load_system(tc.save(tmp_path / "tc.json")).oil == oil
    assert "oil" not in frb.turbocharger().to_dict()  # systems without an oil: files as before
    text = (tmp_path / "tc.toml").read_text().split("[oil]")[0] + '[oil]\nname = "SAE 0W-20"\n'
    (tmp_path / "named.toml").write_text(text)
    assert frb.load_system(tmp_path / "named.toml").oil is OILS["SAE 0W-20"]
    assert oil_from_dict(OILS["SAE 5W-30"].to_dict()) == OILS["SAE 5W-30"]  # a named oil's own numbers: accepted


@pytest.mark.parametrize("table, message", [
    ({"name": "SAE 99W-99"}, "oil: oil name = 'SAE 99W-99' is unknown; known oils: SAE 0W-20"),
    ({"nu40_m2_s": 46e-6}, "oil: lacks nu100_m2_s, density15_kg_m3"),
    ({"nu40": 46e-6}, "unknown key 'nu40' in oil"),
    # trust5: a known oil's name over other numbers was accepted, and its results labelled with that name
    ({"name": "SAE 5W-30", "nu40_m2_s": 60e-6, "nu100_m2_s": 11e-6, "density15_kg_m3": 852.0},
     r"oil: oil name = 'SAE 5W-30' is a known oil, but nu40_m2_s = 6e-05 \(not 6.4e-05\)"),
])
def test_bad_oil_tables_are_refused(table, message):
    with pytest.raises(ParameterError, match=message):
        oil_from_dict(table)
