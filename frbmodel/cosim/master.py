"""Co-simulation master on fmpy's FMU2Slave, driven by the SSP.

Per communication point: the rotor's outputs (journal states, speed) go to the bearings; the bearings'
outputs (force, interface stiffness and damping) are read *after* their inputs are set and go to the rotor;
then all FMUs step with the fixed macro step. Every FMI status is checked; results stream to ``runup.csv`` /
``runup.json`` in the same format as the monolithic run-up, so the same spectrogram and composite figure apply.
Optional step rejection: when an FMU returns Discard, all FMUs are rolled back (FMU state get/set) and the
interval is retried with half the step.
"""
from __future__ import annotations

import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ..errors import FRBError, ParameterError
from ..runup import FILM_LABELS, RunupResult, _columns, _result_from_rows, _Writer
from .ssp import read_ssp

BEARING_NAMES = ("turbine", "compressor")


def system_from_parameters(params):
    """The frbmodel Turbocharger described by an SSP parameter set (rotor system file + bearing parameters)."""
    from dataclasses import replace

    import frbmodel as frb
    from frbmodel.film import Film

    rp = params.get("rotor", {})
    sys_file = rp.get("rotor_file", ("String", ""))[1]
    tc = frb.load_system(sys_file) if sys_file else frb.turbocharger()
    bs = []
    for name, b in zip(BEARING_NAMES, tc.bearings):
        p = {k: v[1] for k, v in params.get(name, {}).items()}
        films = []
        for fname, film in (("inner", b.inner), ("outer", b.outer)):
            films.append(Film(p.get(f"{fname}.radius", film.radius), p.get(f"{fname}.length", film.length),
                              p.get(f"{fname}.clearance", film.clearance), p.get(f"{fname}.viscosity", film.viscosity)))
        bs.append(replace(b, inner=films[0], outer=films[1], ring_mass=p.get("ring.mass", b.ring_mass),
                          ring_inertia=p.get("ring.inertia", b.ring_inertia)))
    model = params.get(BEARING_NAMES[0], {}).get("film_model", ("String", tc.film_model))[1]
    return tc.with_(bearings=tuple(bs), film_model=model)


