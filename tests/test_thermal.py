"""The lumped thermal balance (frbmodel.physics.thermal) and the thermo-hydrodynamic operating point
(frbmodel.linear.thermal): side flow against the finite-volume Reynolds solution and an independent quadrature of the
short-film pressure field, energy conservation, the closed-form adiabatic limit, the zero-power limit, the
constant-viscosity path bit for bit, and the direction of the effects."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import quad

import frbmodel as frb
from frbmodel.core.errors import ConvergenceError, ParameterError
from frbmodel.core.units import RPM
from frbmodel.linear.losses import bearing_losses
from frbmodel.linear.thermal import thermal_losses, thermal_system
from frbmodel.physics.finite_length import reynolds_pressure
from frbmodel.physics.thermal import ThermalModel, bearing_flows, film_temperatures, pressure_flow, side_flow
from frbmodel.system.films import Film
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()  # Table 2, outer clearance 36 µm
SPEEDS = [50e3, 100e3, 150e3, 200e3, 250e3]


@pytest.fixture(scope="module")
def table():
    """The operating points at 333.15 K and 363.15 K supply, 3 bar (computed once for the module)."""
    return thermal_losses(TC, SPEEDS, OIL, [333.15, 363.15], 3e5)


# ------------------------------------------------------------------ flows
def _reynolds_side_flow(eps, lam, n_theta, n_z):
    """Side flow out of both ends of the finite-volume Reynolds solution, in units of ω_s R c L: per end
    −(1/(48 λ²)) ∮ H³ ∂P/∂ζ|_(ζ=½) dθ (p = μ ω_s R² P / c², z = L ζ, λ = L/D), ∂P/∂ζ at the end from the quadratic
    through P = 0 there and the two cells next to it."""
    th, P = reynolds_pressure(eps, lam, n_theta, n_z)
    dz, dth = 1.0 / n_z, 2.0 * math.pi / n_theta
    s1, s2 = 0.5 * dz, 1.5 * dz  # distances of the last two cell centres from the end ζ = ½
    dpdz = -(P[:, -1] * s2 ** 2 - P[:, -2] * s1 ** 2) / (s1 * s2 * (s2 - s1))
    return 2.0 * -np.sum((1.0 - eps * np.cos(th)) ** 3 * dpdz) * dth / (48.0 * lam ** 2)


@pytest.mark.parametrize("eps", [0.2, 0.5])
def test_side_flow_equals_the_finite_volume_reynolds_solution_of_a_short_film(eps):
    """Q_s = ε ω_s R c L against the axial pressure gradient of the finite-volume Reynolds solution
    (:func:`reynolds_pressure`) at both film ends, integrated around the film, at L/D = 0.05 (the short-film theory
    holds to O(λ²)). The solver's end flux is first order in the axial cell size (measured: 1.58 % high at 40 cells,
    0.75 % at 80), so the two grids are Richardson-extrapolated; tolerance 0.5 % (the extrapolated gap is 0.1 %)."""
    lam = 0.05
    q40, q80 = _reynolds_side_flow(eps, lam, 360, 40), _reynolds_side_flow(eps, lam, 360, 80)
    film = Film(radius=0.05, length=0.005, clearance=50e-6, viscosity=0.01)  # L/D = 0.05
    expected = side_flow(film, eps, 1000.0) / (1000.0 * film.radius * film.clearance * film.length)
    assert expected == pytest.approx(eps, rel=1e-15)
    assert 2.0 * q80 - q40 == pytest.approx(expected, rel=5e-3)
    assert abs(q80 - expected) < abs(q40 - expected)  # the grids converge towards the closed form


@pytest.mark.parametrize("eps", [0.05, 0.4, 0.8])
def test_side_flow_equals_a_quadrature_of_the_closed_form_pressure_field(eps):
    """−∮ h³/(12 μ) ∂p/∂z R dϑ at z = ±L/2 over the π-film (ϑ ∈ (−π, 0)) of p = 3 μ c G (z² − L²/4)/h³,
    G = ε ω_s sin ϑ (scipy quad; ∂p/∂z by a central difference, exact for p quadratic in z): 1e-9 (quadrature).
    Mass conservation gives the same flow independently: the Couette inflow ω_s R L h/2 at the widest gap minus
    the outflow at the narrowest."""
    film, w_s, mu = Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3), 1.2e4, 4.9e-3
    R, L, c = film.radius, film.length, film.clearance

    def p(th, z):
        h = c * (1.0 - eps * math.cos(th))
        return 3.0 * mu * c * eps * w_s * math.sin(th) * (z * z - L * L / 4.0) / h ** 3

    def q_z(th, z):
        h, dz = c * (1.0 - eps * math.cos(th)), 1e-4 * L
        return -h ** 3 / (12.0 * mu) * (p(th, z + dz) - p(th, z - dz)) / (2.0 * dz)

    out = quad(lambda th: q_z(th, L / 2) * R, -math.pi, 0.0, epsabs=0, epsrel=1e-12)[0] \
        - quad(lambda th: q_z(th, -L / 2) * R, -math.pi, 0.0, epsabs=0, epsrel=1e-12)[0]
    couette = w_s * R * L / 2.0 * (c * (1.0 + eps) - c * (1.0 - eps))
    assert side_flow(film, eps, w_s) == pytest.approx(out, rel=1e-9)
    assert side_flow(film, eps, w_s) == pytest.approx(couette, rel=1e-14)


@pytest.mark.parametrize("eps", [0.0, 0.3, 0.7])
def test_pressure_flow_equals_a_quadrature_of_the_poiseuille_flow(eps):
    """Both halves of a film fed at mid-length at p: 2 ∮ h³ p / (12 μ L/2) R dθ (scipy quad; 1e-12: quadrature)."""
    film, p = Film(8e-3, 9e-3, 36e-6, 6.4e-3), 3e5
    h = lambda th: film.clearance * (1.0 - eps * math.cos(th))  # noqa: E731
    q = 2.0 * quad(lambda th: h(th) ** 3 * p / (12.0 * film.viscosity * film.length / 2) * film.radius,
                   0.0, 2.0 * math.pi, epsabs=0, epsrel=1e-13)[0]
    assert pressure_flow(film, eps, p) == pytest.approx(q, rel=1e-12)


def test_centrifugal_pressure_of_the_ring_holes_cuts_the_inner_feed():
    """At a ring speed whose centrifugal pressure ρ ω² (R_O² − R_I²)/2 exceeds the supply pressure the holes feed
    nothing (closed form of the feed pressure to 1e-12); without that term they feed."""
    b = TC.bearings[0]
    eq = frb.equilibrium(TC, "J", 250e3).bearings[0]
    p_c = 0.5 * 850.0 * eq.ring_speed ** 2 * (b.outer.radius ** 2 - b.inner.radius ** 2)
    args = (eq.eps_inner, eq.eps_outer, eq.rotor_speed, eq.ring_speed, 0.5 * p_c, 850.0, 0.01)
    f = bearing_flows(b, *args, ThermalModel())
    assert f["feed_pressure"] == pytest.approx(-0.5 * p_c, rel=1e-12) and f["feed_inner"] == 0.0
    assert bearing_flows(b, *args, ThermalModel(centrifugal_feed=False))["feed_inner"] > 0.0


# ------------------------------------------------------------------ the balance
def test_adiabatic_no_exchange_fully_mixed_film_heats_by_P_over_rho_cp_Q():
    """ΔT = P / (ρ c_p Q) (closed form; exact up to rounding, 1e-14), κ = 1, no ring exchange, adiabatic walls."""
    model = ThermalModel(mixing=1.0, film_nusselt=0.0)
    t_i, t_o, t_r = film_temperatures(TC.bearings[0], model, 120.0, 30.0, 2.0, 3.0, 363.15)
    assert t_i == pytest.approx(363.15 + 120.0 / 2.0, rel=1e-14)
    assert t_o == pytest.approx(363.15 + 30.0 / 3.0, rel=1e-14)
    assert math.isnan(t_r)  # an uncoupled ring has no temperature
    half = film_temperatures(TC.bearings[0], ThermalModel(mixing=0.5, film_nusselt=0.0), 120.0, 30.0, 2.0, 3.0,
                             363.15)
    assert half[0] == pytest.approx(363.15 + 0.5 * 60.0, rel=1e-14)  # effective = mean of inlet and outlet


def test_adiabatic_limit_holds_at_the_coupled_operating_point():
    """At the full fixed point (viscosities at the temperatures) with κ = 1 and no exchange, every film's rise is
    P / (ρ(T) c_p Q) from the table's own power and flow columns (1e-9 relative: the fixed point's residual)."""
    model = ThermalModel(mixing=1.0, film_nusselt=0.0)
    df = thermal_losses(TC, [100e3, 200e3], OIL, 363.15, 3e5, model)
    for film in ("inner", "outer"):
        t = df[f"{film} film temperature [K]"]
        rho_cp = np.array([OIL.density(x) for x in t]) * OIL.specific_heat_J_kgK
        expected = 363.15 + df[f"power loss {film} [W]"] / (rho_cp * df[f"{film} flow [m^3/s]"])
        np.testing.assert_allclose(t, expected, rtol=1e-9)


def test_energy_balance_closes_at_every_speed(table):
    """Friction power = heat carried by the oil (ρ(T) c_p Q (T_out − T_in), recomputed here from the table's
    temperatures and flows) + heat to shaft and housing, at every speed; the ring's balance too. Tolerance 1e-9 W
    (the powers are 10 ... 800 W: 1e-12 relative, the 3 × 3 solve's rounding; the fixed point's residual of < 1e-9 K
    moves the density by 1e-12)."""
    for film in ("inner", "outer"):
        rho = np.array([OIL.density(x) for x in table[f"{film} film temperature [K]"]])
        oil_heat = rho * OIL.specific_heat_J_kgK * table[f"{film} flow [m^3/s]"] * (
            table[f"{film} outlet temperature [K]"] - table["supply temperature [K]"])
        np.testing.assert_allclose(oil_heat, table[f"heat to oil {film} [W]"], rtol=1e-9)
    balance = table["power loss [W]"] - table["heat to oil inner [W]"] - table["heat to oil outer [W]"] \
        - table["heat to shaft [W]"] - table["heat to housing [W]"]
    assert np.abs(balance).max() < 1e-9
    assert np.abs(table["energy-balance residual [W]"]).max() < 1e-9
    assert np.abs(table["ring balance residual [W]"]).max() < 1e-9
    assert (table["temperature residual [K]"] < 1e-9).all()


def test_heat_paths_to_shaft_and_housing_close_the_balance():
    """With both wall paths on (hot shaft at 400 K), the balance still closes (1e-9 W) and the shaft heats the
    inner film above its adiabatic temperature."""
    model = ThermalModel(shaft_heat_transfer_W_m2K=2000.0, housing_heat_transfer_W_m2K=500.0,
                         shaft_temperature_K=400.0)
    df = thermal_losses(TC, [100e3], OIL, 363.15, 3e5, model)
    base = thermal_losses(TC, [100e3], OIL, 363.15, 3e5)
    assert np.abs(df["energy-balance residual [W]"]).max() < 1e-9
    assert (df["heat to shaft [W]"] < 0).all()  # heat flows from the hot shaft into the film
    assert (df["inner film temperature [K]"].values > base["inner film temperature [K]"].values).all()


def test_without_power_every_temperature_is_the_supply_temperature():
    """P = 0: T_inner = T_outer = T_ring = T_supply (1e-12 relative: rounding of the 3 × 3 solve); at 1 krpm the
    rise of each film is below the bound P_total / (ρ c_p Q / κ) that energy conservation gives (every heat flow
    leaves through the oil)."""
    for t in film_temperatures(TC.bearings[0], ThermalModel(), 0.0, 0.0, 1.5, 2.5, 330.0):
        assert t == pytest.approx(330.0, rel=1e-12)
    df = thermal_losses(TC, [1e3], OIL, 330.0, 3e5)
    for film in ("inner", "outer"):
        rise = df[f"{film} film temperature [K]"] - 330.0
        cap = OIL.density(330.0) * OIL.specific_heat_J_kgK * df[f"{film} flow [m^3/s]"] / ThermalModel().mixing
        assert ((rise >= 0) & (rise <= df["power loss [W]"] / cap * 1.001)).all()
        assert (rise < 0.05).all()


# ------------------------------------------------------------------ the constant-viscosity path
def test_without_oil_the_results_are_bearing_losses_bit_for_bit():
    """No oil (the system has none): thermal_losses is bearing_losses (method J) column for column, exactly, with
    the ring-speed ratio added; thermal_system returns the system itself."""
    iso = thermal_losses(TC, SPEEDS)
    ref = bearing_losses(TC, SPEEDS, "J")
    pd.testing.assert_frame_equal(iso.drop(columns="RSR [-]"), ref, check_exact=True)
    np.testing.assert_array_equal(iso["RSR [-]"], ref["ring speed [rad/s]"] / (ref["speed [rpm]"] * RPM))
    assert thermal_system(TC, 100e3) is TC


def test_thermal_losses_are_the_projects_losses_at_the_film_viscosities():
    """The powers at the operating point are bearing_losses of the system whose films have the operating point's
    viscosities (thermal_system): one loss kernel, bit for bit."""
    tc_hot = thermal_system(TC, 150e3, OIL, 363.15)
    row = thermal_losses(TC, [150e3], OIL, 363.15)
    ref = bearing_losses(tc_hot, [150e3], "J")
    np.testing.assert_array_equal(row["power loss [W]"], ref["power loss [W]"])
    np.testing.assert_array_equal(row["ring speed [rad/s]"], ref["ring speed [rad/s]"])


# ------------------------------------------------------------------ direction of the effects
def test_colder_oil_is_more_viscous_loses_more_power_and_changes_the_ring_speed(table):
    cold, hot = (table[table["supply temperature [K]"] == t].reset_index(drop=True) for t in (333.15, 363.15))
    for col in ("inner viscosity [Pa s]", "outer viscosity [Pa s]", "power loss [W]"):
        assert (cold[col] > hot[col]).all(), col
    assert (np.abs(cold["RSR [-]"] - hot["RSR [-]"]) > 1e-3).all()


def test_ring_speed_ratio_falls_with_rotor_speed_at_90_C(table):
    """The trend reported for turbochargers (San Andrés & Kerth 2004; Kerth's 2003 thesis; their numbers were not
    available here): the inner film heats more than the outer, its viscosity falls more, and the RSR falls as the
    rotor speeds up — no published number for the Table 2 rotor exists, so the test asserts the direction and that
    the inner film is the hotter one. With constant
    viscosities the method-J RSR rises with speed instead (towards eq. (6))."""
    hot = table[table["supply temperature [K]"] == 363.15]
    for name, grp in hot.groupby("bearing"):
        rsr = grp.sort_values("speed [rpm]")["RSR [-]"].to_numpy()
        assert (np.diff(rsr) < 0).all(), (name, rsr)
        assert (grp["inner film temperature [K]"] > grp["outer film temperature [K]"]).all()
    iso = thermal_losses(TC, [50e3, 250e3])
    turbine = iso[iso["bearing"] == "turbine"]["RSR [-]"].to_numpy()
    assert turbine[1] > turbine[0]


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("kwargs, error, message", [
    (dict(supply_temperature_K=90.0), ParameterError, "supply_temperature_K = 90.0 K is invalid: valid range 243.15"),
    (dict(supply_pressure_Pa=-1.0), ParameterError, "supply_pressure_Pa = -1.0 Pa is invalid: valid range 0"),
    (dict(supply_pressure_Pa=3e7), ParameterError, "valid range 0 ... 2e+06 Pa"),
    (dict(oil="SAE 5W-30"), ParameterError, "oil = 'SAE 5W-30' is a str; expected an Oil"),
    (dict(model=ThermalModel(max_evaluations=2)), ConvergenceError, "did not converge: film-temperature residual"),
    (dict(supply_pressure_Pa=0.0), ParameterError, "the oil flow cannot carry the film's friction power"),
])
def test_bad_thermal_input_is_refused_with_value_and_range(kwargs, error, message):
    args = {**dict(oil=OIL, supply_temperature_K=363.15, supply_pressure_Pa=3e5), **kwargs}
    with pytest.raises(error, match=message.replace(".", r"\.").replace("+", r"\+")):
        thermal_losses(TC, [250e3] if args["supply_pressure_Pa"] == 0.0 else [150e3], **args)


@pytest.mark.parametrize("kwargs, message", [
    (dict(mixing=1.5), "mixing = 1.5 is invalid: valid range 0 < mixing <= 1"),
    (dict(feed_holes=2.5), "feed_holes = 2.5 is invalid: valid range integer >= 0"),
    (dict(film_nusselt=-1.0), "film_nusselt = -1.0 is invalid"),
])
def test_bad_thermal_model_coefficients_are_refused(kwargs, message):
    with pytest.raises(ParameterError, match=message.replace(".", r"\.")):
        ThermalModel(**kwargs)


# ------------------------------------------------------------------ command line
@pytest.mark.parametrize("argv, message", [
    (["--oil", "SAE 5W-30", "--supply-temperature", "90"],
     "--supply-temperature = 90.0 K is invalid: valid range 243.15 ... 473.15 K (-30 ... 200 °C); temperatures are "
     "in K"),
    (["--oil", "SAE 5W-30", "--supply-temperature", "333.15,abc"], "--supply-temperature = '333.15,abc' is invalid"),
    (["--oil", "SAE 5W-30", "--supply-pressure=-2e5"],
     "--supply-pressure = -200000.0 Pa is invalid: valid range 0 ... 2e+06 Pa"),
    (["--oil", "SAE 99W"], "oil name = 'SAE 99W' is unknown; known oils: SAE 0W-20, SAE 5W-30"),
    (["--supply-temperature", "363.15"], "--supply-temperature needs an oil: give --oil NAME"),
    (["--oil", "ISO VG 46", "--method", "F", "--onsets"], "--onsets cannot be combined with --method F"),
    (["--oil", "ISO VG 46", "--run", "somewhere"], "--run cannot be combined with an oil"),
])
def test_cli_losses_refuses_bad_thermal_options_with_one_line_and_writes_nothing(capsys, tmp_path, argv, message):
    from frbmodel.cli import main

    out = tmp_path / "losses"
    code = main(["losses", "--speeds", "1e5", "--out", str(out), *argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_cli_losses_with_an_oil_writes_temperatures_and_the_figure(capsys, tmp_path):
    """The CLI is the library's table: its CSV equals thermal_losses at the same inputs (exactly)."""
    from frbmodel.cli import main

    out = tmp_path / "losses"
    assert main(["losses", "--speeds", "1e5,2e5", "--oil", "SAE 5W-30", "--supply-temperature", "363.15",
                 "--supply-pressure", "4e5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "inner film temperature [K]" in printed and "RSR [-]" in printed
    csv = pd.read_csv(out / "thermal_losses.csv")
    ref = thermal_losses(TC, [1e5, 2e5], OIL, 363.15, 4e5)
    np.testing.assert_allclose(csv["inner film temperature [K]"], ref["inner film temperature [K]"], rtol=1e-15)
    assert (out / "thermal_losses.png").stat().st_size > 10_000
    assert main(["losses", "--speeds", "1e5", "--out", str(tmp_path / "iso")]) == 0  # no oil: as before, with RSR
    assert "RSR [-]" in pd.read_csv(tmp_path / "iso" / "bearing_losses_J.csv")


def test_thermal_figure_has_a_column_per_bearing_with_units(table):
    """The figure takes the table only: 3 panels per bearing, units on every axis, °C on the temperature axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from frbmodel.plots.thermal import plot_thermal_losses

    fig = plot_thermal_losses(table)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels.count("ring-speed ratio RSR [-]") == 2 and labels.count("film temperature [K]") == 2
    assert labels.count("power loss [W]") == 2
    celsius = [c.get_ylabel() for ax in fig.axes if ax.get_ylabel() == "film temperature [K]" for c in ax.child_axes]
    assert celsius == ["[°C]", "[°C]"]
    assert len(fig.legends) == 1 and "supply 333.15 K (60 °C)" in [t.get_text() for t in fig.legends[0].texts]
    plt.close(fig)


def test_inner_to_outer_power_ratio_is_that_of_the_balanced_ring_torque(table):
    """For centred films the balanced ring torque A_I (ω_R − ω_FR) = A_O ω_FR gives P_I / P_O = (ω_R − ω_FR)/ω_FR
    = 1/RSR − 1 whatever the viscosities: the almost unloaded compressor bearing (ε ≈ 0.002) at every thermal
    operating point. Tolerance 1e-5: the pressure-offset terms are O(ε²) (measured ≤ 1e-6)."""
    comp = table[table["bearing"] == "compressor"]
    np.testing.assert_allclose(comp["power loss inner [W]"] / comp["power loss outer [W]"], 1.0 / comp["RSR [-]"] - 1.0,
                               rtol=1e-5)
