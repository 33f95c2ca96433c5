"""Run-up onsets beside the linear onsets versus the oil supply temperature (issue #25 stage 3 item 3): the table of
runup_onsets_vs_supply is the components table of the spectrogram of the thermal run-up itself (the direct calls),
its rows sub-synchronous and inside the ramp; frb losses --onsets --runup-onsets writes it, and its options are
refused with one line when they cannot apply."""
import numpy as np
import pandas as pd
import pytest

import frbmodel as frb
from frbmodel.cli import main
from frbmodel.linear.thermal import OilSupply
from frbmodel.studies.thermal import runup_onsets_vs_supply
from frbmodel.system.oil import OILS

OIL = OILS["SAE 5W-30"]
TC = frb.turbocharger()
RAMP = (60e3, 160e3)  # a tiny case: 0.3 s, where the outer films' ~0.1 X whirl starts at 393 K (~132 krpm)


def test_runup_onsets_are_the_components_of_the_thermal_runup():
    """One supply temperature: the rows equal spectrogram(runup(oil_supply)).components_table() of the same inputs,
    its sub-synchronous rows (exactly: the same deterministic calls); every row is sub-synchronous (frequency ratio
    < 1, the definition) and each finite onset lies inside the ramp; at least one component starts inside it."""
    tab = runup_onsets_vs_supply(TC, OIL, [393.15], speed_range_rpm=RAMP, duration_s=0.3)
    run = frb.runup(TC, speed_rpm=RAMP, duration=0.3, oil_supply=OilSupply(OIL, 393.15))
    ref = frb.spectrogram(run, "turbine_wheel").components_table()
    ref = ref[ref["f/f_rot at first detection [-]"] < 1.0].reset_index(drop=True)
    pd.testing.assert_frame_equal(tab[list(ref.columns)], ref)
    assert (tab["supply temperature [K]"] == 393.15).all() and (tab["ramp time [s]"] == 0.3).all()
    assert (tab["f/f_rot at first detection [-]"] < 1.0).all()
    onsets = tab["onset [rpm]"].dropna()
    assert len(onsets) >= 1 and ((onsets >= RAMP[0]) & (onsets <= RAMP[1])).all()


@pytest.mark.slow
def test_cli_losses_onsets_with_runups_writes_the_run_up_table(tmp_path):
    """frb losses --onsets --runup-onsets: whirl_onsets_runup.csv = runup_onsets_vs_supply of the same inputs
    (1e-12 relative: a CSV round trip of the same numbers), and the figure is written."""
    out = tmp_path / "l"
    assert main(["losses", "--oil", "SAE 5W-30", "--supply-temperature", "393.15", "--speeds", "50000,150000",
                 "--onsets", "--runup-onsets", "--runup-speeds", "60000:160000", "--runup-duration", "0.3",
                 "--out", str(out)]) == 0
    saved = pd.read_csv(out / "whirl_onsets_runup.csv")
    ref = runup_onsets_vs_supply(TC, OIL, [393.15], speed_range_rpm=RAMP, duration_s=0.3)
    np.testing.assert_allclose(saved["onset [rpm]"], ref["onset [rpm]"], rtol=1e-12)
    assert (out / "whirl_onsets.png").exists()


@pytest.mark.parametrize("argv, message", [
    (["--runup-onsets"], "--runup-onsets needs --onsets"),
    (["--onsets", "--runup-duration", "0.5"], "--runup-duration needs --runup-onsets"),
    (["--onsets", "--runup-onsets", "--runup-speeds", "250000:20000"],
     "--runup-speeds = '250000:20000' is invalid: valid range 0 < START < STOP <= 1e6 rpm"),
    (["--onsets", "--runup-onsets", "--runup-speeds", "fast"], "--runup-speeds = 'fast' is invalid: give START:STOP"),
    (["--onsets", "--runup-onsets", "--runup-duration", "0"], "--runup-duration"),
])
def test_cli_refuses_bad_runup_onset_options_with_one_line_and_writes_nothing(capsys, tmp_path, argv, message):
    out = tmp_path / "out"
    code = main(["losses", "--oil", "SAE 5W-30", "--supply-temperature", "393.15", *argv, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()
