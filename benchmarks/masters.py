"""Do the masters agree? (issue #11 item 8, not a test): the SSP system run by four masters against the monolithic
run-up over the first 0.1 s of the co36 run-up (20 -> 250 krpm in 1 s, i.e. 20 -> 43 krpm).

Usage::

    python benchmarks/masters.py [--build build] [--step 1e-5] [--halvings 1]

Runs, each from the SSP's default parameter set (co36, bound by SystemStructure.ssd):

* ``monolithic``: ``frb.runup`` of the same system at rtol 1e-9, atol 1e-12 m (the reference; its own
  uncertainty is printed: the difference to the run-up's defaults rtol 1e-7, atol 1e-10 m);
* ``frb cosim``: frbmodel's staggered master (``frbmodel.cosim.master.cosimulate``; bearings step first, the rotor
  interpolates their force, ``force_interpolation = true``);
* ``libcosim``: the OSP master (libcosimpy) on the extracted SSP, unchanged; journal positions through a
  time-series observer (only the four observed variables are read: a last-value observer reads all ~3000
  variables of the three FMUs at every step, 12x slower);
* ``fmpy container``: an FMU container (``fmpy.container_fmu``) of the three FMUs with the SSP's connections (their
  connectors retyped Float64, the container's own type names) and every co36 parameter as a container parameter
  with the SSV value as start value, driven by fmpy's FMU2Slave (instantiate, setupExperiment, initialization
  mode, doStep every 50 us; the container steps its fixed step inside). ``simulate_fmu`` is not used: it hides
  Discard;
* ``fmpy Jacobi``: a Jacobi loop on fmpy FMU2Slaves (all FMUs step, then every connection is passed, outputs read
  before inputs are set, as libcosim does) whose coupling inputs start consistent with the parameter set (one
  exchange after initialization, rotor -> bearings first). It reproduces libcosim to round-off once the FMUs
  compute their outputs in Initialization Mode (see README "Do the masters agree?").

Prints per master the macro step, the journal x, y of both bearings at t = 0.02, 0.05, 0.1 s and the largest
distance of each journal centre from the monolithic one over [0, 15 ms] and over [0, 0.1 s] [um and % of the
outer clearance], when it first exceeds 1 and 10 um, and the mean orbit radius over 50-100 ms; with
``--halvings``, each co-simulation again at half the step (the coupling error of a Jacobi master
is O(H): its deviation over the first 15 ms halves). Also checks that libcosim and the container set every co36
parameter to its SSV value and which coupling inputs they start from; for the Jacobi masters the period-2
oscillation of the exchanged bearing forces (a force alternating from one macro step to the next, from ~17 ms on);
how much each scheme amplifies a 1e-12 m change of the start state (monolithic and staggered alike, the Jacobi
loop by orders of magnitude more once its force oscillation sets in); the time constants of the ring in its films.
~1.5 min on 2 cores (``--halvings 3``: ~7 min).
"""
from __future__ import annotations

import argparse
import math
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np
from _cli import positive, run_script, whole  # (benchmarks/ is the script's folder)

import frbmodel as frb
from frbmodel.cosim.build import built_ssp
from frbmodel.cosim.fmu import FmuInstance
from frbmodel.cosim.master import cosimulate
from frbmodel.cosim.ssp import read_ssp

DURATION_S = 0.1
SPEED_RPM = (20e3, 20e3 + (250e3 - 20e3) * DURATION_S)  # the first 0.1 s of the 1 s run-up
SAMPLE_S = 5e-5  # every master is sampled on this grid (the monolithic run-up's 20 kHz)
EARLY_S = 0.015  # the Jacobi masters' force oscillation starts at 17-20 ms (10-2.5 us): compare before it
TIMES_S = (0.02, 0.05, 0.1)
BEARINGS = ("turbine", "compressor")


