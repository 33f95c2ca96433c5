"""Nonlinear run-up: FE rotor + both rings (lateral and spin) + nonlinear films, integrated in compiled code.

The equations are docs/theory/equations-of-motion.md#equations-of-motion: all rotor FE DoFs with gyroscopics (``M q̈ + Ω
G q̇ + (K + Ω̇ G) q``), gravity, optional unbalance per wheel, both rings' lateral DoFs and spin speed (ring speed is a
state, driven by the film torques), and the nonlinear film forces of :mod:`frbmodel.physics.film` (short or
finite-length corrected). The rotor speed follows a prescribed profile, or, torque-driven (:meth:`SpeedProfile.torque`),
is a state driven by a drive torque and braked by the journals' film torques
(:func:`frbmodel.physics.dynamics.spin_acceleration`). The recorded results include the film torque on each journal and
each bearing's friction power (:func:`frbmodel.physics.losses.bearing_loss_kernel`). The right-hand side and its
finite-difference Jacobian are compiled with numba; the stiff, error-controlled integration runs in compiled code too
(the Rosenbrock method RODAS, :mod:`frbmodel.nonlinear.rosenbrock`, or Radau IIA, :mod:`frbmodel.nonlinear.compiled`),
or, as the reference, in scipy's LSODA (``integrator="lsoda"``).
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from ..core.errors import (
    MAX_SPEED_RPM,
    ParameterError,
    RunupStopped,
    check_distinct,
    check_finite,
    check_positive,
    check_real,
    check_speed,
)
from ..core.interrupt import deferred_signals
from ..core.progress import simulation_bar
from ..core.units import RPM
from ..linear.equilibrium import bearing_equilibrium
from ..linear.thermal import at_operating_point, check_oil_supply, ring_lag, thermal_losses
from ..linear.whirl import film_names
from ..physics.bearing import ring_speed_ratio
from ..physics.dynamics import film_data_at_speed, rotor_polar_inertia
from ..physics.dynamics import monolithic_jac as _jac
from ..physics.dynamics import monolithic_rhs as _rhs
from ..physics.film import check_model
from ..physics.losses import bearing_loss_kernel, film_arrays
from ..system.methods import check_spring
from .compiled import pack_problem, solve_chunk
from .recorder import Recorder, RunupResult, RunupSchema
from .rosenbrock import FD_TYPICAL_M, STATUS, film_columns, rodas_chunk

#: numerical guard: film forces of trial states beyond this ε are evaluated at this ε
# (docs/theory/films.md#limits-and-validity)
EPS_CAP = 0.999

__all__ = ["CHUNK_SAMPLES", "DEFAULT_ATOL_M", "DEFAULT_RTOL", "INTEGRATORS", "MAX_PROFILE_POINTS", "MAX_SPEED_RPM",
           "PROFILE_HEADER", "Problem", "RunupResult", "RunupStopped", "SEGMENT_STEPS", "SpeedProfile", "Unbalance",
           "atol_vector", "build_problem", "check_speed", "initial_state", "runup", "sample_row", "typical_sizes",
           "sample_rows", "static_rotor_state"]


# --------------------------------------------------------------------------------------------------
# problem set-up
# --------------------------------------------------------------------------------------------------


def _speed_pair(speed_rpm):
    """(start, end) [rpm] of ``runup``'s ``speed_rpm``: two real numbers (each checked by the ramp)."""
    if isinstance(speed_rpm, (str, bytes)) or np.ndim(speed_rpm) != 1 or len(speed_rpm) != 2:
        raise ParameterError(f"speed_rpm = {speed_rpm!r} is invalid: give (start, end) in rpm, e.g. (20e3, 250e3)")
    return speed_rpm[0], speed_rpm[1]


def check_output_rate(output_rate_hz, duration):
    """Return ``float(output_rate_hz)`` [Hz] or raise :class:`ParameterError`: finite, > 0, and at most
    :data:`MAX_SAMPLES` samples over ``duration`` [s] (a run-up's result is held in memory, ~210 bytes a sample for
    the Table 2 system).

    Examples
    --------
    >>> check_output_rate(20e3, 1.0)
    20000.0
    >>> try:
    ...     check_output_rate(1e12, 0.01)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    output_rate_hz = 1e+12 Hz is invalid for duration = 0.01 s: 1e+10 samples, valid range <= 1e+07 samples ...
    """
    rate = check_positive("output_rate_hz", output_rate_hz, "Hz")
    duration = check_positive("duration", duration, "s")
    if duration * rate < 1.0 - 1e-9:  # the run would record nothing after its start
        raise ParameterError(f"duration = {duration:g} s is invalid at output_rate_hz = {rate:g} Hz: it records no "
                             f"sample after t = 0; valid range duration >= 1 / output_rate_hz = {1.0 / rate:g} s")
    if duration * rate > MAX_SAMPLES:
        raise ParameterError(f"output_rate_hz = {rate:g} Hz is invalid for duration = {duration:g} s: "
                             f"{duration * rate:.3g} samples, valid range <= {MAX_SAMPLES:.0e} samples "
                             f"(rate <= {MAX_SAMPLES / duration:.3g} Hz)")
    return rate


#: grid steps on the shortest segment of a piecewise-linear speed profile with kinks: Ω̇ (piecewise constant) is
#: tabulated at the grid points and interpolated linearly, so at a kink it passes from one slope to the next over
#: one step either side, <= 2 % of any segment
SEGMENT_STEPS = 100
#: most output samples of a run-up (held in memory: 1e7 samples of the Table 2 system are ~2 GB)
MAX_SAMPLES = 10_000_000
#: most grid points of a tabulated speed profile (three float arrays of 16 MB each)
MAX_PROFILE_POINTS = 2_000_001
#: a knot lies on a uniform grid when it is within this fraction of a grid step of a grid point
_ON_GRID_TOL = 1e-6
#: slopes of neighbouring segments that differ by less than this (relative to the largest) are no kink (round-off)
_KINK_TOL = 1e-9


def _knot_cells(t):
    """Number of cells N of the coarsest uniform grid on [0, t[-1]] with every knot ``t`` on a grid point (within
    _ON_GRID_TOL of a step), or None (none with fewer than MAX_PROFILE_POINTS points)."""
    from fractions import Fraction

    x = t / t[-1]

    def fits(n):
        return bool(np.all(np.abs(x * n - np.round(x * n)) <= _ON_GRID_TOL))

    n = max(1, int(round(t[-1] / float(np.min(np.diff(t))))))
    if n < MAX_PROFILE_POINTS and fits(n):
        return n
    n = 1
    for v in x[1:-1]:  # least common multiple of the knots' denominators as fractions of the duration
        n = math.lcm(n, Fraction(float(v)).limit_denominator(MAX_PROFILE_POINTS).denominator)
        if n >= MAX_PROFILE_POINTS:
            return None
    return n if fits(n) else None


