"""The flow of the constant-speed model, z(0) -> z(T), for shooting and continuation, and its tolerances.

One object (:class:`ConstantSpeedFlow`) integrates the full nonlinear model of :func:`frbmodel.nonlinear.runup` at a
constant rotor speed in compiled code, without the GIL, so that the monodromy's columns run in threads. The shooting
tolerances, the difference step and the multiplier accuracy used by :mod:`frbmodel.cycles.limitcycle`,
:mod:`frbmodel.cycles.branch` and :mod:`frbmodel.cycles.continuation` are defined here, once.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import ConvergenceError
from ..nonlinear.compiled import pack_problem, solve_chunk
from ..nonlinear.recorder import RunupResult
from ..nonlinear.rosenbrock import FD_TYPICAL_M, NO_MODAL, STATUS, film_columns, rodas_chunk
from ..nonlinear.runup import atol_vector, sample_rows, typical_sizes

#: shooting tolerances: Radau IIA relative tolerance and absolute tolerance on displacements [m] of the flow; the
#: monodromy's difference step (scaled units: 1e-4 of a micrometre, 1e-10 m, on displacements) is ~3e3 times the
#: flow's error (3e-9 of a ~10 µm orbit), so its columns are accurate to ~3e-4 (1e-9 cost 25 % more per branch
#: point: 1.38 vs 1.08 s, quiet machine)
SHOOT_RTOL, SHOOT_ATOL_M = 3e-9, 3e-13


FD_STEP = 1e-4


#: integrator of the shooting flows ("auto", "radau" or "rodas", see :class:`ConstantSpeedFlow`)
FLOW_METHOD = "auto"


#: a flow takes a neighbour's integrator choice as hint (no Rodas probe) at most this many times in a row
HINT_MAX_AGE = 10


#: accuracy of the multipliers' moduli [-]: a double multiplier at 1 (the trivial one and, near a Hopf point or a
#: fold, the critical one) splits by about the square root of the monodromy's error; measured: up to 8e-4 on an
#: orbit 0.5 rpm from the 14.1 krpm Hopf point of the 36 µm system (1.0003 ± 0.0008j, 8 ms period) and 0.9966 ...
#: 1.0037 along the vertical branch at its 2.0 krpm Hopf point (50 ms period; the radial multiplier is 1 there).
#: Multipliers within this of the unit circle count as on it for stability and bifurcation detection
MULTIPLIER_TOL = 5e-3


#: typical displacement [m] that scales the shooting variables (other states scaled alike, :func:`atol_vector`)
SCALE_M = 1e-6


#: threads integrating the monodromy's columns (the compiled solver runs without the GIL)
WORKERS = 2


class ConstantSpeedFlow:
    """The flow z(0) -> z(T) of the constant-speed model, z = the state without φ; compiled, without the GIL.

    Two integrators: CyRK's Radau IIA (:mod:`frbmodel.nonlinear.compiled`; 2-3.5x faster on whirl orbits) and the
    Rosenbrock method of the run-up (:mod:`frbmodel.nonlinear.rosenbrock`). Radau's internal Jacobian differences scale
    with the states themselves, and near an equilibrium (velocities ~0) it degrades: at the 2 krpm Hopf point of the 36
    µm system a 5 ms flow of a 0.1 µm orbit took it 23k steps and 5 s with an error of 4e-4 of the motion, Rodas
    (difference steps from the states' typical sizes) 55 steps and 3e-13 m, 5e-6 of the motion (LSODA at 1e-11 as
    reference). ``method="auto"``: the first flow is integrated by Rodas, then by Radau with twice Rodas' steps as
    budget; Radau is kept for this speed if it finishes, else Rodas. ``hint``: a flow at a neighbouring speed that chose
    Radau — Radau is then tried first, with twice the neighbour's Rodas steps as budget, and Rodas only if it does not
    finish (a continuation saves one Rodas flow per branch point). All flows of one instance use one integrator (the
    monodromy's differences need it).
    """

    def __init__(self, problem, rtol, atol_m, method=None, hint=None):
        import threading


        self.problem, self.rtol, self.method = problem, rtol, method or FLOW_METHOD
        self.atol = atol_vector(problem, atol_m)[0]
        self.evaluations = 0
        self.packed = pack_problem(problem)
        self.fd_scale = typical_sizes(problem, FD_TYPICAL_M)
        self.cols = film_columns(problem.n_rotor, problem.args[3], problem.torque_driven, problem.args[10].size > 0)
        self._probe = threading.Lock()
        #: Rodas steps of the probe (this flow's, or the hint's it relied on); None before a probe
        self.rodas_steps = None
        #: flows since the last full probe along a chain of hints: a hint older than HINT_MAX_AGE is not taken (the
        #: Rodas step count it carries no longer describes the orbit)
        self.hint_age = 0
        ok = hint is not None and hint.method == "radau" and hint.rodas_steps and hint.hint_age < HINT_MAX_AGE
        self._hint_steps, self._hint_age = (hint.rodas_steps, hint.hint_age) if ok else (None, 0)

    def _radau(self, y0, t, max_steps=10**8):

        y, _, message = solve_chunk(self.packed, y0, t, self.rtol, self.atol, max_steps=max_steps)
        return y, message

    def _rodas(self, y0, t):

        y, good, _, steps, _, status = rodas_chunk(y0, np.asarray(t, dtype=float), 1e-7, self.rtol, self.atol,
                                                   self.fd_scale, self.cols, 10**7, float(t[-1]), self.problem.args,
                                                   NO_MODAL)
        return y[:good], (STATUS[status] if status else ""), steps

    def _choose(self, y0, t):
        """The first flow: Rodas, then Radau within twice its steps; keep the one that worked best. With a hint:
        Radau within twice the hint's Rodas steps first."""
        if self._hint_steps is not None:
            y_a, message_a = self._radau(y0, t, max_steps=2 * self._hint_steps + 100)
            if not message_a:
                self.method, self.rodas_steps, self.hint_age = "radau", self._hint_steps, self._hint_age + 1
                return y_a, message_a
        y, message, steps = self._rodas(y0, t)
        self.rodas_steps = steps
        if message:
            self.method = "radau"
            return self._radau(y0, t)
        y_a, message_a = self._radau(y0, t, max_steps=2 * steps + 100)
        self.method = "rodas" if message_a else "radau"
        return (y, message) if message_a else (y_a, message_a)

    def states(self, z0, t):
        """Full states (with φ from 0) at the times ``t`` (from 0)."""
        y0 = np.append(z0, 0.0)
        self.evaluations += 1
        if self.method == "auto":
            with self._probe:  # the monodromy's columns run in threads: one probe
                if self.method == "auto":
                    y, message = self._choose(y0, t)
                    return self._checked(y, message, t)
        y, message = self._radau(y0, t) if self.method == "radau" else self._rodas(y0, t)[:2]
        return self._checked(y, message, t)

    @staticmethod
    def _checked(y, message, t):
        if message:
            raise ConvergenceError(f"limit cycle: the flow failed over {t[-1]:.6g} s ({message})")
        return y

    def __call__(self, z0, T):
        return self.states(z0, np.array([0.0, T]))[-1, :-1]

    def rhs(self, z):
        return self.problem.rhs(0.0, np.append(z, 0.0), np.empty(z.size + 1))[:-1].copy()


def orbit_result(problem, schema, t, y):
    """The sampled orbit as a RunupResult (recorded quantities of each state)."""

    rows = sample_rows(problem, schema, t, y)
    return RunupResult.from_rows(schema, rows, {"system": problem.system.to_dict(), "film_model": problem.film_model,
                                                "profile": problem.profile.description})
