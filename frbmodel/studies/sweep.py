"""Parameter studies on Dask: grids or lists of cases × an analysis, resumable, with a stability map.

A *case* is a set of system parameters (outer clearance, viscosities, unbalance, ring mass, ...) and an analysis:
``campbell`` (linear, given methods), ``runup`` (monolithic nonlinear run-up or run-down) or ``cosim``
(co-simulated run through the FMUs). Cases run as Dask tasks — on a ``distributed.LocalCluster`` (one worker
process per core) by default, or on an existing cluster (``scheduler="tcp://host:port"``), or in-process
(``scheduler="serial"``). Every finished case is written at once to ``<out>/cases/<id>.json`` (atomic rename), a
failing case too (with its error); ``<out>/index.csv`` lists all cases. Rerunning a study skips the finished
ones, so a killed study loses no finished case.

On Dask, every worker loads the compiled kernels and the analysis modules once before the cases
(:func:`prepare_worker`), the cases go out longest-first by :func:`estimated_cost_s` and no more of them are in
flight than the cluster has threads, so a worker that becomes free takes the longest case left (greedy list
scheduling, no guessing by the scheduler). Each run writes ``<out>/run_summary.json`` (:func:`run_summary`):
elapsed time, cluster start, warm-up and the busy time of each worker (its case wall times / elapsed).

Dask and distributed (the ``[dist]`` extra) are imported only when a study runs on a cluster, so the serial
scheduler and everything else work without them; a missing package raises :class:`ModuleNotFoundError` naming it.
"""
from __future__ import annotations

import asyncio
import hashlib
import json
import os
import time
import traceback
from dataclasses import asdict, dataclass, field
from itertools import product
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_positive, check_real, check_speed_count, read_json
from ..core.progress import counter_bar, note
from ..cosim.master import Master, check_record_size, check_whole_steps, cosimulate, operating_point_overrides
from ..cosim.ssp import read_ssp
from ..cycles.branch import check_segments
from ..cycles.continuation import check_max_points, check_starts, continuation, hopf_points
from ..linear.campbell import campbell
from ..linear.thermal import SUPPLY_PRESSURE_PA, OilSupply, check_oil_supply
from ..nonlinear.runup import SpeedProfile, Unbalance, check_output_rate, check_speed, runup
from ..plots.figures import write_html
from ..plots.studies import stability_chart_figure, stability_map_figures
from ..signals.spectral import spectrogram
from ..system.methods import get_method
from ..system.oil import OIL, oil_from_dict
from ..system.parameters import Turbocharger
from ..system.presets import turbocharger
from .warmup import kernels_ready, warmup

#: parameters a study can vary (name -> (unit, description)); "<bearing>" and "<disc>" are the names in the system
#: (the Table 2 system has the bearings "turbine", "compressor" and the discs "turbine_wheel", "compressor_wheel")
PARAMETERS = {
    "outer_clearance": ("m", "radial clearance of both outer films"),
    "inner_clearance": ("m", "radial clearance of both inner films"),
    "viscosity_turbine": ("Pa s", "oil viscosity of both films of the bearing named 'turbine'"),
    "viscosity_compressor": ("Pa s", "oil viscosity of both films of the bearing named 'compressor'"),
    "viscosity_scale": ("-", "factor on all film viscosities (oil temperature)"),
    "ring_mass": ("kg", "mass of both rings"),
    "unbalance_turbine": ("kg m", "unbalance of the disc named 'turbine_wheel' (or 'turbine')"),
    "unbalance_compressor": ("kg m", "unbalance of the disc named 'compressor_wheel' (or 'compressor')"),
    "supply_temperature": ("K", "oil supply temperature: each speed at its thermal operating point (the option "
                                "'oil' or the system's oil; campbell method J and runup)"),
    "supply_pressure": ("Pa", "oil supply pressure above ambient (thermal model, as supply_temperature)"),
}
#: the study parameters of the oil supply (not the system's: :func:`case_oil_supply`)
SUPPLY_PARAMETERS = ("supply_temperature", "supply_pressure")
ANALYSES = ("campbell", "runup", "cosim", "hopf", "bifurcation")
#: the options each analysis takes (:func:`check_options` refuses the others: they were ignored)
ANALYSIS_OPTIONS = {"campbell": ("methods", "speeds_rpm", "oil", "system"),
                    "runup": ("speed_rpm", "duration", "profile", "output_rate_hz", "oil", "system"),
                    "cosim": ("speed_rpm", "duration", "ssp", "parameter_set", "oil", "system"),
                    "hopf": ("speed_rpm", "oil", "system"),
                    "bifurcation": ("speed_rpm", "start", "max_points", "segments", "oil", "system")}
#: output rate [Hz] of a cosim study's runs (cosimulate's default; :func:`_check_cosim_options` bounds their record)
COSIM_OUTPUT_RATE_HZ = 20e3
#: the speed profiles of a runup study (option ``profile``)
RUNUP_PROFILES = ("exponential", "ramp")
#: seconds to wait for an existing Dask scheduler before giving up
SCHEDULER_TIMEOUT_S = 5.0


def _distributed():
    """The ``distributed`` package (imported here, not at module import: it belongs to the ``[dist]`` extra).
    ``dask`` is imported first so that a missing ``[dist]`` extra is reported as the missing package ``dask``."""
    import dask  # noqa: F401
    import distributed

    return distributed


@dataclass
class Case:
    """One case of a study: ``params`` {name: value (SI)}, ``analysis`` and its ``options``.

    Parameters
    ----------
    params : dict
        Study parameter (a key of :data:`PARAMETERS`) -> value in SI units (see its unit there).
    analysis : str
        One of :data:`ANALYSES`.
    options : dict
        Options of the analysis (see :func:`check_options`); ``"system"`` may hold a system dict
        (:meth:`Turbocharger.to_dict`) to vary instead of the Table 2 system.

    Examples
    --------
    >>> case = Case({"outer_clearance": 40e-6}, "campbell", {"methods": ["J"]})
    >>> case.case_id  # doctest: +ELLIPSIS
    'campbell_outer_clearance=4e-05_...'
    """

    params: dict
    analysis: str
    options: dict = field(default_factory=dict)

    @property
    def case_id(self) -> str:
        """File-name-safe, unique id: analysis, parameters and a hash of parameters, analysis and options."""
        key = json.dumps({"p": self.params, "a": self.analysis, "o": self.options}, sort_keys=True)
        readable = "_".join(f"{k}={v:.4g}" for k, v in sorted(self.params.items())) or "base"
        return f"{self.analysis}_{readable}_{hashlib.sha1(key.encode()).hexdigest()[:8]}".replace("/", "-")


