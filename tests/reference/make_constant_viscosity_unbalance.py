"""Generate tests/reference/constant_viscosity_unbalance.json: the method-J unbalance response (complex amplitudes of
every DoF) and its critical-speed table of the Table 2 turbocharger at its constant viscosities, computed by the code
*before* the thermal model entered the unbalance response (commit 8fe8a0b), for tests/test_thermal_unbalance.py
(without an oil supply the results must stay bit for bit the same). JSON floats are written with Python's shortest
round-trip repr, so they read back exactly. To rerun with that commit's code::

    mkdir /tmp/frb_ref && git archive 8fe8a0b | tar -x -C /tmp/frb_ref
    PYTHONPATH=/tmp/frb_ref python tests/reference/make_constant_viscosity_unbalance.py
"""
import json
import subprocess
from pathlib import Path

import numpy as np

import frbmodel as frb

SPEEDS_RPM = [20e3, 40e3, 60e3, 90e3, 130e3, 210e3]


def main():
    ur = frb.unbalance_response(frb.turbocharger(), "J", np.array(SPEEDS_RPM), {"turbine_wheel": (1e-6, 0.0)})
    cs = ur.critical_speeds()
    out = {"commit": "8fe8a0b", "numpy": np.__version__, "speeds_rpm": SPEEDS_RPM,
           "response_real": ur.response.real.tolist(), "response_imag": ur.response.imag.tolist(),
           "critical_speed_rpm": cs["speed [rpm]"].tolist(), "critical_source": cs["source"].tolist()}
    p = Path(__file__).with_name("constant_viscosity_unbalance.json")
    p.write_text(json.dumps(out, indent=1))
    print(f"wrote {p} ({subprocess.run(['date', '-u'], capture_output=True, text=True).stdout.strip()})")


if __name__ == "__main__":
    main()
