"""Generate tests/reference/ross_unbalance_AB.json: unbalance responses of the Table 2 rotor computed by ROSS.

Stored peer results for tests/test_unbalance.py (methods A and B: the rotor on undamped linear springs). ROSS
(ross-rotordynamics 3.x) needs Python >= 3.12, so this script runs in a side interpreter, not in the project's
test environment. To rerun (about 10 s)::

    python3.12 -m venv /work/ross-venv
    /work/ross-venv/bin/pip install 'ross-rotordynamics==3.0.*'
    /work/ross-venv/bin/python tests/reference/make_ross_unbalance.py

The rotor is the one of ``benchmarks/_ross_campbell.py`` (``build_rotor``: 3 Euler-Bernoulli shaft elements with
rotary inertia and gyroscopic terms, no shear, the two wheels as rigid discs, springs at nodes 1 and 2). Two
unbalances act together, so that both the nodes and the phases of the forcing are exercised: 1e-6 kg m at phase
0 on the turbine wheel (node 0) and 0.5e-6 kg m at phase 1 rad on the compressor wheel (node 3). ROSS's
``run_unbalance_response`` solves (K - W^2 M + i W (C + W G)) X = F at each speed W for the complex amplitudes
X of all DoFs (x(t) = Re(X e^{i W t})); the x and y amplitudes of the four nodes are stored as real and imaginary
parts [m]. The JSON records the ROSS, Python, NumPy and SciPy versions and the UTC date of the run. The stored
file was made with ROSS 3.0.0 on Python 3.12.1 (NumPy 2.5.5, SciPy 1.18.1) on 2026-11-28.
"""
import datetime
import json
import platform
import sys
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "benchmarks"))
warnings.filterwarnings("ignore")

#: method -> spring stiffnesses kx, ky [N/m] (the project's defaults for A and B)
CASES = {"A": (1e6, 1e6), "B": (1e6, 2e6)}
#: rotor speeds [rpm]: 1 000 ... 250 000, 84 points (steps of 3 000 rpm)
SPEEDS_RPM = np.linspace(1e3, 250e3, 84)
#: (ROSS node, disc name in frbmodel, m e [kg m], phase [rad])
UNBALANCE = ((0, "turbine_wheel", 1e-6, 0.0), (3, "compressor_wheel", 0.5e-6, 1.0))


def response(rotor, speeds_rpm):
    """Complex x and y amplitudes [m] of the 4 nodes: dict "node<i> x" / "node<i> y" -> (re list, im list)."""
    nodes, me, phase = ([u[k] for u in UNBALANCE] for k in (0, 2, 3))
    res = rotor.run_unbalance_response(nodes, me, phase, speed_range=np.asarray(speeds_rpm) * np.pi / 30.0)
    X = np.asarray(res.forced_resp)  # (ndof, n_speeds), ROSS's 6 DoF per node: x, y, z, alpha, beta, theta
    ndof_node = rotor.number_dof
    out = {}
    for i in range(4):
        for k, axis in enumerate("xy"):
            z = X[i * ndof_node + k]
            out[f"node{i} {axis}"] = {"re [m]": z.real.tolist(), "im [m]": z.imag.tolist()}
    return out


def main():
    import ross as rs
    import scipy
    from _ross_campbell import build_rotor

    cases = {m: {"kx [N/m]": kx, "ky [N/m]": ky, "response": response(build_rotor(kx, ky), SPEEDS_RPM)}
             for m, (kx, ky) in CASES.items()}
    meta = {"generator": "tests/reference/make_ross_unbalance.py", "rotor": "benchmarks/_ross_campbell.py build_rotor",
            "ross": rs.__version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__,
            "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "note": "ROSS run_unbalance_response on undamped springs at nodes 1 and 2; complex amplitudes X with "
                    "x(t) = Re(X exp(i W t)); ROSS's forcing (1, -i) m e W^2 exp(i phase) on (x, y)"}
    data = {"meta": meta, "speeds [rpm]": SPEEDS_RPM.tolist(),
            "unbalance": [{"node": n, "disc": d, "m e [kg m]": me, "phase [rad]": p} for n, d, me, p in UNBALANCE],
            "methods": cases}
    path = HERE / "ross_unbalance_AB.json"
    path.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