def check_options(analysis, options):
    """Validate the options of an analysis before any case runs (a bad option would fail every case).

    Parameters
    ----------
    analysis : str
        One of :data:`ANALYSES`.
    options : dict
        ``campbell``: ``methods`` (letters, default ["J"]) and ``speeds_rpm`` (START, STOP, COUNT) in any order of
        START and STOP; run-ups: ``speed_rpm`` (START, END) — a run-down if END < START — and ``duration`` [s];
        ``hopf``: ``speed_rpm``; ``bifurcation``: ``speed_rpm``, ``start`` ("hopf", a speed [rpm] or a list),
        ``max_points`` (2 ... 10000, default 25) and ``segments`` (1 ... 64, default 1), as
        :func:`frbmodel.cycles.continuation`.
        Every analysis: ``oil``, the name of a named oil or an ``[oil]`` table (dict), for the thermal model
        (:func:`case_oil_supply`).

    Raises
    ------
    ParameterError
        Naming the option, its value and the valid values.

    Examples
    --------
    >>> try:
    ...     check_options("campbell", {"methods": ["J", "Q"]})
    ... except ParameterError as exc:
    ...     print(exc)
    method = 'Q' is unknown; valid methods are A, B, C, D, E, F, G, I, J (the paper has no H)
    """

    if analysis in ANALYSIS_OPTIONS:
        unused = [k for k in options if k not in ANALYSIS_OPTIONS[analysis]]
        if unused:
            raise ParameterError(f"sweep option {unused[0]} = {options[unused[0]]!r:.60} does not apply to analysis "
                                 f"{analysis!r}: its options are {', '.join(ANALYSIS_OPTIONS[analysis])}")
    if options.get("profile", RUNUP_PROFILES[0]) not in RUNUP_PROFILES:
        raise ParameterError(f"runup profile = {options['profile']!r} is unknown; valid: {', '.join(RUNUP_PROFILES)}")
    if "output_rate_hz" in options:
        check_positive("runup output_rate_hz", options["output_rate_hz"], "Hz")
    if analysis == "runup":  # (a run that records nothing failed every case)
        check_output_rate(options.get("output_rate_hz", 10e3), options.get("duration", 2.0))
    if "oil" in options:
        _option_oil(options["oil"])
    if analysis == "campbell":
        for m in options.get("methods", ["J"]):
            get_method(m)
        if "speeds_rpm" in options:
            a, b, n = options["speeds_rpm"]
            check_speed("campbell start speed", a)
            check_speed("campbell stop speed", b)
            if int(n) != n or n < 2:
                raise ParameterError(f"campbell speed count = {n!r} is invalid: valid range integer >= 2")
            check_speed_count(f"campbell speeds_rpm = {options['speeds_rpm']!r}", int(n))  # (the CLI's grid bound)
    else:  # run-ups, co-simulations and Hopf points: a speed range
        if "speed_rpm" in options:
            a, b = options["speed_rpm"]
            check_speed("start speed", a)
            check_speed("end speed", b)
            if a == b and analysis in ("hopf", "bifurcation"):  # (every case failed: exit 4)
                raise ParameterError(f"{analysis} speed_rpm = ({a:g}, {b:g}) rpm is invalid: START and END must "
                                     "differ (the search range)")
        if "duration" in options:
            check_positive("duration", options["duration"], "s")
    if analysis == "bifurcation":
        check_max_points("bifurcation max_points", options.get("max_points", 2), lowest=2)
        check_segments("bifurcation segments", options.get("segments", 1))
        check_starts(options.get("start", "hopf"), options.get("speed_rpm", (1e3, 250e3)), "bifurcation start",
                     "speed_rpm")


def _check_cosim_options(options):
    """The SSP and the duration of a ``cosim`` study as frb cosim checks them, before any case (each case failed,
    exit 4: a missing SSP, an unknown parameter set, a duration that is not a whole number of the SSP's macro steps or
    records more than MAX_SAMPLES): the Master is set up without running, its FMUs not instantiated."""
    if not options.get("ssp"):
        raise ParameterError("analysis 'cosim' needs the option ssp: the SSP of the FMUs (frb build-fmus writes "
                             "build/turbocharger.ssp)")
    duration = check_positive("duration", options.get("duration", 1.0), "s")
    with read_ssp(options["ssp"]) as ssp:
        ssp.parameters(options.get("parameter_set", "co36"))
        step = ssp.step_size or 1e-5  # (the Master's fixed macro step of a study's runs)
    check_whole_steps(duration, step, "cosim duration", "the option duration (frb sweep --duration)", "")
    check_record_size(duration, COSIM_OUTPUT_RATE_HZ, "cosim duration")
    with Master(options["ssp"], options.get("parameter_set", "co36"), stop_time=duration):
        pass  # (the rest of frb cosim's set-up checks: the step's validated range, the parameter set's system)


def grid(params: dict, analysis="campbell", **options):
    """Cases for the Cartesian product of ``params`` {name: list of values}; the options are checked first
    (:func:`check_options`).

    Parameters
    ----------
    params : dict
        Study parameter (a key of :data:`PARAMETERS`) -> values (SI).
    analysis : str
        One of :data:`ANALYSES`.
    **options
        Options of the analysis (see :func:`check_options`).

    Returns
    -------
    list of Case

    Raises
    ------
    ParameterError
        An unknown parameter, analysis or option value, or a parameter value the system refuses (checked value by
        value on the Table 2 system, before any case runs).

    Examples
    --------
    >>> cases = grid({"outer_clearance": [36e-6, 40e-6], "viscosity_scale": [1.0, 2.0]}, "runup",
    ...              speed_rpm=(250e3, 20e3), duration=1.0)
    >>> len(cases), cases[-1].params
    (4, {'outer_clearance': 4e-05, 'viscosity_scale': 2.0})
    """
    names = list(params)
    for n in names:
        if n not in PARAMETERS:
            raise ParameterError(f"study parameter = {n!r} is unknown; valid: {', '.join(PARAMETERS)}")
    if analysis not in ANALYSES:
        raise ParameterError(f"analysis = {analysis!r} is unknown; valid: {', '.join(ANALYSES)}")
    check_options(analysis, options)
    _check_thermal_study(names, analysis, options)
    if analysis == "cosim":  # (it reads the SSP: after the checks of the options alone)
        _check_cosim_options(options)
    oil_base = None  # the system option's oil, if it has one, for the supply values' check
    if isinstance(options.get("system"), dict) and "oil" in options["system"]:
        oil_base = Turbocharger.from_dict(options["system"])
    for n in names:  # each value on its own, before any case runs (a refused value failed every case, exit 4)
        for v in params[n]:
            try:
                tc = build_case_system({n: float(v)})[0]
                case_oil_supply({n: float(v)}, options, tc if oil_base is None else oil_base)
            except ParameterError as exc:
                raise ParameterError(f"study parameter {n} = {v:g} [{PARAMETERS[n][0]}]: {exc}") from None
    return [Case(dict(zip(names, map(float, vals))), analysis, options)
            for vals in product(*(params[n] for n in names))]


def _option_oil(value):
    """The :class:`Oil` of a study's ``oil`` option: a named oil or an ``[oil]`` table (dict)."""

    if isinstance(value, str):
        return OIL(value)
    if isinstance(value, dict):
        return oil_from_dict(value, "sweep option oil")
    raise ParameterError(f"sweep option oil = {value!r:.60} is invalid: the name of a named oil or an [oil] table")


#: the analyses that take an oil supply (the thermal model's quasi-static temperatures at each speed)
THERMAL_ANALYSES = ("campbell", "runup", "hopf", "bifurcation")


