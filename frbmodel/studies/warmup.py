"""Compile the numba kernels once, on purpose and with a visible message (``frb warmup``).

The compiled kernels (film forces, ring equations, the monolithic right-hand side, the co-simulation
components, the bearing losses) are cached by numba next to the package's sources (``__pycache__``; numba falls
back to a per-user folder where that is not writable), so every CLI call, Dask worker and Python session that
imports this frbmodel shares them; the FMUs import their bundled copy from a stable per-user folder
(``~/.cache/frbmodel/fmu-pkg``) for the same reason. Compiling takes ~40 s on a 2-core machine the first time and
a second or two to load afterwards. :func:`warmup` exercises every kernel with a tiny workload and leaves a marker
stamped with the hash of the kernel sources, so :func:`kernels_ready` can tell whether a command would have to
compile first (the CLI then says so before it starts).

>>> isinstance(kernels_ready(), bool)
True
"""
from __future__ import annotations

import time
from pathlib import Path

from ..core.kernel_cache import kernel_sources_digest
from ..core.progress import counter_bar
from ..core.version import __version__
from ..linear.equilibrium import equilibrium
from ..linear.losses import bearing_losses
from ..nonlinear.components import BearingComponent, RotorComponent, ramp_speed
from ..nonlinear.runup import INTEGRATORS, SpeedProfile, runup
from ..physics.film import film_coefficients, film_force
from ..system.presets import turbocharger


def _stamp():
    """The marker's stamp: the hash of every module that uses numba (:func:`kernel_sources_digest`, the one the
    package drops its stale kernel caches by)."""
    return kernel_sources_digest()[:16]


def warmup_marker():
    import numba


    name = f"frbmodel-kernels-{__version__}-numba{numba.__version__}-{_stamp()}.ok"
    pkg_cache = Path(__file__).resolve().parents[1] / "__pycache__"
    try:
        pkg_cache.mkdir(exist_ok=True)
        probe = pkg_cache / ".frb_write_probe"
        probe.touch()
        probe.unlink()
        return pkg_cache / name
    except OSError:
        return Path.home() / ".cache" / "frbmodel" / name


def kernels_ready():
    """True if :func:`warmup` ran for these kernel sources (so numba finds them in its cache)."""
    try:
        return warmup_marker().exists()
    except OSError:
        return False


def _tasks():
    """(label, callable) pairs that exercise every compiled kernel once on a tiny problem."""
    import numpy as np


    tc = turbocharger()
    film = tc.bearings[0].inner

    def component_step():
        bc = BearingComponent(tc.bearings[0])
        journal = np.r_[bc.initialize_equilibrium(tc.bearing_loads[0], 2000.0), 0.0, 0.0]
        bc.outputs(journal, 2000.0)
        bc.step(journal, 2000.0, 0.0, 1e-5, t=0.0)
        bc.losses(journal, 2000.0)
        rc = RotorComponent(tc, ramp_speed(2e4, 2e4, 1.0))
        rc.step(1e-5, np.zeros((2, 2)), np.zeros((2, 2, 2)), np.zeros((2, 2, 2)))

    return [("film forces", lambda: (film_force(film, [1e-6, -2e-6], [0.0, 1e-3], 2e3),
                                     film_coefficients(film, [1e-6, -2e-6], 2e3))),
            ("equilibria, ring torques", lambda: equilibrium(tc, "J", 20e3)),
            ("run-up right-hand side and Jacobian", lambda: runup(tc, profile=SpeedProfile.constant(2e4, 2e-4),
                                                                  duration=2e-4, output_rate_hz=1e4,
                                                                  integrator="lsoda")),
            ("compiled run-up integrators", lambda: [runup(tc, profile=SpeedProfile.constant(2e4, 2e-4),
                                                           duration=2e-4, output_rate_hz=1e4, integrator=i)
                                                     for i in ("rodas", "radau")]),
            ("torque-driven spin", lambda: [runup(tc, profile=SpeedProfile.torque(1e-3, 2e4, 2e-4), duration=2e-4,
                                                  output_rate_hz=1e4, integrator=i) for i in INTEGRATORS]),
            ("co-simulation components", component_step),
            ("bearing losses", lambda: bearing_losses(tc, 20e3))]


def warmup(progress=True):
    """Compile (or load) every numba kernel and mark them ready; returns the wall time [s].

    Parameters
    ----------
    progress : bool
        Show a bar over the kernel groups on stderr.

    Returns
    -------
    float
        Wall time [s]: ~40 s when numba compiles (first run on a 2-core machine), ~1-2 s when it loads its cache.
    """

    t0 = time.perf_counter()
    tasks = _tasks()
    with counter_bar(len(tasks), "numba kernels", progress, unit="group") as bar:
        for label, fn in tasks:
            bar.set_postfix_str(label, refresh=False)
            fn()
            bar.update(1)
    marker = warmup_marker()
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(f"compiled in {time.perf_counter() - t0:.1f} s\n")
    except OSError:
        pass
    return time.perf_counter() - t0