def _trajectory(t, journals):
    """{"t": (n,) [s], bearing: (n, 2) journal x, y [m]} from ``journals`` (n, 2 nb) in BEARINGS order."""
    journals = np.asarray(journals, dtype=float)
    return {"t": np.asarray(t, dtype=float), **{b: journals[:, 2 * i:2 * i + 2] for i, b in enumerate(BEARINGS)}}


def monolithic(rtol, atol):
    """Journal trajectories of the monolithic run-up (``frb.runup``) of the co36 system."""
    r = frb.runup(frb.turbocharger(36e-6), speed_rpm=SPEED_RPM, duration=DURATION_S, rtol=rtol, atol=atol,
                  perturbation=0.05, output_rate_hz=1.0 / SAMPLE_S)
    return _trajectory(r.time, np.hstack([r.journal[b] for b in BEARINGS]))


def frb_cosim(ssp, step, duration=DURATION_S, overrides=None):
    """Journal trajectories of frbmodel's staggered master (``overrides`` as for ``cosimulate``)."""
    r = cosimulate(ssp, "co36", stop_time=duration, step_size=step, output_rate_hz=1.0 / SAMPLE_S,
                   overrides=overrides)
    return _trajectory(r.time, np.hstack([r.journal[b] for b in BEARINGS]))


def _libcosim_execution(folder, step):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
    ex = CosimExecution.from_ssp_file(str(folder), step_size=int(round(step * 1e9)))  # [ns]
    names = {}
    for comp in ("rotor",) + BEARINGS:
        i = ex.slave_index_from_instance_name(comp)
        names[comp] = (i, {(v.name.decode() if isinstance(v.name, bytes) else v.name): v.reference
                           for v in ex.slave_variables(i)})
    return ex, names