def _check_thermal_study(names, analysis, options):
    """A thermal study (an ``oil`` option, or supply parameters with the system option's oil) only where the
    thermal model enters: Campbell diagrams of method J, run-ups, Hopf points and bifurcation diagrams, without the
    constant-viscosity parameters (the co-simulation's FMUs take the supply as inputs, not as a study option)."""
    supply = [n for n in names if n in SUPPLY_PARAMETERS]
    base_oil = isinstance(options.get("system"), dict) and "oil" in options["system"]
    if not (supply or "oil" in options):
        return
    if "oil" not in options and not base_oil:
        raise ParameterError(f"study parameter {supply[0]} needs an oil: give the option oil (frb sweep --oil NAME) "
                             "or a system with an [oil] table")
    if analysis not in THERMAL_ANALYSES:
        raise ParameterError(f"analysis = {analysis!r} cannot take an oil supply: the thermal model is in the "
                             f"{', '.join(THERMAL_ANALYSES)} analyses (campbell: the film methods)")
    springs = [m for m in options.get("methods", ["J"]) if not get_method(m).needs_films]
    if analysis == "campbell" and springs:
        raise ParameterError(f"methods = {options['methods']!r} cannot be combined with an oil supply: method "
                             f"{springs[0]} has linear springs, no oil films; use film methods (C, D, F, G, I, J)")
    fixed = [n for n in names if n.startswith("viscosity_")]
    if fixed:
        raise ParameterError(f"study parameter {fixed[0]} cannot be combined with an oil supply: the thermal model "
                             "sets every film's viscosity from its temperature")


def case_oil_supply(params, options, system):
    """The :class:`~frbmodel.linear.thermal.OilSupply` of a case, or None (constant viscosities).

    Parameters
    ----------
    params : dict
        The case's parameters; ``supply_temperature`` [K] and ``supply_pressure`` [Pa] are used here
        (defaults 363.15 K and 3e5 Pa).
    options : dict
        The case's options; ``oil`` (a named oil or an ``[oil]`` table) names the oil.
    system : Turbocharger
        The case's system; its ``oil`` is used when the options name none.

    Returns
    -------
    OilSupply or None
        None without an oil and without supply parameters.
    """

    oil = _option_oil(options["oil"]) if "oil" in options else system.oil
    given = [n for n in SUPPLY_PARAMETERS if n in params]
    if oil is None:
        if given:
            raise ParameterError(f"study parameter {given[0]} needs an oil: give the option oil (frb sweep --oil NAME) "
                                 "or a system with an [oil] table")
        return None
    supply = OilSupply(oil, params.get("supply_temperature", 363.15), params.get("supply_pressure", SUPPLY_PRESSURE_PA))
    return check_oil_supply(supply, bearings=system.bearings)  # (the feed holes against the case's rings)


def _named_bearing(bearings, key):
    """Index of the bearing that study parameter ``key`` ("viscosity_<bearing>") refers to."""
    name = key[len("viscosity_"):]
    names = [b.name for b in bearings]
    if name not in names:
        raise ParameterError(f"study parameter {key!r} needs a bearing named {name!r}; the system's bearings are "
                             f"{names}")
    return names.index(name)


def _named_disc(system, key):
    """Name of the disc that study parameter ``key`` ("unbalance_<x>") refers to: "<x>_wheel" or "<x>"."""
    stem = key[len("unbalance_"):]
    names = [d.name for d in system.rotor.discs]
    for cand in (f"{stem}_wheel", stem):
        if cand in names:
            return cand
    raise ParameterError(f"study parameter {key!r} needs a disc named {stem + '_wheel'!r} or {stem!r}; the "
                         f"system's discs are {names}")


def build_case_system(params, base=None):
    """System and unbalance list of a case: SI ``params`` (keys of :data:`PARAMETERS`) applied to ``base``.

    Parameters
    ----------
    params : dict
        Study parameter (a key of :data:`PARAMETERS`) -> value in SI units.
    base : Turbocharger, optional
        Default: the Table 2 system. Bearing and disc parameters refer to its bearing and disc names.

    Returns
    -------
    system : Turbocharger
        ``base`` with the parameters applied (the oil-supply parameters are not the system's: they are left to
        :func:`case_oil_supply`).
    unbalance : list of Unbalance
        One per non-zero ``unbalance_<disc>`` parameter (phase 0).

    Raises
    ------
    ParameterError
        An unknown parameter, or one that names a bearing or disc the system does not have.

    Examples
    --------
    >>> tc, unb = build_case_system({"outer_clearance": 40e-6, "unbalance_turbine": 1e-6})
    >>> [b.outer.clearance for b in tc.bearings], unb
    ([4e-05, 4e-05], [Unbalance(disc='turbine_wheel', amount=1e-06, phase=0.0)])
    """
    from dataclasses import replace


    tc = base or turbocharger()
    p = {k: v for k, v in params.items() if k not in SUPPLY_PARAMETERS}
    if "outer_clearance" in p:
        tc = tc.with_outer_clearance(p.pop("outer_clearance"))
    bs = list(tc.bearings)
    if "inner_clearance" in p:
        c = p.pop("inner_clearance")
        bs = [replace(b, inner=replace(b.inner, clearance=c)) for b in bs]
    for key in [k for k in p if k.startswith("viscosity_") and k != "viscosity_scale"]:
        i, mu = _named_bearing(bs, key), p.pop(key)
        bs[i] = replace(bs[i], inner=replace(bs[i].inner, viscosity=mu), outer=replace(bs[i].outer, viscosity=mu))
    if "viscosity_scale" in p:
        s = p.pop("viscosity_scale")
        bs = [replace(b, inner=replace(b.inner, viscosity=b.inner.viscosity * s),
                      outer=replace(b.outer, viscosity=b.outer.viscosity * s)) for b in bs]
    if "ring_mass" in p:
        m = p.pop("ring_mass")
        bs = [replace(b, ring_mass=m) for b in bs]
    unb = []
    for key in [k for k in p if k.startswith("unbalance_")]:
        disc = _named_disc(tc, key)
        amount = tc.rotor.check_unbalance(disc, check_real(key, p.pop(key), "kg m", minimum=0.0, inclusive=True),
                                          key)[1]  # (the disc's own bound, before any case runs)
        if amount > 0:
            unb.append(Unbalance(disc, amount, 0.0))
    if p:
        raise ParameterError(f"study parameters {sorted(p)} are unknown; valid: {', '.join(PARAMETERS)}")
    return tc.with_(bearings=tuple(bs)), unb


