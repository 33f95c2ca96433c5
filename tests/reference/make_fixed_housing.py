"""Reference for tests/test_housing.py: the monolithic right-hand side of the model *before* the housing-frame terms
existed (the fixed-housing model), evaluated at states along two short run-ups, every float stored as its exact
repr, so that the test can check that a housing at rest gives the former model's equations of motion bit for bit
(whatever integrator later walks through them).

Produced by running this script with the frbmodel of commit 5fe3afe (the last commit without the housing terms)
first on sys.path:

    git worktree add /tmp/frb-5fe3afe 5fe3afe
    PYTHONPATH=/tmp/frb-5fe3afe python tests/reference/make_fixed_housing.py

It writes tests/reference/fixed_housing.json: per case the time t, the state y and dy/dt at 9 samples.
"""
import json
from pathlib import Path

import numpy as np

import frbmodel as frb
from frbmodel.nonlinear.runup import SpeedProfile, Unbalance, build_problem, runup

#: (profile, unbalance) per case: a prescribed ramp with a rotating unbalance (every film, ring and unbalance term)
#: and a torque-driven rotor (the spin equation, journal torques)
CASES = {
    "ramp": (lambda: SpeedProfile.ramp(30e3, 32e3, 4e-3), [("turbine_wheel", 2e-6, 0.3)]),
    "torque": (lambda: SpeedProfile.torque(0.05, 40e3, 4e-3), []),
}


def main():
    tc = frb.turbocharger(outer_clearance=36e-6)
    out = {"commit": "5fe3afe", "frbmodel": frb.__version__, "cases": {}}
    for name, (profile, unbalance) in CASES.items():
        unb = [Unbalance(*u) for u in unbalance]
        run = runup(tc, profile=profile(), duration=4e-3, output_rate_hz=20e3, unbalance=unb)
        problem = build_problem(tc, profile(), "short", unb)
        ts = np.linspace(0.0, 4e-3, 9)
        ys = [run.final_state * (1.0 + 1e-3 * k) for k in range(9)]  # near the run's end state, moved apart
        f = [problem.rhs(t, y, np.empty_like(y)).copy() for t, y in zip(ts, ys)]
        out["cases"][name] = {"t": ts.tolist(), "y": [y.tolist() for y in ys], "dydt": [v.tolist() for v in f]}
    path = Path(__file__).with_name("fixed_housing.json")
    path.write_text(json.dumps(out, indent=0))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
