"""Generate tests/reference/ross_campbell_AB.json: natural frequencies of the Table 2 rotor computed by ROSS.

These are stored peer results for tests/test_methods.py (methods A and B: the rotor on linear springs, no
damping). ROSS (ross-rotordynamics 3.x) needs Python >= 3.12, so this script runs in a side interpreter, not in
the project's test environment. To rerun (about 15 s)::

    python3.12 -m venv /work/ross-venv
    /work/ross-venv/bin/pip install 'ross-rotordynamics==3.0.*'
    /work/ross-venv/bin/python tests/reference/make_ross_campbell.py

The rotor is built in ROSS by ``benchmarks/_ross_campbell.py`` (3 Euler-Bernoulli shaft elements with rotary
inertia and gyroscopic terms, no shear; the two wheels as rigid discs). ROSS models 6 DoF per node; its axial
and torsional modes (whirl direction ``None``) are left out because the project's rotor model is lateral only;
the 16 lateral modes (4 nodes x 4 lateral DoF) are kept.
The JSON records the ROSS, Python, NumPy and SciPy versions and the UTC date of the run. The stored file was made
with ROSS 3.0.0 on Python 3.12.1 (NumPy 2.5.5, SciPy 1.18.1) on 2026-11-28.
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

#: method -> (spring stiffnesses kx, ky [N/m], rotor speeds [rpm]); the project's defaults for A and B
CASES = {"A": ((1e6, 1e6), (0.0, 50e3, 100e3, 150e3, 200e3, 250e3)),
         "B": ((1e6, 2e6), (0.0, 50e3, 100e3, 150e3, 200e3, 250e3))}


def lateral_modes(rotor, rpm):
    """All lateral modes of ``rotor`` at ``rpm``: sorted (frequency [Hz], whirl direction) pairs.

    Asking for every eigenvalue (``2 * ndof``) also returns one conjugate (negative frequency) of the highest
    mode; only one of each pair, the positive one, is kept.
    """
    modal = rotor.run_modal(speed=rpm * np.pi / 30.0, num_modes=2 * rotor.ndof)
    wd = np.asarray(modal.wd) / (2.0 * np.pi)
    whirl = modal.whirl_direction()
    out = [(float(f), str(w)) for f, w in zip(wd, whirl) if f > 0.0 and str(w) != "None"]
    return sorted(out)


def main():
    import ross as rs
    import scipy
    from _ross_campbell import build_rotor

    cases = {}
    for method, ((kx, ky), speeds) in CASES.items():
        rotor = build_rotor(kx, ky)
        cases[method] = {"kx [N/m]": kx, "ky [N/m]": ky,
                         "speeds": [{"speed [rpm]": rpm, "modes": [{"frequency [Hz]": f, "whirl": w}
                                                                   for f, w in lateral_modes(rotor, rpm)]}
                                    for rpm in speeds]}
    meta = {"generator": "tests/reference/make_ross_campbell.py", "rotor": "benchmarks/_ross_campbell.py build_rotor",
            "ross": rs.__version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__,
            "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "note": "undamped springs at the bearing nodes 1 and 2; frequencies are ROSS's damped natural "
                    "frequencies wd/2pi (equal to wn here); whirl as ROSS's whirl_direction()"}
    path = HERE / "ross_campbell_AB.json"
    path.write_text(json.dumps({"meta": meta, "methods": cases}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