# --------------------------------------------------------------------------------------------------
# one case (runs on a worker)
# --------------------------------------------------------------------------------------------------
def _onset_rows_campbell(cd):
    """Onset rows of a Campbell result; modes are named by precession and shape, numbered by frequency among
    modes of the same name (mode track indices are not comparable between cases). The onset is the lowest speed
    of an unstable range, whatever the order of the speed grid."""
    rows = []
    ur = cd.unstable_ranges()
    ur = ur.assign(name=ur["precession"] + " " + ur["kind"]).sort_values("f at start [Hz]")
    ur["rank"] = ur.groupby("name").cumcount() + 1
    s_min = float(np.min(cd.speeds_rpm))
    for _, r in ur.iterrows():
        lo, hi = sorted((float(r["from [rpm]"]), float(r["to [rpm]"])))
        f_lo = r["f at start [Hz]"] if r["from [rpm]"] <= r["to [rpm]"] else r["f at end [Hz]"]
        rows.append({"kind": "linear", "method": cd.method, "item": f"{r['name']} #{r['rank']}",
                     "onset [rpm]": lo, "end [rpm]": hi, "f at onset [Hz]": float(f_lo),
                     "onset at sweep start": bool(lo <= s_min)})
    return rows


def _onset_rows_run(run, label, node=None):
    """Onset rows of the sub-synchronous components of a run at ``node`` (default: the first disc). A component
    there from the start of the run has no onset ("onset [rpm]" NaN, "onset at sweep start" True)."""

    seg = min(0.1, max(0.01, (run.time[-1] - run.time[0]) / 40))
    rows = []
    for c in spectrogram(run, node, segment_s=seg).components():
        if c.label.startswith("sub"):
            rows.append({"kind": "nonlinear", "method": label, "item": f"{c.label} ({c.direction})",
                         "onset [rpm]": c.onset_rpm, "onset estimate": c.onset_estimate,
                         "f at onset [Hz]": c.onset_hz, "first detection [rpm]": c.onset_threshold_rpm,
                         "vanishes at [rpm]": c.end_rpm, "onset at sweep start": c.from_start})
    return rows


def _campbell_rows(tc, o, supply=None):

    # ascending grid whatever the order the user gave: the onsets are the lower ends of the unstable ranges
    a, b, n = o.get("speeds_rpm", (10e3, 250e3, 100))
    speeds = np.linspace(min(a, b), max(a, b), int(n))
    rows = []
    for m in o.get("methods", ["J"]):
        rows += _onset_rows_campbell(campbell(tc, m, speeds, oil_supply=supply))
    return rows


def _hopf_rows(tc, o, supply=None):
    """Hopf points of the full model in the speed range (:func:`frbmodel.cycles.continuation.hopf_points`), numbered by
    speed: the linear onsets a two-parameter stability chart is drawn from."""

    lo, hi = sorted(o.get("speed_rpm", (1e3, 250e3)))
    return [{"kind": "linear", "method": "full model", "item": f"Hopf #{k}", "onset [rpm]": hp.speed_rpm,
             "end [rpm]": float("nan"), "f at onset [Hz]": hp.frequency_hz, "onset at sweep start": False}
            for k, hp in enumerate(hopf_points(tc, (lo, hi), oil_supply=supply), start=1)]


def _bifurcation_rows(tc, o, case_dir, supply=None):
    """Limit-cycle branches of the case's system (:func:`frbmodel.cycles.continuation.continuation` over ``speed_rpm``
    from ``start``: its Hopf points by default, or the orbits at given speeds), written to ``case_dir``
    (``branch.csv``, ``bifurcations.csv``, ``branch.nc``, ``bifurcation.png`` / ``.html``); one row per bifurcation
    point (item: type and criticality; "onset [rpm]" its speed)."""

    lo, hi = sorted(o.get("speed_rpm", (1e3, 250e3)))
    bd = continuation(tc, (lo, hi), start=o.get("start", "hopf"), max_points=int(o.get("max_points", 25)),
                      segments=int(o.get("segments", 1)), oil_supply=supply)
    bd.save(case_dir)
    return [{"kind": "bifurcation", "method": "full model",
             "item": b["type"] + (f" ({b['criticality']})" if b.get("criticality") else ""),
             "onset [rpm]": b["speed_rpm"], "end [rpm]": float("nan"), "f at onset [Hz]": b["frequency_hz"],
             "onset at sweep start": False} for b in bd.bifurcations]


def _runup_rows(tc, unb, o, supply=None):

    start, end = o.get("speed_rpm", (1e3, 250e3))
    dur = float(o.get("duration", 2.0))
    prof = SpeedProfile.exponential(start, end, dur) if o.get("profile", "exponential") == "exponential" \
        else SpeedProfile.ramp(start, end, dur)
    run = runup(tc, profile=prof, duration=dur, unbalance=unb, progress=False,
                output_rate_hz=float(o.get("output_rate_hz", 10e3)), oil_supply=supply)
    return _onset_rows_run(run, "run-down" if end < start else "run-up")


def _cosim_rows(tc, unb, o):

    start, end = o.get("speed_rpm", (20e3, 250e3))
    dur = float(o.get("duration", 1.0))
    ov = operating_point_overrides(tc, start, end_rpm=end, ramp_time=dur, perturbation=0.05)
    for b in tc.bearings:  # the SSP names each bearing FMU instance after its bearing
        for fname, film in (("inner", b.inner), ("outer", b.outer)):
            ov[b.name][f"{fname}.clearance"] = ("Real", film.clearance)
            ov[b.name][f"{fname}.viscosity"] = ("Real", film.viscosity)
        ov[b.name]["ring.mass"] = ("Real", b.ring_mass)
    for u in unb:
        ov["rotor"][f"{u.disc}.unbalance"] = ("Real", u.amount)
    run = cosimulate(o["ssp"], o.get("parameter_set", "co36"), stop_time=dur, overrides=ov, progress=False,
                     output_rate_hz=COSIM_OUTPUT_RATE_HZ)
    return _onset_rows_run(run, "co-sim run-down" if end < start else "co-sim")


