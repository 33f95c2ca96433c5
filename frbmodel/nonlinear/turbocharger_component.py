"""The whole turbocharger as one steppable component: FE rotor and both floating-ring bearings (ring lateral and
spin DoFs), integrated by the run-up's compiled monolithic integrator with its own error control.

:class:`TurbochargerComponent` is what the turbocharger FMU (``fmu_src/FloatingRingTurbocharger.py``) steps. It holds
the run-up's problem (:func:`frbmodel.nonlinear.runup.build_problem`: the one right-hand side), its initial state, its
tolerances and its integrator (:func:`frbmodel.nonlinear.rosenbrock.rodas_chunk`); :meth:`TurbochargerComponent.step`
advances exactly to t + h for any h, the inputs (speed, drive torque, housing acceleration) held over the step. Because
the integrator controls its own error, the trajectory does not depend on the step a master chooses, up to the
integrator's tolerance and to how the inputs are sampled: with a prescribed ramp and a step equal to the run-up's solver
call (:data:`frbmodel.nonlinear.runup.CHUNK_SAMPLES` samples) it is :func:`frbmodel.nonlinear.runup.runup` bit for bit.

Inside each step the state is also evaluated on a fixed time grid (``check_rate_hz``, dense output of the
integrator, which does not change the steps): wall contact is checked there as in the run-up, the smallest film
thickness over the step is taken there, and an optional record (the run-up's result files, :meth:`record`) is
written there, so a master at 1 ms steps still gets a 20 kHz orbit record.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numba import njit

from ..core.errors import FilmContactError, IntegrationError, ParameterError, check_finite, check_positive
from ..core.units import RPM, rad_s_to_rpm
from ..linear.thermal import OilSupply, at_operating_point, thermal_losses
from ..physics.film import check_model, film_force_kernel
from .recorder import Recorder, RunupSchema
from .rosenbrock import FD_TYPICAL_M, STATUS, film_columns, rodas_chunk
from .runup import (
    CHUNK_SAMPLES,
    DEFAULT_ATOL_M,
    DEFAULT_RTOL,
    EPS_CAP,
    VISCOSITY_TABLE_MIN_RPM,
    SpeedProfile,
    atol_vector,
    build_problem,
    check_drive_torque_value,
    check_tolerances,
    contact_message,
    film_samples,
    initial_state,
    modal_error_basis,
    sample_rows,
    typical_sizes,
)

#: where the rotor speed comes from (the same names as the rotor FMU's speed_source)
SPEED_SOURCES = ("ramp", "input", "torque")
#: default rate [Hz] of the in-step evaluation grid (contact check, smallest film thickness, record): the run-up's
#: default output rate
CHECK_RATE_HZ = 20e3
#: default eccentricity ratio at which a step is discarded (wall contact), as frb.runup's contact_eps
CONTACT_EPS = 0.98
#: speeds of the component's thermal table (thermal model on): 49 uniformly spaced over its speed range; a change of
#: the supply inputs recomputes it (49 thermal operating points per bearing, ~0.4 s)
THERMAL_TABLE_SPEEDS = 49
#: quantities per bearing of :meth:`TurbochargerComponent.thermal_outputs` (thermal model on): (name, unit, description)
THERMAL_OUTPUTS = (
    ("inner_film_temperature", "K", "inner-film temperature of the thermal operating point at the rotor speed"),
    ("outer_film_temperature", "K", "outer-film temperature of the thermal operating point at the rotor speed"),
    ("oil_flow", "m3/s", "oil flow through both films (side, feed and supply flows) at the rotor speed"),
)
#: quantities per bearing of :meth:`TurbochargerComponent.outputs`: (name, unit, description)
BEARING_OUTPUTS = (
    ("journal_torque", "N.m", "inner-film torque on the journal about +z (negative: it brakes the rotor)"),
    ("power_loss", "W", "friction power of both films"),
    ("housing_force.x", "N", "force of the outer film on the housing, x"),
    ("housing_force.y", "N", "force of the outer film on the housing, y"),
    ("eps_inner", "1", "inner-film eccentricity ratio"),
    ("eps_outer", "1", "outer-film eccentricity ratio"),
    ("h_min_inner", "m", "smallest inner-film thickness over the last step"),
    ("h_min_outer", "m", "smallest outer-film thickness over the last step"),
    ("ring_speed", "rad/s", "ring spin speed"),
    ("ring_speed_ratio", "1", "ring speed / rotor speed"),
    ("journal.x", "m", "journal centre x relative to the housing"),
    ("journal.y", "m", "journal centre y relative to the housing"),
    ("ring.x", "m", "ring centre x relative to the housing"),
    ("ring.y", "m", "ring centre y relative to the housing"),
)


@njit(cache=True)
def _outer_film_forces(y, ring_at, ring_speed_at, geom, polys, eps_cap, out):
    """Force of each bearing's outer film on its ring [N] (:func:`frbmodel.physics.film.film_force_kernel`, capped as in
    the right-hand side) into ``out`` (nb, 2)."""
    for b in range(ring_at.size):
        r = ring_at[b]
        g = geom[b, 1]
        fx, fy, _ = film_force_kernel(g[0], g[1], g[2], g[3], polys[b, 1, 0], polys[b, 1, 1], y[r], y[r + 1],
                                      y[r + 2], y[r + 3], y[ring_speed_at[b]], eps_cap)
        out[b, 0], out[b, 1] = fx, fy


def thermal_table(system, speeds, oil_supply):
    """The thermal operating points (:func:`thermal_losses`) at ``speeds`` [rad/s]: ``speeds``, ``viscosity``
    (4, n) [Pa s] and ``temperature`` (4, n) [K] per film (turbine inner, outer, compressor inner, outer), ``flow``
    (n_bearings, n) [m³/s] through both films of each bearing."""
    tab = thermal_losses(system, speeds / RPM, oil_supply.oil, oil_supply.supply_temperature_K,
                         oil_supply.supply_pressure_Pa, oil_supply.model)
    nb, n = len(system.bearings), speeds.size

    def films(a, b):
        return np.ascontiguousarray(tab[[a, b]].to_numpy().reshape(n, nb, 2).reshape(n, 2 * nb).T)

    flow = (tab["inner flow [m^3/s]"] + tab["outer flow [m^3/s]"]).to_numpy().reshape(n, nb).T
    return {"speeds": np.asarray(speeds, dtype=float), "viscosity": films("inner viscosity [Pa s]",
                                                                          "outer viscosity [Pa s]"),
            "temperature": films("inner film temperature [K]", "outer film temperature [K]"),
            "flow": np.ascontiguousarray(flow)}


def thermal_output_names(system):
    """Names, units and descriptions of :meth:`TurbochargerComponent.thermal_outputs`: :data:`THERMAL_OUTPUTS` per
    bearing (``<bearing>_bearing.<quantity>``).

    Examples
    --------
    >>> import frbmodel as frb
    >>> [n for n, _, _ in thermal_output_names(frb.turbocharger())][:2]
    ['turbine_bearing.inner_film_temperature', 'turbine_bearing.outer_film_temperature']
    """
    return [(f"{b.name}_bearing.{q}", u, f"{b.name} bearing: {d}") for b in system.bearings for q, u, d in
            THERMAL_OUTPUTS]


def output_names(system):
    """Names, units and descriptions of :meth:`TurbochargerComponent.outputs`, in its order: ``rotor_speed``,
    ``rotor_angle``, then :data:`BEARING_OUTPUTS` per bearing (``<bearing>_bearing.<quantity>``), then
    ``<disc>.x``, ``<disc>.y`` per disc.

    Parameters
    ----------
    system : Turbocharger

    Returns
    -------
    list of (str, str, str)

    Examples
    --------
    >>> import frbmodel as frb
    >>> names = [n for n, _, _ in output_names(frb.turbocharger())]
    >>> len(names), names[:3], names[-1]
    (34, ['rotor_speed', 'rotor_angle', 'turbine_bearing.journal_torque'], 'compressor_wheel.y')
    """
    out = [("rotor_speed", "rad/s", "rotor spin speed"), ("rotor_angle", "rad", "rotor rotation angle about +z")]
    for b in system.bearings:
        out += [(f"{b.name}_bearing.{q}", u, f"{b.name} bearing: {d}") for q, u, d in BEARING_OUTPUTS]
    for d in system.rotor.discs:
        out += [(f"{d.name}.{q}", "m", f"{d.name} centre {q} relative to the housing") for q in "xy"]
    return out


class TurbochargerComponent:
    """The monolithic turbocharger model advanced step by step (see the module description).

    Parameters
    ----------
    system : Turbocharger
        Two bearings (the run-up's layout).
    speed_source : {"ramp", "input", "torque"}
        "ramp": linear from ``speed_start`` to ``speed_end`` in ``ramp_time``, then constant (the run-up's
        :meth:`~frbmodel.nonlinear.runup.SpeedProfile.ramp`); "input": the ``speed_in`` of each :meth:`step`, held over
        the step; "torque": the speed is a state, J_p Ω̇ = T_drive + Σ T_J (the torque-driven run-up), with the
        ``drive_torque`` of each step held over it.
    speed_start, speed_end : float
        Rotor speed [rad/s] at t = 0 and after the ramp ("ramp"); ``speed_start`` is the start speed of "torque".
    ramp_time : float
        Duration of the ramp [s], > 0.
    film_model : str, optional
        Default: the system's.
    unbalance : sequence of Unbalance
    rtol, atol : float
        The run-up's tolerances: relative [-] and absolute on displacements [m] (the others scaled from it,
        :func:`frbmodel.nonlinear.runup.atol_vector`).
    speed_scale : float, optional
        Largest rotor speed [rad/s] that scales the velocity and speed tolerances (the run-up uses the largest speed
        of its run); default: the larger of ``speed_start`` and ``speed_end``.
    contact_eps : float
        A step in which a film's eccentricity ratio exceeds this (at the check grid or the step's end) fails with
        :class:`~frbmodel.core.errors.FilmContactError`, the state unchanged.
    perturbation, initial
        Initial state as in :func:`frbmodel.nonlinear.runup.runup` (the method-J equilibrium at the start speed, offset
        by
        ``perturbation`` clearances in +x).
    initial_speed : float, optional
        "input": the speed before the first step [rad/s] (the equilibrium is found there); default ``speed_start``.
    check_rate_hz : float
        Rate [Hz] of the in-step grid for the contact check, the smallest film thickness and the record.
    oil : Oil, optional
        The thermal model (docs/theory/thermal.md#turbocharger-fmu): the films' viscosities follow the rotor speed
        through a table of thermal operating points (:data:`THERMAL_TABLE_SPEEDS` speeds over the speed range:
        ``speed_start`` ... ``speed_end`` for "ramp", 1000 rpm ... the speed scale otherwise; held constant outside)
        at the supply temperature [K] and pressure [Pa] of each :meth:`step` (recomputed when they change), and
        :meth:`thermal_outputs` gives the film temperatures and oil flows. None: constant viscosities, bit for bit.
    supply_temperature_K, supply_pressure_Pa : float
        The supply state before the first step (thermal model on): the initial equilibrium is at its temperatures.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> c = TurbochargerComponent(tc, "ramp", 1500 * RPM, 1500 * RPM, 1.0)
    >>> c.step(1e-3)
    >>> round(c.t, 12), round(rad_s_to_rpm(c.outputs()[0]))
    (0.001, 1500)
    """

    def __init__(self, system, speed_source="ramp", speed_start=20e3 * RPM, speed_end=250e3 * RPM, ramp_time=1.0,
                 film_model=None, unbalance=(), rtol=DEFAULT_RTOL, atol=DEFAULT_ATOL_M, speed_scale=None,
                 contact_eps=CONTACT_EPS, perturbation=0.05, initial="equilibrium", initial_speed=None,
                 check_rate_hz=CHECK_RATE_HZ, oil=None, supply_temperature_K=363.15, supply_pressure_Pa=3e5):
        if speed_source not in SPEED_SOURCES:
            raise ParameterError(f"speed_source = {speed_source!r} is unknown; valid: {', '.join(SPEED_SOURCES)}")
        self.system, self.speed_source = system, speed_source
        w0 = check_positive("speed_start", speed_start, "rad/s")
        w1 = check_positive("speed_end", speed_end, "rad/s")
        scale = max(w0, w1) if speed_scale is None else check_positive("speed_scale", speed_scale, "rad/s")
        self.ramp_time = check_positive("ramp_time", ramp_time, "s")
        if speed_source == "input":
            w0 = check_positive("speed_in at the start", w0 if initial_speed is None else initial_speed, "rad/s")
        self.contact_eps = float(contact_eps)
        if not 0.0 < self.contact_eps < 1.0:
            raise ParameterError(f"contact_eps = {contact_eps!r} is invalid: valid range 0 < contact_eps < 1")
        self.check_rate_hz = check_positive("check_rate_hz", check_rate_hz, "Hz")
        self.rtol, atol = check_tolerances(system, rtol, atol)
        self._oil, self._supply = oil, None
        if oil is not None:  # the films at the start speed's temperatures: the initial equilibrium is there
            speeds = self._thermal_speeds(w0, w1, scale)
            self._supply = OilSupply(oil, supply_temperature_K, supply_pressure_Pa)
            self._thermal = thermal_table(system, speeds, self._supply)
            system = at_operating_point(system, max(w0 / RPM, speeds[0] / RPM), self._supply)
        self.problem = build_problem(system, self._profile(w0, w1), check_model(film_model or system.film_model),
                                     unbalance)
        if oil is not None:
            self.problem = replace(self.problem, args=self.problem.args[:22] + (self._thermal["speeds"],
                                                                                  self._thermal["viscosity"]))
        self.y = initial_state(self.problem, initial, perturbation)
        self.modal, self.atol = modal_error_basis(self.problem, atol_vector(self.problem, atol, scale)[0], scale)

        self.fd_scale = typical_sizes(self.problem, FD_TYPICAL_M, scale)
        self.cols = film_columns(self.problem.n_rotor, self.problem.args[3], self.problem.torque_driven,
                                 self.problem.args[10].size > 0)
        self.t, self.h = 0.0, 1e-7  # time [s]; the integrator's next step [s] (the run-up's first step)
        self.schema = RunupSchema.from_system(system)
        self._layout()
        self._recorder = None
        self._set_inputs(0.0, 0.0, w0, 0.0, (0.0, 0.0))
        self._evaluate(np.array([0.0]), self.y[None, :], first=True)

    def warm_up(self):
        """Load (or compile) the integrator's and the outputs' compiled kernels now, not in the first step: one
        integration of a copy of the state over 1 ns (nothing is kept)."""

        ts = np.array([self.t, self.t + 1e-9])
        rodas_chunk(self.y.copy(), ts, 1e-9, self.rtol, self.atol, self.fd_scale, self.cols, 100, 1e-9,
                    self.problem.args, self.modal)
        self.outputs()

    # ------------------------------------------------------------------ set-up
    def _thermal_speeds(self, w0, w1, scale):
        """Uniform speed grid [rad/s] of the thermal table."""
        lo = min(w0, w1) if self.speed_source == "ramp" else VISCOSITY_TABLE_MIN_RPM * RPM
        hi = max(w0, w1) if self.speed_source == "ramp" else max(scale, lo)
        lo = max(min(lo, hi), VISCOSITY_TABLE_MIN_RPM * RPM)
        hi = max(hi, lo * (1.0 + 1e-9))
        return np.linspace(lo, hi, THERMAL_TABLE_SPEEDS)

    def _set_supply(self, temperature_K, pressure_Pa):
        """Recompute the thermal table in place (the RHS holds its arrays) when the supply state changes."""
        if self._oil is None or (temperature_K, pressure_Pa) == (self._supply.supply_temperature_K,
                                                                  self._supply.supply_pressure_Pa):
            return
        sup = OilSupply(self._oil, temperature_K, pressure_Pa)
        new = thermal_table(self.system, self._thermal["speeds"], sup)
        for k in ("viscosity", "temperature", "flow"):
            self._thermal[k][:] = new[k]
        self._supply = sup

    def _profile(self, w0, w1):
        """The speed table of the RHS: the run-up's ramp (the same arrays as SpeedProfile.ramp in rad/s), a
        2-point table rewritten before each step ("input"), or a torque-driven profile ("torque")."""
        if self.speed_source == "ramp":
            a = (w1 - w0) / self.ramp_time
            self._w_end = w1
            return SpeedProfile(np.array([0.0, self.ramp_time]), np.array([w0, w1]), np.array([a, a]),
                                f"linear ramp {rad_s_to_rpm(w0):.0f} -> {rad_s_to_rpm(w1):.0f} rpm in "
                                f"{self.ramp_time:g} s, then constant")
        if self.speed_source == "input":
            return SpeedProfile(np.array([0.0, 1.0]), np.full(2, w0), np.zeros(2), "speed from the input speed_in")
        return SpeedProfile(np.array([0.0, 1.0]), np.full(2, w0), np.zeros(2),
                            f"torque-driven from {rad_s_to_rpm(w0):.0f} rpm, drive torque from the input", np.zeros(2))

    def _layout(self):
        """Index arrays into the state for :meth:`outputs` and the compiled film evaluation."""
        p, system = self.problem, self.system
        nb = len(system.bearings)
        self._journal_at = np.array([4 * b.node for b in system.bearings], dtype=np.int64)
        self._ring_at = np.array([p.ring_index(b) for b in range(nb)], dtype=np.int64)
        self._ring_speed_at = np.array([p.ring_speed_index(b) for b in range(nb)], dtype=np.int64)
        self._disc_at = np.array([4 * d.node + k for d in system.rotor.discs for k in (0, 1)], dtype=np.intp)
        self._clearance = np.array([[b.inner.clearance, b.outer.clearance] for b in system.bearings])
        self._force = np.empty((nb, 2))

    # ------------------------------------------------------------------ stepping
    def _set_inputs(self, t, h, speed, torque, housing, ramp_done=False):
        """Write the inputs held over [t, t + h] into the RHS's arrays (in place); ``ramp_done``: the speed is
        constant from now on ("ramp")."""
        p = self.problem
        p.housing_acc[:] = housing
        if self.speed_source == "input":
            p.profile.t[:] = (t, t + max(h, 1e-9))
            p.profile.omega[:] = speed
        elif self.speed_source == "torque":
            p.profile.drive_torque[:] = torque
        elif ramp_done and p.profile.omega_dot[0] != 0.0:  # after the ramp: constant speed_end
            p.profile.t[:] = (self.ramp_time, 2.0 * self.ramp_time)
            p.profile.omega[:] = self._w_end
            p.profile.omega_dot[:] = 0.0

    def _grid(self, t, t_end):
        """The times of one integrator call: t, the check grid strictly inside (t, t_end), t_end."""
        k0 = math.floor(t * self.check_rate_hz + 1e-9) + 1
        k1 = math.ceil(t_end * self.check_rate_hz - 1e-9)
        inner = np.arange(k0, k1) / self.check_rate_hz
        return np.concatenate(([t], inner[(inner > t) & (inner < t_end)], [t_end]))

    def step(self, h, speed_in=None, drive_torque=0.0, housing_acc=(0.0, 0.0), t=None, supply_temperature_K=None,
             supply_pressure_Pa=None):
        """Advance by ``h`` [s], exactly to t + h, with the inputs held over the step.

        Parameters
        ----------
        h : float
            Step [s], > 0 (any size: the integrator takes its own steps inside).
        speed_in : float, optional
            Rotor speed [rad/s] over the step ("input").
        drive_torque : float
            Net external torque on the rotor [N m] ("torque").
        housing_acc : (float, float)
            Housing acceleration (a_x, a_y) [m/s²].
        t : float, optional
            The master's time at the start of the step [s]; must equal :attr:`t` (within 1e-9 of the step).
        supply_temperature_K, supply_pressure_Pa : float, optional
            Oil supply temperature [K] and pressure [Pa] over the step (thermal model on; None: unchanged). Refused
            without the thermal model.

        Raises
        ------
        ParameterError
            A bad step or input (non-finite, out of range), or a start time that is not the component's time.
        FilmContactError
            A film's eccentricity ratio exceeded ``contact_eps`` in the step.
        IntegrationError
            The integrator failed (its reason).
        Nothing of a failed step is kept.
        """
        h = check_positive("step size", h, "s")
        t_end = self.t + h
        if t is not None:  # the master's clock is the truth (it may add steps with another rounding)
            t = check_finite("step start time", t, "s")
            if abs(t - self.t) > 1e-3 * h:
                raise ParameterError(f"step start time = {t!r} s is invalid: the component is at t = {self.t!r} s "
                                     "(a step was skipped, or a state was not restored)")
            t_end = t + h
        w = check_positive("speed_in", speed_in, "rad/s") if self.speed_source == "input" else None
        tq = (check_drive_torque_value("drive_torque", drive_torque, self.problem.polar_inertia)
              if self.speed_source == "torque" else 0.0)
        acc = [check_finite(f"housing acceleration {q}", a, "m/s2") for q, a in zip("xy", housing_acc)]
        given = [n for n, v in (("supply_temperature_K", supply_temperature_K),
                                ("supply_pressure_Pa", supply_pressure_Pa)) if v is not None]
        if given and self._oil is None:
            raise ParameterError(f"{given[0]} needs the thermal model: the component has no oil (constant "
                                 "viscosities)")
        if given:
            sup = self._supply
            self._set_supply(sup.supply_temperature_K if supply_temperature_K is None else float(supply_temperature_K),
                             sup.supply_pressure_Pa if supply_pressure_Pa is None else float(supply_pressure_Pa))
        near = 1e-6 * h  # a ramp end this close to the step's start or end is taken as there (no sliver of a step)
        if self.speed_source == "ramp" and self.t + near < self.ramp_time < t_end - near:  # a knot: stop there
            self._advance(self.ramp_time, w, tq, acc)
        self._advance(t_end, w, tq, acc, ramp_done=self.t >= self.ramp_time - near)

    def _advance(self, t_end, w, tq, acc, ramp_done=False):

        self._set_inputs(self.t, t_end - self.t, w, tq, acc, ramp_done)
        ts = self._grid(self.t, t_end)
        budget = 500_000 * max(1, min(ts.size - 1, CHUNK_SAMPLES))
        ys, good, h, steps, rejected, status = rodas_chunk(self.y, ts, self.h, self.rtol, self.atol, self.fd_scale,
                                                           self.cols, budget, t_end - self.t, self.problem.args,
                                                           self.modal)
        if status or good < ts.size or not np.all(np.isfinite(ys)):
            why = STATUS.get(status, "non-finite state")
            raise IntegrationError(f"the integrator failed between t = {self.t:.9g} s and {t_end:.9g} s at "
                                   f"{rad_s_to_rpm(self._speed(self.y)):.0f} rpm (compiled Rosenbrock solver: {why})")
        self._evaluate(ts[1:], ys[1:])
        self.y, self.t, self.h = ys[-1].copy(), float(t_end), float(h)

    def _speed(self, y):
        p = self.problem
        return float(y[p.speed_index]) if p.torque_driven else float(np.interp(self.t, p.profile.t, p.profile.omega))

    def _evaluate(self, ts, ys, first=False):
        """Film quantities at the step's grid (one compiled pass): the contact check (raises before anything is
        kept), the smallest film thicknesses, the end state's outputs; the record's rows at the grid points."""
        p = self.problem
        n, nb = ts.size, self._ring_at.size
        w = ys[:, p.speed_index].copy() if p.torque_driven else np.interp(ts, p.profile.t, p.profile.omega)
        eps, torque, power = np.zeros((n, 2 * nb)), np.empty((n, nb)), np.empty((n, nb))
        film_samples(ts, ys, w, p.args, p.diag, p.geom, p.polys, self._journal_at, self._ring_at, self._ring_speed_at,
                     p.n_rotor, EPS_CAP, eps, torque, power)
        worst = np.flatnonzero(eps.max(axis=1) > self.contact_eps)
        if worst.size:
            row = sample_rows(p, self.schema, ts[worst[:1]], ys[worst[:1]])[0]
            raise FilmContactError(contact_message(self.schema, row, self.contact_eps, "the initial state is at "
                                                   "the wall (check start speed, clearances, perturbation)" if first
                                                   else "the step is not taken"))
        thickness = self._clearance.ravel() * (1.0 - eps)
        h_min = thickness.min(axis=0) if first else np.minimum(thickness.min(axis=0), self._thickness_end)
        self._thickness_end, self._h_min = thickness[-1], h_min
        self._end = (float(w[-1]), ys[-1], eps[-1], torque[-1], power[-1])
        self._out = None
        if self._recorder is not None:
            on_grid = np.abs(ts * self.check_rate_hz - np.round(ts * self.check_rate_hz)) <= 1e-6
            self._recorder.extend(sample_rows(p, self.schema, ts[on_grid | first], ys[on_grid | first]))

    # ------------------------------------------------------------------ outputs
    def outputs(self):
        """The output values at the current time, in the order of :func:`output_names` (SI units).

        Returns
        -------
        ndarray
        """
        if self._out is None:
            w, y, eps, torque, power = self._end
            _outer_film_forces(y, self._ring_at, self._ring_speed_at, self.problem.geom, self.problem.polys,
                               EPS_CAP, self._force)
            nb = self._ring_at.size
            per = np.empty((nb, len(BEARING_OUTPUTS)))
            ring_speed = y[self._ring_speed_at]
            per[:, 0], per[:, 1] = torque, power
            per[:, 2:4] = -self._force
            per[:, 4:6] = eps.reshape(nb, 2)
            per[:, 6:8] = self._h_min.reshape(nb, 2)
            per[:, 8], per[:, 9] = ring_speed, ring_speed / w
            per[:, 10], per[:, 11] = y[self._journal_at], y[self._journal_at + 1]
            per[:, 12], per[:, 13] = y[self._ring_at], y[self._ring_at + 1]
            self._out = np.concatenate([(w, y[2 * self.problem.n_rotor + 10]), per.ravel(), y[self._disc_at]])
        return self._out

    def thermal_outputs(self):
        """Film temperatures [K] and oil flows [m³/s] of the thermal operating point at the current rotor speed, in
        the order of :func:`thermal_output_names` (thermal model on; the table interpolated linearly in speed).

        Returns
        -------
        ndarray
        """
        if self._oil is None:
            raise ParameterError("thermal outputs need the thermal model: the component has no oil")
        w, th = self._end[0], self._thermal
        nb = len(self.system.bearings)
        out = np.empty((nb, len(THERMAL_OUTPUTS)))
        for b in range(nb):
            out[b, 0] = np.interp(w, th["speeds"], th["temperature"][2 * b])
            out[b, 1] = np.interp(w, th["speeds"], th["temperature"][2 * b + 1])
            out[b, 2] = np.interp(w, th["speeds"], th["flow"][b])
        return out.ravel()

    # ------------------------------------------------------------------ record and state
    def record(self, out_dir, meta=None):
        """Write the run-up's result files (``runup.csv``, ``runup.json``) into ``out_dir`` from now on, one row
        per point of the check grid (``check_rate_hz``), streamed as the steps go.

        Parameters
        ----------
        out_dir : str or Path
        meta : dict, optional
            Metadata for ``runup.json``.
        """
        self._recorder = Recorder(self.schema, 1024, out_dir, {
            "system": self.system.to_dict(), "film_model": self.problem.film_model,
            "profile": self.problem.profile.description, "output_rate_hz": self.check_rate_hz,
            "integrator": "rodas", "rtol": self.rtol, "atol_displacement_m": float(self.atol[0]),
            "speed_source": self.speed_source, "units": "SI; speed in rpm", **(meta or {})})
        self._recorder.extend(sample_rows(self.problem, self.schema, np.array([self.t]), self._end[1][None, :]))

    def close_record(self, status="finished", message=""):
        """Finish the record (status and message into ``runup.json``); returns its RunupResult or None."""
        if self._recorder is None:
            return None
        rec, self._recorder = self._recorder, None
        return rec.close(status, message)

    def state(self):
        """Everything a later :meth:`set_state` needs (JSON-safe): time, state, next step, held tables, the end
        values of the last step."""
        p = self.problem
        w, y, eps, torque, power = self._end
        return {"t": self.t, "h": self.h, "y": self.y.tolist(),
                **({"supply": [self._supply.supply_temperature_K, self._supply.supply_pressure_Pa]}
                   if self._oil is not None else {}),
                "profile": [p.profile.t.tolist(), p.profile.omega.tolist(), p.profile.omega_dot.tolist()],
                "end": [w, y.tolist(), eps.tolist(), torque.tolist(), power.tolist()],
                "h_min": self._h_min.tolist(), "thickness_end": self._thickness_end.tolist()}

    def set_state(self, st):
        """Restore a :meth:`state` (a record made meanwhile is cut back to its time).

        Parameters
        ----------
        st : dict
            A :meth:`state`.
        """
        p = self.problem
        if "supply" in st:
            self._set_supply(*(float(v) for v in st["supply"]))
        self.t, self.h, self.y = float(st["t"]), float(st["h"]), np.array(st["y"], dtype=float)
        for arr, v in zip((p.profile.t, p.profile.omega, p.profile.omega_dot), st["profile"]):
            arr[:] = v
        w, y, eps, torque, power = st["end"]
        self._end = (float(w), np.array(y), np.array(eps), np.array(torque), np.array(power))
        self._h_min, self._thickness_end = np.array(st["h_min"]), np.array(st["thickness_end"])
        self._out = None
        if self._recorder is not None:
            self._recorder.truncate(self.t)
