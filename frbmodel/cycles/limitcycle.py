"""Periodic whirl orbits (limit cycles) of the full nonlinear model at a constant rotor speed.

The model is the one of :func:`frbmodel.nonlinear.runup` (FE rotor, both rings' lateral DoFs and spin, nonlinear films,
gravity, optional unbalance) at a constant speed Ω; its state without the rotation angle φ (which only grows,
φ = Ω t) is z, of 2 n_r + 10 components. Without unbalance the system is autonomous: a whirl orbit has an unknown
period, found by single shooting with a phase condition (:mod:`frbmodel.cycles.shooting`); with unbalance it is forced
with the rotor period, and the orbit is locked to 1X or a sub-harmonic ``2π k / Ω``. The flow is integrated in
compiled code (:mod:`frbmodel.nonlinear.compiled`, Radau IIA at tight tolerances), the monodromy matrix by forward
differences of the flow, and its eigenvalues are the Floquet multipliers.

The guess comes from a constant-speed simulation from the equilibrium (``settle_s``): the period is read from the
upward crossings of the turbine journal's x through its mean, and the smallest multiple of that interval after
which the state returns to itself is taken (a period-doubled orbit returns after two); if none returns, the
response is not periodic (a torus: two whirl frequencies) and that is reported instead of an orbit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ConvergenceError, ParameterError, check_positive
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..core.units import RPM
from ..linear.thermal import at_operating_point, check_oil_supply
from ..nonlinear.compiled import pack_problem, solve_chunk
from ..nonlinear.recorder import RunupResult
from ..nonlinear.runup import (
    RunupSchema,
    SpeedProfile,
    Unbalance,
    atol_vector,
    build_problem,
    check_speed,
    initial_state,
    runup,
)
from ..physics.film import check_model
from ..signals.orbits import orbits
from .branch import check_segments, hopf_guess, shoot_segments
from .flow import FD_STEP, MULTIPLIER_TOL, SCALE_M, SHOOT_ATOL_M, SHOOT_RTOL, WORKERS, ConstantSpeedFlow, orbit_result
from .shooting import shoot, stable_multipliers

#: a state returns to itself (period found) when it comes back within this fraction of the orbit's size
RETURN_TOL = 0.02


@dataclass
class LimitCycle(Result):
    """A periodic orbit of the full model at constant speed (:func:`limit_cycle`).

    Attributes
    ----------
    speed_rpm : float
        Rotor speed [rpm].
    period : float
        Minimal period [s] found (the forcing's multiple for an unbalanced rotor).
    orbit : RunupResult
        The orbit sampled over one period (recorded quantities, SI units), time from 0 to ``period``.
    multipliers : ndarray (n,)
        Floquet multipliers, largest modulus first (complex).
    stable : bool
        No non-trivial multiplier outside the unit circle by more than their accuracy :data:`MULTIPLIER_TOL`.
    state : ndarray (n,)
        The full state (without the rotation angle) at the start of the period, SI units.
    monodromy : ndarray (n, n)
        Monodromy matrix at the solution (SI units); its eigenvalues are the multipliers.
    autonomous : bool
        True without unbalance (the period was an unknown).
    meta : dict
        Speed, film model, tolerances, Newton iterations and residual, guess.
    """

    NC_GLOB = "limit_cycle*.nc"  # (Result.load of a folder)
    speed_rpm: float
    period: float
    orbit: object
    multipliers: np.ndarray
    stable: bool
    state: np.ndarray
    autonomous: bool = True
    meta: dict = field(default_factory=dict)
    monodromy: np.ndarray = field(default=None, repr=False)

    @property
    def frequency_hz(self):
        """Orbit frequency 1 / period [Hz]."""
        return 1.0 / self.period

    @property
    def frequency_ratio(self):
        """Orbit frequency over rotor frequency [-] (e.g. ~0.3-0.5 for oil whirl)."""
        return self.frequency_hz / (self.speed_rpm / 60.0)

    def orbit_radius(self, name):
        """Largest distance [m] of a disc or journal (by name) from its time-averaged centre over one period.

        Parameters
        ----------
        name : str
            A disc name (e.g. ``"turbine_wheel"``) or bearing name (its journal).

        Returns
        -------
        float
            Radius [m].
        """
        o = self.orbit
        xy = o.displacement.get(name, o.journal.get(name))
        if xy is None:
            raise ParameterError(f"orbit_radius: {name!r} is neither a disc ({', '.join(o.displacement)}) nor a "
                                 f"bearing ({', '.join(o.journal)})")
        xy = xy[:-1]  # one period, without the repeated end point
        return float(np.max(np.hypot(*(xy - xy.mean(axis=0)).T)))

    @property
    def max_eps(self):
        """Largest eccentricity ratio [-] of each film over one period, in the order of ``orbit.film_labels``
        (turbine inner, turbine outer, compressor inner, compressor outer)."""
        return self.orbit.eccentricity.max(axis=0)

    @property
    def mean_ring_speed_ratio(self):
        """Mean ring speed / rotor speed [-] of each bearing over one period."""
        return self.orbit.ring_speed_ratio[:-1].mean(axis=0)

    @property
    def nontrivial_multipliers(self):
        """The Floquet multipliers without the trivial one (closest to 1) of an autonomous orbit."""
        if not self.autonomous:
            return self.multipliers
        return np.delete(self.multipliers, int(np.argmin(np.abs(self.multipliers - 1.0))))

    def summary(self):
        """One-line description: speed, frequency, stability, largest multiplier, radius, max ε."""
        mu = self.nontrivial_multipliers
        lead = mu[int(np.argmax(np.abs(mu)))]
        kind = "stable" if self.stable else "unstable"
        return (f"{self.speed_rpm:.0f} rpm: {kind} orbit, {self.frequency_hz:.2f} Hz "
                f"({self.frequency_ratio:.3f} X), largest multiplier |{abs(lead):.4f}|, turbine wheel radius "
                f"{self.orbit_radius(self.orbit.schema.discs[0]) * 1e6:.2f} um, max eps "
                f"{np.array2string(self.max_eps, precision=3)}")

    def to_dataframe(self):
        """The orbit over one period as a table (the run-up's columns, units in the names)."""
        return self.orbit.to_dataframe()

    def to_xarray(self):
        """The orbit (:meth:`RunupResult.to_xarray`) with the multipliers and the orbit's scalars.

        Returns
        -------
        xarray.Dataset
        """
        ds = self.orbit.to_xarray()
        ds["multiplier_real"] = variable(("multiplier",), self.multipliers.real, "-", "Floquet multiplier, real part")
        ds["multiplier_imag"] = variable(("multiplier",), self.multipliers.imag, "-", "Floquet multiplier, imag part")
        ds["state"] = variable(("state_index",), self.state, "SI", "state at the start of the period")
        ds.attrs.update(netcdf_attrs({"limit_cycle": {"speed_rpm": self.speed_rpm, "period_s": self.period,
                                                      "stable": self.stable, "autonomous": self.autonomous,
                                                      **self.meta}}))
        return ds

    @classmethod
    def from_xarray(cls, ds):
        """The limit cycle from a dataset of :meth:`to_xarray` (e.g. a ``limit_cycle_<rpm>.nc`` of :meth:`save`).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        LimitCycle
            Without the monodromy matrix (not stored).
        """

        lc = decode_attr(ds.attrs["limit_cycle"])
        orbit = RunupResult.from_xarray(ds.drop_vars(["multiplier_real", "multiplier_imag", "state"]))
        orbit.meta.pop("limit_cycle", None)
        head = {k: lc.pop(k) for k in ("speed_rpm", "period_s", "stable", "autonomous")}
        return cls(float(head["speed_rpm"]), float(head["period_s"]), orbit,
                   ds["multiplier_real"].values + 1j * ds["multiplier_imag"].values, bool(head["stable"]),
                   ds["state"].values.copy(), bool(head["autonomous"]), lc)

    @property
    def stem(self) -> str:
        """File stem of :meth:`save`: ``limit_cycle_<rpm>``."""
        return f"limit_cycle_{self.speed_rpm:.0f}"

    def save(self, out_dir):
        """Write ``<stem>.csv`` (:meth:`to_dataframe`), ``<stem>.nc`` (:meth:`to_xarray`) and the figures
        ``<stem>.png`` / ``.html`` into the folder ``out_dir`` (created if missing); a path ending in ``.nc`` writes
        only that file. Returns the paths."""
        if Path(out_dir).suffix == ".nc":
            return self.to_netcdf(out_dir)
        return self.save_files(out_dir, self.stem)

    def plot(self, title=None):
        """Orbits over one period (journal in ring, ring in housing, wheels;
        :class:`frbmodel.signals.orbits.Orbits`)."""

        return orbits(self.orbit, time_s=(0.0, self.period)).plot(title=title or self.summary())

    def plot_html(self, path=None, title=None, include_plotlyjs=None):
        """Interactive orbits over one period (written to ``path`` if given).

        Parameters
        ----------
        path : str or Path, optional
            The HTML file (not written if None).
        title : str, optional
            Figure title (default: :meth:`summary`).
        include_plotlyjs : {"directory", True}, optional
            As for :func:`frbmodel.plots.figures.write_html`: plotly.js beside the page, or embedded in it.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        return orbits(self.orbit, time_s=(0.0, self.period)).plot_html(path, title=title or self.summary(),
                                                                       include_plotlyjs=include_plotlyjs)


def _crossings(t, x):
    """Times of the upward crossings of x through its mean (linear interpolation)."""
    x = x - x.mean()
    k = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k]), k


#: revolutions at most in the sampled end of a settling run (its orbit read-off): 9 whirl periods down to 0.045 X
TAIL_REVOLUTIONS = 200


def settle_guess(problem, settle_s, samples_per_rev=40, max_multiple=4, y0=None):
    """Guess (z0, period) from a constant-speed simulation of ``settle_s`` [s] from the method-J equilibrium (or
    from the full state ``y0``, e.g. a run-up's: :func:`runup_state`).

    Returns
    -------
    z0 : ndarray
        State at the last upward crossing of the turbine journal's x through its mean.
    period : float
        Smallest multiple of the mean crossing interval after which the state returns within RETURN_TOL.
    info : dict
        Crossing interval, multiple, return distance.

    Raises
    ------
    ConvergenceError
        The response settles on no periodic orbit (no crossings, or no return: quasi-periodic).
    """

    w = float(problem.profile.omega[0])
    dt = 2 * math.pi / w / samples_per_rev
    # the last TAIL_REVOLUTIONS revolutions, at most half the settling time (9 whirl periods down to ~0.05 X)
    tail = min(settle_s / 2, TAIL_REVOLUTIONS * 2 * math.pi / w)
    y0 = initial_state(problem) if y0 is None else y0
    atol = atol_vector(problem)[0]
    packed = pack_problem(problem)
    y_mid, _, msg = solve_chunk(packed, y0, np.array([0.0, settle_s - tail]), 1e-8, atol)
    if msg:
        raise ConvergenceError(f"limit cycle guess: the settling run failed ({msg})")
    t = settle_s - tail + np.arange(int(tail / dt) + 1) * dt
    y, _, msg = solve_chunk(packed, y_mid[-1], t, 1e-8, atol)
    if msg:
        raise ConvergenceError(f"limit cycle guess: the settling run failed ({msg})")
    if not np.all(np.isfinite(y)):
        raise ConvergenceError(f"limit cycle guess: the settling run at {w / RPM:.0f} rpm left the valid states "
                               "(non-finite: the journal or ring reached its wall)")
    j = 4 * problem.system.bearings[0].node
    tc, k = _crossings(t, y[:, j])
    if np.ptp(y[:, j]) < 1e-9 or tc.size < 2:
        raise ConvergenceError(f"limit cycle guess: no whirl at {w / RPM:.0f} rpm after {settle_s:g} s (the journal "
                               "stays at its equilibrium or drifts): no orbit to continue from")
    if tc.size < 2 * max_multiple + 1:
        need = 2 * (2 * max_multiple + 1) * float(np.mean(np.diff(tc)))
        remedy = (f"use settle_s >= {need:.2g} s" if tail >= settle_s / 2 else
                  f"the whirl is slower than {2 * max_multiple + 1} periods in {TAIL_REVOLUTIONS} revolutions: give "
                  "a guess (a neighbouring orbit, 'hopf' or (state, period))")
        raise ConvergenceError(f"limit cycle guess: only {tc.size} whirl periods in the last {tail:.3g} s of the "
                               f"settling run at {w / RPM:.0f} rpm ({2 * max_multiple + 1} needed to find the period): "
                               + remedy)
    size = np.ptp(y[:, :problem.n_rotor], axis=0).max()
    last = k[-1]
    for m in range(1, max_multiple + 1):
        back = k[-1 - m]
        dist = float(np.max(np.abs(y[last, :problem.n_rotor] - y[back, :problem.n_rotor]))) / size
        if dist < RETURN_TOL:
            return y[last, :-1].copy(), float(tc[-1] - tc[-1 - m]), {"crossing_interval_s": float(np.mean(np.diff(tc))),
                                                                     "multiple": m, "return_distance": dist}
    raise ConvergenceError(f"limit cycle guess: at {w / RPM:.0f} rpm the response does not repeat within "
                           f"{max_multiple} whirl periods (closest return {dist:.2g} of the orbit size): it is not "
                           "periodic (quasi-periodic: two whirl frequencies) or has not settled (longer settle_s)")


def _forced_guess(problem, y, t, samples_per_rev, max_multiple):
    """Guess of a forced (unbalanced) orbit: the state at the last whole rotor revolution and the smallest number of
    revolutions after which it returns (samples every 1/samples_per_rev revolution from a whole revolution)."""
    w = float(problem.profile.omega[0])
    size = np.ptp(y[:, :problem.n_rotor], axis=0).max()
    last = (y.shape[0] - 1) // samples_per_rev * samples_per_rev
    dist = math.inf
    for m in range(1, max_multiple + 1):
        back = last - m * samples_per_rev
        dist = float(np.max(np.abs(y[last, :problem.n_rotor] - y[back, :problem.n_rotor]))) / max(size, 1e-30)
        if dist < RETURN_TOL:
            return y[last, :-1].copy(), m * 2 * math.pi / w, {"multiple": m, "return_distance": dist}
    raise ConvergenceError(f"limit cycle guess: at {w / RPM:.0f} rpm the unbalance response does not repeat within "
                           f"{max_multiple} revolutions (closest return {dist:.2g} of the orbit size): not locked to "
                           "1X or a sub-harmonic (quasi-periodic), or not settled (longer settle_s)")


def limit_cycle(system, speed_rpm, guess=None, film_model=None, unbalance=(), settle_s=0.3, tol=1e-6,
                samples=400, max_iter=25, segments=1, oil_supply=None):
    """Periodic whirl orbit of the full nonlinear model at a constant rotor speed, with its Floquet multipliers.

    Parameters
    ----------
    system : Turbocharger
        The system (two floating-ring bearings).
    speed_rpm : float
        Constant rotor speed [rpm].
    guess : LimitCycle, RunupResult, "hopf" or (ndarray, float), optional
        A nearby orbit (e.g. at a neighbouring speed); ``"hopf"``: the orbit born at the nearest Hopf point, followed
        there from its eigenvector (:func:`frbmodel.cycles.branch.hopf_guess`; autonomous orbits only); a recorded
        run-up or run-down of this system, whose state where it passes the speed (re-simulated, :func:`runup_state`)
        settles for ``settle_s`` instead of the equilibrium: the orbit of the attractor the run is on there; or (state
        without the rotation angle [SI], period [s]). Default: settle from the equilibrium for ``settle_s`` and read the
        orbit off (:func:`settle_guess`).
    film_model : {"short", "short_corrected"}, optional
        Default: the system's.
    unbalance : sequence of Unbalance
        With unbalance the orbit is forced: its period is a whole number of rotor revolutions.
    settle_s : float
        Settling time [s] of the guess simulation.
    tol : float
        Newton tolerance on the scaled residual (displacements in µm: 1e-6 is 1e-12 m).
    samples : int
        Samples of the returned orbit over one period.
    max_iter : int
        Newton iterations at most.
    segments : int
        Shooting segments: 1 single shooting; m > 1 multiple shooting
        (:func:`frbmodel.cycles.branch.shoot_segments`),
        for strongly unstable orbits (a flow over the period amplifies errors by the largest multiplier |mu|, a
        segment by ~|mu|^(1/m)); autonomous orbits only.
    oil_supply : OilSupply, optional
        The thermal model: the orbit of the system at the thermal operating point of ``speed_rpm``
        (:func:`frbmodel.linear.thermal.thermal_system`: the films' viscosities at their temperatures there, the
        quasi-static temperatures of a run-up at that constant speed); ``meta`` records it (``oil_supply``) and the
        four viscosities [Pa s] (``film_viscosities_Pa_s``). A recorded run-up as ``guess`` is refused with it.
        Default None: constant viscosities.

    Returns
    -------
    LimitCycle

    Raises
    ------
    ConvergenceError
        No whirl, no periodic response (quasi-periodic), or Newton failed — with the reason.
    ParameterError
        Invalid speed or settling time.
    """

    speed_rpm = check_speed("speed", speed_rpm)
    system = _at_supply(system, speed_rpm, guess, oil_supply)
    model = check_model(film_model or system.film_model)
    problem = build_problem(system, SpeedProfile.constant(speed_rpm, 1.0), model, unbalance)
    forced = any(u.amount > 0 for u in unbalance)
    _check_segments(segments, forced)
    _check_newton(tol, samples, max_iter)
    z0, period, info, m0 = _initial_guess(system, problem, model, speed_rpm, guess, settle_s, forced)
    flow = ConstantSpeedFlow(problem, SHOOT_RTOL, SHOOT_ATOL_M)
    scale = atol_vector(problem, SCALE_M)[0][:-1]
    if segments != 1:
        sol = _multiple(system, model, speed_rpm, z0, period, segments, forced, tol, max_iter)
    else:
        sol = shoot(flow, flow.rhs, z0, period, scale=scale, autonomous=not forced, tol=tol, max_iter=max_iter,
                    fd_step=FD_STEP, workers=WORKERS, monodromy0=m0)
        sol = _minimal_period(flow, sol, scale, forced, tol, max_iter)
    t = np.linspace(0.0, sol.period, samples + 1)
    y = flow.states(sol.z0, t)
    orbit = orbit_result(problem, RunupSchema.from_system(system), t, y)
    meta = {"film_model": model, "rtol": SHOOT_RTOL, "atol_displacement_m": SHOOT_ATOL_M, "newton_iterations":
            sol.iterations, "residual_scaled": sol.residual, "flow_integrations": flow.evaluations, "guess": info}
    if oil_supply is not None:
        meta.update(oil_supply=oil_supply.to_dict(),
                    film_viscosities_Pa_s=[f.viscosity for b in system.bearings for f in (b.inner, b.outer)])
    stable = stable_multipliers(sol.nontrivial_multipliers, MULTIPLIER_TOL)
    return LimitCycle(speed_rpm, sol.period, orbit, sol.multipliers, stable, sol.z0, not forced, meta, sol.monodromy)


def _at_supply(system, speed_rpm, guess, oil_supply):
    """``system`` at the thermal operating point of ``speed_rpm`` (unchanged without an oil supply); a recorded
    run-up as the guess is refused with an oil supply (its re-simulation would need the run's viscosity table)."""

    supply = check_oil_supply(oil_supply, bearings=system.bearings)
    if supply is not None and isinstance(guess, RunupResult):
        raise ParameterError("guess = a RunupResult cannot be combined with oil_supply: the run is re-simulated at "
                             "constant viscosities; give a LimitCycle, 'hopf', (state, period) or no guess")
    return at_operating_point(system, speed_rpm, supply)


def _initial_guess(system, problem, model, speed_rpm, guess, settle_s, forced):
    """(state, period, info, monodromy or None) of each kind of ``guess`` of :func:`limit_cycle`."""

    if guess is None:
        return (*_guess(problem, settle_s, forced), None)
    if isinstance(guess, LimitCycle):
        return guess.state.copy(), guess.period, {"from_orbit_at_rpm": guess.speed_rpm}, guess.monodromy
    if isinstance(guess, str):
        if guess != "hopf" or forced:
            raise ParameterError(f"guess = {guess!r} is invalid" + (" with unbalance (a Hopf point's orbit is "
                                                                    "autonomous)" if guess == "hopf" else
                                                                    ": 'hopf', a LimitCycle, a RunupResult or "
                                                                    "(state, period)"))
        return (*hopf_guess(system, speed_rpm, model), None)
    if isinstance(guess, RunupResult):
        y_run, from_run = runup_state(guess, system, speed_rpm)
        y_run[-1] = 0.0  # the rotation angle: a forced orbit's revolutions are counted from angle 0 at t = 0
        z0, period, info = _guess(problem, settle_s, forced, y0=y_run)
        return z0, period, {**from_run, **info}, None
    return (*_given_guess(guess, problem.n_states - 1), {"given": True}, None)


def _given_guess(guess, n):
    """(state, period) of a guess given as a pair, or a ParameterError naming what is wrong with it."""
    try:
        state, period = guess
        state, period = np.asarray(state, dtype=float), float(period)
    except (TypeError, ValueError):
        raise ParameterError(f"guess = {type(guess).__name__} is invalid: a LimitCycle, a RunupResult, 'hopf' or "
                             "(state without the rotation angle [SI], period [s])") from None
    if state.shape != (n,) or not np.all(np.isfinite(state)):
        raise ParameterError(f"guess state: shape {state.shape}{'' if np.all(np.isfinite(state)) else ', non-finite'}"
                             f" is invalid: {n} finite values (the run-up state without the rotation angle) needed")
    if not (math.isfinite(period) and period > 0):
        raise ParameterError(f"guess period = {period!r} s is invalid: valid range (0, inf) s")
    return state, period


def _check_segments(segments, forced):
    """Refuse a segment count that is not a whole number in 1 ... MAX_SEGMENTS, or > 1 for a forced orbit (before
    any work)."""
    check_segments("segments", segments)
    if forced and segments > 1:
        raise ParameterError(f"segments = {segments} is for autonomous orbits: with unbalance use segments = 1")


#: the loosest Newton tolerance of :func:`limit_cycle` (scaled residual, displacements in µm: 1e-3 is 1 nm)
MAX_TOL = 1e-3
#: the fewest points per period of a limit cycle's orbit
MIN_SAMPLES = 16


def _check_newton(tol, samples, max_iter):
    """Refuse, before the settling run, a Newton tolerance outside 0 < tol <= :data:`MAX_TOL`, fewer than
    :data:`MIN_SAMPLES` orbit points or fewer than one Newton iteration (they were used only after seconds of
    settling: tol = 1e3 would accept any orbit, samples = 1 draw it with two points)."""
    tol = check_positive("tol", tol)
    if tol > MAX_TOL:
        raise ParameterError(f"tol = {tol!r} is invalid: valid range 0 < tol <= {MAX_TOL:g} (the scaled residual, "
                             "displacements in µm; a looser one accepts an orbit that is not periodic)")
    for name, v, low in (("samples", samples, MIN_SAMPLES), ("max_iter", max_iter, 1)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
            raise ParameterError(f"{name} = {v!r} is invalid: valid range integer >= {low}")


def _multiple(system, model, speed_rpm, z0, period, segments, forced, tol, max_iter):
    """Multiple shooting of an autonomous orbit."""

    return shoot_segments(system, model, speed_rpm, z0, period, int(segments), tol, max_iter)


def _minimal_period(flow, sol, scale, forced, tol, max_iter):
    """The orbit with its minimal period: if the state already returns after T / d (d = 4, 3, 2; for a forced orbit
    only divisors that leave whole revolutions), shoot again from there (a guess spanning two periods converges to
    the doubled orbit, which is a solution too)."""

    revs = round(sol.period * float(flow.problem.profile.omega[0]) / (2 * math.pi)) if forced else 0
    for d in (4, 3, 2):
        if forced and revs % d:
            continue
        end = flow(sol.z0, sol.period / d)
        if np.max(np.abs(end - sol.z0) / scale) < 1e3 * tol:
            return shoot(flow, flow.rhs, sol.z0, sol.period / d, scale=scale, autonomous=not forced, tol=tol,
                         max_iter=max_iter, fd_step=FD_STEP, workers=WORKERS)
    return sol


#: largest journal position difference between a re-simulated run-up and the recorded run at the guess sample, as a
#: fraction of the inner clearance, that still counts as the same run (the same integrator and tolerances give ~1e-9;
#: a round-off-seeded whirl growing at that time can make the runs part)
RERUN_TOL = 0.05


def _rerun_inputs(run, system):
    """Unbalance and run-up options of a recorded monolithic run-up, or a ParameterError saying why it cannot be
    re-simulated for ``system``."""

    meta = run.meta
    why = ("it is a co-simulation (its states live in the FMUs)" if "ssp" in meta else
           "it is torque-driven" if meta.get("speed_source") == "torque" else
           "it ran on linear springs" if meta.get("linear_springs_N_per_m") is not None else
           "its metadata has no system" if "system" not in meta else
           "it was computed for another system" if meta["system"] != system.to_dict() else "")
    if why:
        raise ParameterError(f"guess = a run-up result: {why}; a run-up guess re-simulates a monolithic, "
                             "speed-prescribed frb.runup of the same system")
    unb = [Unbalance(**u) for u in meta.get("unbalance", [])]
    opts = {k: meta[m] for k, m in (("rtol", "rtol"), ("atol", "atol_displacement_m"), ("integrator", "integrator"),
                                    ("perturbation", "perturbation_of_clearance"), ("contact_eps", "contact_eps"),
                                    ("output_rate_hz", "output_rate_hz")) if m in meta}
    return unb, opts


def runup_state(run, system, speed_rpm):
    """The full state of a recorded run-up where its speed first reaches ``speed_rpm``, to start a limit-cycle
    guess from the attractor the run is on there (e.g. a run-down's whirl where a settling run from the equilibrium
    finds another orbit).

    The recorded results hold no full state, so the run is re-simulated up to the first sample at or past that
    speed: the same system, unbalance, start, tolerances and integrator, with the recorded speeds as a
    piecewise-linear profile (exact for a ramp). The re-simulated journal positions there are checked against the
    recorded ones (:data:`RERUN_TOL` of the inner clearance).

    Parameters
    ----------
    run : RunupResult
        A monolithic, speed-prescribed run-up (or run-down) of ``system`` (:func:`frbmodel.nonlinear.runup`, or loaded).
    system : Turbocharger
    speed_rpm : float

    Returns
    -------
    state : ndarray
        Full state vector of the run-up problem at that sample [SI] (re-simulated with the run's film model and
        contact limit).
    info : dict
        ``run_time_s``, ``run_speed_rpm`` of the sample, ``rerun_difference_of_clearance``.

    Raises
    ------
    ParameterError
        The run cannot be re-simulated (co-simulation, torque-driven, linear springs, another system) or does not
        reach the speed.
    ConvergenceError
        The re-simulation departs from the recorded run by more than :data:`RERUN_TOL`.
    """

    unb, opts = _rerun_inputs(run, system)
    d = np.asarray(run.speed_rpm, dtype=float) - speed_rpm
    hit = np.flatnonzero((d[:-1] < 0) != (d[1:] < 0))
    if not hit.size:
        raise ParameterError(f"speed {speed_rpm:.0f} rpm is not reached by the run-up guess (its speeds "
                             f"{np.min(run.speed_rpm):.0f} ... {np.max(run.speed_rpm):.0f} rpm)")
    k = int(hit[0]) + 1
    prof = SpeedProfile.piecewise_linear(run.time[:k + 1], run.speed_rpm[:k + 1], "the recorded run's speeds")
    rerun = runup(system, profile=prof, duration=float(run.time[k]), film_model=run.meta.get("film_model"),
                  unbalance=unb, progress=False, **opts)
    diff = max(float(np.max(np.abs(rerun.journal[b.name][-1] - run.journal[b.name][k]))) / b.inner.clearance
               for b in system.bearings)
    info = {"run_time_s": float(run.time[k]), "run_speed_rpm": float(run.speed_rpm[k]),
            "rerun_difference_of_clearance": diff}
    if not diff <= RERUN_TOL:
        raise ConvergenceError(f"limit cycle guess: the run-up re-simulated to t = {run.time[k]:.6g} s "
                               f"({run.speed_rpm[k]:.0f} rpm) differs from the recorded run by {diff:.2g} of the inner "
                               f"clearance (> {RERUN_TOL}): the run is not reproducible there (a whirl growing from "
                               "round-off, or another version or integrator); use the default settling guess or a "
                               "seeded (unbalanced) run")
    return rerun.final_state, info


def _guess(problem, settle_s, forced, samples_per_rev=40, max_multiple=4, y0=None):
    """(z0, period, info) from a settling simulation (from the equilibrium or ``y0``): forced by whole
    revolutions, autonomous by crossings."""

    settle_s = check_positive("settle_s", settle_s, "s")
    if not forced:
        return settle_guess(problem, settle_s, samples_per_rev, max_multiple, y0)

    rev = 2 * math.pi / float(problem.profile.omega[0])
    n_rev = max(int(settle_s / rev), 2 * max_multiple + 1)
    tail = min(n_rev // 2, 60)
    t = (n_rev - tail) * rev + np.arange(tail * samples_per_rev + 1) * rev / samples_per_rev
    packed, atol = pack_problem(problem), atol_vector(problem)[0]
    y_start = initial_state(problem) if y0 is None else y0
    y_mid, _, msg = solve_chunk(packed, y_start, np.array([0.0, t[0]]), 1e-8, atol)
    y, _, msg2 = solve_chunk(packed, y_mid[-1], t, 1e-8, atol) if not msg else (None, 0, msg)
    if msg or msg2:
        raise ConvergenceError(f"limit cycle guess: the settling run failed ({msg or msg2})")
    return _forced_guess(problem, y, t, samples_per_rev, max_multiple)


__all__ = ["LimitCycle", "limit_cycle", "runup_state", "settle_guess"]
