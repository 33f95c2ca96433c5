"""Nonlinear run-up: FE rotor + both rings (lateral and spin) + nonlinear films, integrated with LSODA.

The equations are physics.md §7: all rotor FE DoFs with gyroscopics (``M q̈ + Ω G q̇ + (K + Ω̇ G) q``),
gravity, optional unbalance per wheel, both rings' lateral DoFs and spin speed (ring speed is a state, driven
by the film torques), and the nonlinear film forces of :mod:`frbmodel.film` (short or finite-length corrected).
The rotor speed follows a prescribed profile. The right-hand side and its finite-difference Jacobian are
compiled with numba; the stiff, error-controlled integration is LSODA (scipy).
"""
from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .dynamics import jac as _jac
from .dynamics import rhs as _rhs
from .equilibrium import RPM, bearing_equilibrium
from .errors import FRBError, ParameterError, check_positive
from .film import check_model, correction_polys

#: numerical guard: film forces of trial states beyond this ε are evaluated at this ε (physics.md §2.7)
EPS_CAP = 0.999
FILM_LABELS = ("turbine inner", "turbine outer", "compressor inner", "compressor outer")


class RunupStopped(FRBError):
    """A run-up stopped before its end (wall contact, integrator failure). ``.result`` holds what was computed;
    the files written so far stay on disk."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


# --------------------------------------------------------------------------------------------------
# problem set-up
# --------------------------------------------------------------------------------------------------
@dataclass
class SpeedProfile:
    """Rotor speed vs time, tabulated (linear interpolation inside the RHS).

    Build with :meth:`ramp`, :meth:`constant` or :meth:`from_function`.
    """

    t: np.ndarray  # [s], uniform grid
    omega: np.ndarray  # [rad/s]
    omega_dot: np.ndarray  # [rad/s²]
    description: str

    @classmethod
    def ramp(cls, start_rpm, end_rpm, duration):
        t = np.array([0.0, duration])
        w = np.array([start_rpm, end_rpm]) * RPM
        a = (w[1] - w[0]) / duration
        return cls(t, w, np.array([a, a]), f"linear ramp {start_rpm:.0f} -> {end_rpm:.0f} rpm in {duration:g} s")

    @classmethod
    def constant(cls, speed_rpm, duration):
        return cls(np.array([0.0, duration]), np.full(2, speed_rpm * RPM), np.zeros(2),
                   f"constant {speed_rpm:.0f} rpm")

    @classmethod
    def exponential(cls, start_rpm, end_rpm, duration, n=20001):
        """Constant relative acceleration: Ω(t) = Ω0 (Ω1/Ω0)^(t/T) — equal time per speed octave, so low-speed
        onsets get as many vibration periods as high-speed ones."""
        t = np.linspace(0.0, duration, n)
        rate = math.log(end_rpm / start_rpm) / duration
        w = start_rpm * RPM * np.exp(rate * t)
        return cls(t, w, rate * w, f"exponential ramp {start_rpm:.0f} -> {end_rpm:.0f} rpm in {duration:g} s")

    @classmethod
    def from_function(cls, fun, duration, n=20001):
        """``fun(t [s]) -> speed [rpm]``, tabulated on ``n`` points; Ω̇ by central differences."""
        t = np.linspace(0.0, duration, n)
        w = np.array([float(fun(x)) for x in t]) * RPM
        if not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise ParameterError("speed profile function must return finite speeds > 0 rpm for 0 <= t <= duration")
        return cls(t, w, np.gradient(w, t), "user function")

    def __call__(self, t):
        return np.interp(t, self.t, self.omega)


@dataclass
class Unbalance:
    """Unbalance of one wheel: ``amount`` [kg m] (mass × eccentricity) at ``phase`` [rad] (from +x, CCW)."""

    disc: str
    amount: float
    phase: float = 0.0


@dataclass
class RunupResult:
    """Sampled result of a run-up (SI units; speeds also in rpm).

    Attributes
    ----------
    time : (n,) [s]
    speed_rpm : (n,) rotor speed [rpm]
    ring_speed : (n, 2) ring spin speeds [rad/s] (turbine, compressor)
    ring_speed_ratio : (n, 2) [-]
    journal, ring : dict bearing name -> (n, 2) positions [m] relative to the housing
    eccentricity : (n, 4) ε of the four films (turbine inner/outer, compressor inner/outer)
    displacement : dict node name ("turbine_wheel", "compressor_wheel", "node<i>") -> (n, 2) [m]
    status : "finished" | "stopped"
    message : str
    """

    time: np.ndarray
    speed_rpm: np.ndarray
    ring_speed: np.ndarray
    journal: dict
    ring: dict
    eccentricity: np.ndarray
    displacement: dict
    status: str = "finished"
    message: str = ""
    meta: dict = field(default_factory=dict)

    @property
    def ring_speed_ratio(self):
        return self.ring_speed / (self.speed_rpm * RPM)[:, None]

    def to_dataframe(self):
        """One row per sample; units in the column names."""
        import pandas as pd

        d = {"time [s]": self.time, "speed [rpm]": self.speed_rpm}
        for i, name in enumerate(("turbine", "compressor")):
            d[f"ring speed {name} [rad/s]"] = self.ring_speed[:, i]
            d[f"RSR {name} [-]"] = self.ring_speed_ratio[:, i]
        for name, arr in self.journal.items():
            d[f"journal {name} x [m]"], d[f"journal {name} y [m]"] = arr[:, 0], arr[:, 1]
        for name, arr in self.ring.items():
            d[f"ring {name} x [m]"], d[f"ring {name} y [m]"] = arr[:, 0], arr[:, 1]
        for k, lab in enumerate(FILM_LABELS):
            d[f"eps {lab} [-]"] = self.eccentricity[:, k]
        for name, arr in self.displacement.items():
            d[f"{name} x [m]"], d[f"{name} y [m]"] = arr[:, 0], arr[:, 1]
        return pd.DataFrame(d)

    @classmethod
    def load(cls, path):
        """Read a run-up written by :func:`runup` (``runup.csv`` + ``runup.json`` in a folder, or the CSV)."""
        import pandas as pd

        path = Path(path)
        csv = path / "runup.csv" if path.is_dir() else path
        meta_p = csv.with_suffix(".json")
        meta = json.loads(meta_p.read_text()) if meta_p.exists() else {}
        df = pd.read_csv(csv)
        return cls.from_dataframe(df, meta)

    @classmethod
    def from_dataframe(cls, df, meta=None):
        meta = meta or {}
        names = ("turbine", "compressor")
        ring_speed = np.column_stack([df[f"ring speed {n} [rad/s]"].to_numpy() for n in names])
        journal = {n: df[[f"journal {n} x [m]", f"journal {n} y [m]"]].to_numpy() for n in names}
        ring = {n: df[[f"ring {n} x [m]", f"ring {n} y [m]"]].to_numpy() for n in names}
        ecc = np.column_stack([df[f"eps {lab} [-]"].to_numpy() for lab in FILM_LABELS])
        disp = {}
        for col in df.columns:
            if col.endswith(" x [m]") and not col.startswith(("journal", "ring")):
                name = col[:-len(" x [m]")]
                disp[name] = df[[f"{name} x [m]", f"{name} y [m]"]].to_numpy()
        return cls(df["time [s]"].to_numpy(), df["speed [rpm]"].to_numpy(), ring_speed, journal, ring, ecc, disp,
                   meta.get("status", "finished"), meta.get("message", ""), meta)


class _Writer:
    """Streams samples to ``runup.csv`` (header with units) and metadata to ``runup.json``."""

    def __init__(self, out_dir, columns, meta):
        self.dir = Path(out_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.csv = self.dir / "runup.csv"
        self.json = self.dir / "runup.json"
        self.meta = meta
        with open(self.csv, "w") as fh:
            fh.write(",".join(columns) + "\n")
        self.write_meta("running", "")

    def append(self, rows):
        with open(self.csv, "a") as fh:
            np.savetxt(fh, rows, delimiter=",", fmt="%.10g")

    def write_meta(self, status, message):
        self.meta.update({"status": status, "message": message})
        self.json.write_text(json.dumps(self.meta, indent=2, default=str))


def _columns(node_names):
    cols = ["time [s]", "speed [rpm]", "ring speed turbine [rad/s]", "RSR turbine [-]",
            "ring speed compressor [rad/s]", "RSR compressor [-]"]
    for n in ("turbine", "compressor"):
        cols += [f"journal {n} x [m]", f"journal {n} y [m]"]
    for n in ("turbine", "compressor"):
        cols += [f"ring {n} x [m]", f"ring {n} y [m]"]
    cols += [f"eps {lab} [-]" for lab in FILM_LABELS]
    for n in node_names:
        cols += [f"{n} x [m]", f"{n} y [m]"]
    return cols


def static_rotor_state(system, journal_positions):
    """Rotor DoFs q [m, rad] of the static equilibrium with prescribed journal centres (list of (x, y)).

    The rotor on two supports is statically determinate, so prescribing both journals fixes q and the
    gravity load is carried by exactly the bearing reactions of :attr:`Turbocharger.bearing_loads`.
    """
    rotor = system.rotor
    f = rotor.gravity_load(system.gravity)
    cons = []
    vals = []
    for b, pos in zip(system.bearings, journal_positions):
        cons += [4 * b.node, 4 * b.node + 1]
        vals += [pos[0], pos[1]]
    cons = np.array(cons)
    free = np.setdiff1d(np.arange(rotor.n_dof), cons)
    q = np.zeros(rotor.n_dof)
    q[cons] = vals
    q[free] = np.linalg.solve(rotor.K[np.ix_(free, free)], f[free] - rotor.K[np.ix_(free, cons)] @ q[cons])
    return q


def runup(system, speed_rpm=(20e3, 250e3), duration=1.0, profile=None, film_model=None, unbalance=(),
          output_rate_hz=20e3, rtol=1e-6, atol_scale=1.0, perturbation=0.05, out_dir=None, progress=True,
          contact_eps=0.98, linear_springs=None, initial="equilibrium", max_step=None, nsteps=500_000):
    """Nonlinear run-up simulation (the monolithic reference).

    Parameters
    ----------
    system : Turbocharger
    speed_rpm : (float, float)
        Start and end speed [rpm] of a linear ramp (ignored if ``profile`` is given).
    duration : float
        Simulated time [s].
    profile : SpeedProfile or callable, optional
        ``SpeedProfile.constant(...)``, ``SpeedProfile.ramp(...)``, or ``fun(t) -> rpm``.
    film_model : {"short", "short_corrected"}, optional
        Default: the system's.
    unbalance : sequence of Unbalance
        Per wheel, e.g. ``[Unbalance("turbine_wheel", 1e-6, 0.0)]`` (1 g mm).
    output_rate_hz : float
        Sampling rate of the stored results [Hz] (default 20 kHz; the spectra resolve up to half of it).
    rtol, atol_scale : float
        LSODA relative tolerance; absolute tolerances are 1e-9 m × atol_scale on displacements (scaled for
        velocities, rotations and ring speeds).
    perturbation : float
        Initial offset of both journals and rings in +x, as a fraction of their film clearance.
    out_dir : path, optional
        Stream ``runup.csv`` and ``runup.json`` there while integrating.
    progress : bool
        Print progress (simulated time, speed, wall time, ETA) to stderr.
    contact_eps : float
        Stop (with results written) when a film's ε exceeds this value: the member reaches its wall.
    linear_springs : float, optional
        Replace the films by isotropic linear springs of this stiffness [N/m] at the journals (method A's
        bearing; the rings then stay idle). For verification.
    initial : "equilibrium" | "centred"
        Start from the method-J static equilibrium at the start speed (plus ``perturbation``), or centred.

    Returns
    -------
    RunupResult

    Raises
    ------
    RunupStopped
        Wall contact or integrator failure; ``exc.result`` holds the samples up to that time.
    """
    from scipy.integrate import ode

    model = check_model(film_model or system.film_model)
    duration = check_positive("duration", duration, "s")
    output_rate_hz = check_positive("output_rate_hz", output_rate_hz, "Hz")
    if profile is None:
        s0, s1 = float(speed_rpm[0]), float(speed_rpm[1])
        for nm, v in (("start speed", s0), ("end speed", s1)):
            check_positive(nm, v, "rpm")
        profile = SpeedProfile.ramp(s0, s1, duration)
    elif not isinstance(profile, SpeedProfile):
        profile = SpeedProfile.from_function(profile, duration)
    if not 0.0 < contact_eps < 1.0:
        raise ParameterError(f"contact_eps = {contact_eps!r} is invalid: valid range 0 < contact_eps < 1")
    rotor = system.rotor
    n_r = rotor.n_dof
    n = 2 * n_r + 11
    springs = 0.0 if linear_springs is None else check_positive("linear_springs", linear_springs, "N/m")

    # --- constant data for the compiled RHS
    minv = np.linalg.inv(rotor.M)
    k_mat = np.ascontiguousarray(rotor.K)
    g_mat = np.ascontiguousarray(rotor.G)
    f_grav = rotor.gravity_load(system.gravity)
    jn = np.array([b.node for b in system.bearings], dtype=np.int64)
    geom = np.array([[[f.radius, f.length, f.clearance, f.viscosity] for f in (b.inner, b.outer)]
                     for b in system.bearings])
    polys = np.zeros((2, 2, 2, 5))
    for i, b in enumerate(system.bearings):
        for k, film in enumerate((b.inner, b.outer)):
            for m_, p in enumerate(correction_polys(film, model)):
                polys[i, k, m_, 5 - p.size:] = p
    ring_m = np.array([b.ring_mass for b in system.bearings])
    ring_i = np.array([b.ring_inertia for b in system.bearings])
    unb_node = np.array([rotor.disc(u.disc).node for u in unbalance], dtype=np.int64)
    unb_me = np.array([check_positive(f"unbalance of {u.disc}", u.amount, "kg m", allow_zero=True) for u in unbalance])
    unb_phase = np.array([float(u.phase) for u in unbalance])
    tg, wg, wdg = profile.t, profile.omega, profile.omega_dot
    if tg.size > 2:  # uniform grid required by _interp
        assert np.allclose(np.diff(tg), tg[1] - tg[0])
    diag = np.zeros(4)
    args = (minv, k_mat, g_mat, f_grav, n_r, jn, geom, polys, ring_m, ring_i, system.gravity, unb_node, unb_me,
            unb_phase, tg, wg, wdg, springs, EPS_CAP, diag)

    # --- initial state
    w0 = float(wg[0])
    y0 = np.zeros(n)
    clear_i = [b.inner.clearance for b in system.bearings]
    clear_o = [b.outer.clearance for b in system.bearings]
    if springs > 0:
        ktot = rotor.K.copy()
        for b in system.bearings:
            ktot[4 * b.node, 4 * b.node] += springs
            ktot[4 * b.node + 1, 4 * b.node + 1] += springs
        y0[:n_r] = np.linalg.solve(ktot, f_grav)
        y0[4 * jn[0]] += perturbation * clear_i[0]
        y0[4 * jn[1]] += perturbation * clear_i[1]
        from .bearing import ring_speed_ratio
        y0[2 * n_r + 8: 2 * n_r + 10] = [ring_speed_ratio(b) * w0 for b in system.bearings]
    else:
        loads = system.bearing_loads
        if initial == "equilibrium":
            eqs = [bearing_equilibrium(b, loads[i], w0, "J", model, system.gravity)
                   for i, b in enumerate(system.bearings)]
            journals = [e.journal for e in eqs]
            rings = [e.ring for e in eqs]
            wfr = [e.ring_speed for e in eqs]
        elif initial == "centred":
            from .bearing import ring_speed_ratio

            journals = rings = [np.zeros(2), np.zeros(2)]
            wfr = [ring_speed_ratio(b) * w0 for b in system.bearings]
        else:
            raise ParameterError(f"initial = {initial!r} is unknown; valid: 'equilibrium', 'centred'")
        journals = [np.asarray(j) + np.array([perturbation * (ci + co), 0.0])
                    for j, ci, co in zip(journals, clear_i, clear_o)]
        rings = [np.asarray(r) + np.array([perturbation * co, 0.0]) for r, co in zip(rings, clear_o)]
        y0[:n_r] = static_rotor_state(system, journals)
        for i in range(2):
            y0[2 * n_r + 4 * i: 2 * n_r + 4 * i + 2] = rings[i]
            y0[2 * n_r + 8 + i] = wfr[i]

    # --- tolerances and FD scales
    pos_tol = 1e-9 * atol_scale
    atol = np.empty(n)
    atol[:n_r] = pos_tol
    atol[2:n_r:4] = atol[3:n_r:4] = pos_tol / 0.03  # rotations ~ displacement / arm length
    atol[n_r:2 * n_r] = atol[:n_r] * max(w0, float(wg.max()))
    for i in range(2):
        b = 2 * n_r + 4 * i
        atol[b:b + 2] = pos_tol
        atol[b + 2:b + 4] = pos_tol * max(w0, float(wg.max()))
    atol[2 * n_r + 8:2 * n_r + 10] = 1e-6 * float(wg.max()) * atol_scale
    atol[2 * n_r + 10] = 1e-6 * atol_scale
    scale = np.maximum(atol * 1e3, 1e-12)

    f_buf = np.zeros(n)
    jac_buf, f0, work = np.zeros((n, n)), np.zeros(n), np.zeros(n)
    nfev = [0]
    njev = [0]

    def fun(t, y):
        nfev[0] += 1
        return _rhs(t, y, f_buf, *args).copy()

    def jac(t, y):
        njev[0] += 1
        return _jac(t, y, jac_buf, f0, work, scale, *args)

    # --- sampling and output
    n_out = int(math.floor(duration * output_rate_hz + 1e-9)) + 1
    t_out = np.arange(n_out) / output_rate_hz
    node_names = []
    node_idx = []
    for d in rotor.discs:
        node_names.append(d.name)
        node_idx.append(d.node)
    columns = _columns(node_names)
    meta = {"system": system.to_dict(), "film_model": model, "profile": profile.description, "duration_s": duration,
            "output_rate_hz": output_rate_hz, "rtol": rtol, "atol_displacement_m": pos_tol,
            "unbalance": [u.__dict__ for u in unbalance], "linear_springs_N_per_m": linear_springs,
            "perturbation_of_clearance": perturbation, "contact_eps": contact_eps, "units": "SI; speed in rpm"}
    writer = _Writer(out_dir, columns, meta) if out_dir is not None else None
    rows = np.full((n_out, len(columns)), np.nan)

    def record(k, t, y):
        _rhs(t, y, f_buf, *args)  # fills diag with the films' eccentricities
        w = float(np.interp(t, tg, wg))
        row = [t, w / RPM, y[2 * n_r + 8], y[2 * n_r + 8] / w, y[2 * n_r + 9], y[2 * n_r + 9] / w]
        for b in system.bearings:
            row += [y[4 * b.node], y[4 * b.node + 1]]
        for i in range(2):
            row += [y[2 * n_r + 4 * i], y[2 * n_r + 4 * i + 1]]
        row += list(diag) if springs == 0 else [0.0] * 4
        for nd in node_idx:
            row += [y[4 * nd], y[4 * nd + 1]]
        rows[k] = row

    solver = ode(fun, jac).set_integrator("lsoda", rtol=rtol, atol=atol, nsteps=nsteps,
                                          max_step=max_step or 0.0)
    solver.set_initial_value(y0, 0.0)
    record(0, 0.0, y0)
    t_wall = time.perf_counter()
    last_print = t_wall
    last_flush = 0
    status, message = "finished", ""
    k_done = 1
    for k in range(1, n_out):
        y = solver.integrate(t_out[k])
        if not solver.successful() or not np.all(np.isfinite(y)):
            status = "stopped"
            message = (f"integrator failed at t = {solver.t:.6g} s, speed {float(np.interp(solver.t, tg, wg)) / RPM:.0f} "
                       f"rpm (LSODA return code {solver.get_return_code()}); results up to there are kept")
            break
        record(k, t_out[k], y)
        k_done = k + 1
        if springs == 0:
            ecc = rows[k, -4 - 2 * len(node_idx): len(columns) - 2 * len(node_idx)]
            worst = int(np.argmax(ecc))
            if ecc[worst] > contact_eps:
                status = "stopped"
                message = (f"{FILM_LABELS[worst].split()[0]} bearing, {FILM_LABELS[worst].split()[1]} film: "
                           f"eccentricity ratio {ecc[worst]:.4f} exceeds contact_eps = {contact_eps} "
                           f"(the {'journal' if 'inner' in FILM_LABELS[worst] else 'ring'} reaches its wall) at "
                           f"t = {t_out[k]:.6g} s, rotor speed {rows[k, 1]:.0f} rpm; results up to there are kept")
                break
        now = time.perf_counter()
        if writer is not None and (k - last_flush >= 2000):
            writer.append(rows[last_flush + 1 if last_flush else 0:k + 1])
            last_flush = k
        if progress and now - last_print > 1.0:
            last_print = now
            el = now - t_wall
            frac = t_out[k] / duration
            sys.stderr.write(f"\rrun-up: t = {t_out[k]:.4f}/{duration:g} s  {rows[k, 1]:8.0f} rpm  "
                             f"wall {el:6.1f} s  ETA {el / frac * (1 - frac):6.1f} s ")
            sys.stderr.flush()
    wall = time.perf_counter() - t_wall
    if progress:
        sys.stderr.write(f"\rrun-up: {status} after {wall:.1f} s wall, {nfev[0]} RHS and {njev[0]} Jacobian "
                         f"evaluations{' ' * 20}\n")
    rows = rows[:k_done]
    meta.update({"wall_time_s": wall, "rhs_evaluations": nfev[0], "jacobian_evaluations": njev[0],
                 "samples": int(k_done)})
    if writer is not None:
        writer.append(rows[last_flush + 1 if last_flush else 0:])
        writer.write_meta(status, message)
    result = _result_from_rows(rows, columns, node_names, status, message, meta)
    if status != "finished":
        raise RunupStopped(message, result)
    return result


def _result_from_rows(rows, columns, node_names, status, message, meta):
    import pandas as pd

    df = pd.DataFrame(rows, columns=columns)
    res = RunupResult.from_dataframe(df, {"status": status, "message": message})
    res.meta = meta
    return res

