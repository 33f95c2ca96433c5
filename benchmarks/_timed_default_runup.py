"""One timed main-job run-up at the defaults of whichever frbmodel is first on sys.path (for
benchmarks/default_convergence.py, which runs it with the code of the issue's filing and with today's, alternating).

Prints one JSON line: wall [s] of frb.runup(turbocharger(36 µm), 20 -> 250 krpm in 1 s, 40 kHz output) after a short
untimed run that loads the compiled kernels, the solver steps, and the file frbmodel was imported from.
"""
import json
import time

import frbmodel as frb

tc = frb.turbocharger(36e-6)
frb.runup(tc, speed_rpm=(20e3, 25e3), duration=0.01)  # load the kernels (not timed)
t0 = time.perf_counter()
run = frb.runup(tc, speed_rpm=(20e3, 250e3), duration=1.0, output_rate_hz=40e3)
wall = time.perf_counter() - t0
print(json.dumps({"wall_s": wall, "solver_steps": run.meta.get("solver_steps"), "frbmodel": frb.__file__}))