def run_case(case: Case, out_dir) -> dict:
    """Run one case and write ``<out>/cases/<id>.json`` (status, parameters, onset rows, wall and CPU time; or the
    error).

    The case's system is the Table 2 system, or ``case.options["system"]`` (a dict as
    :meth:`Turbocharger.to_dict` writes it), with the case's parameters applied (:func:`build_case_system`).
    An exception inside the case is not raised: the case is recorded as failed, with the error and a traceback.

    Parameters
    ----------
    case : Case
        The case.
    out_dir : str or Path
        Study folder; the case file goes to ``<out_dir>/cases/<case_id>.json``.

    Returns
    -------
    dict
        ``case_id``, ``status`` ("finished" or "failed"), ``error``, ``wall_time_s``, ``cpu_time_s`` (CPU time of
        the process during the case) and ``worker`` (host:pid of the process that ran the case).

    Examples
    --------
    A case with a broken system description fails, and its file says why:

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     res = run_case(Case({}, "campbell", {"system": {"rotr": {}}}), tmp)
    ...     on_disk = json.loads((Path(tmp) / "cases" / f"{res['case_id']}.json").read_text())
    >>> res["status"], on_disk["status"], on_disk["error"]  # doctest: +ELLIPSIS
    ('failed', 'failed', "ParameterError: unknown key 'rotr'...")
    """
    out = Path(out_dir)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    rec = {"case_id": case.case_id, "params": case.params, "analysis": case.analysis, "options": case.options,
           "host": os.uname().nodename, "pid": os.getpid(), "started": time.time()}
    cpu0 = time.process_time()
    try:
        o = dict(case.options)
        base = None
        if "system" in o:
            base = Turbocharger.from_dict(o["system"])
        tc, unb = build_case_system(case.params, base)
        supply = case_oil_supply(case.params, o, tc)
        if supply is not None and case.analysis not in THERMAL_ANALYSES:
            raise ParameterError(f"analysis = {case.analysis!r} cannot take an oil supply")
        if case.analysis == "campbell":
            rows = _campbell_rows(tc, o, supply)
        elif case.analysis == "runup":
            rows = _runup_rows(tc, unb, o, supply)
        elif case.analysis == "cosim":
            rows = _cosim_rows(tc, unb, o)
        elif case.analysis == "hopf":
            rows = _hopf_rows(tc, o, supply)
        elif case.analysis == "bifurcation":
            rows = _bifurcation_rows(tc, o, out / "cases" / case.case_id, supply)
        else:
            raise ParameterError(f"analysis = {case.analysis!r} is unknown; valid: {', '.join(ANALYSES)}")
        rec.update({"status": "finished", "rows": rows})
    except Exception as exc:  # noqa: BLE001  (a failing case is recorded, the study goes on)
        rec.update({"status": "failed", "error": f"{type(exc).__name__}: {exc}",
                    "traceback": traceback.format_exc(limit=5)})
    rec["wall_time_s"] = time.time() - rec["started"]
    rec["cpu_time_s"] = time.process_time() - cpu0  # this process's CPU: wall >> CPU means waiting for a core
    tmp = out / "cases" / f".{case.case_id}.json.tmp{os.getpid()}"
    tmp.write_text(json.dumps(rec, indent=1, default=float))
    os.replace(tmp, out / "cases" / f"{case.case_id}.json")  # atomic: a case file is complete or absent
    return {"case_id": case.case_id, "status": rec["status"], "error": rec.get("error", ""),
            "wall_time_s": rec["wall_time_s"], "cpu_time_s": rec["cpu_time_s"], "worker": f"{rec['host']}:{rec['pid']}"}


# --------------------------------------------------------------------------------------------------
# scheduling: cost estimate, worker preparation
# --------------------------------------------------------------------------------------------------
#: rough wall-time rates on the 2-core reference machine (issue #13), used only to order cases. A run-up costs
#: about the same per simulated second whatever its speeds (the implicit integrator's steps follow the whirl, a few
#: hundred Hz, not the rotor speed): 5.4 s/s for the 0.5 s 20k -> 250k rpm ramp, 7.0 s/s for the 1 s exponential
#: main job with the compiled Radau integrator, although the ramp turns 1.5x more revolutions per second
COST_RUNUP_S_PER_SIMULATED_S = 6.0
#: factor on a run-up or co-simulation with an unbalance: the integrator then resolves the 1X orbit on every
#: revolution, not only the whirl after its onset (measured, 0.5 s 20k -> 250k rpm ramps at 38-42 um: 2.5 s with
#: 1 g mm on the turbine wheel, 1.5-1.7 s without)
COST_UNBALANCE_FACTOR = 1.5
#: a co-simulation step is 10 us of simulated time: 0.27 ms wall per step
COST_COSIM_S_PER_SIMULATED_S = 27.0
#: one Campbell speed of one method (eigenvalues, equilibria for the film methods)
COST_CAMPBELL_S_PER_SPEED = 2e-3


#: wall time [s] of one ``hopf`` case (60 equilibrium Jacobians and the Brent refinements; measured 0.5-1 s)
COST_HOPF_S = 1.0
#: wall time [s] per branch point of a ``bifurcation`` case (1-5 s measured at 36 um; its Hopf points' branches:
#: about four, each ``max_points`` long)
COST_BIFURCATION_S_PER_POINT = 4 * 2.0


def estimated_cost_s(case) -> float:
    """Rough wall time [s] of a case from its analysis and options, to order a study.

    Run-ups: simulated duration × :data:`COST_RUNUP_S_PER_SIMULATED_S`; co-simulations: duration ×
    :data:`COST_COSIM_S_PER_SIMULATED_S`; both × :data:`COST_UNBALANCE_FACTOR` if an ``unbalance_*`` parameter is
    > 0; Campbell: speeds × methods × :data:`COST_CAMPBELL_S_PER_SPEED`; Hopf points: :data:`COST_HOPF_S`; bifurcation
    diagrams: that plus ``max_points`` × :data:`COST_BIFURCATION_S_PER_POINT`. Only the
    order of the estimates matters; the defaults of the options are those :func:`run_case` uses.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    float
        Estimated wall time [s].

    Examples
    --------
    >>> estimated_cost_s(Case({}, "runup", {"speed_rpm": (20e3, 250e3), "duration": 0.5}))
    3.0
    >>> estimated_cost_s(Case({"unbalance_turbine": 1e-6}, "runup", {"speed_rpm": (20e3, 250e3), "duration": 0.5}))
    4.5
    >>> estimated_cost_s(Case({}, "campbell", {"methods": ["A", "J"], "speeds_rpm": (1e3, 250e3, 200)}))
    0.8
    """
    o = case.options
    if case.analysis == "campbell":
        n = int(o.get("speeds_rpm", (10e3, 250e3, 100))[2])
        return n * len(o.get("methods", ["J"])) * COST_CAMPBELL_S_PER_SPEED
    if case.analysis == "hopf":
        return COST_HOPF_S
    if case.analysis == "bifurcation":
        return COST_HOPF_S + int(o.get("max_points", 25)) * COST_BIFURCATION_S_PER_POINT
    forced = any(k.startswith("unbalance_") and v > 0 for k, v in case.params.items())
    factor = COST_UNBALANCE_FACTOR if forced else 1.0
    if case.analysis == "cosim":
        return float(o.get("duration", 1.0)) * COST_COSIM_S_PER_SIMULATED_S * factor
    return float(o.get("duration", 2.0)) * COST_RUNUP_S_PER_SIMULATED_S * factor


def longest_first(cases):
    """The cases sorted by :func:`estimated_cost_s`, longest first; equal estimates keep their given order.

    Parameters
    ----------
    cases : list of Case

    Returns
    -------
    list of Case

    Examples
    --------
    >>> cases = [Case({}, "runup", {"duration": d}) for d in (0.1, 0.4, 0.2)]
    >>> [c.options["duration"] for c in longest_first(cases)]
    [0.4, 0.2, 0.1]
    """
    return sorted(cases, key=lambda c: -estimated_cost_s(c))  # sorted() is stable


#: this process's preparation as a study worker (see prepare_worker)
_WORKER = {"prepare_calls": 0, "warmups": 0, "warmup_s": None}


def worker_state() -> dict:
    """This process's preparation for study cases: ``host``, ``pid``, ``package`` (the folder of the frbmodel this
    process imported), ``prepare_calls`` (calls of :func:`prepare_worker`), ``warmups`` (kernel warm-ups done: 0 or
    1) and ``warmup_s`` [s] (None before).

    Examples
    --------
    >>> sorted(worker_state())
    ['host', 'package', 'pid', 'prepare_calls', 'warmup_s', 'warmups']
    """
    return {"host": os.uname().nodename, "pid": os.getpid(), "package": str(Path(__file__).resolve().parents[1]),
            **_WORKER}


