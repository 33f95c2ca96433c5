"""Generate tests/reference/constant_viscosity_campbell.json: the method-J Campbell diagram and the exact film whirl
onsets of the Table 2 turbocharger at its constant viscosities, computed by the code *before* the thermal model
entered the Campbell diagram (commit 3fb56f2), for tests/test_thermal_campbell.py (without an oil supply the results
must stay bit for bit the same). JSON floats are written with Python's shortest round-trip repr, so they read back
exactly. To rerun with that commit's code::

    mkdir /tmp/frb_ref && git archive 3fb56f2 | tar -x -C /tmp/frb_ref
    PYTHONPATH=/tmp/frb_ref python tests/reference/make_constant_viscosity_campbell.py
"""
import json
import subprocess
from pathlib import Path

import numpy as np

import frbmodel as frb

SPEEDS_RPM = [20e3, 90e3, 210e3]


def main():
    cd = frb.campbell(frb.turbocharger(), "J", np.array(SPEEDS_RPM))
    out = {"commit": "3fb56f2", "numpy": np.__version__, "speeds_rpm": SPEEDS_RPM,
           "eigenvalues_real": cd.eigenvalues.real.tolist(), "eigenvalues_imag": cd.eigenvalues.imag.tolist(),
           "whirl_margin": cd.whirl_margin.tolist(), "whirl_hz": cd.whirl_hz.tolist(),
           "ring_speed_ratio": cd.ring_speed_ratio.tolist(), "whirl_onset_rpm": cd.whirl_onset_rpm.tolist()}
    p = Path(__file__).with_name("constant_viscosity_campbell.json")
    p.write_text(json.dumps(out, indent=1))
    print(f"wrote {p} ({subprocess.run(['date', '-u'], capture_output=True, text=True).stdout.strip()})")


if __name__ == "__main__":
    main()