def libcosim(folder, step):
    """Journal trajectories of libcosim (fixed-step Jacobi master) running the SSP folder unchanged, with the
    bearing forces after every step (``"force"``, see :func:`alternating_force`)."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    ex, names = _libcosim_execution(folder, step)
    obs = CosimObserver.create_time_series(buffer_size=int(round(DURATION_S / step)) + 10)
    ex.add_observer(obs)
    i, vr = names["rotor"]
    series = [(i, vr[f"{b}_bearing.journal.{q}"]) for b in BEARINGS for q in "xy"]
    series += [(names[b][0], names[b][1][f"force.{q}"]) for b in BEARINGS for q in "xy"]
    for slave, ref in series:
        obs.start_time_series(slave, ref, CosimVariableType.REAL)
    n = int(round(DURATION_S / step))
    ex.step(n)
    # samples from step 1 on: libcosimpy drops samples whose step number is 0 from the count it returns
    cols = [obs.time_series_real_samples(slave, ref, 1, n) for slave, ref in series]
    t = np.array(cols[0][0]) * 1e-9
    values = np.column_stack([c[2] for c in cols])
    every = int(round(SAMPLE_S / step))
    keep = slice(every - 1, None, every)
    traj = _trajectory(np.concatenate([[0.0], t[keep]]), np.vstack([np.full(4, np.nan), values[keep, :4]]))
    traj["force"] = (t, values[:, 4:])
    return traj


def alternating_force(run):
    """(largest amplitude [N] of the period-2 component of the exchanged bearing forces after the first ms, first
    time [s] it exceeds 0.1 N there) from ``run["force"] = (t, (n, 2 nb) forces after each step)``:
    |F[k+1] - 2 F[k] + F[k-1]| / 4 is the amplitude of a force alternating from step to step and ~1e-3 N for the
    smooth whirl (30 N at 140 Hz, 10 us steps)."""
    t, f = run["force"]
    a = np.abs(f[2:] - 2 * f[1:-1] + f[:-2]).max(axis=1) / 4
    hit = np.flatnonzero((a > 0.1) & (t[1:-1] > 1e-3))  # after the first ms: libcosim's start-up jump is there
    return float(a[t[1:-1] > 1e-3].max()), (float(t[1:-1][hit[0]]) if hit.size else math.nan)


def libcosim_start(folder, params, connected):
    """:func:`compare_start` of libcosim: the values after its first step (the inputs are those it stepped with)."""
    from libcosimpy.CosimObserver import CosimObserver

    ex, names = _libcosim_execution(folder, 1e-5)
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    ex.step(1)

    def read(comp, name, typ):
        i, vr = names[comp]
        return (obs.last_real_values(i, [vr[name]]) if typ == "Real" else obs.last_string_values(i, [vr[name]]))[0]

    return compare_start(params, connected, read)


#: coupling inputs whose value in the first step is reported (start value in the SSV, overwritten by connections)
START_PROBE = (("turbine", "journal.x"), ("turbine", "rotor_speed"), ("rotor", "turbine_bearing.force.y"),
               ("rotor", "turbine_bearing.journal_ref.x"), ("rotor", "turbine_bearing.stiffness.xx"))


def compare_start(params, connected, read):
    """(parameters whose value differs from the SSV, number compared, {coupling input: value}) from
    ``read(component, name, SSP type)``; connected inputs (start values in the SSV too) are not compared but the
    :data:`START_PROBE` ones are reported."""
    bad, total = [], 0
    for comp, ps in params.items():
        for name, (typ, val) in ps.items():
            if (comp, name) in connected:
                continue
            total += 1
            got = read(comp, name, typ)
            got = got.decode() if isinstance(got, bytes) else got
            if got != val:
                bad.append(f"{comp}.{name} = {got!r} (SSV {val!r})")
    return bad, total, {f"{c}.{n}": read(c, n, "Real") for c, n in START_PROBE}


def build_container(folder, step, dest):
    """An fmpy FMU container of the SSP's components and connections; every parameter of the default set is a
    container parameter with its SSV value as start value; outputs: the rotor's journal x, y per bearing."""
    from attrs import evolve
    from fmpy import read_model_description
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Configuration, Connection
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable

    with read_ssp(folder) as ssp:
        params = ssp.parameters()
        comps, mvars = {}, {}
        for name, path in ssp.components.items():
            md = read_model_description(str(path))
            comps[name] = Component(name=name, filename=Path(path), modelDescription=md)
            mvars[name] = {v.name: v for v in md.modelVariables}
        retype = lambda v: evolve(v, type="Float64")  # noqa: E731  (the container's connections need it)
        cons = [Connection(comps[s], [retype(mvars[s][a])], comps[d], [retype(mvars[d][b])])
                for s, a, d, b in ssp.connections]
    variables = [ModelVariable(name="time", type="Real", causality="independent", variability="continuous")]
    mapping = {}

    def expose(comp, name, **kw):
        v = ModelVariable(name=f"{comp}.{name}", **kw)
        variables.append(v)
        mapping[v] = [(comps[comp], mvars[comp][name])]

    for comp, ps in params.items():
        for name, (typ, val) in ps.items():
            expose(comp, name, type=typ, causality="parameter", variability="fixed", initial="exact",
                   start=repr(float(val)) if typ == "Real" else str(val))
    for b in BEARINGS:
        for q in "xy":
            expose("rotor", f"{b}_bearing.journal.{q}", type="Real", causality="output", variability="continuous",
                   initial="calculated")
    md = ModelDescription(fmiVersion="2.0", modelName="turbocharger_container",
                          instantiationToken="{" + str(uuid.uuid4()) + "}",
                          coSimulation=CoSimulation(modelIdentifier="container_fmu", fixedInternalStepSize=step),
                          defaultExperiment=DefaultExperiment(startTime="0", stopTime=repr(DURATION_S)),
                          modelVariables=variables)
    work = Path(tempfile.mkdtemp(prefix="frb_container_"))
    (work / "unzip").mkdir()
    create_container_fmu(Configuration(parallelDoStep=False, modelDescription=md, components=list(comps.values()),
                                       connections=cons, variableMappings=mapping), work / "unzip", Path(dest))
    return Path(dest), params