def prepare_worker() -> dict:
    """Import the analysis modules and load the compiled kernels (:func:`frbmodel.studies.warmup.warmup`) into this
    process once; later calls return at once. Run on every Dask worker before the cases of a study.

    Returns
    -------
    dict
        :func:`worker_state` after the preparation.
    """
    _WORKER["prepare_calls"] += 1
    if _WORKER["warmups"] == 0:
        t0 = time.perf_counter()
        warmup(progress=False)
        _WORKER["warmup_s"] = time.perf_counter() - t0
        _WORKER["warmups"] += 1
    return worker_state()


async def _prepare_worker_async():
    """:func:`prepare_worker` off the worker's event loop (which keeps answering the scheduler meanwhile)."""
    return await asyncio.to_thread(prepare_worker)



# --------------------------------------------------------------------------------------------------
# study
# --------------------------------------------------------------------------------------------------
def _load(out):
    recs = {}
    for f in sorted((Path(out) / "cases").glob("*.json")):
        try:
            recs[f.stem] = json.loads(f.read_text())
        except (OSError, json.JSONDecodeError):
            continue  # a damaged file counts as not finished
    return recs


def write_index(cases, out):
    """Write ``<out>/index.csv`` (one row per case: parameters, status, error, wall time, file) and
    ``<out>/study.json`` (the cases); returns the index as a pandas DataFrame.

    Parameters
    ----------
    cases : list of Case
        All cases of the study (a case without a file is "pending").
    out : str or Path
        Study folder (must exist).

    Returns
    -------
    pandas.DataFrame
        The index.

    Examples
    --------
    >>> import tempfile
    >>> cases = grid({"outer_clearance": [36e-6, 40e-6]}, "campbell")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     index = write_index(cases, tmp)
    >>> index[["outer_clearance [m]", "status"]].to_dict("list")
    {'outer_clearance [m]': [3.6e-05, 4e-05], 'status': ['pending', 'pending']}
    """
    import pandas as pd

    recs = _load(out)
    rows = []
    for c in cases:
        r = recs.get(c.case_id, {})
        rows.append({"case_id": c.case_id, "analysis": c.analysis, **{f"{k} [{PARAMETERS[k][0]}]": v
                                                                       for k, v in c.params.items()},
                     "status": r.get("status", "pending"), "error": r.get("error", ""),
                     "wall time [s]": r.get("wall_time_s", float("nan")), "file": f"cases/{c.case_id}.json"})
    df = pd.DataFrame(rows)
    tmp = Path(out) / ".index.csv.tmp"
    df.to_csv(tmp, index=False)
    os.replace(tmp, Path(out) / "index.csv")
    (Path(out) / "study.json").write_text(json.dumps([asdict(c) | {"case_id": c.case_id} for c in cases], indent=1))
    return df


class _this_package_first_on_path:
    """While a LocalCluster starts its worker processes (spawned with this process's ``sys.path``), put the folder
    holding this frbmodel first on it, so the workers import the same package as the client: other copies may be on
    the path before it (building FMUs in-process leaves pythonfmu's staging folder, with a copy of frbmodel, at its
    head), and a copy whose numba cache is empty compiles every kernel anew in each worker (measured: 40 s)."""

    def __enter__(self):
        import sys

        self.root = str(Path(__file__).resolve().parents[2])
        self.saved = list(sys.path)
        sys.path[:] = [self.root] + [p for p in sys.path if p != self.root]
        return self

    def __exit__(self, *exc):
        import sys

        sys.path[:] = self.saved


def _client(scheduler, n_workers):
    """(client, cluster or None): a new LocalCluster with ``n_workers`` processes, or a client of the scheduler
    at address ``scheduler`` — which must answer within :data:`SCHEDULER_TIMEOUT_S`."""
    dist = _distributed()
    if scheduler is None:
        with _this_package_first_on_path():
            cluster = dist.LocalCluster(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1,
                                        processes=True, dashboard_address=":0")
        return dist.Client(cluster, set_as_default=False), cluster  # never the user's default client
    check_scheduler(scheduler)  # before any Client exists: a failed one prints a traceback when collected
    try:
        return dist.Client(scheduler, timeout=SCHEDULER_TIMEOUT_S, set_as_default=False), None
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(f"scheduler = {scheduler!r} is unreachable: {exc} (expected the address of a running "
                             f"Dask scheduler, tcp://host:port; waited {SCHEDULER_TIMEOUT_S:g} s)") from None


def check_scheduler(scheduler):
    """Nothing for ``None`` (a local cluster) and ``"serial"``; else a :class:`ParameterError` unless ``scheduler``
    is ``tcp://host:port`` (or ``host:port``) and a TCP connection to it opens within :data:`SCHEDULER_TIMEOUT_S`."""
    import re
    import socket

    if scheduler is None or scheduler == "serial":
        return

    m = re.fullmatch(r"(?:tcp://)?\[?([^\]/]+?)\]?:(\d+)/?", str(scheduler))
    if m is None:
        raise ParameterError(f"scheduler = {scheduler!r} is unreachable: not an address of the form tcp://host:port "
                             "(expected a running Dask scheduler, or 'serial', or none for a local cluster)")
    try:
        socket.create_connection((m.group(1), int(m.group(2))), timeout=SCHEDULER_TIMEOUT_S).close()
    except (OSError, ValueError) as exc:
        raise ParameterError(f"scheduler = {scheduler!r} is unreachable: {exc} (expected the address of a running "
                             f"Dask scheduler, tcp://host:port; waited {SCHEDULER_TIMEOUT_S:g} s)") from None