def _tabulate(t, rpm):
    """Uniform grid (t_grid [s], Ω [rad/s], Ω̇ [rad/s²]) of the piecewise-linear speed through the knots (t [s],
    rpm), and a note on the grid. Knots on the grid are exact; Ω̇ is the slope of Ω in each cell, the mean of the
    two slopes at a kink."""
    w = rpm * RPM
    slopes = np.diff(w) / np.diff(t)
    kinks = bool(np.any(np.abs(np.diff(slopes)) > _KINK_TOL * max(float(np.max(np.abs(slopes))), 1e-300)))
    exact = _knot_cells(t)
    base = exact or int(math.ceil(t[-1] / float(np.min(np.diff(t))) - 1e-9))
    if base >= MAX_PROFILE_POINTS:
        raise ParameterError(f"speed profile: time steps down to {float(np.min(np.diff(t))):g} s over {t[-1]:g} s "
                             f"need {base + 1} grid points; valid: at most {MAX_PROFILE_POINTS} (resample it coarser)")
    refine = 1
    if kinks:  # at least SEGMENT_STEPS steps on the shortest segment (within the size limit)
        cells_shortest = float(np.min(np.diff(t))) * base / t[-1]
        refine = max(1, min(int(math.ceil(SEGMENT_STEPS / cells_shortest - 1e-9)),
                            (MAX_PROFILE_POINTS - 1) // base))
    n = base * refine
    tg = np.linspace(0.0, t[-1], n + 1)
    if exact:
        idx = np.round(t / t[-1] * exact).astype(np.int64) * refine
        wg = np.interp(np.arange(n + 1), idx, w)
        cell = slopes[np.searchsorted(idx, np.arange(n), side="right") - 1]
        note = "every point of the table on the grid"
    else:
        wg = np.interp(tg, t, w)
        cell = np.diff(wg) / np.diff(tg)
        dev = float(np.max(np.abs(np.interp(t, tg, wg) - w))) / RPM
        note = f"points off the grid: speed within {dev:.3g} rpm of the table"
    wd = np.empty(n + 1)
    wd[0], wd[-1] = cell[0], cell[-1]
    wd[1:-1] = np.where(cell[:-1] == cell[1:], cell[1:], 0.5 * (cell[:-1] + cell[1:]))
    return tg, wg, wd, f"uniform grid of {n + 1} points, step {t[-1] / n:.6g} s, {note}"


def _check_knots(t, rpm, where):
    """Check a speed table: at least 2 points, t[0] = 0, times increasing, speeds in range; ``where(i)`` names
    point i in the messages."""
    if t.size < 2:
        raise ParameterError(f"{where(None)}: {t.size} point(s); a speed profile needs at least 2 (time [s], "
                             "speed [rpm])")
    t, rpm = [float(x) for x in t], [float(x) for x in rpm]
    for i in range(len(t)):
        if not math.isfinite(t[i]):
            raise ParameterError(f"{where(i)}: time = {t[i]!r} s is invalid: it must be finite")
        if i == 0 and t[0] != 0.0:
            raise ParameterError(f"{where(0)}: time = {t[0]!r} s is invalid: the profile must start at t = 0 s")
        if i > 0 and not t[i] > t[i - 1]:
            raise ParameterError(f"{where(i)}: time = {t[i]!r} s is invalid: valid range > {t[i - 1]!r} s (the "
                                 "previous time: times must increase)")
        check_speed(f"{where(i)}: speed", rpm[i])


#: the header a speed-profile CSV must have (case and spaces aside)
PROFILE_HEADER = ("time [s]", "speed [rpm]")


def _read_profile_csv(path):
    """Times [s], speeds [rpm] and the line number of each row of a speed-profile CSV (header checked)."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise ParameterError(f"{path}: cannot read the speed profile: {reason}") from None
    want = ", ".join(PROFILE_HEADER)
    t, rpm, lines, header = [], [], [], None
    for num, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        if header is None:
            header = tuple(" ".join(f.lower().split()) for f in fields)
            if header != PROFILE_HEADER:
                raise ParameterError(f"{path}, line {num}: header {line!r} is invalid: expected {want!r} (the units "
                                     "in brackets: seconds and rpm)")
            continue
        if len(fields) != 2:
            raise ParameterError(f"{path}, line {num}: {line!r} has {len(fields)} values; expected 2 ({want}), "
                                 "separated by a comma")
        for name, f in zip(PROFILE_HEADER, fields):
            try:
                float(f)
            except ValueError:
                raise ParameterError(f"{path}, line {num}: {name} = {f!r} is not a number") from None
        t.append(float(fields[0]))
        rpm.append(float(fields[1]))
        lines.append(num)
    if header is None:
        raise ParameterError(f"{path}: empty; expected the header {want!r} and at least 2 rows")
    return np.array(t), np.array(rpm), lines


@dataclass
class SpeedProfile:
    """Rotor speed vs time, tabulated (linear interpolation inside the RHS), or a torque-driven rotor.

    Build with :meth:`ramp`, :meth:`constant`, :meth:`exponential`, :meth:`from_function`, :meth:`from_csv`,
    :meth:`piecewise_linear` or :meth:`up_down`. A profile whose speed falls is a run-down (:attr:`direction`
    ``"down"``); one that rises and then falls is ``"up-down"``. :meth:`torque` makes the rotor
    speed a state instead: J_p Ω̇ = T_drive(t) + Σ T_J
    (docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up); then ``omega`` holds only the start speed
    and ``drive_torque`` the drive torque [N m] on the grid ``t``.

    Parameters
    ----------
    t : ndarray (nt,)
        Uniform time grid [s], from 0 to the duration.
    omega : ndarray (nt,)
        Rotor speed Ω on the grid [rad/s] (torque-driven: the start speed everywhere).
    omega_dot : ndarray (nt,)
        Rotor acceleration Ω̇ on the grid [rad/s²] (torque-driven: zeros, unused).
    description : str
        Human-readable description (written to the result's metadata).
    drive_torque : ndarray (nt,), optional
        Drive torque [N m] on the grid ``t`` of a torque-driven rotor; None for a prescribed speed.

    Examples
    --------
    >>> p = SpeedProfile.ramp(250e3, 20e3, 1.0)
    >>> p.direction, p.description
    ('down', 'linear run-down 250000 -> 20000 rpm in 1 s')
    >>> round(float(p(0.5)) * 60 / (2 * np.pi))  # speed at t = 0.5 s [rpm]
    135000
    """

    t: np.ndarray  # [s], uniform grid
    omega: np.ndarray  # [rad/s]
    omega_dot: np.ndarray  # [rad/s²]
    description: str
    drive_torque: np.ndarray | None = None  # [N m] on the grid t (torque-driven rotor), else None

    @property
    def torque_driven(self):
        """True if the rotor speed is a state driven by :attr:`drive_torque` (:meth:`torque`)."""
        return self.drive_torque is not None

    @property
    def direction(self):
        """``"up"`` or ``"down"`` (the speed never falls / never rises, and changes), ``"constant"``, ``"up-down"``
        (it rises to its top speed and then falls: a run-up followed by a run-down, :meth:`up_down`) or
        ``"mixed"`` (any other course). Torque-driven: ``"up"`` if the mean drive torque is positive, else
        ``"down"`` (the films only brake).

        Examples
        --------
        >>> [SpeedProfile.piecewise_linear([0, 1, 2], s).direction for s in ([1e3, 2e3, 2e3], [2e3, 1e3, 2e3])]
        ['up', 'mixed']
        """
        if self.torque_driven:
            return "up" if float(np.mean(self.drive_torque)) > 0 else "down"
        d = np.diff(self.omega)
        if not np.any(d):
            return "constant"
        if np.all(d >= 0) or np.all(d <= 0):
            return "up" if d.sum() > 0 else "down"
        top = int(np.argmax(self.omega))
        return "up-down" if np.all(d[:top] >= 0) and np.all(d[top:] <= 0) else "mixed"

    @staticmethod
    def _checked(start_rpm, end_rpm, duration):
        return (check_speed("start speed", start_rpm), check_speed("end speed", end_rpm),
                check_positive("duration", duration, "s"))

    @classmethod
    def ramp(cls, start_rpm, end_rpm, duration):
        """Linear ramp from ``start_rpm`` to ``end_rpm`` [rpm] in ``duration`` [s] (a run-down if end < start).

        Parameters
        ----------
        start_rpm, end_rpm : float
            Start and end rotor speed [rpm], each in 0 < speed <= :data:`MAX_SPEED_RPM`.
        duration : float
            Ramp time [s], > 0.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> p = SpeedProfile.ramp(20e3, 80e3, 2.0)
        >>> round(float(p.omega_dot[0]) * 60 / (2 * np.pi))  # acceleration [rpm/s]
        30000
        """
        start_rpm, end_rpm, duration = cls._checked(start_rpm, end_rpm, duration)
        t = np.array([0.0, duration])
        w = np.array([start_rpm, end_rpm]) * RPM
        a = (w[1] - w[0]) / duration
        kind = "run-down" if end_rpm < start_rpm else "ramp"
        return cls(t, w, np.array([a, a]), f"linear {kind} {start_rpm:.0f} -> {end_rpm:.0f} rpm in {duration:g} s")

    @classmethod
    def constant(cls, speed_rpm, duration):
        """Constant speed for a duration.

        Parameters
        ----------
        speed_rpm : float
            Rotor speed [rpm].
        duration : float
            Simulated time [s], > 0.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> SpeedProfile.constant(100e3, 0.1).direction
        'constant'
        """
        speed_rpm, _, duration = cls._checked(speed_rpm, speed_rpm, duration)
        return cls(np.array([0.0, duration]), np.full(2, speed_rpm * RPM), np.zeros(2),
                   f"constant {speed_rpm:.0f} rpm")

    @classmethod
    def exponential(cls, start_rpm, end_rpm, duration, n=20001):
        """Constant relative acceleration: Ω(t) = Ω0 (Ω1/Ω0)^(t/T) — equal time per speed octave, so low-speed
        onsets get as many vibration periods as high-speed ones.

        Parameters
        ----------
        start_rpm, end_rpm : float
            Start and end rotor speed [rpm].
        duration : float
            Duration T [s], > 0.
        n : int
            Number of grid points of the table.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> p = SpeedProfile.exponential(10e3, 40e3, 2.0, n=5)
        >>> (p.omega * 60 / (2 * np.pi)).round(6).tolist()  # one octave per second
        [10000.0, 14142.135624, 20000.0, 28284.271247, 40000.0]
        """
        start_rpm, end_rpm, duration = cls._checked(start_rpm, end_rpm, duration)
        t = np.linspace(0.0, duration, n)
        rate = math.log(end_rpm / start_rpm) / duration
        w = start_rpm * RPM * np.exp(rate * t)
        kind = "run-down" if end_rpm < start_rpm else "ramp"
        return cls(t, w, rate * w, f"exponential {kind} {start_rpm:.0f} -> {end_rpm:.0f} rpm in {duration:g} s")

    @classmethod
    def from_function(cls, fun, duration, n=20001):
        """A speed profile from a function, tabulated on ``n`` points; Ω̇ by central differences.

        Parameters
        ----------
        fun : callable
            ``fun(t [s]) -> speed [rpm]``, in 0 < speed <= :data:`MAX_SPEED_RPM` for 0 <= t <= duration.
        duration : float
            Duration [s], > 0.
        n : int
            Number of grid points of the table.

        Returns
        -------
        SpeedProfile

        Raises
        ------
        ParameterError
            If ``fun`` gives a speed out of range (naming the time).

        Examples
        --------
        >>> p = SpeedProfile.from_function(lambda t: 1000.0 + 500.0 * t, 2.0, n=5)
        >>> p.direction, (p.omega * 60 / (2 * np.pi)).round(9).tolist()
        ('up', [1000.0, 1250.0, 1500.0, 1750.0, 2000.0])
        """
        duration = check_positive("duration", duration, "s")
        t = np.linspace(0.0, duration, n)
        rpm = np.array([float(fun(x)) for x in t])
        bad = np.flatnonzero(~(np.isfinite(rpm) & (rpm > 0) & (rpm <= MAX_SPEED_RPM)))
        if bad.size:
            raise ParameterError(f"speed profile function: speed = {float(rpm[bad[0]])!r} rpm at t = {t[bad[0]]:g} s "
                                 f"is invalid: valid range 0 < speed <= {MAX_SPEED_RPM:.0e} rpm for 0 <= t <= duration")
        w = rpm * RPM
        return cls(t, w, np.gradient(w, t), "user function")

    @classmethod
    def torque(cls, drive_torque_Nm, start_rpm, duration, n=20001):
        """Torque-driven rotor: the speed starts at ``start_rpm`` and follows J_p Ω̇ = T_drive(t) + Σ T_J, with the
        journals' film torques T_J braking it (docs/theory/equations-of-motion.md#linear-form-and-nonlinear-run-up; J_p
        from the system's rotor).

        Parameters
        ----------
        drive_torque_Nm : float or callable
            Net external torque about +z [N m] (turbine minus compressor), constant or ``fun(t [s]) -> N m``
            (tabulated on ``n`` points).
        start_rpm : float
            Initial rotor speed [rpm].
        duration : float
            Simulated time [s], > 0.
        n : int
            Number of grid points of a tabulated drive torque function.

        Returns
        -------
        SpeedProfile

        Raises
        ------
        ParameterError
            If the start speed or duration is out of range or the drive torque is not finite.

        Examples
        --------
        >>> p = SpeedProfile.torque(2e-3, 2000, 0.1)
        >>> p.torque_driven, p.description
        (True, 'torque-driven from 2000 rpm, drive torque 0.002 N m, 0.1 s')
        """
        start_rpm, _, duration = cls._checked(start_rpm, start_rpm, duration)
        if callable(drive_torque_Nm):
            t = np.linspace(0.0, duration, n)
            tq = np.array([float(drive_torque_Nm(x)) for x in t])
            text = "user function"
        else:
            t = np.array([0.0, duration])
            tq = np.full(2, check_finite("drive torque", drive_torque_Nm, "N m"))
            text = f"{tq[0]:g} N m"
        bad = np.flatnonzero(~np.isfinite(tq))
        if bad.size:
            raise ParameterError(f"drive torque = {tq[bad[0]]!r} N m at t = {t[bad[0]]:g} s is invalid: it must be "
                                 "finite")
        return cls(t, np.full(t.size, start_rpm * RPM), np.zeros(t.size),
                   f"torque-driven from {start_rpm:.0f} rpm, drive torque {text}, {duration:g} s", tq)

    @classmethod
    def piecewise_linear(cls, t_s, speed_rpm, description=None):
        """Speed linear between the points of a table (t [s], speed [rpm]), tabulated on the uniform grid the
        right-hand side needs (:func:`frbmodel.physics.dynamics.interp_uniform`).

        The grid is the coarsest uniform one that holds every point of the table (e.g. the table's own step if it
        is uniform), so the speed is exact there and in between; a table whose points fit no uniform grid of at
        most :data:`MAX_PROFILE_POINTS` points is sampled with a step at most its smallest, and the description
        says how far the speed then departs from the table. Ω̇ is piecewise constant (the slope of each segment);
        where the slope changes (a kink) the grid is refined to at least :data:`SEGMENT_STEPS` steps on the
        shortest segment, because the tabulated Ω̇ is interpolated linearly: it takes the mean of both slopes at
        the kink and passes from one to the other within one step either side (its integral over the run is
        still the speed change). A table of two points is the same profile as :meth:`ramp`, bit for bit.

        Parameters
        ----------
        t_s : array_like (n,)
            Times [s], starting at 0 and increasing, n >= 2.
        speed_rpm : array_like (n,)
            Rotor speed at those times [rpm], each in 0 < speed <= :data:`MAX_SPEED_RPM`.
        description : str, optional
            Description for the result's metadata (default: the table's extent and the grid).

        Returns
        -------
        SpeedProfile

        Raises
        ------
        ParameterError
            Fewer than 2 points, a first time other than 0, times not increasing, a speed out of range (naming
            the point), or a table that needs more than :data:`MAX_PROFILE_POINTS` grid points.

        Examples
        --------
        >>> p = SpeedProfile.piecewise_linear([0.0, 0.2, 0.5], [20e3, 60e3, 60e3])
        >>> p.t.size, round(float(p.t[1] - p.t[0]), 9), p.direction  # 0.1 s holds both points: 100 steps on 0.2 s
        (251, 0.002, 'up')
        >>> round(float(p(0.1)) / RPM), [round(float(p.omega_dot[k]) / RPM) for k in (50, 100, 150)]  # [rpm/s]
        (40000, [200000, 100000, 0])
        """
        t = np.asarray(t_s, dtype=float).ravel()
        rpm = np.asarray(speed_rpm, dtype=float).ravel()
        if t.size != rpm.size:
            raise ParameterError(f"speed profile: {t.size} times and {rpm.size} speeds; they must pair up")
        _check_knots(t, rpm, lambda i: "speed profile" + ("" if i is None else f", point {i}"))
        tg, wg, wd, grid = _tabulate(t, rpm)
        text = description or (f"piecewise-linear profile of {t.size} points, {rpm.min():.0f} ... {rpm.max():.0f} "
                               f"rpm in {t[-1]:g} s")
        return cls(tg, wg, wd, f"{text}; {grid}")

    @classmethod
    def from_csv(cls, path):
        """Speed profile from a CSV table with the header ``time [s], speed [rpm]`` (the speed linear in between,
        see :meth:`piecewise_linear` for the grid and Ω̇).

        Blank lines and lines starting with ``#`` are skipped; the separator is a comma.

        Parameters
        ----------
        path : str or Path
            The CSV file: a header line ``time [s], speed [rpm]`` (units in brackets), then one ``time, speed``
            row per point, the first at time 0, times increasing, speeds in 0 < speed <= :data:`MAX_SPEED_RPM`.

        Returns
        -------
        SpeedProfile

        Raises
        ------
        ParameterError
            Naming the file, the line, the value and the valid range: a missing or different header, a row that
            is not two numbers, a first time other than 0, a time not above the previous one, a speed out of
            range, fewer than 2 rows; or an unreadable file.

        Examples
        --------
        >>> import tempfile
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     path = Path(tmp) / "ramp.csv"
        ...     _ = path.write_text("time [s], speed [rpm]\\n0, 20000\\n1.0, 60000\\n")
        ...     p = SpeedProfile.from_csv(path)
        >>> q = SpeedProfile.ramp(20e3, 60e3, 1.0)
        >>> all(np.array_equal(a, b) for a, b in ((p.t, q.t), (p.omega, q.omega), (p.omega_dot, q.omega_dot)))
        True
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     path = Path(tmp) / "bad.csv"
        ...     _ = path.write_text("time [s], speed [rpm]\\n0, 20000\\n0.5, -3\\n")
        ...     try:
        ...         SpeedProfile.from_csv(path)
        ...     except ParameterError as exc:
        ...         print(str(exc).replace(str(path), "bad.csv"))
        bad.csv, line 3: speed = -3.0 rpm is invalid: valid range is finite and > 0 rpm
        """
        if not str(path).strip():  # (Path("") is the current folder: "cannot read the speed profile: Is a directory")
            raise ParameterError(f"speed profile file = {str(path)!r} is invalid: give the path of a CSV file")
        if Path(path).is_dir():
            raise ParameterError(f"speed profile file = {str(path)!r} is a folder; expected a CSV file")
        path = Path(path)
        t, rpm, lines = _read_profile_csv(path)
        _check_knots(t, rpm, lambda i: f"{path}" + ("" if i is None else f", line {lines[i]}"))
        tg, wg, wd, grid = _tabulate(t, rpm)
        return cls(tg, wg, wd, f"speed profile {path.name} ({t.size} rows, {rpm.min():.0f} ... {rpm.max():.0f} rpm "
                               f"in {t[-1]:g} s); {grid}")

    @classmethod
    def up_down(cls, start_rpm, top_rpm, ramp_s, hold_s=0.0, end_rpm=None):
        """A run-up followed by a run-down in one run (to see hysteresis): linear from ``start_rpm`` to
        ``top_rpm`` in ``ramp_s``, held for ``hold_s``, then linear down to ``end_rpm`` in ``ramp_s``
        (:attr:`direction` ``"up-down"``; tabulated by :meth:`piecewise_linear`).

        Parameters
        ----------
        start_rpm, top_rpm : float
            Start and top rotor speed [rpm], top > start.
        ramp_s : float
            Duration of each ramp [s], > 0.
        hold_s : float
            Time at the top speed [s], >= 0.
        end_rpm : float, optional
            End speed [rpm], below the top (default: ``start_rpm``).

        Returns
        -------
        SpeedProfile
            Duration 2 ``ramp_s`` + ``hold_s``.

        Raises
        ------
        ParameterError
            A speed or time out of range, or a top speed not above the start and end speeds.

        Examples
        --------
        >>> p = SpeedProfile.up_down(20e3, 60e3, 0.5)
        >>> p.direction, float(p.t[-1]), [round(float(p(t)) / RPM) for t in (0.0, 0.25, 0.5, 0.75, 1.0)]
        ('up-down', 1.0, [20000, 40000, 60000, 40000, 20000])
        """
        start = check_speed("start speed", start_rpm)
        top = check_speed("top speed", top_rpm)
        end = start if end_rpm is None else check_speed("end speed", end_rpm)
        ramp_s = check_positive("ramp time", ramp_s, "s")
        hold_s = check_positive("hold time", hold_s, "s", allow_zero=True)
        if not top > max(start, end):
            raise ParameterError(f"top speed = {top_rpm!r} rpm is invalid: valid range > {max(start, end):g} rpm "
                                 "(above the start and end speeds)")
        t = [0.0, ramp_s] + ([ramp_s + hold_s] if hold_s > 0 else []) + [2 * ramp_s + hold_s]
        rpm = [start, top] + ([top] if hold_s > 0 else []) + [end]
        hold = f", {hold_s:g} s at the top" if hold_s > 0 else ""
        return cls.piecewise_linear(t, rpm, f"run-up and run-down {start:.0f} -> {top:.0f} -> {end:.0f} rpm, "
                                            f"{ramp_s:g} s each way{hold}")

    def __call__(self, t):
        """Prescribed rotor speed [rad/s] at ``t`` [s] (for a torque-driven profile: the start speed).

        Parameters
        ----------
        t : float or array_like
            Time [s].

        Returns
        -------
        float or ndarray
            Ω [rad/s], linearly interpolated in the table.
        """
        return np.interp(t, self.t, self.omega)


@dataclass
class Unbalance:
    """Unbalance of one wheel: ``amount`` [kg m] (mass × eccentricity) at ``phase`` [rad] (from +x, CCW).

    Parameters
    ----------
    disc : str
        Name of the rotor disc that carries it (e.g. ``"turbine_wheel"``).
    amount : float
        Unbalance m e [kg m], >= 0 (1e-6 kg m = 1 g mm).
    phase : float
        Angular position at rotation angle 0 [rad], from +x, counter-clockwise.

    Examples
    --------
    >>> u = Unbalance("turbine_wheel", 1e-6)
    >>> u.amount * 1e6, u.phase  # [g mm], [rad]
    (1.0, 0.0)
    """

    disc: str
    amount: float
    phase: float = 0.0

    def __post_init__(self):  # (an infinite phase ended the run at t = 0: "singular iteration matrix", exit 3)
        # (the amount was checked by the run-up only, after its thermal table; its upper bound is the disc's own,
        # applied where the unbalance meets its rotor: unbalance_arrays)
        self.amount = check_real(f"unbalance of {self.disc}", self.amount, "kg m", minimum=0.0, inclusive=True)
        self.phase = check_real(f"unbalance phase of {self.disc}", self.phase, "rad")


def unbalance_arrays(rotor, unbalance):
    """Disc nodes, m e [kg m] and phases [rad] of the :class:`Unbalance` list ``unbalance`` on ``rotor``, or a
    :class:`ParameterError`: each disc at most once (two entries on one disc were summed; give their resultant) and
    each m e within its disc's bound (:meth:`frbmodel.system.rotor.Rotor.check_unbalance`).

    Examples
    --------
    >>> from frbmodel.system.presets import turbocharger
    >>> unbalance_arrays(turbocharger().rotor, [Unbalance("compressor_wheel", 2e-6, 0.5)])
    (array([3]), array([2.e-06]), array([0.5]))
    """
    unbalance = list(unbalance)
    names = [u.disc for u in unbalance]
    check_distinct(f"unbalance discs {names}", names)
    checked = [rotor.check_unbalance(u.disc, u.amount) for u in unbalance]
    return (np.array([d.node for d, _ in checked], dtype=np.int64), np.array([a for _, a in checked], dtype=float),
            np.array([float(u.phase) for u in unbalance], dtype=float))


@dataclass
class Problem:
    """Constant data of a monolithic run-up: the compiled RHS's arguments and the state layout.

    State y = [q (n_r), q̇ (n_r), ring_b (x, y, vx, vy) for each bearing, ring speeds, rotation angle] and, for a
    torque-driven rotor, the rotor speed [rad/s] last. Build with :func:`build_problem`.

    Parameters
    ----------
    system : Turbocharger
        The system (two bearings).
    profile : SpeedProfile
        Rotor speed profile.
    film_model : str
        Film model (``"short"`` or ``"short_corrected"``).
    args : tuple
        Trailing arguments of :func:`frbmodel.physics.dynamics.monolithic_rhs` / ``monolithic_jac``.
    n_rotor : int
        Number of rotor DoFs n_r (4 per node).
    springs : float
        Linear journal spring stiffness [N/m] instead of the films; 0 for films.
    diag : ndarray (4,)
        Filled by each RHS call with the films' eccentricity ratios [-].
    polar_inertia : float
        Rotor polar moment of inertia J_p [kg m²].
    geom : ndarray (2, 2, 4), optional
        Film data per bearing (:func:`frbmodel.physics.losses.film_arrays`) [m, m, m, Pa s].
    polys : ndarray (2, 2, 2, 5), optional
        Correction polynomials per bearing.

    Examples
    --------
    >>> import frbmodel as frb
    >>> p = build_problem(frb.turbocharger(), SpeedProfile.constant(100e3, 0.1), "short")
    >>> p.n_rotor, p.n_states, p.ring_index(1), p.ring_speed_index(0), p.speed_index
    (16, 43, 36, 40, None)
    >>> round(p.speed(0.05) * 60 / (2 * np.pi))  # [rpm]
    100000
    """

    system: object
    profile: SpeedProfile
    film_model: str
    args: tuple  # trailing arguments of frbmodel.physics.dynamics.monolithic_rhs / monolithic_jac
    n_rotor: int
    springs: float
    diag: np.ndarray  # filled by each RHS call with the films' eccentricity ratios
    polar_inertia: float = 0.0  # rotor J_p [kg m²]
    geom: np.ndarray | None = None  # (2, 2, 4) film data per bearing (frbmodel.physics.losses.film_arrays)
    polys: np.ndarray | None = None  # (2, 2, 2, 5) correction polynomials per bearing

    @property
    def torque_driven(self):
        """True if the rotor speed is a state (:meth:`SpeedProfile.torque`)."""
        return self.profile.torque_driven

    @property
    def housing_acc(self):
        """The housing acceleration (a_x, a_y) [m/s²] the right-hand side reads (an array in :attr:`args`; zero in a
        run-up, set by a stepped component before each call of the integrator)."""
        return self.args[18]

    @property
    def n_states(self):
        """Length of the state vector: 2 n_r + 11 (+ 1 for a torque-driven rotor)."""
        return 2 * self.n_rotor + 11 + (1 if self.torque_driven else 0)

    @property
    def speed_index(self):
        """Index of the rotor speed in the state (torque-driven rotor), else None."""
        return 2 * self.n_rotor + 11 if self.torque_driven else None

    def ring_index(self, b):
        """Index of bearing ``b``'s ring x in the state (followed by y, vx, vy).

        Parameters
        ----------
        b : int
            Bearing index (order of ``system.bearings``).

        Returns
        -------
        int
        """
        return 2 * self.n_rotor + 4 * b

    def ring_speed_index(self, b):
        """Index of bearing ``b``'s ring spin speed [rad/s] in the state.

        Parameters
        ----------
        b : int
            Bearing index (order of ``system.bearings``).

        Returns
        -------
        int
        """
        return 2 * self.n_rotor + 8 + b

    def rhs(self, t, y, out):
        """dy/dt of the compiled model (:func:`frbmodel.physics.dynamics.monolithic_rhs`); also fills :attr:`diag`.

        Parameters
        ----------
        t : float
            Time [s].
        y : ndarray (n_states,)
            State (SI units).
        out : ndarray (n_states,)
            Receives dy/dt.

        Returns
        -------
        ndarray (n_states,)
            ``out``.
        """
        return _rhs(t, y, out, *self.args)

    def speed(self, t, y=None):
        """Rotor speed [rad/s] at time ``t`` [s] (torque-driven: from the state ``y``).

        Parameters
        ----------
        t : float
            Time [s].
        y : ndarray (n_states,), optional
            State; needed for a torque-driven rotor.

        Returns
        -------
        float
            Ω [rad/s].
        """
        if self.torque_driven:
            return float(y[self.speed_index])
        return float(np.interp(t, self.profile.t, self.profile.omega))


def housing_mass(rotor):
    """M T_x and M T_y (2, n_r) of the rotor [kg, kg m]: the load of a unit housing acceleration along x and y is
    minus these rows (:meth:`frbmodel.system.rotor.Rotor.translation_load`;
    :func:`frbmodel.physics.dynamics.monolithic_rhs`)."""
    return np.vstack([rotor.translation_load(1.0, 0.0), rotor.translation_load(0.0, 1.0)])


#: rotor speeds of the quasi-static viscosity table over a run-up's speed range (docs/theory/thermal.md#run-ups)
VISCOSITY_TABLE_SPEEDS = 97
#: lowest speed of the viscosity table [rpm] (below it the table holds its first row: the films are then within
#: 0.1 K of the supply temperature)
VISCOSITY_TABLE_MIN_RPM = 1e3


def viscosity_table(system, speeds_rpm, oil_supply):
    """Film viscosities [Pa s] over rotor speed from the thermal operating points (:func:`thermal_losses`) on a
    uniform grid through ``speeds_rpm``'s range: the quasi-static temperatures of a run-up.

    Parameters
    ----------
    system : Turbocharger
    speeds_rpm : array_like
        The speeds the run covers [rpm] (its profile).
    oil_supply : OilSupply

    Returns
    -------
    speeds : ndarray (nv,)
        Uniform grid [rad/s] from max(min speed, 1000 rpm) to the highest speed (:data:`VISCOSITY_TABLE_SPEEDS`
        points; one point for a constant speed, repeated).
    table : ndarray (4, nv)
        Viscosities [Pa s]: turbine inner, outer, compressor inner, outer.
    """
    lo = max(float(np.min(speeds_rpm)), VISCOSITY_TABLE_MIN_RPM)
    hi = max(float(np.max(speeds_rpm)), lo)
    grid = np.linspace(lo, hi, VISCOSITY_TABLE_SPEEDS) if hi > lo * (1 + 1e-12) else np.array([lo, lo * (1 + 1e-9)])
    tab = thermal_losses(system, grid, oil_supply.oil, oil_supply.supply_temperature_K, oil_supply.supply_pressure_Pa,
                         oil_supply.model)
    nb = len(system.bearings)
    mu = tab[["inner viscosity [Pa s]", "outer viscosity [Pa s]"]].to_numpy().reshape(grid.size, nb, 2)
    return grid * RPM, np.ascontiguousarray(mu.reshape(grid.size, 2 * nb).T)


def table_speeds_rpm(profile, polar_inertia):
    """The rotor speeds [rpm] the viscosity table must span: a prescribed profile's speeds; torque-driven, from
    :data:`VISCOSITY_TABLE_MIN_RPM` to the bound Ω₀ + ∫ max(T_drive, 0) dt / J_p (the films' torques only brake the
    journal, so the speed cannot exceed it; the trapezoidal rule on the clipped nodes is an upper bound of the
    integral of the clipped piecewise-linear torque, max(·, 0) being convex)."""
    if not profile.torque_driven:
        return profile.omega / RPM
    impulse = float(np.trapezoid(np.maximum(profile.drive_torque, 0.0), profile.t))
    top = (float(profile.omega[0]) + impulse / polar_inertia) / RPM
    return np.array([VISCOSITY_TABLE_MIN_RPM, max(top, VISCOSITY_TABLE_MIN_RPM)])


def lagged_viscosity_table(system, profile, oil_supply):
    """Film viscosities [Pa s] over rotor speed with the rings' temperatures as states (:func:`ring_lag` along the
    profile's speed history, ``oil_supply.model.ring_heat_capacity_J_K``): on a monotonic prescribed profile each
    speed is passed once, so the lagged temperatures are a function of the speed and go into the same uniform
    table as :func:`viscosity_table`'s (the compiled right-hand side is unchanged).

    Parameters
    ----------
    system : Turbocharger
    profile : SpeedProfile
        Prescribed, strictly monotonic in speed.
    oil_supply : OilSupply

    Returns
    -------
    speeds : ndarray (nv,)
        Uniform grid [rad/s] (:data:`VISCOSITY_TABLE_SPEEDS` points) over the profile's speeds.
    table : ndarray (4, nv)
        Viscosities [Pa s]: turbine inner, outer, compressor inner, outer.
    """
    check_lag_profile(profile)
    w = np.asarray(profile.omega, dtype=float)
    d = np.diff(w)
    lo, hi = max(float(w.min()) / RPM, VISCOSITY_TABLE_MIN_RPM), float(w.max()) / RPM
    grid = np.linspace(lo, hi, VISCOSITY_TABLE_SPEEDS)
    inc = d[0] > 0
    times = np.interp(grid * RPM, w if inc else w[::-1], profile.t if inc else profile.t[::-1])
    order = np.argsort(times)
    mu = ring_lag(system, times[order], grid[order], oil_supply)[4]
    table = np.empty_like(mu)
    table[:, order] = mu
    return grid * RPM, np.ascontiguousarray(table)


def check_lag_profile(profile, name="profile", capacity_name="ring_heat_capacity_J_K"):
    """Refuse a profile on which the rings' lagged temperatures are not a function of the speed (torque-driven,
    constant, or not monotonic): a ParameterError naming ``name`` and ``capacity_name``."""
    w = np.asarray(profile.omega, dtype=float)
    d = np.diff(w)
    if profile.torque_driven or w.size < 2 or not (np.all(d > 0) or np.all(d < 0)):
        raise ParameterError(f"{name} = {profile.description} cannot take {capacity_name}: the rings' temperatures as "
                             "states need a prescribed profile whose speed rises or falls throughout (a ramp or an "
                             "exponential run-up/run-down), so that they are a function of the speed; leave "
                             f"{capacity_name} unset (quasi-static temperatures)")


def check_runup_oil(oil_supply, profile, integrator="rodas", linear_springs=None, names=("integrator", "profile"),
                    system=None):
    """Refuse an oil supply a run cannot use: not an :class:`OilSupply`, linear springs (no films) or feed holes
    that do not fit the rings of ``system`` (:func:`frbmodel.linear.thermal.check_oil_supply`). Every
    integrator takes it (the ``"radau"`` path packs the viscosity table, :func:`frbmodel.nonlinear.compiled.
    pack_problem`), and so does a torque-driven rotor (its table spans :func:`table_speeds_rpm`); ``profile``,
    ``integrator`` and ``names`` are kept for the callers (the CLI's option names)."""
    sup = check_oil_supply(oil_supply, bearings=() if system is None else system.bearings)
    if sup is None:
        return None
    if linear_springs is not None:
        raise ParameterError("linear_springs cannot take an oil supply: the journals have no films")
    if sup.model.ring_heat_capacity_J_K is not None:
        check_lag_profile(profile, names[1], "--ring-heat-capacity" if names[1].startswith("--") else
                          "ring_heat_capacity_J_K")
    return sup


def build_problem(system, profile, film_model, unbalance=(), linear_springs=None, oil_supply=None):
    """Problem set-up: matrices, film geometry and correction polynomials, rings, unbalance, speed table.

    Parameters
    ----------
    system : Turbocharger
        Two bearings (the compiled RHS's layout).
    profile : SpeedProfile
        Rotor speed profile (uniform time grid).
    film_model : {"short", "short_corrected"}
        Film model.
    unbalance : sequence of Unbalance
        Rotating unbalances.
    linear_springs : float, optional
        Isotropic journal springs [N/m] instead of the films (method A's bearing, for verification).
    oil_supply : OilSupply, optional
        The thermal model with quasi-static temperatures: the films' viscosities follow the rotor speed through
        :func:`viscosity_table` (interpolated in the compiled right-hand side); with the model's
        ``ring_heat_capacity_J_K`` the rings' temperatures lag (:func:`lagged_viscosity_table`, monotonic prescribed
        profiles only); ``problem.system`` is the system at the start speed's operating point (its initial
        equilibrium). None: constant viscosities, bit for bit.

    Returns
    -------
    Problem

    Raises
    ------
    ParameterError
        Not two bearings, an unbalance outside its disc's range or on a disc twice (:func:`unbalance_arrays`), a
        negative spring stiffness, a non-uniform time grid, a torque-driven rotor without polar inertia, or an oil
        supply with linear springs.

    Examples
    --------
    See :class:`Problem`.
    """
    if len(system.bearings) != 2:
        raise ParameterError(f"the run-up needs exactly 2 bearings, the system has {len(system.bearings)}")
    rotor = system.rotor
    springs = 0.0 if linear_springs is None else check_spring("linear_springs", linear_springs)
    unb_node, unb_me, unb_phase = unbalance_arrays(rotor, unbalance)  # (before the thermal tables: it was after)
    sup = check_runup_oil(oil_supply, profile, "rodas", linear_springs, system=system)
    visc = (None, None)
    if sup is not None:
        visc = lagged_viscosity_table(system, profile, sup) if sup.model.ring_heat_capacity_J_K is not None else \
            viscosity_table(system, table_speeds_rpm(profile, rotor_polar_inertia(rotor)), sup)
        system = at_operating_point(system, max(float(profile.omega[0]) / RPM, VISCOSITY_TABLE_MIN_RPM), sup)
    arrays = [film_arrays(b, film_model) for b in system.bearings]
    geom = np.array([a[0] for a in arrays])
    polys = np.array([a[1] for a in arrays])
    tg = profile.t
    if tg.size > 2 and not np.allclose(np.diff(tg), tg[1] - tg[0]):
        raise ParameterError("speed profile: the time grid must be uniform (SpeedProfile builds it so)")
    diag = np.zeros(4)
    args = (rotor.acceleration_matrices, rotor.gravity_load(system.gravity), rotor.n_dof,
            np.array([b.node for b in system.bearings], dtype=np.int64), geom, polys,
            np.array([b.ring_mass for b in system.bearings]), np.array([b.ring_inertia for b in system.bearings]),
            system.gravity, unb_node, unb_me, unb_phase, tg, profile.omega, profile.omega_dot, springs, EPS_CAP, diag,
            np.zeros(2), housing_mass(rotor))
    jp = rotor_polar_inertia(rotor)
    if profile.torque_driven and not jp > 0:
        raise ParameterError(f"rotor polar inertia = {jp!r} kg m^2 is invalid for a torque-driven rotor: valid "
                             "range > 0")
    # polar inertia, drive torque (None: a prescribed speed) and the viscosity table (None, None: constant
    # viscosities) last, so the arguments have one layout
    args = args + (jp, np.asarray(profile.drive_torque, dtype=float) if profile.torque_driven else None) + visc
    return Problem(system, profile, film_model, args, rotor.n_dof, springs, diag, jp, geom, polys)


def initial_state(problem, initial="equilibrium", perturbation=0.05):
    """Initial state y0: the method-J static equilibrium at the start speed (``initial="equilibrium"``) or centred
    members (``"centred"``), both journals and rings offset in +x by ``perturbation`` × their clearances; with
    linear springs the static deflection on the springs.

    Parameters
    ----------
    problem : Problem
        The run-up problem (:func:`build_problem`).
    initial : {"equilibrium", "centred"}
        Start from the static equilibrium or from centred journals and rings (ring speeds by eq. (6)).
    perturbation : float
        Offset in +x [-], as a fraction of the clearance: the ring by its outer clearance, the journal by the sum
        of both (so that the inner film is offset by its clearance fraction too).

    Returns
    -------
    ndarray (problem.n_states,)
        y0 in SI units.

    Raises
    ------
    ParameterError
        For an unknown ``initial``.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> p = build_problem(tc, SpeedProfile.constant(100e3, 0.1), "short")
    >>> y0 = initial_state(p, "centred", perturbation=0.05)
    >>> b = tc.bearings[0]
    >>> bool(np.isclose(y0[4 * b.node], 0.05 * (b.inner.clearance + b.outer.clearance), rtol=1e-12, atol=0))
    True
    """

    system, rotor, n_r = problem.system, problem.system.rotor, problem.n_rotor
    w0 = float(problem.profile.omega[0])
    y0 = np.zeros(problem.n_states)
    if problem.torque_driven:
        y0[problem.speed_index] = w0
    clear_i = [b.inner.clearance for b in system.bearings]
    clear_o = [b.outer.clearance for b in system.bearings]
    if problem.springs > 0:
        ktot = rotor.K.copy()
        for b in system.bearings:
            ktot[4 * b.node, 4 * b.node] += problem.springs
            ktot[4 * b.node + 1, 4 * b.node + 1] += problem.springs
        y0[:n_r] = np.linalg.solve(ktot, rotor.gravity_load(system.gravity))
        for b, ci in zip(system.bearings, clear_i):
            y0[4 * b.node] += perturbation * ci
        y0[[problem.ring_speed_index(i) for i in range(2)]] = [ring_speed_ratio(b) * w0 for b in system.bearings]
        return y0
    if initial == "equilibrium":
        loads = system.bearing_loads
        eqs = [bearing_equilibrium(b, loads[i], w0, "J", problem.film_model, system.gravity)
               for i, b in enumerate(system.bearings)]
        journals, rings, wfr = [e.journal for e in eqs], [e.ring for e in eqs], [e.ring_speed for e in eqs]
    elif initial == "centred":
        journals = rings = [np.zeros(2), np.zeros(2)]
        wfr = [ring_speed_ratio(b) * w0 for b in system.bearings]
    else:
        raise ParameterError(f"initial = {initial!r} is unknown; valid: 'equilibrium', 'centred'")
    journals = [np.asarray(j) + np.array([perturbation * (ci + co), 0.0])
                for j, ci, co in zip(journals, clear_i, clear_o)]
    rings = [np.asarray(r) + np.array([perturbation * co, 0.0]) for r, co in zip(rings, clear_o)]
    y0[:n_r] = static_rotor_state(system, journals)
    for i in range(2):
        y0[problem.ring_index(i):problem.ring_index(i) + 2] = rings[i]
        y0[problem.ring_speed_index(i)] = wfr[i]
    return y0


def _speed_bound(problem):
    """Largest rotor speed [rad/s] of the run: the profile's, or for a torque-driven rotor the start speed plus the
    largest drive torque acting alone (the films only brake) over the whole duration, at most MAX_SPEED_RPM."""
    w_max = max(float(problem.profile.omega[0]), float(problem.profile.omega.max()))
    if problem.torque_driven:
        tq = max(0.0, float(np.max(problem.profile.drive_torque)))
        w_max = min(w_max + tq * float(problem.profile.t[-1]) / problem.polar_inertia, MAX_SPEED_RPM * RPM)
    return w_max


#: shortest time [s] in which a drive torque alone may take the rotor from standstill to MAX_SPEED_RPM: a larger
#: torque overshoots the speed bound inside one solver call (1e9 N m reached 3.8e9 rpm inside one 50 µs sample with
#: LSODA, and kept the compiled Radau solver from returning to take Ctrl-C for minutes); 1 ms is 13e3 N m for the
#: Table 2 rotor, four orders above a turbocharger's turbine torque (~0.01 ... 1 N m)
MIN_TORQUE_TIME_S = 1e-3


def check_drive_torque(system, profile, name="drive torque"):
    """Refuse a torque-driven ``profile`` whose largest |drive torque| [N m] would take the ``system``'s rotor from
    standstill to :data:`MAX_SPEED_RPM` in less than :data:`MIN_TORQUE_TIME_S` (a prescribed speed passes)."""
    if getattr(profile, "torque_driven", False):
        check_drive_torque_value(name, float(np.max(np.abs(profile.drive_torque))), rotor_polar_inertia(system.rotor))


def check_drive_torque_value(name, torque, polar_inertia):
    """``float(torque)`` [N m], or a :class:`ParameterError` when it is not finite or |torque| would take a rotor of
    ``polar_inertia`` [kg m²] from standstill to :data:`MAX_SPEED_RPM` in less than :data:`MIN_TORQUE_TIME_S` (the
    run-up's profile and the FMUs' ``drive_torque`` input alike).

    >>> check_drive_torque_value("drive_torque", 0.5, 1.26e-4)
    0.5
    """
    tq = check_finite(name, torque, "N m")
    limit = polar_inertia * MAX_SPEED_RPM * RPM / MIN_TORQUE_TIME_S
    if abs(tq) > limit:
        raise ParameterError(f"{name} = {tq:g} N m is invalid: valid range |torque| <= {limit:.3g} N m (it would take "
                             f"the rotor, polar inertia {polar_inertia:.3g} kg m², to {MAX_SPEED_RPM:.0e} rpm in under "
                             f"{MIN_TORQUE_TIME_S * 1e3:g} ms; a turbine gives ~0.01 ... 1 N m)")
    return tq


#: valid range of the relative tolerance [-]: above it a run "finishes" after a handful of steps with a meaningless
#: trajectory (measured: rtol 1 or 5, 9-15 solver steps for a 1 s run-up), below it round-off dominates
RTOL_RANGE = (1e-13, 1e-4)
#: the absolute tolerance on displacements may be at most this fraction of the smallest film clearance
ATOL_MAX_OF_CLEARANCE = 1e-3


def check_tolerances(system, rtol, atol, names=("rtol", "atol")):
    """``(rtol, atol)`` as floats, or a :class:`ParameterError` naming the option, its value and the valid range:
    rtol within :data:`RTOL_RANGE`, atol [m] > 0 and at most :data:`ATOL_MAX_OF_CLEARANCE` of the smallest film
    clearance of ``system``.

    Examples
    --------
    >>> import frbmodel as frb
    >>> check_tolerances(frb.turbocharger(), 1e-7, 1e-11)
    (1e-07, 1e-11)
    >>> try:
    ...     check_tolerances(frb.turbocharger(), 1e-7, 1.0, ("--rtol", "--atol"))
    ... except ParameterError as exc:
    ...     print(exc)
    --atol = 1.0 m is invalid: valid range (0, 3.4e-08] m (1e-3 of the smallest film clearance, 3.4e-05 m)
    """
    rtol = check_positive(names[0], rtol)
    lo, hi = RTOL_RANGE
    if not lo <= rtol <= hi:
        raise ParameterError(f"{names[0]} = {rtol!r} is invalid: valid range [{lo:g}, {hi:g}] (larger tolerances "
                             "end a run after a few meaningless steps)")
    atol = check_positive(names[1], atol, "m")
    c_min = min(min(b.inner.clearance, b.outer.clearance) for b in system.bearings)
    if atol > ATOL_MAX_OF_CLEARANCE * c_min:
        raise ParameterError(f"{names[1]} = {atol!r} m is invalid: valid range (0, {ATOL_MAX_OF_CLEARANCE * c_min:.3g}]"
                             f" m (1e-3 of the smallest film clearance, {c_min:.3g} m)")
    return rtol, atol


#: default integrator tolerances of the run-up. The absolute tolerance decides (measured on the main job, c_o = 36
#: µm): with 1e-10 m the turbine journal of the first 0.1 s is 2.5e-3 c_o off the converged trajectory (rtol 1e-10,
#: atol 1e-13 m), and the components inside the large whirl at 200 krpm moved by up to 80 Hz with a tighter
#: tolerance (issue #24); with 1e-11 m that trajectory is within 7e-5 c_o of the converged one.
#: (Before that: 1e-6 / 1e-9 m moved the first whirl onset by 7-11 %.)
DEFAULT_RTOL = 1e-7
DEFAULT_ATOL_M = 1e-11


def atol_vector(problem, atol=DEFAULT_ATOL_M, speed_scale=None):
    """LSODA absolute tolerances per state: ``atol`` [m] on displacements, scaled by a 0.03 m arm for rotations,
    by the largest rotor speed for velocities; ring speeds and the rotor speed of a torque-driven rotor
    1e-6 × (atol / 1e-9 m) × that speed [rad/s], the rotation angle 1e-6 × (atol / 1e-9 m) rad.
    The largest speed of a torque-driven run is bounded by the drive torque alone (films only brake).

    Parameters
    ----------
    problem : Problem
        The run-up problem.
    atol : float
        Absolute tolerance on displacements [m].
    speed_scale : float, optional
        The largest rotor speed [rad/s] that scales the velocity and speed tolerances; default: the run's
        (:func:`_speed_bound`). A stepped component whose speed comes from an input gives its own.

    Returns
    -------
    atol : ndarray (problem.n_states,)
        Absolute tolerance per state (in each state's unit).
    scale : ndarray (problem.n_states,)
        Floor of the finite-difference step per state (:func:`frbmodel.physics.dynamics.monolithic_jac`).

    Examples
    --------
    >>> import frbmodel as frb
    >>> p = build_problem(frb.turbocharger(), SpeedProfile.constant(100e3, 0.1), "short")
    >>> atol, scale = atol_vector(p, 1e-10)
    >>> atol[:2].tolist(), round(float(atol[2]) * 0.03 / 1e-10, 9)  # x, y [m]; a rotation [rad] x 0.03 m arm
    ([1e-10, 1e-10], 1.0)
    """
    n_r = problem.n_rotor
    w_max = _speed_bound(problem) if speed_scale is None else float(speed_scale)
    pos_tol = float(atol)
    atol_scale = pos_tol / 1e-9
    atol = np.empty(problem.n_states)
    atol[:n_r] = pos_tol
    atol[2:n_r:4] = atol[3:n_r:4] = pos_tol / 0.03  # rotations ~ displacement / arm length
    atol[n_r:2 * n_r] = atol[:n_r] * w_max
    for i in range(2):
        b = problem.ring_index(i)
        atol[b:b + 2] = pos_tol
        atol[b + 2:b + 4] = pos_tol * w_max
    atol[2 * n_r + 8:2 * n_r + 10] = 1e-6 * w_max * atol_scale
    atol[2 * n_r + 10] = 1e-6 * atol_scale
    if problem.torque_driven:
        atol[problem.speed_index] = 1e-6 * w_max * atol_scale
    return atol, np.maximum(atol * 1e3, 1e-12)


def modal_error_basis(problem, atol, speed_scale=None):
    """The rotor part of RODAS's error norm in modal coordinates (:func:`frbmodel.nonlinear.rosenbrock.rodas_chunk`).

    Per state, the velocity tolerance of :func:`atol_vector` is the displacement tolerance × the largest rotor speed,
    so a free-free bending mode far above it (the Table 2 rotor's 5.4 ... 51.7 kHz) is held to a displacement
    amplitude 1.3 ... 12 times smaller than the tolerance: the steps in the developed whirl were set by the
    velocity error of modes that carry nothing. In the modes' own coordinates each mode k is held to the same
    amplitude: displacement tolerance ``atol[0]`` and velocity tolerance ``atol[0] × max(ω_k, Ω_max)``. Measured on
    the main job (rtol 1e-7, atol 1e-11 m): 80 251 steps instead of 148 922, the spectra at 150-230 krpm and every
    onset as with both tolerances tightened tenfold (benchmarks/default_convergence.py).

    Parameters
    ----------
    problem : Problem
        The run-up problem (its ``args[0][1]`` = M⁻¹K of the free-free rotor).
    atol : ndarray (problem.n_states,)
        Absolute tolerances per state (:func:`atol_vector`).
    speed_scale : float, optional
        The largest rotor speed Ω_max [rad/s]; default: the run's (:func:`_speed_bound`).

    Returns
    -------
    modal : ndarray (n_rotor, n_rotor)
        Maps the rotor's displacements (and velocities) to the mode amplitudes [m] ([m/s]): the inverse of the mode
        shapes of M⁻¹K, each scaled to a largest translation of 1.
    atol : ndarray (problem.n_states,)
        ``atol`` with its first 2 n_rotor entries the tolerances of those amplitudes.

    Examples
    --------
    >>> import frbmodel as frb
    >>> p = build_problem(frb.turbocharger(), SpeedProfile.constant(100e3, 0.1), "short")
    >>> modal, tol = modal_error_basis(p, atol_vector(p, 1e-11)[0])
    >>> float(tol[0]), round(float(tol[2 * p.n_rotor - 1] / 1e-11 / (2 * np.pi)))  # the 51.7 kHz mode's velocity
    (1e-11, 51685)
    """
    n_r = problem.n_rotor
    lam, vec = np.linalg.eig(problem.args[0][1])
    order = np.argsort(lam.real)
    lam, vec = lam.real[order], vec.real[:, order]
    translation = np.zeros(n_r, dtype=bool)
    translation[0::4] = translation[1::4] = True
    vec = vec / np.max(np.abs(vec[translation]), axis=0)
    w_max = _speed_bound(problem) if speed_scale is None else float(speed_scale)
    out = np.array(atol, dtype=float)
    out[:n_r] = float(atol[0])
    out[n_r:2 * n_r] = float(atol[0]) * np.maximum(np.sqrt(np.clip(lam, 0.0, None)), w_max)
    return np.ascontiguousarray(np.linalg.inv(vec)), out


def typical_sizes(problem, displacement_m=1e-5, speed_scale=None):
    """Typical size of each state, the floor of the compiled Rosenbrock integrator's difference steps
    (:func:`frbmodel.nonlinear.rosenbrock.jacobian`): ``displacement_m`` (about a film clearance) on displacements and,
    scaled from it as in :func:`atol_vector`, on rotations and velocities; the largest rotor speed on the ring speeds
    and the rotor speed, 1 rad on the rotation angle (the scales on which the model's forces change).

    Parameters
    ----------
    problem : Problem
        The run-up problem.
    displacement_m : float
        Typical displacement [m].
    speed_scale : float, optional
        The largest rotor speed [rad/s], as for :func:`atol_vector`.

    Returns
    -------
    ndarray (problem.n_states,)
        Typical size per state (in each state's unit).
    """
    size = atol_vector(problem, displacement_m, speed_scale)[0]
    w_max = _speed_bound(problem) if speed_scale is None else float(speed_scale)
    size[[problem.ring_speed_index(0), problem.ring_speed_index(1)]] = w_max
    size[2 * problem.n_rotor + 10] = 1.0
    if problem.torque_driven:
        size[problem.speed_index] = w_max
    return size


def static_rotor_state(system, journal_positions):
    """Rotor DoFs q [m, rad] of the static equilibrium with prescribed journal centres (list of (x, y)).

    The rotor on two supports is statically determinate, so prescribing both journals fixes q and the
    gravity load is carried by exactly the bearing reactions of :attr:`Turbocharger.bearing_loads`.

    Parameters
    ----------
    system : Turbocharger
        The system (its rotor, bearing nodes and gravity).
    journal_positions : sequence of (float, float)
        Journal centre (x, y) [m] of each bearing, in the order of ``system.bearings``.

    Returns
    -------
    ndarray (n_r,)
        Rotor DoFs q [m, rad].

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> q = static_rotor_state(tc, [(0.0, -1e-6), (0.0, -2e-6)])
    >>> [q[4 * b.node:4 * b.node + 2].round(12).tolist() for b in tc.bearings]
    [[0.0, -1e-06], [0.0, -2e-06]]
    """
    return system.rotor.static_deflection([b.node for b in system.bearings], journal_positions, system.gravity)


def _losses(problem, y, w):
    """Film torque on each journal [N m] and friction power of each bearing [W] in state ``y`` at rotor speed ``w``
    [rad/s] (:func:`frbmodel.physics.losses.bearing_loss_kernel`, positions capped as in the RHS); NaN on linear
    springs."""
    nb = len(problem.system.bearings)
    if problem.springs > 0:
        return np.full(nb, np.nan), np.full(nb, np.nan)
    n_r = problem.n_rotor
    torque, power = np.empty(nb), np.empty(nb)
    for i, b in enumerate(problem.system.bearings):
        j = 4 * b.node
        r = problem.ring_index(i)
        ring = np.append(y[r:r + 4], y[problem.ring_speed_index(i)])
        geom = film_data_at_speed(problem.geom, w, problem.args[22], problem.args[23])
        t_j, p_i, p_o = bearing_loss_kernel(geom[i], problem.polys[i], y[j], y[j + 1], y[n_r + j],
                                            y[n_r + j + 1], ring, w, EPS_CAP)
        torque[i], power[i] = t_j, p_i + p_o
    return torque, power


def sample_row(problem, schema, t, y, buf):
    """One named result row (:meth:`RunupSchema.row`) of the state ``y`` at time ``t`` [s]; ``buf`` (n_states,) is
    work space. Fills ``problem.diag`` with the films' eccentricity ratios."""
    problem.rhs(t, y, buf)  # fills problem.diag with the films' eccentricities
    system, n_r = problem.system, problem.n_rotor
    journal = [y[4 * b.node:4 * b.node + 2] for b in system.bearings]
    ring = [y[problem.ring_index(i):problem.ring_index(i) + 2] for i in range(2)]
    eps = problem.diag if problem.springs == 0 else np.zeros(4)
    discs = [y[4 * d.node:4 * d.node + 2] for d in system.rotor.discs]
    w = problem.speed(t, y)
    torque, power = _losses(problem, y, w)
    return schema.row(t, w / RPM, y[2 * n_r + 8:2 * n_r + 10], journal, ring, eps, discs, journal_torque=torque,
                      power_loss=power)


@njit(cache=True)
def film_samples(ts, ys, ws, args, diag, geom, polys, journal_at, ring_at, ring_speed_at, n_r, eps_cap, eps, torque,
                  power):
    """For each state ys[k] at time ts[k] [s] and rotor speed ws[k] [rad/s]: the films' eccentricity ratios as the
    RHS fills ``diag`` (one :func:`frbmodel.physics.dynamics.monolithic_rhs` call with ``args``) into eps[k], and, per
    bearing b, the journal torque [N m] and friction power [W] of :func:`frbmodel.physics.losses.bearing_loss_kernel`
    into torque[k, b], power[k, b] (as :func:`_losses`)."""
    buf = np.empty(ys.shape[1])
    ring = np.empty(5)
    for k in range(ts.size):
        y = ys[k]
        _rhs(ts[k], y, buf, *args)
        for i in range(diag.size):
            eps[k, i] = diag[i]
        g = film_data_at_speed(geom, ws[k], args[22], args[23])
        for b in range(journal_at.size):
            j, r = journal_at[b], ring_at[b]
            for m in range(4):
                ring[m] = y[r + m]
            ring[4] = y[ring_speed_at[b]]
            t_j, p_i, p_o = bearing_loss_kernel(g[b], polys[b], y[j], y[j + 1], y[n_r + j], y[n_r + j + 1], ring,
                                                ws[k], eps_cap)
            torque[k, b] = t_j
            power[k, b] = p_i + p_o


def sample_rows(problem, schema, ts, ys):
    """The result rows of many states at once: row k equals :func:`sample_row` of ``ys[k]`` at ``ts[k]``, bit for
    bit (the same kernels, called in one compiled loop instead of once per sample from Python).

    Parameters
    ----------
    problem : Problem
        The run-up problem; :attr:`Problem.diag` is left holding the last state's eccentricity ratios.
    schema : RunupSchema
        Column layout of the rows.
    ts : ndarray (n,)
        Times [s].
    ys : ndarray (n, n_states)
        States (SI units; layout of :class:`Problem`).

    Returns
    -------
    ndarray (n, len(schema.columns))
        The rows (:meth:`RunupSchema.rows`).

    Examples
    --------
    >>> import frbmodel as frb
    >>> p = build_problem(frb.turbocharger(), SpeedProfile.constant(30e3, 1e-3), "short")
    >>> schema, y0 = RunupSchema.from_system(p.system), initial_state(p)
    >>> rows = sample_rows(p, schema, np.array([0.0, 1e-4]), np.array([y0, y0]))
    >>> bool(np.array_equal(rows[1], sample_row(p, schema, 1e-4, y0, np.empty(p.n_states))))
    True
    """
    ts = np.ascontiguousarray(ts, dtype=float).ravel()
    ys = np.ascontiguousarray(ys, dtype=float).reshape(ts.size, problem.n_states)
    system, n_r, n = problem.system, problem.n_rotor, ts.size
    nb = len(system.bearings)
    journal_at = np.array([4 * b.node for b in system.bearings], dtype=np.int64)
    ring_at = np.array([problem.ring_index(i) for i in range(nb)], dtype=np.int64)
    ring_speed_at = np.array([problem.ring_speed_index(i) for i in range(nb)], dtype=np.int64)
    if problem.torque_driven:
        w = ys[:, problem.speed_index].copy()
    else:  # np.interp of an array: value by value as problem.speed's np.interp of a float
        w = np.interp(ts, problem.profile.t, problem.profile.omega)
    eps, torque, power = np.zeros((n, 2 * nb)), np.full((n, nb), np.nan), np.full((n, nb), np.nan)
    if problem.springs == 0 and n:
        film_samples(ts, ys, w, problem.args, problem.diag, problem.geom, problem.polys, journal_at, ring_at,
                      ring_speed_at, n_r, EPS_CAP, eps, torque, power)
    pairs = np.stack([journal_at, journal_at + 1], axis=1)
    rings = np.stack([ring_at, ring_at + 1], axis=1)
    discs = np.array([[4 * d.node, 4 * d.node + 1] for d in system.rotor.discs], dtype=np.int64).reshape(-1, 2)
    return schema.rows(ts, w / RPM, ys[:, ring_speed_at], ys[:, pairs], ys[:, rings], eps, ys[:, discs],
                       journal_torque=torque, power_loss=power)


def contact_message(schema, row, contact_eps, kept="results up to there are kept"):
    """Message when a film's ε in ``row`` exceeds ``contact_eps`` (the member reaches its wall), else None; it ends
    with ``kept`` (what happens to the results)."""
    ecc = row[schema.eps_slice()]
    worst = int(np.argmax(ecc))
    if not ecc[worst] > contact_eps:
        return None
    bearing, film = schema.bearings[worst // 2], ("inner", "outer")[worst % 2]
    member = "journal" if film == "inner" else "ring"
    return (f"{bearing} bearing, {film} film: eccentricity ratio {ecc[worst]:.4f} exceeds contact_eps = "
            f"{contact_eps} (the {member} reaches its wall) at t = {row[0]:.6g} s, rotor speed {row[1]:.0f} rpm; "
            f"{kept}")


def _speed_message(row):
    """Message when the speed of a torque-driven rotor in ``row`` left 0 < speed <= MAX_SPEED_RPM, else None."""
    if 0.0 < row[1] <= MAX_SPEED_RPM:
        return None
    return (f"rotor speed {row[1]:.0f} rpm at t = {row[0]:.6g} s left the valid range 0 < speed <= "
            f"{MAX_SPEED_RPM:.0e} rpm (drive torque too small to overcome the film friction, or too large); "
            "results up to there are kept")


#: time integrators of the run-up: the compiled Rosenbrock method (default), the compiled Radau IIA path and scipy's
#: LSODA (the former path, kept as the reference they are checked against)
INTEGRATORS = ("rodas", "radau", "lsoda")
#: output samples per call of the compiled solver (it restarts at each call; between calls the run-up records,
#: checks contact, signals and progress). Measured on the 1 s benchmark run-up: 100 samples took 8.7 s, 1000 took
#: 21 s (the solver's cost grows with the number of output times per call)
CHUNK_SAMPLES = 100


#: solver steps per call of a compiled solver: it returns after at most this many, so that the run checks for Ctrl-C /
#: SIGTERM at least this often (measured on the main job: 39 µs per RODAS step, 155 µs per Radau step, so 0.2 s and
#: 0.8 s; the main job takes ~750 and ~250 steps per call, never near it); a sample interval
#: that needs more steps gets the budget doubled from call to call, up to ``nsteps``
CALL_STEPS = 5_000


class _SolverStop(Exception):
    """Raised inside LSODA's right-hand side to end the solver call (a stop request, or the speed out of range)."""


def _speed_out_of_range(problem, y):
    """True when ``problem`` is torque-driven and the rotor speed in state ``y`` left 0 < speed <= MAX_SPEED_RPM."""
    return problem.torque_driven and not 0.0 < problem.speed(0.0, y) <= MAX_SPEED_RPM * RPM


def _lsoda_samples(problem, y0, t_out, opts, counts):
    """scipy's LSODA from sample to sample, calling the compiled RHS and Jacobian from Python; the stop request
    (``opts["check"]``) and the speed bound are checked at every right-hand-side evaluation. Yields (k, ys, "") with
    the state ys (1, n_states) at each output time t_out[k], k >= 1, or (k, empty ys, message) once when it fails."""
    from scipy.integrate import ode

    n = problem.n_states
    atol, scale = opts["atol"]
    f_buf, jac_buf, f0, work = np.zeros(n), np.zeros((n, n)), np.zeros(n), np.zeros(n)

    def fun(t, y):
        counts["rhs_evaluations"] += 1
        if opts["pending"]() or _speed_out_of_range(problem, y):
            raise _SolverStop
        return _rhs(t, y, f_buf, *problem.args).copy()

    def jac(t, y):
        counts["jacobian_evaluations"] += 1
        return _jac(t, y, jac_buf, f0, work, scale, *problem.args)

    solver = ode(fun, jac).set_integrator("lsoda", atol=atol, rtol=opts["rtol"], nsteps=opts["nsteps"],
                                          max_step=opts["max_step"] or 0.0)
    solver.set_initial_value(y0, 0.0)
    for k in range(1, t_out.size):
        try:
            y = solver.integrate(t_out[k])
        except _SolverStop:
            opts["check"]()  # a stop request raises here; else the speed left its range
            yield k, np.empty((0, n)), (f"stopped: the torque-driven rotor speed left the valid range 0 < speed <= "
                                        f"{MAX_SPEED_RPM:.0e} rpm after t = {t_out[k - 1]:.6g} s (drive torque too "
                                        "small to overcome the film friction, or too large); results up to there "
                                        "are kept")
            return
        if not solver.successful() or not np.all(np.isfinite(y)):
            w_fail = problem.speed(solver.t, solver.y)
            yield k, np.empty((0, n)), (f"integrator failed at t = {solver.t:.6g} s, speed {w_fail / RPM:.0f} rpm "
                                        f"(LSODA return code {solver.get_return_code()}); results up to there are kept")
            return
        yield k, y[None, :], ""


def _bounded_calls(problem, call, y0, t_out, opts):
    """Drive a compiled solver ``call(y, ts, budget) -> (ys, exhausted, message)`` (``ys``: the states at the first
    rows of ``ts``, from ``ts[0]``) over ``t_out``, CHUNK_SAMPLES output times and at most a step budget per call
    (:data:`CALL_STEPS`, doubled while an interval makes no progress, up to ``opts["nsteps"]`` per interval), the stop
    request checked between calls. Yields (k, ys, message) as :func:`_lsoda_samples`, ys the states at t_out[k:]."""
    y, a, budget = y0, 0, min(CALL_STEPS, opts["nsteps"])
    while a < t_out.size - 1:
        ts = t_out[a:a + CHUNK_SAMPLES + 1]
        ys, exhausted, message = call(y, ts, budget)
        if exhausted and not message and ys.shape[0] > 1:  # progress: go on from the last sample reached
            budget = min(CALL_STEPS, opts["nsteps"])
        elif exhausted and not message and budget < opts["nsteps"]:
            budget = min(2 * budget, opts["nsteps"])
        elif exhausted and not message:
            message = _failure(problem, ts, ys, y, ys.shape[0],
                               f"step budget exhausted: more than nsteps = {opts['nsteps']} solver steps in one output "
                               "interval")
        if message or ys.shape[0] > 1:
            yield a + 1, ys[1:], message
        if message:
            return
        if ys.shape[0] > 1:
            y, a = ys[-1], a + ys.shape[0] - 1
        opts["check"]()


def _failure(problem, ts, ys, y, good, message, hint=""):
    """The message of a compiled solver that failed after ``good`` rows of ``ys`` (``y``: the call's start state)."""
    t_fail = ts[max(good - 1, 0)]
    w_fail = problem.speed(t_fail, ys[good - 1] if good else y)
    return (f"integrator failed after t = {t_fail:.6g} s, speed {w_fail / RPM:.0f} rpm ({message}{hint}); results "
            "up to there are kept")


def _radau_samples(problem, y0, t_out, opts, counts):
    """The compiled Radau IIA solver (:mod:`frbmodel.nonlinear.compiled`; a speed out of range makes its right-hand
    side NaN), driven by :func:`_bounded_calls`. Yields as :func:`_lsoda_samples`."""

    packed = pack_problem(problem)

    def call(y, ts, budget):
        ys, steps, message = solve_chunk(packed, y, ts, opts["rtol"], opts["atol"][0], budget, opts["max_step"])
        counts["solver_steps"] += steps
        good = ys.shape[0]
        bad = np.flatnonzero(~np.all(np.isfinite(ys), axis=1))
        if bad.size:
            good, message = int(bad[0]), message or "non-finite state"
        exhausted = steps >= budget and not bad.size
        if message and not exhausted:
            hint = (f"; a torque-driven speed beyond {MAX_SPEED_RPM:.0e} rpm ends it so" if problem.torque_driven
                    else "")
            return ys[:max(good, 1)], False, _failure(problem, ts, ys, y, good, message or "compiled Radau solver",
                                                      hint)
        return ys[:good], exhausted, ""

    yield from _bounded_calls(problem, call, y0, t_out, opts)


def _rodas_samples(problem, y0, t_out, opts, counts):
    """The compiled Rosenbrock solver (:mod:`frbmodel.nonlinear.rosenbrock`; the speed bound checked at every step),
    the step size carried from call to call, driven by :func:`_bounded_calls`. Yields as :func:`_lsoda_samples`."""

    atol = opts["atol"][0]
    scale = typical_sizes(problem, FD_TYPICAL_M)
    cols = film_columns(problem.n_rotor, problem.args[3], problem.torque_driven, problem.args[10].size > 0)
    state = {"h": 1e-7}
    max_step = opts["max_step"] or float(t_out[-1])
    modal, atol = modal_error_basis(problem, atol)

    def call(y, ts, budget):
        ys, good, state["h"], steps, rejected, status = rodas_chunk(y, ts, state["h"], opts["rtol"], atol, scale,
                                                                    cols, budget, max_step, problem.args, modal)
        counts["solver_steps"] += steps
        counts["rejected_steps"] += rejected
        bad = np.flatnonzero(~np.all(np.isfinite(ys[:good]), axis=1))
        message = STATUS[status] if status not in (0, 1) else ""
        if bad.size:
            good, message = int(bad[0]), message or "non-finite state"
        if message:
            return ys[:max(good, 1)], False, _failure(problem, ts, ys, y, good,
                                                      f"compiled Rosenbrock solver: {message}")
        return ys[:good], status == 1, ""

    yield from _bounded_calls(problem, call, y0, t_out, opts)


def _first_stop(problem, schema, rows, contact_eps):
    """(i, message) for the first of ``rows`` at which the run stops (wall contact, :func:`contact_message`,
    checked first; a torque-driven speed out of range, :func:`_speed_message`), or (None, "")."""
    stop = np.zeros(rows.shape[0], dtype=bool)
    if problem.springs == 0:
        ecc = rows[:, schema.eps_slice()]
        worst = ecc[np.arange(rows.shape[0]), np.argmax(ecc, axis=1)]  # the film contact_message looks at
        stop |= worst > contact_eps
    if problem.torque_driven:
        stop |= ~((rows[:, 1] > 0.0) & (rows[:, 1] <= MAX_SPEED_RPM))
    hit = np.flatnonzero(stop)
    if not hit.size:
        return None, ""
    row = rows[int(hit[0])]
    message = contact_message(schema, row, contact_eps) if problem.springs == 0 else None
    return int(hit[0]), message or _speed_message(row)


def _show_progress(bar, t_out, rows, k):
    """Progress as after each sample k, k + 1, ... of ``rows``: at the last sample whose index is a multiple of
    200, the simulated time and the speed."""
    last = (k + rows.shape[0] - 1) // 200 * 200
    if rows.shape[0] and last >= k:
        bar.update(float(t_out[last]) - bar.n)
        bar.set_postfix_str(f"{rows[last - k, 1]:.0f} rpm", refresh=False)


def _integrate(problem, y0, rec, t_out, solver_opts, contact_eps, progress):
    """The integration loop: the chosen integrator's samples recorded a solver call's worth at a time (their rows
    built in one compiled pass, :func:`sample_rows`), wall contact and speed checked on every row (the run stops at
    the first offending row, recorded). Returns (status, message, counts, the state at the last recorded sample)."""
    integrator = solver_opts["integrator"]
    counts = {"lsoda": {"rhs_evaluations": 0, "jacobian_evaluations": 0}, "radau": {"solver_steps": 0},
              "rodas": {"solver_steps": 0, "rejected_steps": 0}}[integrator]
    stepper = {"lsoda": _lsoda_samples, "radau": _radau_samples, "rodas": _rodas_samples}[integrator]
    rec.extend(sample_rows(problem, rec.schema, t_out[:1], y0[None, :]))
    status, message, last = "finished", "", y0
    label = {"down": "run-down", "up-down": "run-up/down"}.get(problem.profile.direction, "run-up")
    with deferred_signals() as signals, simulation_bar(t_out[-1], label, progress) as bar:
        opts = {**solver_opts, "check": signals.check, "pending": lambda: signals.pending is not None}
        samples = stepper(problem, y0, t_out, opts, counts)
        for k, ys, failure in samples:
            rows = sample_rows(problem, rec.schema, t_out[k:k + ys.shape[0]], ys)
            stop, message = _first_stop(problem, rec.schema, rows, contact_eps)
            rec.extend(rows if stop is None else rows[:stop + 1])
            if ys.shape[0]:
                last = ys[-1] if stop is None else ys[stop]
            _show_progress(bar, t_out, rows if stop is None else rows[:stop], k)
            message = message or failure
            if message:
                status = "stopped"
                break
            signals.check()  # Ctrl-C / SIGTERM between solver calls, never inside the compiled callbacks
    return status, message, counts, last


def runup(system, speed_rpm=None, duration=1.0, profile=None, film_model=None, unbalance=(),
          output_rate_hz=20e3, rtol=DEFAULT_RTOL, atol=DEFAULT_ATOL_M, perturbation=0.05, out_dir=None, progress=False,
          contact_eps=0.98, linear_springs=None, initial="equilibrium", max_step=None, nsteps=500_000,
          integrator="rodas", oil_supply=None):
    """Nonlinear run-up simulation (the monolithic reference).

    Parameters
    ----------
    system : Turbocharger
        The system (two bearings).
    speed_rpm : (float, float), optional
        Start and end speed [rpm] of a linear ramp; default (20 000, 250 000). Refused together with ``profile``.
    duration : float
        Simulated time [s].
    profile : SpeedProfile or callable, optional
        ``SpeedProfile.constant(...)``, ``SpeedProfile.ramp(...)``, ``fun(t) -> rpm``, or a torque-driven rotor
        ``SpeedProfile.torque(drive_torque_Nm, start_rpm, duration)`` (the speed is then a state; the recorded
        ``journal torque <bearing> [N m]`` columns are the film torques that brake it).
    film_model : {"short", "short_corrected"}, optional
        Default: the system's.
    unbalance : sequence of Unbalance
        Per disc, e.g. ``[Unbalance("turbine_wheel", 1e-6, 0.0)]`` (1 g mm).
    output_rate_hz : float
        Sampling rate of the stored results [Hz] (default 20 kHz; the spectra resolve up to half of it).
    rtol, atol : float
        LSODA relative tolerance [-] and absolute tolerance on displacements [m] (the other states' are scaled
        from it, see
        :func:`atol_vector`).
    perturbation : float
        Initial offset of both journals and rings in +x, as a fraction of their film clearance.
    out_dir : path, optional
        Stream ``runup.csv`` and ``runup.json`` there while integrating.
    progress : bool
        Show a progress bar (simulated time, speed, elapsed, ETA) on stderr (default off; on in the CLI).
    contact_eps : float
        Stop (with results written) when a film's ε exceeds this value: the member reaches its wall.
    linear_springs : float, optional
        Replace the films by isotropic linear springs of this stiffness [N/m] at the journals (method A's
        bearing; the rings then stay idle). For verification.
    initial : "equilibrium" | "centred"
        Start from the method-J static equilibrium at the start speed (plus ``perturbation``), or centred.
    max_step, nsteps : optional
        The integrator's largest step [s] and step budget per output interval.
    integrator : {"rodas", "radau", "lsoda"}
        ``"rodas"`` (default): compiled Rosenbrock method RODAS with the rotor's Jacobian block exact and only the
        film columns by differences (:mod:`frbmodel.nonlinear.rosenbrock`); ``"radau"``: CyRK's compiled Radau IIA
        (:mod:`frbmodel.nonlinear.compiled`); ``"lsoda"``: scipy's LSODA calling the compiled right-hand side and
        Jacobian from
        Python (the former path, kept as the reference; slowest on film runs, 3.7x on the benchmark run-up, but
        the fastest on undamped ``linear_springs`` runs, where every rotor mode keeps ringing).
    oil_supply : OilSupply, optional
        The thermal model with quasi-static film temperatures (docs/theory/thermal.md#run-ups): the films'
        viscosities follow the rotor speed through a table of the thermal operating points over the profile's speed
        range (:func:`viscosity_table`, interpolated in the compiled right-hand side and in the recorded losses);
        the initial equilibrium is at the start speed's temperatures. A torque-driven rotor's table spans
        :func:`table_speeds_rpm` (1 krpm up to the speed its drive torque could reach without friction). Every
        integrator. The metadata record the supply and the table. None: constant viscosities, bit for bit.

    Returns
    -------
    RunupResult

    Raises
    ------
    RunupStopped
        Wall contact or integrator failure; ``exc.result`` holds the samples up to that time.

    Examples
    --------
    >>> from frbmodel import turbocharger
    >>> from frbmodel.nonlinear.runup import SpeedProfile, runup
    >>> run = runup(turbocharger(), profile=SpeedProfile.constant(1500, 0.002), duration=0.002, output_rate_hz=5e3)
    >>> run.time.tolist(), run.status
    ([0.0, 0.0002, 0.0004, 0.0006, 0.0008, 0.001, 0.0012, 0.0014, 0.0016, 0.0018, 0.002], 'finished')
    """
    model = check_model(film_model or system.film_model)
    duration = check_positive("duration", duration, "s")
    output_rate_hz = check_output_rate(output_rate_hz, duration)
    rtol, atol = check_tolerances(system, rtol, atol)
    if profile is None:
        profile = SpeedProfile.ramp(*_speed_pair((20e3, 250e3) if speed_rpm is None else speed_rpm), duration)
    elif speed_rpm is not None:
        raise ParameterError(f"speed_rpm = {speed_rpm!r} and profile are mutually exclusive: the profile gives the "
                             "rotor speed (leave speed_rpm out)")
    elif not isinstance(profile, SpeedProfile):
        profile = SpeedProfile.from_function(profile, duration)
    if duration > float(profile.t[-1]) * (1 + 1e-9) and not profile.torque_driven:
        # beyond its table a profile would hold its last speed *and* its last acceleration: inconsistent
        raise ParameterError(f"duration = {duration:g} s is longer than the speed profile "
                             f"({float(profile.t[-1]):g} s): valid range 0 < duration <= the profile's length")
    if not 0.0 < contact_eps < 1.0:
        raise ParameterError(f"contact_eps = {contact_eps!r} is invalid: valid range 0 < contact_eps < 1")
    if integrator not in INTEGRATORS:
        raise ParameterError(f"integrator = {integrator!r} is unknown; valid: {', '.join(map(repr, INTEGRATORS))}")
    check_drive_torque(system, profile)
    check_runup_oil(oil_supply, profile, integrator, linear_springs, system=system)
    problem = build_problem(system, profile, model, unbalance, linear_springs, oil_supply)
    y0 = initial_state(problem, initial, perturbation)
    atol_v, scale = atol_vector(problem, atol)
    t_out = np.arange(int(math.floor(duration * output_rate_hz + 1e-9)) + 1) / output_rate_hz
    meta = {"system": system.to_dict(), "film_model": model, "profile": profile.description, "duration_s": duration,
            "output_rate_hz": output_rate_hz, "integrator": integrator, "rtol": rtol, "atol_displacement_m": atol,
            "error_norm": "rotor in free-free modal coordinates" if integrator == "rodas" else "per state",
            "unbalance": [u.__dict__ for u in unbalance], "linear_springs_N_per_m": linear_springs,
            "perturbation_of_clearance": perturbation, "contact_eps": contact_eps, "units": "SI; speed in rpm",
            **({"speed_source": "torque", "polar_inertia_kg_m2": problem.polar_inertia} if problem.torque_driven
               else {})}
    if oil_supply is not None:
        meta.update(oil_supply=oil_supply.to_dict(), film_temperatures="quasi-static in rotor speed",
                    viscosity_table={"speed [rpm]": (problem.args[22] / RPM).tolist(),
                                     "viscosity [Pa s]": problem.args[23].tolist(),
                                     "films": list(film_names(system))})
    t_wall = time.perf_counter()
    with Recorder(RunupSchema.from_system(system), t_out.size, out_dir, meta) as rec:
        status, message, counts, last = _integrate(
            problem, y0, rec, t_out, {"atol": (atol_v, scale), "rtol": rtol, "nsteps": nsteps, "integrator": integrator,
                                      "max_step": max_step or 0.0}, contact_eps, progress)
        wall = time.perf_counter() - t_wall
        if progress:
            work = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in counts.items())
            sys.stderr.write(f"run-up: {status} after {wall:.1f} s wall ({integrator}: {work})\n")
        result = rec.close(status, message, wall_time_s=wall, **counts)
        result.final_state = np.array(last, dtype=float)
    if status != "finished":
        raise RunupStopped(message, result)
    return result
