"""The thermal model with every film method (issue #25 item 3, "the ring-speed ratio and methods A–J"): the
operating point is solved with the method's own equilibrium, so with eq. (6) (methods C, D, F, G) the RSR follows
the films' viscosity ratio and falls with speed as the inner film heats (constant 0.199 at Table 2's viscosities),
the energy balance closes for every method, and a method's thermal Campbell diagram is its Campbell diagram of the
by-hand system at each speed's viscosities."""

import numpy as np
import pytest
from _reference import with_viscosities_by_hand

import frbmodel as frb
from frbmodel.linear.thermal import OilSupply, thermal_losses
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
SPEEDS = [50e3, 100e3, 150e3, 200e3, 250e3]


@pytest.fixture(scope="module")
def table_f():
    return thermal_losses(TC, SPEEDS, OIL, 363.15, method="F")


def test_eq6_rsr_is_the_closed_form_at_the_thermal_viscosities_and_falls_with_speed(table_f):
    """Eq. (6), 1 / (1 + (μ_O/μ_I)(L_O/L_I)(c_I/c_O)(D_O/D_I)³), evaluated here from Table 2's geometry and the
    table's own film viscosities: equal to round-off (1e-12); it falls with speed (the inner film heats more than
    the outer, as reported for turbochargers), below the constant-viscosity 0.199."""
    for b in TC.bearings:
        rows = table_f[table_f["bearing"] == b.name]
        mu_i, mu_o = rows["inner viscosity [Pa s]"].to_numpy(), rows["outer viscosity [Pa s]"].to_numpy()
        closed = 1.0 / (1.0 + (mu_o / mu_i) * (b.outer.length / b.inner.length) * (b.inner.clearance /
                        b.outer.clearance) * (b.outer.radius / b.inner.radius) ** 3)
        np.testing.assert_allclose(rows["RSR [-]"], closed, rtol=1e-12)
        assert np.all(np.diff(rows["RSR [-]"]) < 0) and rows["RSR [-]"].max() < 0.199
    assert set(table_f["method"]) == {"F"}


@pytest.mark.parametrize("method", ["C", "D", "F", "G", "I", "J"])
def test_the_energy_balance_closes_for_every_film_method(method):
    """Friction power = heat to the oil + walls (solver tolerance: the residual is the film-temperature fixed point's
    1e-9 K times conductances of a few W/K, so 1e-7 W), and the RSR differs from J's for the eq. (6)/(7) methods
    (so the method is used: by 5e-4 relative for I, whose Petroff balance at the solved ε is close to the full
    torque balance; far more than the 1e-9 of the fixed points)."""
    t = thermal_losses(TC, [150e3], OIL, 363.15, method=method)
    assert np.abs(t["energy-balance residual [W]"]).max() < 1e-7
    j = thermal_losses(TC, [150e3], OIL, 363.15, method="J")
    if method != "J":
        assert np.max(np.abs(t["RSR [-]"] / j["RSR [-]"] - 1)) > 1e-4


def test_a_thermal_campbell_of_method_f_is_the_campbell_of_its_by_hand_system():
    """campbell(method F, oil_supply) at 120 krpm against campbell(method F) of Table 2 with the four viscosities
    of thermal_losses(method="F") copied in by hand: the same operations, so the eigenvalues to 1e-10."""
    sup = OilSupply(OIL, 333.15)
    cd = frb.campbell(TC, "F", [120e3], whirl=False, oil_supply=sup)
    tab = thermal_losses(TC, [120e3], OIL, 333.15, method="F")
    ref = frb.campbell(with_viscosities_by_hand(TC, tab), "F", [120e3], whirl=False)
    np.testing.assert_allclose(cd.frequencies_hz, ref.frequencies_hz, rtol=1e-10)
    np.testing.assert_allclose(cd.damping, ref.damping, rtol=1e-8, atol=1e-12)
    plain = frb.campbell(TC, "F", [120e3], whirl=False)
    assert not np.allclose(cd.damping, plain.damping, rtol=1e-3)  # the oil moved the modes


def test_cli_losses_with_method_f_writes_its_table(tmp_path, capsys):
    from frbmodel.cli import main

    out = tmp_path / "f"
    assert main(["losses", "--oil", "SAE 5W-30", "--method", "F", "--speeds", "50000:250000:3",
                 "--supply-temperature", "363.15", "--out", str(out)]) == 0
    import pandas as pd

    df = pd.read_csv(out / "thermal_losses_F.csv")
    ref = thermal_losses(TC, [50e3, 150e3, 250e3], OIL, 363.15, method="F")
    np.testing.assert_allclose(df["RSR [-]"], ref["RSR [-]"], rtol=1e-12)
