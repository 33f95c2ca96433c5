"""The split bearing component with the thermal model (issue #25 stage 3 item 5, component level): its power loss at
the equilibrium of a supply temperature equals thermal_losses there (issue #25's FMU acceptance, 0.1 %), its film
temperatures and oil flow are those of the operating point, and without an oil it is unchanged."""
import numpy as np
import pytest

import frbmodel as frb
from frbmodel.core.errors import ParameterError
from frbmodel.core.units import rpm_to_rad_s
from frbmodel.linear.thermal import OilSupply, thermal_losses
from frbmodel.nonlinear.components import BearingComponent
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
W = rpm_to_rad_s(100e3)


@pytest.mark.parametrize("t_s", [333.15, 393.15])
def test_bearing_component_power_loss_equals_thermal_losses(t_s):
    """Each bearing at 100 krpm (a node of its 49-speed table, so the table's viscosities are those of the thermal
    operating point there), at its method-J equilibrium with perturbation 0: power loss = thermal_losses' within
    0.1 % (issue #25's acceptance; the component's losses are the loss kernel at the same equilibrium), film
    temperatures within 5 mK and the oil flow within 1e-9 relative (the table's own rows). Changing the supply
    recomputes the table: the loss then equals the other supply temperature's."""
    tab = thermal_losses(TC, 100e3, OIL, t_s)
    other = 333.15 if t_s != 333.15 else 393.15
    tab2 = thermal_losses(TC, 100e3, OIL, other)
    for k, (b, load) in enumerate(zip(TC.bearings, TC.bearing_loads)):
        bc = BearingComponent(b)
        bc.use_oil(OilSupply(OIL, t_s), load, np.linspace(rpm_to_rad_s(50e3), rpm_to_rad_s(150e3), 49))
        x, y = bc.initialize_equilibrium(load, W)
        _, power = bc.losses([x, y, 0.0, 0.0], W)
        row = tab.iloc[k]
        assert power == pytest.approx(row["power loss [W]"], rel=1e-3)
        t_i, t_o, q = bc.thermal_outputs(W)
        assert abs(t_i - row["inner film temperature [K]"]) < 5e-3
        assert abs(t_o - row["outer film temperature [K]"]) < 5e-3
        assert q == pytest.approx(row["inner flow [m^3/s]"] + row["outer flow [m^3/s]"], rel=1e-9)
        bc.set_supply(OilSupply(OIL, other))
        x, y = bc.initialize_equilibrium(load, W)
        assert bc.losses([x, y, 0.0, 0.0], W)[1] == pytest.approx(tab2.iloc[k]["power loss [W]"], rel=1e-3)


def test_without_an_oil_the_bearing_component_is_unchanged_and_refuses_thermal_calls():
    """No oil: the film data array is the constant one, untouched by the calls (bit for bit); thermal calls refused."""
    b = TC.bearings[0]
    bc = BearingComponent(b)
    geom0 = bc.geom.copy()
    x, y = bc.initialize_equilibrium(TC.bearing_loads[0], W)
    bc.exchange([x, y, 0.0, 0.0], W)
    np.testing.assert_array_equal(bc.geom, geom0)
    with pytest.raises(ParameterError, match="thermal outputs need the thermal model"):
        bc.thermal_outputs(W)
    with pytest.raises(ParameterError, match="an oil supply needs the thermal model"):
        bc.set_supply(OilSupply(OIL))
    with pytest.raises(ParameterError, match="thermal table speeds are invalid"):
        bc.use_oil(OilSupply(OIL), TC.bearing_loads[0], [W])


def test_bearing_fmu_oil_supply_input_sets_the_power_loss_as_thermal_losses(built, tmp_path):
    """The split bearing FMU (turbine bearing: its default parameters) with oil = SAE 5W-30, journal and ring at the
    method-J equilibrium of thermal_system at 100 krpm, 333.15 K (an independent path: the linear equilibrium of the
    system with the thermal viscosities), rotor speed 100 krpm: power_loss = thermal_losses within 0.1 % (issue #25's
    acceptance; the FMU interpolates its 49-speed table 10 ... 250 krpm, nodes 5 krpm apart), the film temperatures
    within 5 mK, the oil flow within 1e-3 (linear interpolation of the table). Changing the supply input to 393.15 K
    recomputes the table: the film temperatures are then 393.15 K's. Without the oil, a changed supply input
    discards the step."""
    pytest.importorskip("fmpy")
    from _fmu import Slave
    from fmpy.fmi1 import FMICallException

    from frbmodel.linear.thermal import thermal_system

    fmu = built / "fmus" / "FloatingRingBearing.fmu"
    names = ["power_loss", "inner_film_temperature", "outer_film_temperature", "oil_flow"]
    e = frb.equilibrium(thermal_system(TC, 100e3, OIL, 333.15), "J", 100e3).bearings[0]
    s = Slave(fmu, "oil", tmp_path, {"oil": "SAE 5W-30", "oil_supply_temperature": 333.15, "ring.x0": e.ring[0],
                                     "ring.y0": e.ring[1], "ring.speed0": e.ring_speed})
    s.set({"journal.x": e.journal[0], "journal.y": e.journal[1], "rotor_speed": W})
    for t_s in (333.15, 393.15):
        s.set({"oil_supply_temperature": t_s})
        out = s.get(names)
        ref = thermal_losses(TC, 100e3, OIL, t_s).iloc[0]
        if t_s == 333.15:  # the journal and ring are at this supply's equilibrium
            assert out[0] == pytest.approx(ref["power loss [W]"], rel=1e-3)
        assert out[1] == pytest.approx(ref["inner film temperature [K]"], abs=5e-3)
        assert out[2] == pytest.approx(ref["outer film temperature [K]"], abs=5e-3)
        assert out[3] == pytest.approx(ref["inner flow [m^3/s]"] + ref["outer flow [m^3/s]"], rel=1e-3)
    s.close()
    plain = Slave(fmu, "plain", tmp_path)
    plain.set({"oil_supply_temperature": 333.15, "rotor_speed": W})
    with pytest.raises(FMICallException, match="discard"):
        plain.s.doStep(0.0, 1e-5)
    plain.close()
