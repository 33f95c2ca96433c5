"""Co-simulation master on fmpy's FMU2Slave, driven by the SSP (:class:`Master`, :func:`cosimulate`).

Per communication point: the rotor's outputs (journal states, speed) go to the bearings; the bearings' outputs
(force, interface stiffness and damping, the journal state they belong to) are read *after* their inputs are set and
go to the rotor. Then the bearings step first (journal on a quadratic path) and publish their end-of-step force and
journal acceleration, which go to the rotor before it steps (staggered coupling, README "Using the FMUs"). One
getReal per FMU and direction, one setReal per FMU and step: the rotor's inputs (the bearings' outputs of the
communication point, their end-of-step values, a profile's speed) are set together just before its doStep, and at a
recorded point the recorded outputs come with the exchange's getReal calls (11 FMI calls per macro step, was 13).
Every FMI call goes through :meth:`FmuInstance.call` (status checked, optional trace). Results stream through the
:class:`~frbmodel.nonlinear.recorder.Recorder` in the same format as the monolithic run-up, so the same spectrogram and
composite figure apply. Optional rollback: an interval that an FMU discards (or whose new state gives non-finite
outputs) is retried with half the step after restoring all FMU states. Optional error-controlled macro step
(``adaptive``): each step's coupling error is the journal path defect (:meth:`Master.coupling_error`); steps above
the tolerance are rolled back and retried shorter. The rotor speed can follow a
:class:`~frbmodel.nonlinear.runup.SpeedProfile` through the rotor FMU's ``speed_in`` (``profile``).
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from ..core.errors import CosimStopped, ParameterError, check_positive
from ..core.interrupt import deferred_signals
from ..core.progress import simulation_bar
from ..core.units import rad_s_to_rpm, rpm_to_rad_s
from ..linear.equilibrium import equilibrium
from ..nonlinear.recorder import Recorder, RunupResult, RunupSchema
from ..nonlinear.runup import ATOL_MAX_OF_CLEARANCE, MAX_SAMPLES, check_drive_torque_value
from ..physics.dynamics import rotor_polar_inertia
from ..physics.film import Film
from ..system.parameters import load_system
from ..system.presets import turbocharger
from .fmu import FmiCallFailed, FmuHost
from .fmu_system import rotor_system_of_fmu
from .ssp import read_ssp

BEARING_FMU, ROTOR_FMU = "FloatingRingBearing", "TurbochargerRotor"
#: connectors passed after the bearings have stepped (staggered coupling)
END_OF_STEP = ("force_end", "journal_accel")
#: macro steps [s] whose coupling error was measured against the monolithic run-up (README "Using the FMUs"):
#: 10 µs reproduces the run-up's onsets; at 20 µs slow components still differ; 1 ms is wrong by up to Δε = 0.64
VALIDATED_STEP_S = (1e-7, 2e-5)
#: bearing outputs recorded per bearing, in the order the recorder's row needs them
BEARING_RECORD = ("ring.speed", "ring.x", "ring.y", "eps_inner", "eps_outer")
#: bearing outputs recorded per bearing when the FMU has them (film torque on the journal [N m], power loss [W])
BEARING_LOSSES = ("journal_torque", "power_loss")
#: length [s] of the first sub-step of a profile-driven run. The rotor FMU's speed input (speed_source = "input")
#: takes its angular acceleration from its last two inputs and has none before the first step, so a first macro
#: step of full length would run at constant speed (an error of half a step's speed change in that step). After
#: this sub-step it has the profile's slope; the sub-step's own missing acceleration changes the rotation angle by
#: Ω̇ δ²/2 (~1e-14 rad at the main job's 24 000 rad/s²), far below round-off of the states.
PRIME_STEP_S = 1e-9
#: default tolerance of the adaptive macro step: the largest accepted journal path defect per step (see
#: :meth:`Master.coupling_error`) as a fraction of the bearing's inner clearance
COUPLING_TOL = 2e-4
#: largest tolerance of the adaptive macro step (a fraction of the inner clearance, as :data:`COUPLING_TOL`): the
#: monolithic run-up's bound on its local displacement error (``atol`` at most 1e-3 of the smallest film clearance,
#: :data:`frbmodel.nonlinear.runup.ATOL_MAX_OF_CLEARANCE`), and the path defect of the longest validated step on the
#: main job: O(h³) from the 1.3e-4 measured at 10 µs, 8 × 1.3e-4 ≈ 1e-3 at 20 µs. A larger tolerance asks for steps
#: beyond the validated range, which the step cap (:data:`ADAPTIVE_MAX_STEP_S`) overrides without a word: it would
#: decide no step (10 was accepted and ran as the fixed 12.5 µs run)
MAX_COUPLING_TOL = ATOL_MAX_OF_CLEARANCE
#: default longest adaptive step [s]. Measured on the main job's first 0.5 s (20 -> 135 krpm, 0.1 g mm seed): a fixed
#: 12.5 µs step gives every onset of the 10 µs run within 0.04 %, while at 15 µs a spurious 0.52X component (285 Hz
#: from 32.9 krpm) appears, and at 20 µs the 35 and 52 krpm components are lost — although the path defect there
#: is a tenth of its value at high speed: the low-speed components are sensitive to the step in a way no local
#: error estimate of the coupling shows, so the step is capped where it was checked.
ADAPTIVE_MAX_STEP_S = 1.25e-5


def check_coupling_tol(name, tolerance):
    """``float(tolerance)`` if 0 < tolerance <= :data:`MAX_COUPLING_TOL` (the adaptive macro step's path defect per
    step as a fraction of the inner clearance), else a :class:`ParameterError` naming ``name``, the value and the
    range.

    Examples
    --------
    >>> try:
    ...     check_coupling_tol("coupling tolerance", 10.0)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    coupling tolerance = 10.0 is invalid: valid range 0 < tolerance <= 0.001 (of the inner clearance per step: ...
    """
    tol = check_positive(name, tolerance)
    if tol > MAX_COUPLING_TOL:
        raise ParameterError(f"{name} = {tolerance!r} is invalid: valid range 0 < tolerance <= {MAX_COUPLING_TOL:g} "
                             "(of the inner clearance per step: the run-up's displacement tolerance bound; a larger "
                             "one asks for steps beyond the validated range, which the step cap overrides)")
    return tol


def _checked_profile(profile):
    """``profile`` (None or a prescribed-speed SpeedProfile) or a ParameterError saying why not."""
    if profile is None:
        return None
    if not all(hasattr(profile, a) for a in ("t", "omega", "description")) or not callable(profile):
        raise ParameterError(f"profile = {profile!r} is invalid: use a frbmodel.nonlinear.runup.SpeedProfile (e.g. "
                             "SpeedProfile.from_csv)")
    if getattr(profile, "torque_driven", False):
        raise ParameterError(f"profile = {profile.description!r} is torque-driven: a co-simulation takes a "
                             "prescribed speed profile; for a torque-driven rotor use the rotor parameter "
                             "speed_source = 'torque' (frb cosim --speed-source torque)")
    return profile


def check_whole_steps(stop_time, step_size, what="stop time", option="--stop-time", other=" (or --adaptive)"):
    """Raise :class:`ParameterError` unless ``stop_time`` is a whole number of fixed macro steps ``step_size`` [s]
    (to 1e-9 of a step): the run takes round(T / H) steps, so it ended short of or beyond the stop time it reported.
    ``option`` is where the user gives the stop time and ``other`` the way around it, for the message."""
    n = stop_time / step_size
    if abs(n - round(n)) > 1e-6:
        lo, hi = math.floor(n) * step_size, math.ceil(n) * step_size
        raise ParameterError(f"{what} = {stop_time!r} s is not a whole number of macro steps of {step_size!r} s "
                             f"({n:.6g} steps): the run would end at {round(n) * step_size:.9g} s; valid: a multiple "
                             f"of the step as {option}, e.g. {lo:.9g} or {hi:.9g} s{other}")


def check_record_size(stop_time, output_rate_hz, what="stop time"):
    """``float(output_rate_hz)`` if a co-simulation to ``stop_time`` [s] records at most
    :data:`~frbmodel.nonlinear.runup.MAX_SAMPLES` samples at that rate [Hz], else a :class:`ParameterError` naming
    ``what``, the rate and the valid range (the recorder holds them in memory: 2e8 samples asked for 39 GB)."""
    rate = check_positive("output_rate_hz", output_rate_hz, "Hz")
    if stop_time * rate > MAX_SAMPLES:
        raise ParameterError(f"{what} = {stop_time:g} s is invalid at output_rate_hz = {rate:g} Hz: "
                             f"{stop_time * rate:.3g} samples, valid range <= {MAX_SAMPLES:.0e} samples ({what} <= "
                             f"{MAX_SAMPLES / rate:g} s)")
    return rate


def _profile_stop_time(profile, stop_time):
    """The stop time [s] of a profile-driven run: the profile's last time by default; later is an error."""
    end = float(profile.t[-1])
    if stop_time is None:
        return end
    if stop_time > end * (1.0 + 1e-12):
        raise ParameterError(f"stop time = {stop_time:g} s is beyond the speed profile's last time {end:g} s "
                             f"({profile.description}): valid range up to {end:g} s")
    return stop_time


def system_from_parameters(params, default=None):
    """The frbmodel Turbocharger described by an SSP parameter set: the rotor's ``rotor_file`` (empty: ``default``,
    the system the rotor FMU was built for, else Table 2) with each bearing's film and ring parameters taken from
    the bearing component of the same name."""
    from dataclasses import replace


    sys_file = params.get("rotor", {}).get("rotor_file", ("String", ""))[1]
    tc = load_system(sys_file) if sys_file else (default if default is not None else turbocharger())
    bs = []
    for b in tc.bearings:
        p = {k: v[1] for k, v in params.get(b.name, {}).items()}
        films = [Film(p.get(f"{f}.radius", film.radius), p.get(f"{f}.length", film.length),
                      p.get(f"{f}.clearance", film.clearance), p.get(f"{f}.viscosity", film.viscosity))
                 for f, film in (("inner", b.inner), ("outer", b.outer))]
        bs.append(replace(b, inner=films[0], outer=films[1], ring_mass=p.get("ring.mass", b.ring_mass),
                          ring_inertia=p.get("ring.inertia", b.ring_inertia)))
    model = params.get(tc.bearings[0].name, {}).get("film_model", ("String", tc.film_model))[1]
    return tc.with_(bearings=tuple(bs), film_model=model)


class Master(FmuHost):
    """Fixed-step (optionally rolling-back) or error-controlled co-simulation of an SSP system of one rotor and its
    bearing FMUs.

    Parameters
    ----------
    ssp : path
        ``.ssp`` archive or folder (SystemStructure.ssd + resources/).
    parameter_set : str
        Name of the parameter set (``co36``, ``co40``, ``co42``, ``co46``).
    stop_time, step_size : float, optional
        Default: the SSP's DefaultExperiment stop time and OSP fixed step [s].
    overrides : dict, optional
        {component: {parameter: (type, value)}} applied after the parameter set.
    coupling : {"jacobian", "force"}
        "force" drops the stiffness/damping connections (plain force exchange, for comparison).
    rollback : bool
        Retry a discarded interval with half steps (up to ``max_halvings``) after restoring all FMU states.
    trace : callable, optional
        Receives one line per FMI call (``frb cosim --trace-fmi``).
    unvalidated_step : bool
        Allow a macro step outside :data:`VALIDATED_STEP_S` (otherwise a ParameterError).
    profile : SpeedProfile, optional
        Prescribed rotor speed (:class:`frbmodel.nonlinear.runup.SpeedProfile`, e.g. ``SpeedProfile.from_csv``; not
        torque-driven). The rotor runs with ``speed_source = "input"``: ``speed_in`` is the profile's speed at
        t = 0 during initialization and the profile's speed at the start of every (sub)step before it is taken
        (again after a rollback). The rotor FMU takes the angular acceleration over a step from its last two speed
        inputs (none before the first step), so the first macro step starts with a sub-step of
        :data:`PRIME_STEP_S`: from the second sub-step on, the rotor's speed is linear over each step with the
        profile's slope, as in the ramp mode. Default stop time: the profile's last time; a later one is an error.
    adaptive : bool
        Error-controlled macro step (``step_size`` is then the first step, and the output interval is that of the
        fixed-step run, ``round(1 / (step_size · output_rate_hz))`` steps): every step is taken after saving all
        FMU states, its coupling error :meth:`coupling_error` is compared with ``tolerance``, and the step is
        accepted (and the next one grown, at most ×2) or rolled back and retried shorter (at least ×1/4), within
        ``min_step`` ... ``max_step``. The steps land on the output times (each output interval is split into equal
        steps no longer than the proposed one), so the recorded samples are FMU states, not interpolations. Needs
        the Jacobian coupling with the staggered connections and FMUs that can get and set their state.
    tolerance : float
        Largest accepted path defect per step as a fraction of each bearing's inner clearance (default
        :data:`COUPLING_TOL`).
    min_step, max_step : float, optional
        Bounds of the adaptive step [s] (default: the lower end of :data:`VALIDATED_STEP_S` and
        :data:`ADAPTIVE_MAX_STEP_S`; outside :data:`VALIDATED_STEP_S` only with ``unvalidated_step``). A step at
        ``min_step`` is accepted whatever its error (counted in the metadata as ``forced_steps``).

    Attributes
    ----------
    steps_taken, rejected_steps : int
        Steps accepted and steps rejected (rolled back) so far.
    accepted_steps : list of (float, float)
        Adaptive only: start time and length [s] of every accepted step, in order.

    Use as a context manager (or call :meth:`close`): the FMU instances are freed and the extracted files deleted.
    """

    def __init__(self, ssp, parameter_set="co36", stop_time=None, step_size=None, overrides=None,
                 coupling="jacobian", rollback=False, max_halvings=6, trace=None, unvalidated_step=False,
                 profile=None, adaptive=False, tolerance=COUPLING_TOL, min_step=None, max_step=None):
        if coupling not in ("jacobian", "force"):
            raise ParameterError(f"coupling = {coupling!r} is unknown; valid: 'jacobian', 'force'")
        self.ssp_path, self.parameter_set, self.coupling = ssp, parameter_set, coupling
        self.fmus, self._tmp = {}, None
        self.profile = _checked_profile(profile)
        self.ssp = read_ssp(ssp)
        what = "stop time" if stop_time is not None or profile is None else "stop time (the speed profile's last time)"
        try:
            if self.profile is not None:
                stop_time = _profile_stop_time(self.profile, stop_time)
            self._configure(parameter_set, stop_time, step_size, overrides, rollback, max_halvings, trace,
                            unvalidated_step)
            self.adaptive = bool(adaptive)
            if self.adaptive and self.rollback:
                raise ParameterError("rollback = True (--rollback) does not apply with adaptive = True (--adaptive): "
                                     "the adaptive step already rolls back every discarded or too inaccurate step "
                                     "and retries it shorter, down to its min_step; use one of them")
            if self.adaptive:
                self._configure_adaptive(tolerance, min_step, max_step, unvalidated_step)
            else:
                check_whole_steps(self.stop_time, self.step_size, what)
        except BaseException:
            self.ssp.close()
            raise

    def _configure(self, parameter_set, stop_time, step_size, overrides, rollback, max_halvings, trace,
                   unvalidated_step):
        self.params = self.ssp.parameters(parameter_set)
        for comp, ov in (overrides or {}).items():
            self.params.setdefault(comp, {}).update(ov)
        self.stop_time = float(stop_time if stop_time is not None else (self.ssp.stop_time or 1.0))
        self.step_size = float(step_size if step_size is not None else (self.ssp.step_size or 1e-5))
        H, T = self.step_size, self.stop_time
        if not (H > 0 and T > 0 and math.isfinite(H) and math.isfinite(T)):
            raise ParameterError(f"step size = {H!r} s and stop time = {T!r} s must be finite and > 0")
        if T < H * (1 - 1e-9):
            raise ParameterError(f"stop time = {T!r} s is invalid: it is shorter than the macro step {H!r} s, so the "
                                 f"run would take no step; valid range >= {H!r} s")
        lo, hi = VALIDATED_STEP_S
        if not lo <= H <= hi and not unvalidated_step:
            raise ParameterError(f"macro step = {H:g} s is outside the validated range {lo:g} ... {hi:g} s (the "
                                 "coupling error was measured there; larger steps give wrong orbits without failing). "
                                 "Use --unvalidated-step (unvalidated_step=True) to run it anyway")
        self.rollback, self.max_halvings, self.trace = bool(rollback), int(max_halvings), trace
        self.system = system_from_parameters(self.params, self._rotor_system())
        torque = self.params.get("rotor", {}).get("drive_torque")
        if torque is not None:  # (the rotor FMU would discard the first step: a folder with one sample, exit 3)
            check_drive_torque_value("drive torque", torque[1], rotor_polar_inertia(self.system.rotor))
        self.fmi_time_s = 0.0
        self.fmi_calls = {}  # {function: [calls, wall time [s]]} over all FMU instances, collected at close()
        self.rejected_steps = 0
        self.steps_taken = 0
        self.forced_steps = 0  # adaptive steps accepted at min_step above the tolerance
        self._xvals, self._evals = [[], []], []  # the values of the last exchange (per phase) and end-of-step pass
        if self.profile is not None:
            self._profile_parameters(overrides)

    def _configure_adaptive(self, tolerance, min_step, max_step, unvalidated_step):
        """Check the adaptive step's tolerance and bounds (the first step is ``step_size``, clipped to them)."""

        if self.coupling != "jacobian":
            raise ParameterError("the adaptive macro step estimates the coupling error of the staggered Jacobian "
                                 f"coupling; coupling = {self.coupling!r} has none: use coupling = 'jacobian'")
        self.tolerance = check_coupling_tol("coupling tolerance", tolerance)
        lo, hi = VALIDATED_STEP_S
        self.min_step = check_positive("min_step", lo if min_step is None else min_step, "s")
        self.max_step = check_positive("max_step", ADAPTIVE_MAX_STEP_S if max_step is None else max_step, "s")
        if self.min_step > self.max_step:
            raise ParameterError(f"min_step = {self.min_step:g} s is above max_step = {self.max_step:g} s")
        if not unvalidated_step and not lo <= self.min_step <= self.max_step <= hi:
            raise ParameterError(f"adaptive step bounds {self.min_step:g} ... {self.max_step:g} s are outside the "
                                 f"validated range {lo:g} ... {hi:g} s; use --unvalidated-step "
                                 "(unvalidated_step=True) to run them anyway")
        self.step_size = min(max(self.step_size, self.min_step), self.max_step)
        self.accepted_steps = []  # (t [s], h [s]) of every accepted step

    def _profile_parameters(self, overrides):
        """Refuse overrides that set another speed source than the profile's (set up in :meth:`setup`)."""
        for comp, ov in (overrides or {}).items():
            source = ov.get("speed_source", ("String", "input"))[1]
            if source != "input":
                raise ParameterError(f"{comp}.speed_source = {source!r} conflicts with the speed profile "
                                     f"({self.profile.description}): a profile drives the rotor through speed_in "
                                     "(speed_source = 'input')")

    def _rotor_system(self):
        """The system the SSP's rotor FMU was built for (None if the SSP has no rotor FMU file to read)."""
        import zipfile


        for path in self.ssp.components.values():
            if ROTOR_FMU in Path(path).name and zipfile.is_zipfile(path):  # (FMU errors are reported at setup)
                return rotor_system_of_fmu(path)
        return None

    # ------------------------------------------------------------------ set-up
    def setup(self):
        """Extract and instantiate every FMU, identify rotor and bearings, plan the exchange."""
        self._instantiate("frb_cosim_")
        rotors = [f for f in self.fmus.values() if f.model_identifier == ROTOR_FMU]
        if len(rotors) != 1:
            raise ParameterError(f"{self.ssp_path}: the system needs exactly one {ROTOR_FMU} component, found "
                                 f"{[f.name for f in rotors]}")
        self.rotor = rotors[0]
        names = [b.name for b in self.system.bearings]
        found = sorted(f.name for f in self.fmus.values() if f.model_identifier == BEARING_FMU)
        if sorted(names) != found:
            raise ParameterError(f"{self.ssp_path}: the {BEARING_FMU} components {found} do not match the rotor "
                                 f"system's bearings {names}")
        self.bearings = [self.fmus[n] for n in names]
        self._check_fed_inputs()
        self._plan_exchange()
        self.schema = RunupSchema.from_system(self.system)
        self._rec_rotor = self.rotor.vr(["rotor_speed"] + [f"{n}_bearing.journal.{q}" for n in names for q in "xy"] +
                                        [f"{d}.{q}" for d in self.schema.discs for q in "xy"])
        self._rec_bearing = [b.vr(BEARING_RECORD + (BEARING_LOSSES if all(map(b.has, BEARING_LOSSES)) else ()))
                             for b in self.bearings]
        self._speed_vr = []
        if self.profile is not None:  # speed_source "input", speed_in = the profile at t = 0
            self.params.setdefault(self.rotor.name, {}).update(speed_source=("String", "input"),
                                                               speed_in=("Real", float(self.profile(0.0))))
            self._speed_vr = self.rotor.vr(["speed_in"])
        self._plan_recording()
        self._primed = self.profile is None
        if self.adaptive:
            self._plan_defect()
        return self

    def _check_fed_inputs(self):
        """Refuse an SSP that connects an output whose value depends directly on an input that no connection feeds
        (e.g. a bearing's force without its journal.x connection: the input kept its start value, the parameter
        set's initial journal position, and the run 'finished' with that journal fixed there)."""
        fed = {(e_el, e_c) for _, _, e_el, e_c in self.ssp.connections}
        read = {(s_el, s_c) for s_el, s_c, _, _ in self.ssp.connections}
        for f in self.fmus.values():
            for out in f.md.outputs:
                if (f.name, out.variable.name) not in read:
                    continue
                for d in out.dependencies or ():
                    if d.causality == "input" and (f.name, d.name) not in fed:
                        raise ParameterError(f"{self.ssp_path}: the connected output {f.name}.{out.variable.name} "
                                             f"depends on the input {f.name}.{d.name}, which no connection feeds (it "
                                             "would keep its initial value over the whole run); connect it")

    def _plan_exchange(self):
        """Group the SSP connections into two phases (rotor -> bearings, then bearings -> rotor, so that the
        bearings' outputs are read after their inputs are set), one getReal per source and one setReal per
        destination each, and the end-of-step links (bearings -> rotor after the bearings stepped)."""
        groups, end = {}, {}
        for s_el, s_c, e_el, e_c in self.ssp.connections:
            if self.coupling == "force" and s_c.startswith(("stiffness", "damping")):
                self.params.setdefault(e_el, {})[e_c] = ("Real", 0.0)  # no interface Jacobian at all
                continue
            if s_c.startswith(END_OF_STEP):
                if self.coupling == "jacobian":
                    if e_el != self.rotor.name:
                        raise ParameterError(f"the staggered connection {s_el}.{s_c} -> {e_el}.{e_c} must end at "
                                             "the rotor")
                    end.setdefault(s_el, []).append((s_c, e_c))
                continue
            groups.setdefault((s_el, e_el), []).append((s_c, e_c))
        if end:
            self.params.setdefault(self.rotor.name, {})["force_interpolation"] = ("Boolean", True)
        self._phases = [self._phase([(s, e, c) for (s, e), c in groups.items() if (s == self.rotor.name) == first])
                        for first in (True, False)]
        self._end_gets = [(self.fmus[s], self.fmus[s].vr([a for a, _ in c])) for s, c in end.items()]
        self._end_dvr = self.rotor.vr([b for c in end.values() for _, b in c])
        # the rotor's inputs from the second phase are set together with its other inputs, just before its doStep
        # (one setReal per step; nothing reads the rotor in between: its outputs depend on its state only)
        sets = self._phases[1][1]
        self._rotor_sets = [(dvr, idx) for dst, dvr, idx in sets if dst is self.rotor]
        self._phases[1] = (self._phases[1][0], [x for x in sets if x[0] is not self.rotor])
        self._rotor_in_vr = None  # speed_in, end-of-step values, second-phase values (made in _plan_recording)
        self._rotor_pending = []

    def _plan_recording(self):
        """The value references read at a recorded communication point: each source's exchange values followed by
        its recorded outputs (rotor: speed, journals, discs; bearings: :data:`BEARING_RECORD` and, when the FMU has
        them, :data:`BEARING_LOSSES`), so that a recorded point costs no extra FMI call."""
        extra = {self.rotor.name: self._rec_rotor, **{b.name: v for b, v in zip(self.bearings, self._rec_bearing)}}
        self._rec_phases = []
        for gets, _sets in self._phases:
            self._rec_phases.append([(src, svr + extra.pop(src.name, [])) for src, svr in gets])
        self._rec_rest = [(self.fmus[n], v) for n, v in extra.items()]  # sources not read in the exchange
        self._rotor_in_vr = (list(self._speed_vr) + (list(self._end_dvr) if self._end_gets else []) +
                             [r for dvr, _ in self._rotor_sets for r in dvr])
        self._stash = None

    def _plan_defect(self):
        """Positions, in the exchanged values, of what :meth:`coupling_error` needs: per bearing its journal_ref
        outputs (= its journal inputs) after the exchange and its journal_accel after it stepped."""
        if not self._end_gets:
            raise ParameterError(f"{self.ssp_path}: the adaptive macro step needs the staggered connections "
                                 f"({', '.join(END_OF_STEP)} -> rotor)")
        stateless = [f.name for f in self.fmus.values() if not f.can_state]
        if stateless:
            raise ParameterError(f"the adaptive macro step rolls back rejected steps: FMUs {stateless} cannot get and "
                                 "set their state")

        def positions(gets):
            where, pos = {}, 0
            for src, svr in gets:
                names = {v.valueReference: n for n, v in src.vars.items()}
                for ref in svr:
                    where.setdefault((src.name, names[ref]), pos)
                    pos += 1
            return where

        after, end = positions(self._phases[1][0]), positions(self._end_gets)
        try:  # per bearing: positions of journal_ref x, y, vx, vy and journal_accel x, y; the inner clearance [m]
            self._defect_plan = [(*(after[(f.name, f"journal_ref.{q}")] for q in ("x", "y", "vx", "vy")),
                                  *(end[(f.name, f"journal_accel.{q}")] for q in "xy"), b.inner.clearance)
                                 for f, b in zip(self.bearings, self.system.bearings)]
        except KeyError as exc:
            raise ParameterError(f"{self.ssp_path}: the adaptive macro step needs the connection of {exc.args[0]} "
                                 "to the rotor") from None

    def coupling_error(self, before, end, after, h):
        """Coupling error of the step just taken, relative to the tolerance (<= 1: accepted).

        The staggered scheme's one approximation: each bearing integrates its ring along the journal path
        x_p(τ) = x0 + v0 τ + a τ²/2 it extrapolated from its inputs, while the rotor's force model is exact for
        forces linear in the journal state *given* that path. The error is therefore how far the journal left the
        path: the path defect max(|x(h) − x_p(h)|, h |v(h) − v_p(h)|) per bearing, as a fraction of its inner
        clearance, divided by the tolerance; the largest over the bearings. It is O(h³) per step (the journal's
        jerk; ×8 measured for a doubled step), so the controller scales the step by (1 / error)^(1/3).

        Why this estimate: it needs no FMI call (x0, v0 are the bearings' journal_ref outputs, a their
        journal_accel, x(h), v(h) their journal_ref after the next exchange). The interface-force defect (bearing
        force at the new journal state minus the rotor's force model there) sees the path defect only through the
        films' nonlinearity and is dominated by the bearings holding the rotor speed over a step (~5e-4 N along
        the main job's ramp, whatever the orbit). Step doubling costs three FMU steps per accepted step, so with
        the step capped at twice the SSP's by the validated range it could never take fewer FMU steps than the
        fixed-step run.

        Parameters
        ----------
        before, after : list of float
            Bearing outputs of the exchange at the start and at the end of the step (second exchange phase).
        end : list of float
            End-of-step values of the bearings (force_end, journal_accel).
        h : float
            The step [s].

        Returns
        -------
        float
            The largest path defect over the bearings / (tolerance · inner clearance).
        """
        worst = 0.0  # plain floats: a handful of values per bearing, once per step
        for ix, iy, ivx, ivy, iax, iay, clearance in self._defect_plan:
            ax, ay, vx, vy = end[iax], end[iay], before[ivx], before[ivy]
            dx = after[ix] - (before[ix] + h * (vx + 0.5 * h * ax))
            dy = after[iy] - (before[iy] + h * (vy + 0.5 * h * ay))
            dvx, dvy = after[ivx] - (vx + h * ax), after[ivy] - (vy + h * ay)
            worst = max(worst, math.hypot(dx, dy) / clearance, h * math.hypot(dvx, dvy) / clearance)
        return worst / self.tolerance

    def _phase(self, links):
        gets, dests, pos = {}, {}, 0
        for src, _dst, conns in links:
            gets.setdefault(src, []).extend(self.fmus[src].vr([a for a, _ in conns]))
        offsets = {}
        for src in gets:
            offsets[src] = pos
            pos += len(gets[src])
        seen = {src: 0 for src in gets}
        for src, dst, conns in links:
            d = dests.setdefault(dst, ([], []))
            d[0].extend(self.fmus[dst].vr([b for _, b in conns]))
            d[1].extend(range(offsets[src] + seen[src], offsets[src] + seen[src] + len(conns)))
            seen[src] += len(conns)
        return ([(self.fmus[s], v) for s, v in gets.items()], [(self.fmus[d], v, i) for d, (v, i) in dests.items()])

    def initialize(self):
        """setupExperiment, parameters (parameter set + overrides) in initialization mode, first exchange."""
        for fmu in self.fmus.values():
            fmu.call("setupExperiment", None, 0.0, None)
            fmu.call("enterInitializationMode")
            try:
                fmu.set_parameters(self.params.get(fmu.name, {}))
            except (FmiCallFailed, ParameterError):
                raise
            except Exception as exc:  # noqa: BLE001  (a value fmpy cannot convert)
                raise CosimStopped(f"{fmu.name}: setting parameters failed: {exc}") from None
            fmu.call("exitInitializationMode")
        self.exchange(record=True)

    # ------------------------------------------------------------------ exchange
    def exchange(self, record=False):
        """Pass all coupling values at the current communication point (two phases). The rotor's inputs of the
        second phase are kept and set with its other inputs before its next doStep (:meth:`_set_rotor_inputs`).
        With ``record``, the recorded outputs are read in the same getReal calls and kept for :meth:`sample`."""
        t0 = time.perf_counter()
        stash = {} if record else None
        self._stash = None
        try:
            for phase, (gets, sets) in enumerate(self._phases):
                vals = []
                for i, (src, svr) in enumerate(self._rec_phases[phase] if record else gets):
                    v = src.call("getReal", svr)
                    if record:  # the exchange values, then the recorded ones (recorded as they are, NaN included)
                        n = len(gets[i][1])
                        stash[src.name], v = v[n:], v[:n]
                    if not math.isfinite(sum(v)):
                        names = [n for n, var in src.vars.items() if var.valueReference in gets[i][1]]
                        raise CosimStopped(f"{src.name}: non-finite output among {names}, with status OK")
                    vals += v
                self._xvals[phase] = vals
                for dst, dvr, idx in sets:
                    dst.call("setReal", dvr, [vals[i] for i in idx])
            vals = self._xvals[1]
            self._rotor_pending = [vals[i] for _, idx in self._rotor_sets for i in idx]
            if record:
                for src, svr in self._rec_rest:
                    stash[src.name] = src.call("getReal", svr)
                self._stash = stash
        finally:
            self.fmi_time_s += time.perf_counter() - t0

    def _set_rotor_inputs(self, t):
        """All of the rotor's inputs in one setReal before its doStep at ``t``: the profile's speed (if any), the
        bearings' end-of-step values (staggered coupling, read here) and the kept second-phase values."""
        vals = [float(self.profile(t))] if self.profile is not None else []
        if self._end_gets:
            end = []
            for src, svr in self._end_gets:
                v = src.call("getReal", svr)
                if not math.isfinite(sum(v)):
                    raise CosimStopped(f"{src.name}: published a non-finite end-of-step force")
                end += v
            self._evals = end
            vals += end
        self.rotor.call("setReal", self._rotor_in_vr, vals + self._rotor_pending)

    # ------------------------------------------------------------------ step
    def _do_step(self, t, h, record=False):
        """Bearings, rotor inputs, rotor, exchange (``record``: with the recorded outputs). Returns None or
        (message, retryable, fmu)."""
        t0 = time.perf_counter()
        self._stash = None
        try:
            for fmu in self.bearings:
                fmu.call("doStep", t, h, True)
            self._set_rotor_inputs(t)
            self.rotor.call("doStep", t, h, True)
        except FmiCallFailed as exc:
            return str(exc), exc.discarded, exc.fmu
        except CosimStopped as exc:
            return str(exc), True, None
        finally:
            self.fmi_time_s += time.perf_counter() - t0
        try:  # the new journal states may already put a film at its wall: non-finite outputs
            self.exchange(record)
        except CosimStopped as exc:
            return str(exc), True, None
        return None

    def step(self, t, H, record=False):
        """Advance from ``t`` by ``H`` [s]; with rollback, rejected intervals are retried with halved steps.
        ``record``: the last exchange also reads the recorded outputs (for :meth:`sample` at ``t + H``). Returns the
        new time. Raises :class:`CosimStopped` naming the FMU and the interval."""
        t_target, h = t + H, H
        while t < t_target - 1e-12 * H:
            h = min(h, t_target - t)
            if not self._primed:  # a profile's first sub-step gives the rotor its speed-input history
                h = min(h, PRIME_STEP_S)
            states = self._get_states() if self.rollback else None
            failure = self._do_step(t, h, record)
            retry = (failure is not None and failure[1] and self.rollback and bool(states)
                     and h > H / 2 ** self.max_halvings)
            if states:
                self._restore_and_free(states, restore=retry)
            if retry:
                h /= 2
                self.rejected_steps += 1
                self.exchange()
                continue
            if failure is not None:
                msg, retryable, _ = failure
                tried = (f" (after {self.max_halvings} step halvings with rollback)"
                         if retryable and self.rollback else "")
                raise CosimStopped(f"{msg} in the interval t = {t:.6g} s + {h:.3g} s{tried}")
            t += h
            self.steps_taken += 1
            if not self._primed:
                self._primed, h = True, H
        return t_target

    # ------------------------------------------------------------------ adaptive step
    def _try_step(self, t, h, record=False):
        """One step of the adaptive run from ``t`` by ``h`` [s], after saving all FMU states. Returns ``(accepted,
        error)`` (error: :meth:`coupling_error`, inf for a discarded step; 0 for the run's first step, whose
        bearings have no journal history yet and take the linear path as in the fixed-step run). A rejected step
        is rolled back; a failure that cannot be retried (or one at ``min_step``) raises :class:`CosimStopped`."""
        states = self._get_states()
        before = self._xvals[1]
        failure = self._do_step(t, h, record)
        at_min = h <= self.min_step * (1.0 + 1e-9)
        if failure is not None and (not failure[1] or at_min):
            self._restore_and_free(states, restore=False)
            msg, retryable, _ = failure
            raise CosimStopped(f"{msg} in the interval t = {t:.6g} s + {h:.3g} s" +
                               (" (adaptive step at its min_step)" if retryable else ""))
        err = math.inf if failure is not None else (
            self.coupling_error(before, self._evals, self._xvals[1], h) if t > 0 else 0.0)
        accepted = err <= 1.0 or at_min
        self._restore_and_free(states, restore=not accepted)
        if accepted:
            self.steps_taken += 1
            self.forced_steps += err > 1.0
            self.accepted_steps.append((t, h))
        else:
            self.rejected_steps += 1
            self.exchange()
        return accepted, err

    def _next_step(self, h, err):
        """The step [s] proposed after a step ``h`` with relative error ``err``: h · 0.9 err^(-1/3) (the error is
        O(h³)), at most ×2 (so the FMUs' backward differences over the last step stay valid), at least ×1/4, ×1/2
        after a discarded step; within min_step ... max_step."""
        factor = 0.5 if not math.isfinite(err) else (2.0 if err <= 0 else 0.9 * err ** (-1.0 / 3.0))
        return min(self.max_step, max(self.min_step, h * min(2.0, max(0.25, factor))))

    def _advance_adaptive(self, T, dt, rec, signals, bar):
        """Step to ``T`` with the error-controlled step and record at the output times k ``dt`` [s] (and ``T``),
        on which the steps land: each output interval is split into equal steps no longer than the proposed one."""
        t, h = 0.0, self.step_size
        if not self._primed:
            t = self.step(0.0, PRIME_STEP_S)
            self.accepted_steps.append((0.0, t))
        n_out = max(1, int(math.floor(T / dt + 1e-9)))
        times = [k * dt for k in range(1, n_out + 1)] + ([T] if T - n_out * dt > 1e-9 * dt else [])
        for k, t_out in enumerate(times, 1):
            n, h_try = 0, h  # steps left in this output interval, of h_try each (a step grows between intervals)
            while t_out - t > 1e-12 * dt:
                if n == 0 or h < h_try * (1.0 - 1e-9):
                    n = max(1, math.ceil((t_out - t) / h - 1e-9))
                    h_try = (t_out - t) / n
                accepted, err = self._try_step(t, h_try, record=n == 1)
                if accepted:
                    t, n = (t_out if n == 1 else t + h_try), n - 1
                h = self._next_step(h_try, err)
            rec.append(self.sample(t_out))
            signals.check()
            if k % 200 == 0:
                bar.update(t - bar.n)
                bar.set_postfix_str(f"{rec.last[1]:.0f} rpm, step {h * 1e6:.1f} us", refresh=False)

    def _advance_fixed(self, T, H, every, rec, signals, bar):
        """Step to ``T`` by ``H`` [s], recording every ``every``-th communication point."""
        t = 0.0
        for k in range(1, int(round(T / H)) + 1):
            t = self.step(t, H, record=k % every == 0)
            if k % every == 0:
                rec.append(self.sample(t))
                signals.check()
            if k % 1000 == 0:
                bar.update(t - bar.n)
                bar.set_postfix_str(f"{rec.last[1]:.0f} rpm", refresh=False)

    def _get_states(self):
        t0 = time.perf_counter()
        states = {n: f.save_state() for n, f in self.fmus.items() if f.can_state}
        self.fmi_time_s += time.perf_counter() - t0
        return states

    def _restore_and_free(self, states, restore):
        for n, st in states.items():
            if restore:
                self.fmus[n].call("setFMUstate", st)
            self.fmus[n].drop_state(st)

    # ------------------------------------------------------------------ record
    def sample(self, t):
        """The recorder row at time ``t`` from the rotor's and bearings' outputs: those read with the last exchange
        when it was a recorded one (``exchange(record=True)``, no step since), else read now (journal torque and
        power loss NaN for a bearing FMU without the outputs :data:`BEARING_LOSSES`)."""
        stash = self._stash
        if stash is None:
            stash = {f.name: f.call("getReal", v) for f, v in [(self.rotor, self._rec_rotor),
                                                               *zip(self.bearings, self._rec_bearing)]}
        r = stash[self.rotor.name]
        b = np.full((len(self.bearings), len(BEARING_RECORD) + len(BEARING_LOSSES)), math.nan)
        for i, f in enumerate(self.bearings):
            v = stash[f.name]
            b[i, :len(v)] = v
        nb, nd = len(self.bearings), len(self.schema.discs)
        journal = np.reshape(r[1:1 + 2 * nb], (nb, 2))
        discs = np.reshape(r[1 + 2 * nb:1 + 2 * nb + 2 * nd], (nd, 2))
        return self.schema.row(t, rad_s_to_rpm(r[0]), b[:, 0], journal, b[:, 1:3], b[:, 3:5], discs,
                               journal_torque=b[:, 5], power_loss=b[:, 6])

    def _adaptive_stats(self):
        """Metadata of the adaptive step at the end of a run (empty for a fixed step)."""
        if not self.adaptive:
            return {}
        h = [step for _, step in self.accepted_steps]
        return {"forced_steps": self.forced_steps, "shortest_step_s": min(h, default=None),
                "longest_step_s": max(h, default=None)}

    def meta(self, output_rate_hz):
        return {"ssp": str(self.ssp_path), "parameter_set": self.parameter_set, "step_size_s": self.step_size,
                "stop_time_s": self.stop_time, "output_rate_hz": output_rate_hz, "system": self.system.to_dict(),
                "coupling": self.coupling, "rollback": self.rollback, "units": "SI; speed in rpm",
                "master": "frbmodel.cosim (fmpy FMU2Slave, staggered interface-Jacobian coupling)",
                **({} if self.profile is None else
                   {"speed_source": "input", "speed_profile": self.profile.description,
                    "speed_profile_end_s": float(self.profile.t[-1])}),
                **({} if not self.adaptive else
                   {"adaptive": True, "coupling_tol": self.tolerance, "min_step_s": self.min_step,
                    "max_step_s": self.max_step, "error_estimate": "journal path defect / inner clearance"})}

    # ------------------------------------------------------------------ run / close
    def run(self, out_dir=None, progress=False, output_rate_hz=20e3):
        """Set up, initialize and step to the stop time, recording every n-th communication point
        (n = round(1 / (H · output_rate_hz)), at least 1; adaptive: at the same times, see ``adaptive``). Returns a
        :class:`RunupResult` (``meta``: wall time, time inside FMI calls, steps taken and rejected); raises
        :class:`CosimStopped` (with ``.result``) when an FMU fails."""
        H, T = self.step_size, self.stop_time
        check_record_size(T, output_rate_hz)
        every = max(1, int(round(1.0 / (H * output_rate_hz))))
        n_steps = int(round(T / H))
        t_wall = time.perf_counter()
        status, message = "finished", ""
        if not self.fmus:  # before the recorder writes anything: a refused SSP leaves no result files
            try:
                self.setup()
            except BaseException:
                self.close()
                raise
        with Recorder(RunupSchema.from_system(self.system), n_steps // every + 2, out_dir,
                      self.meta(1.0 / (H * every))) as rec:
            try:
                self.initialize()
                rec.append(self.sample(0.0))
                with deferred_signals() as signals, simulation_bar(T, "cosim", progress) as bar:
                    if self.adaptive:
                        self._advance_adaptive(T, H * every, rec, signals, bar)
                    else:
                        self._advance_fixed(T, H, every, rec, signals, bar)
            except CosimStopped as exc:
                status, message = "stopped", str(exc)
            finally:
                self.close()
            wall = time.perf_counter() - t_wall
            if progress:
                sys.stderr.write(f"cosim: {status} after {wall:.1f} s wall "
                                 f"({self.fmi_time_s / max(wall, 1e-9):.0%} in FMI calls)\n")
            result = rec.close(status, message, wall_time_s=wall, fmi_time_s=self.fmi_time_s,
                               rejected_steps=self.rejected_steps, steps_taken=self.steps_taken,
                               fmi_calls={f: [n, round(w, 6)] for f, (n, w) in sorted(self.fmi_calls.items())},
                               **self._adaptive_stats())
        if status != "finished":
            raise CosimStopped(message, result)
        return result

    def _freed(self, fmu):
        """Add a freed instance's call counts and times to :attr:`fmi_calls`."""
        for function, (n, wall) in fmu.calls.items():
            stat = self.fmi_calls.setdefault(function, [0, 0.0])
            stat[0] += n
            stat[1] += wall


def cosimulate(ssp, parameter_set="co36", stop_time=None, step_size=None, out_dir=None, progress=False,
               rollback=False, output_rate_hz=20e3, overrides=None, max_halvings=6, coupling="jacobian",
               trace=None, unvalidated_step=False, profile=None, adaptive=False, tolerance=COUPLING_TOL,
               min_step=None, max_step=None):
    """Run the SSP system with frbmodel's master (see :class:`Master` for the parameters).

    ``out_dir``: stream ``runup.csv`` / ``runup.json`` there; ``output_rate_hz``: sampling rate of the recorded
    results [Hz] (default 20 kHz, as the monolithic run-up); ``progress``: progress bar on stderr.

    Returns
    -------
    RunupResult
        ``meta`` has the wall time, the time inside FMI calls (in total and, as ``fmi_calls``, per FMI function:
        number of calls and wall time [s]), the numbers of steps taken and rejected (adaptive: also the tolerance,
        the step bounds, the shortest and longest step taken).

    Raises
    ------
    CosimStopped
        An FMU failed; the message names it; ``.result`` holds the samples so far (also on disk).
    """
    master = Master(ssp, parameter_set, stop_time, step_size, overrides, coupling, rollback, max_halvings, trace,
                    unvalidated_step, profile=profile, adaptive=adaptive, tolerance=tolerance, min_step=min_step,
                    max_step=max_step)
    return master.run(out_dir, progress, output_rate_hz)


__all__ = ["Master", "cosimulate", "CosimStopped", "RunupResult", "operating_point_overrides",
           "system_from_parameters", "check_coupling_tol", "check_record_size", "COUPLING_TOL", "MAX_COUPLING_TOL",
           "PRIME_STEP_S", "VALIDATED_STEP_S"]


def operating_point_overrides(system, speed_rpm, end_rpm=None, ramp_time=1.0, method="J", perturbation=0.0):
    """Parameter overrides that start the SSP system at the ``method`` equilibrium at ``speed_rpm`` (plus the
    same initial offset as :func:`frbmodel.nonlinear.runup.runup`'s ``perturbation``): rotor speed profile and initial
    journal positions, ring positions and speeds."""

    eq = equilibrium(system, method, speed_rpm)
    w0 = rpm_to_rad_s(speed_rpm)
    w1 = rpm_to_rad_s(end_rpm if end_rpm is not None else speed_rpm)
    ov = {"rotor": {"speed_start": ("Real", w0), "speed_end": ("Real", w1), "ramp_time": ("Real", float(ramp_time))}}
    for b, e in zip(system.bearings, eq.bearings):
        name, prefix, ci, co = b.name, f"{b.name}_bearing", b.inner.clearance, b.outer.clearance
        jx, jy = float(e.journal[0] + perturbation * (ci + co)), float(e.journal[1])
        ov["rotor"][f"{prefix}.journal_x0"] = ("Real", jx)
        ov["rotor"][f"{prefix}.journal_y0"] = ("Real", jy)
        # the bearing's inputs start at the same operating point (the parameter set's start values belong to its
        # own start speed: paired with this ring position they can put the journal through its wall)
        ov[name] = {"ring.x0": ("Real", float(e.ring[0] + perturbation * co)), "ring.y0": ("Real", float(e.ring[1])),
                    "ring.speed0": ("Real", float(e.ring_speed)), "journal.x": ("Real", jx), "journal.y": ("Real", jy),
                    "rotor_speed": ("Real", w0)}
    return ov