def container(fmu, params, connected):
    """Journal trajectories of the container FMU driven by fmpy, and :func:`compare_start` after its
    initialization (the values of its first step)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="container")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    start = compare_start(params, connected, lambda c, n, typ: (s.getReal if typ == "Real" else s.getString)(
        [vr[f"{c}.{n}"]])[0])
    out_vr = [vr[f"rotor.{b}_bearing.journal.{q}"] for b in BEARINGS for q in "xy"]
    rows = [s.getReal(out_vr)]
    n = int(round(DURATION_S / SAMPLE_S))
    for k in range(n):
        s.doStep(k * SAMPLE_S, SAMPLE_S)  # the container steps its fixed step inside
        rows.append(s.getReal(out_vr))
    s.terminate()
    s.freeInstance()
    return _trajectory(np.arange(n + 1) * SAMPLE_S, rows), start


def fmpy_jacobi(folder, step, duration=DURATION_S, overrides=None):
    """Journal trajectories of a Jacobi loop on fmpy FMU2Slaves, coupling inputs consistent at the start
    (``overrides``: {component: {parameter: (type, value)}} applied after the parameter set)."""
    with read_ssp(folder) as ssp, tempfile.TemporaryDirectory(prefix="frb_jacobi_") as tmp:
        params = ssp.parameters()
        for comp, ov in (overrides or {}).items():
            params[comp].update(ov)
        fmus = {n: FmuInstance(n, p, tmp) for n, p in ssp.components.items()}
        links = [(fmus[s], fmus[s].vr([a]), fmus[d], fmus[d].vr([b])) for s, a, d, b in ssp.connections]
        try:
            for name, f in fmus.items():
                f.call("setupExperiment", None, 0.0, None)
                f.call("enterInitializationMode")
                f.set_parameters(params.get(name, {}))
                f.call("exitInitializationMode")
            for src, svr, dst, dvr in links:  # rotor -> bearings first: the bearings' outputs belong to them
                dst.call("setReal", dvr, src.call("getReal", svr))
            out_vr = fmus["rotor"].vr([f"{b}_bearing.journal.{q}" for b in BEARINGS for q in "xy"])
            force_at = [[k for k, c in enumerate(ssp.connections) if c[0] == b and c[1] == f"force.{q}"][0]
                        for b in BEARINGS for q in "xy"]
            forces = []
            rows, n, every = [fmus["rotor"].call("getReal", out_vr)], int(round(duration / step)), \
                int(round(SAMPLE_S / step))
            for k in range(n):
                for f in fmus.values():
                    f.call("doStep", k * step, step, True)
                vals = [src.call("getReal", svr) for src, svr, _, _ in links]  # all outputs, then all inputs
                for (_, _, dst, dvr), v in zip(links, vals):
                    dst.call("setReal", dvr, v)
                forces.append([vals[k][0] for k in force_at])
                if (k + 1) % every == 0:
                    rows.append(fmus["rotor"].call("getReal", out_vr))
        finally:
            for f in fmus.values():
                f.free()
    traj = _trajectory(np.arange(len(rows)) * SAMPLE_S, rows)
    traj["force"] = (np.arange(1, len(forces) + 1) * step, np.array(forces))
    return traj


def sensitivity(ssp_path, folder, step, params, delta_m=1e-12, times_s=(0.015, 0.03)):
    """Amplification of a perturbation: the largest change of a journal centre over [0, t] divided by ``delta_m``,
    after moving the turbine ring's start position by ``delta_m`` in x, for frb cosim and the fmpy Jacobi loop;
    for the monolithic run-up (which cannot move the ring alone) after moving the journals by ``delta_m`` and the
    rings by ``delta_m`` c_o / (c_i + c_o) (its ``perturbation``). Returns {master: [amplification at each t]}."""
    ov = {"turbine": {"ring.x0": ("Real", params["turbine"]["ring.x0"][1] + delta_m)}}
    t_end = max(times_s)
    clearance = params["turbine"]["inner.clearance"][1] + params["turbine"]["outer.clearance"][1]
    pairs = {"monolithic": [frb.runup(frb.turbocharger(36e-6), speed_rpm=SPEED_RPM, duration=DURATION_S, rtol=1e-10,
                                      atol=1e-13, perturbation=0.05 + d / clearance, output_rate_hz=1.0 / SAMPLE_S)
                            for d in (0.0, delta_m)],
             "frb cosim": [frb_cosim(ssp_path, step, t_end, o) for o in (None, ov)],
             "fmpy Jacobi": [fmpy_jacobi(folder, step, t_end, o) for o in (None, ov)]}
    pairs["monolithic"] = [_trajectory(r.time, np.hstack([r.journal[b] for b in BEARINGS]))
                           for r in pairs["monolithic"]]
    out = {}
    for name, (a, b) in pairs.items():
        d = np.max([np.abs(a[k] - b[k]).max(axis=1) for k in BEARINGS], axis=0)
        out[name] = [float(d[a["t"] <= t + 1e-12].max() / delta_m) for t in times_s]
    return out


def deviation(run, ref, t_end):
    """Largest distance [m] of each journal centre of ``run`` from ``ref`` over [0, t_end] (samples at the
    reference's times; the libcosim trajectory has no t = 0 sample, NaN, skipped)."""
    out = {}
    for b in BEARINGS:
        x = np.column_stack([np.interp(ref["t"], run["t"], run[b][:, k]) for k in range(2)])
        d = np.hypot(*(x - ref[b]).T)[ref["t"] <= t_end + 1e-12]
        out[b] = float(np.nanmax(d))
    return out


def at(run, t):
    """Journal x, y [m] of each bearing at the sample nearest ``t`` [s]."""
    i = int(np.argmin(np.abs(run["t"] - t)))
    return {b: run[b][i] for b in BEARINGS}


def _runs(ssp_path, folder, steps, tmp):
    """[(master, macro step [s], trajectories, wall time [s])] and the start checks of libcosim / container."""
    runs, checks = [], {}
    for step in steps:
        jobs = [("frb cosim", frb_cosim, (ssp_path, step)), ("libcosim", libcosim, (folder, step)),
                ("fmpy container", _container_run, (folder, step, tmp, checks)),
                ("fmpy Jacobi", fmpy_jacobi, (folder, step))]
        for name, job, job_args in jobs:
            t0 = time.perf_counter()
            traj = job(*job_args)
            runs.append((name, step, traj, time.perf_counter() - t0))
            print(f"  {name:<16} H = {step * 1e6:5.2f} us  {runs[-1][3]:6.1f} s wall", flush=True)
    return runs, checks


def _container_run(folder, step, tmp, checks):
    fmu, params = build_container(folder, step, Path(tmp) / f"container_{step * 1e9:.0f}ns.fmu")
    traj, checks["fmpy container"] = container(fmu, params, connected_inputs(folder))
    return traj


def connected_inputs(folder):
    """{(component, input)} of every connection's end: inputs whose SSV start value a master may overwrite."""
    with read_ssp(folder) as ssp:
        return {(e_el, e_c) for _, _, e_el, e_c in ssp.connections}


def _print_positions(ref, runs):
    print("\nJournal centre x, y [um] (monolithic: rtol 1e-9, atol 1e-12 m)")
    head = "".join(f"{f't = {t:g} s':>18}" for t in TIMES_S)
    for b in BEARINGS:
        print(f"\n  {b:<12}{'H [us]':>10}{head}")
        for name, step, run, _ in [("monolithic", math.nan, ref, 0.0)] + runs:
            vals = "".join(f"{x * 1e6:9.2f}{y * 1e6:9.2f}" for x, y in (at(run, t)[b] for t in TIMES_S))
            print(f"  {name:<16}{step * 1e6:6.2f}{vals}" if step == step else f"  {name:<16}{'-':>6}{vals}")


def first_exceeds(run, ref, threshold_m):
    """First time [s] at which a journal centre of ``run`` is farther than ``threshold_m`` from ``ref`` (NaN:
    never within the run)."""
    d = np.zeros_like(ref["t"])
    for b in BEARINGS:
        x = np.column_stack([np.interp(ref["t"], run["t"], run[b][:, k]) for k in range(2)])
        d = np.fmax(d, np.hypot(*(x - ref[b]).T))
    hit = np.flatnonzero(d > threshold_m)
    return float(ref["t"][hit[0]]) if hit.size else math.nan


def orbit_radius(run, b, t0=0.05, t1=DURATION_S):
    """Mean distance [m] of bearing ``b``'s journal centre from its mean position over [t0, t1] (whirl size)."""
    w = (run["t"] >= t0) & (run["t"] <= t1 + 1e-12)
    x = run[b][w]
    return float(np.nanmean(np.hypot(*(x - np.nanmean(x, axis=0)).T)))


def _print_deviations(ref, runs, clearance):
    print(f"\nLargest distance from the monolithic journal centre [um] (% of the outer clearance "
          f"{clearance * 1e6:.0f} um), turbine / compressor; first time [ms] either journal is > 1 um, > 10 um "
          f"away; mean orbit radius over 50-100 ms [um]")
    print(f"  {'master':<16}{'H [us]':>7}{'[0, 15 ms]':>20}{'[0, 0.1 s]':>16}{'% c_o':>12}{'> 1 um':>9}"
          f"{'> 10 um':>8}{'orbit radius':>16}")
    print(f"  {'monolithic':<16}{'-':>7}{'':>48}{'':>17}{orbit_radius(ref, 'turbine') * 1e6:8.1f}"
          f"{orbit_radius(ref, 'compressor') * 1e6:8.1f}")
    early = {}
    for name, step, run, _ in runs:
        e, f = deviation(run, ref, EARLY_S), deviation(run, ref, DURATION_S)
        early[(name, step)] = max(e.values())
        t1, t10 = (first_exceeds(run, ref, d) * 1e3 for d in (1e-6, 1e-5))
        print(f"  {name:<16}{step * 1e6:7.2f}{e['turbine'] * 1e6:10.4f}{e['compressor'] * 1e6:10.4f}"
              f"{f['turbine'] * 1e6:8.2f}{f['compressor'] * 1e6:8.2f}"
              f"{f['turbine'] / clearance * 100:6.0f}{f['compressor'] / clearance * 100:6.0f}{t1:9.1f}{t10:8.1f}"
              f"{orbit_radius(run, 'turbine') * 1e6:8.1f}{orbit_radius(run, 'compressor') * 1e6:8.1f}")
    print("\n  period-2 oscillation of the exchanged bearing forces (force alternating from step to step) after the "
          "first ms: largest amplitude [N], first time > 0.1 N [ms]")
    for name, step, run, _ in runs:
        if "force" in run:
            amp, t_on = alternating_force(run)
            print(f"  {name:<16}{step * 1e6:7.2f}{amp:10.3f}{t_on * 1e3:9.2f}")
    steps = sorted({s for _, s in early}, reverse=True)
    if len(steps) > 1:
        print("\n  halving the step: deviation over [0, 15 ms] at H / at H/2 (O(H): 2, O(H^2): 4)")
        for name in dict.fromkeys(n for n, _ in early):
            print(f"  {name:<16}" + "".join(f"{early[(name, a)] / early[(name, b)]:7.2f}"
                                             for a, b in zip(steps, steps[1:])))


def ring_time_constants(params, speeds_rpm=SPEED_RPM):
    """{(bearing, rpm): shortest time constant [s] of the ring's lateral motion in its films}, from the bearing's
    linearization (ring speed held) at the method-J equilibrium of the co36 system."""
    from frbmodel.core.units import rpm_to_rad_s
    from frbmodel.nonlinear.components import BearingComponent

    tc = frb.turbocharger(params[BEARINGS[0]]["outer.clearance"][1])
    out = {}
    for rpm in speeds_rpm:
        for b, e in zip(tc.bearings, frb.equilibrium(tc, "J", rpm).bearings):
            bc = BearingComponent(b, tc.film_model)
            bc.ring[:] = [e.ring[0], e.ring[1], 0.0, 0.0, e.ring_speed]
            a = bc.linearization([e.journal[0], e.journal[1], 0.0, 0.0], rpm_to_rad_s(rpm))[0]
            out[(b.name, rpm)] = 1.0 / float(np.max(-np.linalg.eigvals(a).real))
    return out


def _print_checks(params, checks, ref):
    print("\nStart of each master")
    j0 = max(abs(ref[b][0, k] - params["rotor"][f"{b}_bearing.journal_{q}0"][1])
             for b in BEARINGS for k, q in enumerate("xy"))
    print(f"  SSV journal start vs monolithic initial state: {j0:.1e} m")
    print("  SSV start values of coupling inputs: " +
          ", ".join(f"{c}.{n} = {params[c][n][1]:.4g}" for c, n in START_PROBE))
    for name, (bad, total, first) in checks.items():
        print(f"  {name}: {total - len(bad)} of {total} parameters (not connected inputs) as in the SSV" +
              (f"; differ: {bad}" if bad else ""))
        print(f"  {name}: coupling inputs of the first step: " +
              ", ".join(f"{k} = {v:.4g}" for k, v in first.items()))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build", help="folder of frb build-fmus (built if missing)")
    ap.add_argument("--step", type=positive, default=1e-5, help="macro step H [s] of every master (default: 10 us)")
    ap.add_argument("--halvings", type=whole, default=1,
                    help="also run each co-simulation at H/2, H/4, ... (default: 1; 0: only H)")
    args = ap.parse_args(argv)
    ssp_path = built_ssp(args.build)
    t0 = time.perf_counter()
    ref = monolithic(1e-9, 1e-12)
    loose = monolithic(1e-7, 1e-10)
    print(f"monolithic: {time.perf_counter() - t0:.1f} s wall; defaults (rtol 1e-7, atol 1e-10 m) vs reference: "
          f"{max(deviation(loose, ref, DURATION_S).values()) * 1e6:.1e} um")
    steps = tuple(args.step / 2 ** k for k in range(args.halvings + 1))
    with read_ssp(ssp_path) as ssp, tempfile.TemporaryDirectory(prefix="frb_masters_") as tmp:
        params = ssp.parameters()
        runs, checks = _runs(ssp_path, ssp.root, steps, tmp)
        checks = {"libcosim": libcosim_start(ssp.root, params, connected_inputs(ssp.root)), **checks}
        t0 = time.perf_counter()
        amp = sensitivity(ssp_path, ssp.root, args.step, params)
        print(f"  sensitivity runs: {time.perf_counter() - t0:.1f} s wall")
    clearance = params[BEARINGS[0]]["outer.clearance"][1]
    _print_positions(ref, runs)
    _print_deviations(ref, runs, clearance)
    _print_checks(params, checks, ref)
    print("\nShortest time constant of the ring's lateral motion in its films (bearing linearization, method-J "
          "equilibrium): " + ", ".join(f"{b} {rpm / 1e3:g} krpm {tau * 1e6:.1f} us"
                                       for (b, rpm), tau in ring_time_constants(params).items()))
    print(f"\nAmplification of a 1e-12 m change of the start state (largest journal change / 1e-12 m), "
          f"H = {args.step * 1e6:g} us")
    for name, a in amp.items():
        print(f"  {name:<16}" + "".join(f"  [0, {t * 1e3:g} ms] {v:9.1f}" for t, v in zip((0.015, 0.03), a)))


if __name__ == "__main__":
    run_script(main)