def run_study(cases, out_dir, scheduler=None, n_workers=None, progress=False, retry_failed=False):
    """Run all unfinished cases of a study; returns the index DataFrame.

    On Dask, each worker first loads the compiled kernels once (:func:`prepare_worker`; on a new LocalCluster the
    kernels are compiled here first if they never were), then the cases run longest-first
    (:func:`longest_first`), one per worker thread at a time. Every run that runs cases writes
    ``<out_dir>/run_summary.json`` (:func:`run_summary`: elapsed time, cluster start, warm-up, each worker's busy
    time) and, with ``progress``, prints it.

    Parameters
    ----------
    cases : list of Case
        The study (e.g. :func:`grid`); ids must be unique.
    out_dir : str or Path
        Study folder (created); cases with a file there are skipped.
    scheduler : None | "serial" | str
        None: a new dask.distributed LocalCluster with ``n_workers`` processes (default: one per core);
        "serial": in this process, no Dask; otherwise the address of an existing Dask scheduler
        (``tcp://host:port``), which must answer within :data:`SCHEDULER_TIMEOUT_S`.
    n_workers : int, optional
        Worker processes of the LocalCluster (>= 1).
    progress : bool
        Show a progress bar over the cases to run (done / total, elapsed, ETA; :mod:`frbmodel.core.progress`) and the
        study's messages (cases finished before and to run, Dask dashboard address, failed cases, the run summary
        with each worker's busy time); default off, on in the CLI.
    retry_failed : bool
        Also rerun cases that failed before.

    Returns
    -------
    pandas.DataFrame
        The study's index (also ``<out_dir>/index.csv``).

    Raises
    ------
    ParameterError
        Duplicate cases, ``n_workers`` < 1, or an unreachable ``scheduler``.
    ModuleNotFoundError
        ``dask`` / ``distributed`` missing (the ``[dist]`` extra) for a scheduler other than "serial".

    Examples
    --------
    In this process, without Dask; the failing case is recorded and the study goes on:

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     index = run_study([Case({}, "campbell", {"system": {"rotr": {}}})], tmp, scheduler="serial")
    >>> index["status"].tolist()
    ['failed']
    """

    if n_workers is not None and (int(n_workers) != n_workers or n_workers < 1):
        raise ParameterError(f"workers = {n_workers!r} is invalid: valid range integer >= 1 (worker processes)")
    out = Path(out_dir)
    ids = [c.case_id for c in cases]
    if len(set(ids)) != len(ids):
        raise ParameterError("the study has duplicate cases")
    if scheduler != "serial":
        _distributed()  # a missing [dist] extra is reported before anything is written
    (out / "cases").mkdir(parents=True, exist_ok=True)
    done = _load(out)
    todo = [c for c in cases if c.case_id not in done or (retry_failed and done[c.case_id].get("status") == "failed")]
    write_index(cases, out)
    n_total, n_skip = len(cases), len(cases) - len(todo)
    def say(msg):
        note(msg, progress)

    say(f"study: {n_total} cases, {n_skip} already finished, {len(todo)} to run -> {out.resolve()}")
    if not todo:
        return write_index(cases, out)
    t0 = time.perf_counter()
    results, info = _run_cases(cases, todo, out, scheduler, n_workers, progress, say)
    summary = _summarize(results, time.perf_counter() - t0, "serial" if scheduler == "serial" else "dask", info)
    (out / "run_summary.json").write_text(json.dumps(summary, indent=1))
    say(_summary_text(summary))
    return write_index(cases, out)


def _run_cases(cases, todo, out, scheduler, n_workers, progress, say):
    """Run the cases ``todo`` of the study ``cases`` serially or on Dask, behind a progress bar, re-indexing after
    each; returns (the case results, the Dask timing and worker states)."""

    results, info = [], {}
    with counter_bar(len(todo), "study", progress, unit="case") as bar:
        def report(res):
            results.append(res)
            bar.update(1)
            bar.set_postfix_str(f"{res['case_id']}: {res['status']} ({res['wall_time_s']:.1f} s)")
            if res["status"] == "failed":
                say(f"  {res['case_id']}: failed - {res['error'][:200]}")
            write_index(cases, out)

        if scheduler == "serial":
            for c in todo:
                report(run_case(c, out))
        else:
            info = _run_on_dask(todo, out, scheduler, n_workers, report, say)
    return results, info


def _run_on_dask(todo, out, scheduler, n_workers, report, say):
    """Prepare every worker once, then run the cases longest-first with at most one case per worker thread in
    flight, ``report`` each result as it arrives; returns timing and the workers' states for the summary."""
    dist = _distributed()
    if scheduler is None:
        if not kernels_ready():  # compile once here; the workers then load numba's cache instead of compiling
            say("compiling the numba kernels once before starting the workers (first run only)")
            warmup(progress=False)
    t0 = time.perf_counter()
    client, cluster = _client(scheduler, n_workers)
    info = {"cluster_start_s": time.perf_counter() - t0}
    try:
        say(f"dask: {len(client.scheduler_info().get('workers', {}))} workers, dashboard {client.dashboard_link}")
        t1 = time.perf_counter()
        try:
            client.run(_prepare_worker_async)
        except Exception as exc:  # noqa: BLE001  (the cases then load the kernels themselves)
            say(f"  worker warm-up failed ({exc}); each worker's first case loads the kernels")
        info["warmup_s"] = time.perf_counter() - t1
        queue = longest_first(todo)
        pending = dist.as_completed(loop=client.loop)

        def fill():  # one case per worker thread (re-read: workers may join or leave)
            while queue and pending.count() < max(1, sum(client.nthreads().values())):
                c = queue.pop(0)
                pending.add(client.submit(run_case, c, str(out), key=f"frb-{c.case_id}", pure=False))

        t2 = time.perf_counter()
        with client.as_current():  # this study's client, not the session's default
            fill()
            for fut in pending:
                fill()  # the next case goes out before this one is reported
                try:
                    report(fut.result())
                except Exception as exc:  # noqa: BLE001  (a lost worker: the case stays pending; a rerun does it)
                    say(f"  a task failed outside the case handler: {exc}")
        info["cases_s"] = time.perf_counter() - t2
        try:
            info["workers"] = client.run(worker_state)
        except Exception:  # noqa: BLE001  (a lost worker: the summary then lists the workers from the cases)
            pass
    finally:
        t3 = time.perf_counter()
        client.close()
        if cluster is not None:
            cluster.close()
        info["close_s"] = time.perf_counter() - t3
    return info


def _summarize(results, elapsed_s, mode, info):
    """The run summary (see :func:`run_summary`) from the case results of this run and the Dask timing."""
    per = {}
    for st in info.get("workers", {}).values():
        per[f"{st['host']}:{st['pid']}"] = {"cases": 0, "busy_s": 0.0, "cpu_s": 0.0, "warmup_s": st.get("warmup_s")}
    for r in results:
        w = per.setdefault(r["worker"], {"cases": 0, "busy_s": 0.0, "cpu_s": 0.0, "warmup_s": None})
        w["cases"] += 1
        w["busy_s"] += float(r["wall_time_s"])
        w["cpu_s"] += float(r["cpu_time_s"])
    for w in per.values():
        w["busy_fraction"] = w["busy_s"] / elapsed_s if elapsed_s > 0 else float("nan")
    return {"scheduler": mode, "cases_run": len(results), "elapsed_s": elapsed_s,
            **{k: info.get(k) for k in ("cluster_start_s", "warmup_s", "cases_s", "close_s")},
            "case_wall_sum_s": sum(w["busy_s"] for w in per.values()),
            "case_cpu_sum_s": sum(w["cpu_s"] for w in per.values()), "workers": per}


def _summary_text(summary):
    """One line per worker: cases, busy time and busy fraction; a header with elapsed, cluster start, warm-up."""
    head = f"{summary['cases_run']} cases in {summary['elapsed_s']:.1f} s ({summary['scheduler']}"
    if summary["cluster_start_s"] is not None:
        head += (f"; cluster start {summary['cluster_start_s']:.1f} s, worker warm-up {summary['warmup_s']:.1f} s, "
                 f"cases {summary['cases_s']:.1f} s, cluster close {summary['close_s']:.1f} s")
    lines = [head + "); worker busy time = its case wall times / elapsed:"]
    for name, w in summary["workers"].items():
        lines.append(f"  {name}: {w['cases']} cases, busy {w['busy_s']:.1f} s ({w['busy_fraction']:.0%}), CPU "
                     f"{w['cpu_s']:.1f} s")
    return "\n".join(lines)