class CosimStopped(FRBError):
    """The co-simulation stopped early; ``.result`` holds the samples up to there (also on disk)."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class _Fmu:
    def __init__(self, name, path, tmp):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.name = name
        self.md = read_model_description(str(path))
        self.dir = extract(str(path), unzipdir=str(Path(tmp) / name))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.slave.instantiate(loggingOn=True)
        self.can_state = bool(self.md.coSimulation.canGetAndSetFMUstate)

    def vr(self, names):
        try:
            return [self.vars[n].valueReference for n in names]
        except KeyError as exc:
            raise ParameterError(f"FMU {self.name!r} has no variable {exc.args[0]!r}") from None

    def set_parameters(self, params):
        for name, (typ, val) in params.items():
            vr = self.vr([name])
            {"Real": self.slave.setReal, "Integer": self.slave.setInteger, "Boolean": self.slave.setBoolean,
             "String": self.slave.setString}[typ](vr, [val])


def _call(fmu, what, fn, *args):
    from fmpy.fmi1 import FMICallException

    try:
        return fn(*args)
    except FMICallException as exc:
        raise CosimStopped(f"{fmu.name}: {what} failed ({exc})") from None


def cosimulate(ssp, parameter_set="co36", stop_time=None, step_size=None, out_dir=None, progress=True,
               rollback=False, output_rate_hz=20e3, overrides=None, max_halvings=6, coupling="jacobian"):
    """Run the SSP system with frbmodel's master.

    Parameters
    ----------
    ssp : path
        ``.ssp`` archive or folder (SystemStructure.ssd + resources/).
    parameter_set : str
        Name of the .ssv set (``co36``, ``co40``, ``co42``, ``co46``).
    stop_time, step_size : float, optional
        Default: the SSP's DefaultExperiment stop time and OSP fixed step [s].
    out_dir : path, optional
        Stream ``runup.csv`` / ``runup.json`` there.
    rollback : bool
        Retry a Discarded interval with half steps after restoring all FMU states.
    output_rate_hz : float
        Sampling rate of the recorded results [Hz]: every n-th communication point with n = round(1 / (H rate)),
        at least 1 (default 20 kHz, as the monolithic run-up).
    overrides : dict, optional
        {component: {parameter: (type, value)}} applied after the parameter set.
    coupling : {"jacobian", "force"}
        "force" drops the stiffness/damping connections (plain force exchange, for comparison).

    Returns
    -------
    RunupResult (``meta`` has wall time, FMI call time, steps).

    Raises
    ------
    CosimStopped
        An FMU failed; the message names it and its log; ``.result`` holds the samples so far.
    """
    sys_ = read_ssp(ssp)
    params = sys_.parameters(parameter_set)
    for comp, ov in (overrides or {}).items():
        params.setdefault(comp, {}).update(ov)
    stop_time = float(stop_time if stop_time is not None else (sys_.stop_time or 1.0))
    H = float(step_size if step_size is not None else (sys_.step_size or 2e-5))
    if not (H > 0 and stop_time > 0 and math.isfinite(H) and math.isfinite(stop_time)):
        raise ParameterError(f"step size = {H!r} s and stop time = {stop_time!r} s must be finite and > 0")
    output_every = max(1, int(round(1.0 / (H * output_rate_hz))))
    tmp = tempfile.mkdtemp(prefix="frb_cosim_")
    fmus = {name: _Fmu(name, path, tmp) for name, path in sys_.components.items()}
    rotor = fmus["rotor"]
    bearings = [fmus[n] for n in BEARING_NAMES]
    # connections grouped: rotor -> bearings (pass 1), bearings -> rotor (pass 2, after the bearings' inputs)
    if coupling not in ("jacobian", "force"):
        raise ParameterError(f"coupling = {coupling!r} is unknown; valid: 'jacobian', 'force'")
    groups, end_groups = {}, {}
    for s_el, s_c, e_el, e_c in sys_.connections:
        if coupling == "force" and (s_c.startswith("stiffness") or s_c.startswith("damping")):
            params.setdefault(e_el, {})[e_c] = ("Real", 0.0)  # no interface Jacobian at all
            continue
        if s_c.startswith(("force_end", "journal_accel")):  # staggered: passed after the bearings have stepped
            if coupling == "jacobian":
                end_groups.setdefault((s_el, e_el), []).append((s_c, e_c))
            continue
        groups.setdefault((s_el, e_el), []).append((s_c, e_c))
    if end_groups:
        params.setdefault("rotor", {})["force_interpolation"] = ("Boolean", True)
    order = sorted(groups, key=lambda k: 0 if k[0] == "rotor" else 1)
    links = [(fmus[s], fmus[e], fmus[s].vr([c[0] for c in groups[(s, e)]]), fmus[e].vr([c[1] for c in groups[(s, e)]]))
             for s, e in order]
    end_links = [(fmus[s], fmus[e], fmus[s].vr([c[0] for c in g]), fmus[e].vr([c[1] for c in g]))
                 for (s, e), g in end_groups.items()]
    if any(e != "rotor" for _, e in end_groups):
        raise ParameterError("the staggered connections (force_end, journal_accel) must end at the rotor")
    end_src = [(src, svr) for src, _, svr, _ in end_links]  # one getReal per bearing, one setReal on the rotor
    end_dvr = [v for *_, dvr in end_links for v in dvr]
    # two phases (rotor -> bearings, then bearings -> rotor, so that the bearings' outputs are read after their
    # inputs are set); per phase one getReal per source and one setReal per destination
    phases = []
    for from_rotor in (True, False):
        mine = [lk for lk in links if (lk[0] is rotor) == from_rotor]
        srcs = {}
        for src, dst, svr, dvr in mine:
            srcs.setdefault(src, []).append((dst, svr, dvr))
        gets = [(src, [v for _, svr, _ in ls for v in svr]) for src, ls in srcs.items()]
        dests = {}
        pos = 0
        for src, ls in srcs.items():
            for dst, svr, dvr in ls:
                d = dests.setdefault(dst, ([], []))
                d[0].extend(dvr)
                d[1].extend(range(pos, pos + len(svr)))
                pos += len(svr)
        phases.append((gets, [(dst, dvr, idx) for dst, (dvr, idx) in dests.items()]))
    # recorded variables
    rec_rotor = rotor.vr(["rotor_speed"] + [f"{b}_bearing.journal.{q}" for b in BEARING_NAMES for q in "xy"] +
                         [f"{w}.{q}" for w in ("turbine_wheel", "compressor_wheel") for q in "xy"])
    rec_bear = [b.vr(["ring.speed", "ring.x", "ring.y", "eps_inner", "eps_outer"]) for b in bearings]
    columns = _columns(["turbine_wheel", "compressor_wheel"])
    meta = {"ssp": str(ssp), "parameter_set": parameter_set, "step_size_s": H, "stop_time_s": stop_time,
            "output_rate_hz": 1.0 / (H * output_every),
            "system": system_from_parameters(params).to_dict(),
            "coupling": coupling,
            "master": "frbmodel.cosim (fmpy FMU2Slave, staggered interface-Jacobian coupling)", "rollback": rollback,
            "units": "SI; speed in rpm"}
    writer = _Writer(out_dir, columns, meta) if out_dir is not None else None
    n_steps = int(round(stop_time / H))
    rows = np.full((n_steps // output_every + 2, len(columns)), np.nan)
    t_fmi = 0.0

    def exchange():
        nonlocal t_fmi
        t0 = time.perf_counter()
        for gets, sets in phases:
            vals = []
            for src, svr in gets:
                v = _call(src, "getReal", src.slave.getReal, svr)
                if not math.isfinite(sum(v)):
                    names = [n for n, var in src.vars.items() if var.valueReference in svr]
                    raise CosimStopped(f"{src.name}: non-finite output among {names} (see the FMU log)")
                vals += v
            for dst, dvr, idx in sets:
                _call(dst, "setReal", dst.slave.setReal, dvr, [vals[i] for i in idx])
        t_fmi += time.perf_counter() - t0

    def record(k, t):
        r = rotor.slave.getReal(rec_rotor)
        w = r[0]
        b = [fmu.slave.getReal(v) for fmu, v in zip(bearings, rec_bear)]
        row = [t, w * 30 / math.pi, b[0][0], b[0][0] / w if w else 0.0, b[1][0], b[1][0] / w if w else 0.0,
               r[1], r[2], r[3], r[4], b[0][1], b[0][2], b[1][1], b[1][2], b[0][3], b[0][4], b[1][3], b[1][4],
               r[5], r[6], r[7], r[8]]
        rows[k] = row

    from fmpy.fmi1 import FMICallException

    status, message = "finished", ""
    n_rejected = 0
    k_rec = 0
    last_flush = 0
    t_wall = time.perf_counter()
    try:
        for fmu in fmus.values():
            _call(fmu, "setupExperiment", fmu.slave.setupExperiment, None, 0.0, None)
            _call(fmu, "enterInitializationMode", fmu.slave.enterInitializationMode)
            try:
                fmu.set_parameters(params.get(fmu.name, {}))
            except FRBError:
                raise
            except Exception as exc:  # noqa: BLE001
                raise CosimStopped(f"{fmu.name}: setting parameters failed: {exc}") from None
            _call(fmu, "exitInitializationMode", fmu.slave.exitInitializationMode)
        exchange()  # links are ordered rotor -> bearings first: bearing forces are read after their inputs are set
        record(0, 0.0)
        k_rec = 1
        t = 0.0
        last_print = t_wall
        for k in range(1, n_steps + 1):
            t_target = k * H
            h = H
            while t < t_target - 1e-12 * H:
                h = min(h, t_target - t)
                states = None
                if rollback:
                    t0 = time.perf_counter()
                    states = {n: f.slave.getFMUstate() for n, f in fmus.items() if f.can_state}
                    t_fmi += time.perf_counter() - t0
                failure = None  # (FMU, what happened) of a rejected interval
                t0 = time.perf_counter()
                # staggered: bearings first (journal extrapolated), their end-of-step force to the rotor, then the
                # rotor with the force interpolated over the step
                for fmu in (*bearings, rotor):
                    if fmu is rotor and end_links:
                        vals = []
                        for src, svr in end_src:
                            v = _call(src, "getReal", src.slave.getReal, svr)
                            if not math.isfinite(sum(v)):
                                failure = (src, "published a non-finite end-of-step force")
                                break
                            vals += v
                        if failure:
                            break
                        _call(rotor, "setReal", rotor.slave.setReal, end_dvr, vals)
                    try:
                        fmu.slave.doStep(t, h)
                    except FMICallException as exc:
                        st = int(exc.status)
                        failure = (fmu, "doStep returned status " +
                                   ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"][st], st)
                        break
                t_fmi += time.perf_counter() - t0
                if failure is None:
                    try:  # the new journal states may already put a film at its wall: non-finite outputs
                        exchange()
                    except CosimStopped as exc:
                        failure = (None, str(exc))
                retryable = failure is not None and (len(failure) < 3 or failure[2] == 2)  # Discard, non-finite
                retry = retryable and rollback and states and h > H / 2 ** max_halvings
                if retry:
                    for n, f in fmus.items():
                        if n in states:
                            f.slave.setFMUstate(states[n])
                if states:
                    for n, f in fmus.items():
                        if n in states:
                            f.slave.freeFMUstate(states[n])
                if retry:
                    h /= 2
                    n_rejected += 1
                    exchange()
                    continue
                if failure is not None:
                    who = f"{failure[0].name}: " if failure[0] is not None else ""
                    tried = f" (after {max_halvings} step halvings with rollback)" if retryable and rollback else ""
                    raise CosimStopped(f"{who}{failure[1]} in the interval t = {t:.6g} s + {h:.3g} s{tried}" +
                                       ("; see the FMU log above" if failure[0] is not None else ""))
                t += h
            if k % output_every == 0:
                record(k_rec, t)
                k_rec += 1
            now = time.perf_counter()
            if writer is not None and k_rec - last_flush >= 2000:
                writer.append(rows[last_flush:k_rec])
                last_flush = k_rec
            if progress and now - last_print > 1.0:
                last_print = now
                el = now - t_wall
                frac = t / stop_time
                sys.stderr.write(f"\rcosim: t = {t:.4f}/{stop_time:g} s  {rows[k_rec - 1, 1]:8.0f} rpm  wall {el:6.1f} s  "
                                 f"ETA {el / frac * (1 - frac):6.1f} s ")
                sys.stderr.flush()
    except CosimStopped as exc:
        status, message = "stopped", str(exc)
    finally:
        wall = time.perf_counter() - t_wall
        for fmu in fmus.values():
            try:
                fmu.slave.terminate()
                fmu.slave.freeInstance()
            except Exception:  # noqa: BLE001  (an FMU that already failed may refuse)
                pass
        shutil.rmtree(tmp, ignore_errors=True)
    if progress:
        sys.stderr.write(f"\rcosim: {status} after {wall:.1f} s wall ({t_fmi / max(wall, 1e-9):.0%} in FMI calls)"
                         f"{' ' * 30}\n")
    rows = rows[:k_rec]
    meta.update({"wall_time_s": wall, "fmi_time_s": t_fmi, "samples": int(k_rec), "rejected_steps": n_rejected})
    if writer is not None:
        writer.append(rows[last_flush if k_rec else 0:] if k_rec else rows[:0])
        writer.write_meta(status, message)
    result = _result_from_rows(rows, columns, ["turbine_wheel", "compressor_wheel"], status, message, meta)
    if status != "finished":
        raise CosimStopped(message, result)
    return result


__all__ = ["cosimulate", "CosimStopped", "RunupResult", "FILM_LABELS"]


def operating_point_overrides(system, speed_rpm, end_rpm=None, ramp_time=1.0, method="J", perturbation=0.0):
    """Parameter overrides that start the SSP system at the ``method`` equilibrium at ``speed_rpm`` (plus the
    same initial offset as :func:`frbmodel.runup.runup`'s ``perturbation``): rotor speed profile and initial
    journal positions, ring positions and speeds."""
    from ..equilibrium import equilibrium

    eq = equilibrium(system, method, speed_rpm)
    w0 = speed_rpm * math.pi / 30
    w1 = (end_rpm if end_rpm is not None else speed_rpm) * math.pi / 30
    ov = {"rotor": {"speed_start": ("Real", w0), "speed_end": ("Real", w1), "ramp_time": ("Real", float(ramp_time))}}
    for name, prefix, b, e in zip(BEARING_NAMES, ("turbine_bearing", "compressor_bearing"), system.bearings,
                                  eq.bearings):
        ci, co = b.inner.clearance, b.outer.clearance
        ov["rotor"][f"{prefix}.journal_x0"] = ("Real", float(e.journal[0] + perturbation * (ci + co)))
        ov["rotor"][f"{prefix}.journal_y0"] = ("Real", float(e.journal[1]))
        ov[name] = {"ring.x0": ("Real", float(e.ring[0] + perturbation * co)), "ring.y0": ("Real", float(e.ring[1])),
                    "ring.speed0": ("Real", float(e.ring_speed))}
    return ov