def run_summary(out_dir):
    """The summary of the last :func:`run_study` call on ``out_dir`` that ran cases (``<out>/run_summary.json``).

    Parameters
    ----------
    out_dir : str or Path
        Study folder.

    Returns
    -------
    dict
        ``scheduler`` ("serial" or "dask"), ``cases_run``, ``elapsed_s`` (the run's wall time [s], cluster start
        included), ``cluster_start_s`` (new cluster or connection), ``warmup_s`` (:func:`prepare_worker` on all
        workers), ``cases_s`` (first case submitted to last result) and ``close_s`` [s] (Dask only, else None),
        ``case_wall_sum_s``, ``case_cpu_sum_s`` and
        ``workers``: {"host:pid": {``cases``, ``busy_s`` (sum of its case wall times [s]), ``busy_fraction``
        (busy_s / elapsed_s), ``cpu_s`` (its CPU time during the cases [s]), ``warmup_s`` (its kernel warm-up [s];
        None if not warmed up by the study)}}.

    Raises
    ------
    FileNotFoundError
        If no run of the study has run cases yet.
    """
    return read_json(Path(out_dir) / "run_summary.json", "study summary")


def stability_map(out_dir):
    """Long table of onsets per finished case: swept parameters, linear (method-mode) and nonlinear
    (sub-synchronous component) onsets [rpm] and frequencies [Hz].

    Parameters
    ----------
    out_dir : str or Path
        Folder of a study (:func:`run_study`).

    Returns
    -------
    pandas.DataFrame
        One row per onset: ``case_id``, ``analysis``, the swept parameters with units, ``kind`` ("linear" or
        "nonlinear"), ``method``, ``item`` (mode or component), ``onset [rpm]``, ``f at onset [Hz]``, ...;
        empty if no case has finished.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     print(stability_map(tmp).empty)
    True
    """
    import pandas as pd

    rows = []
    for cid, rec in _load(out_dir).items():
        if rec.get("status") != "finished":
            continue
        for r in rec.get("rows", []):
            rows.append({"case_id": cid, "analysis": rec["analysis"],
                         **{f"{k} [{PARAMETERS[k][0]}]": v for k, v in rec["params"].items()}, **r})
    return pd.DataFrame(rows)


def plot_stability_map(out_dir, parameter=None):
    """Onset speed vs the (first) swept parameter, one line per linear mode / nonlinear component; writes
    ``stability_map.png`` / ``.html`` / ``.csv`` into ``out_dir``.

    Parameters
    ----------
    out_dir : path
        Folder of a study (:func:`run_study`).
    parameter : str, optional
        Swept parameter on the x axis (default: the first).

    Returns
    -------
    list of Path
        The CSV and, if there are onsets, the PNG and HTML figures.
    """
    import matplotlib.pyplot as plt


    out = Path(out_dir)
    df = stability_map(out)
    paths = [out / "stability_map.csv"]
    df.to_csv(paths[0], index=False)
    if df.empty:
        return paths
    pcols = [c for c in df.columns if c.split(" [")[0] in PARAMETERS]
    pcol = next((c for c in pcols if parameter and c.startswith(parameter)), pcols[0] if pcols else None)
    fig, pfig = stability_map_figures(df, pcol)  # (frbmodel.plots.studies)
    p = out / "stability_map.png"
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)
    p = out / "stability_map.html"
    write_html(pfig, p)
    paths.append(p)
    if len(pcols) >= 2:
        paths += plot_stability_chart(out_dir, pcols[0].split(" [")[0], pcols[1].split(" [")[0])
    return paths


def plot_stability_chart(out_dir, x, y, item=None):
    """Two-parameter stability chart of a study over two swept parameters: the onset speed of one linear mode (default
    the first: ``Hopf #1`` of a ``hopf`` study, else the lowest-speed item) as a filled contour over (x, y); writes
    ``stability_chart.png`` and ``stability_chart.csv`` (the grid) into ``out_dir``.

    Parameters
    ----------
    out_dir : path
        Folder of a study over (at least) the parameters ``x`` and ``y``.
    x, y : str
        Swept parameters (keys of :data:`PARAMETERS`) on the axes.
    item : str, optional
        The onset drawn (a value of the stability map's ``item`` column).

    Returns
    -------
    list of Path
        CSV and PNG; nothing if fewer than 2 x 2 finished cases carry the item.
    """
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    df = stability_map(out)
    if df.empty:
        return []
    df = df[df["kind"] == "linear"]
    if df.empty:  # no linear onsets (a run-up or bifurcation study): no chart
        return []
    item = item or ("Hopf #1" if (df["item"] == "Hopf #1").any() else
                    df.sort_values("onset [rpm]")["item"].iloc[0])
    xc, yc = f"{x} [{PARAMETERS[x][0]}]", f"{y} [{PARAMETERS[y][0]}]"
    grid_ = df[df["item"] == item].pivot_table(index=yc, columns=xc, values="onset [rpm]", aggfunc="min")
    if grid_.shape[0] < 2 or grid_.shape[1] < 2:
        return []
    paths = [out / "stability_chart.csv", out / "stability_chart.png"]
    grid_.to_csv(paths[0])
    fig = stability_chart_figure(grid_.columns.to_numpy(), grid_.index.to_numpy(), grid_.to_numpy(), xc, yc, item)
    fig.savefig(paths[1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    return paths


EXAMPLES = {
    "outer-clearance": dict(params={"outer_clearance": [36e-6, 38e-6, 40e-6, 42e-6, 44e-6, 46e-6]},
                            analyses=[("campbell", {"methods": ["J"], "speeds_rpm": (1e3, 250e3, 250)}),
                                      ("runup", {"speed_rpm": (1e3, 250e3), "duration": 2.0})]),
}


def example_cases(name):
    """Cases of a built-in study (a key of :data:`EXAMPLES`).

    Parameters
    ----------
    name : str
        A key of :data:`EXAMPLES`, e.g. ``"outer-clearance"``.

    Returns
    -------
    list of Case

    Raises
    ------
    ParameterError
        For an unknown name.

    Examples
    --------
    >>> sorted({c.analysis for c in example_cases("outer-clearance")}), len(example_cases("outer-clearance"))
    (['campbell', 'runup'], 12)
    """
    if name not in EXAMPLES:
        raise ParameterError(f"example = {name!r} is unknown; valid: {', '.join(EXAMPLES)}")
    ex = EXAMPLES[name]
    return [c for a, o in ex["analyses"] for c in grid(ex["params"], a, **o)]


__all__ = ["Case", "grid", "check_options", "run_case", "run_study", "stability_map", "plot_stability_map",
           "example_cases", "write_index", "PARAMETERS", "ANALYSES",
           "plot_stability_chart", "SCHEDULER_TIMEOUT_S", "build_case_system", "case_oil_supply", "SUPPLY_PARAMETERS",
           "estimated_cost_s", "longest_first", "COST_RUNUP_S_PER_SIMULATED_S", "COST_COSIM_S_PER_SIMULATED_S",
           "COST_CAMPBELL_S_PER_SPEED", "COST_HOPF_S", "COST_UNBALANCE_FACTOR", "prepare_worker", "worker_state",
           "run_summary"]
