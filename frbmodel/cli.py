"""Command line interface ``frb``."""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from .core.errors import (
    FRBError,
    ParameterError,
    RunStopped,
    check_distinct,
    check_finite,
    check_positive,
    check_speed,
    check_speed_count,
    check_speeds_in_range,
)
from .core.interrupt import Terminated
from .core.manifest import claim as claim_folder
from .core.manifest import extend
from .core.version import __version__
from .cosim.build import build_fmus
from .cosim.linearize import campbell_from_fmu, linearize
from .cosim.master import COUPLING_TOL, MAX_COUPLING_TOL, cosimulate
from .cosim.sources import find_source
from .cosim.ssp import read_ssp
from .cosim.system_master import SystemMaster, is_system_ssp
from .cycles.branch import MAX_SEGMENTS, hopf_dataframe
from .cycles.continuation import MAX_BRANCH_POINTS, BifurcationDiagram, check_starts, continuation, hopf_points
from .linear.campbell import campbell
from .linear.equilibrium import equilibrium
from .linear.losses import bearing_losses, with_ring_speed_ratio
from .linear.modal import modes_from_state
from .linear.modeshape import save_mode_shapes
from .linear.thermal import (
    SUPPLY_PRESSURE_PA,
    OilSupply,
    at_operating_point,
    check_oil_supply,
    check_supply_pressure,
    thermal_losses,
)
from .linear.unbalance import bode_figure, critical_speeds, location_names, unbalance_response
from .nonlinear.recorder import RunupResult
from .nonlinear.runup import (
    DEFAULT_ATOL_M,
    DEFAULT_RTOL,
    INTEGRATORS,
    SpeedProfile,
    Unbalance,
    check_drive_torque,
    check_output_rate,
    check_runup_oil,
    check_tolerances,
    runup,
    unbalance_arrays,
)
from .plots.figures import html_plotlyjs, system_run_figure
from .plots.losses import plot_bearing_losses
from .plots.thermal import plot_onsets_vs_supply, plot_thermal_losses
from .studies.compare import check_clearances, compare
from .studies.paper import paper_figures
from .studies.run_outputs import (
    check_convergence,
    orbit_windows,
    replot_unbalance,
    save_bifurcation_diagram,
    write_composites,
    write_orbits,
    write_up_down_halves,
    write_waterfalls,
)
from .studies.sweep import (
    PARAMETERS,
    check_scheduler,
    example_cases,
    grid,
    plot_stability_map,
    run_study,
    stability_map,
    write_index,
)
from .studies.thermal import RUNUP_RATE_HZ, onsets_vs_supply, runup_onsets_vs_supply
from .studies.warmup import kernels_ready, warmup, warmup_marker
from .system.methods import MAX_SPRING_N_M, METHODS, get_method
from .system.oil import OIL, T_MIN_K, check_temperature
from .system.parameters import load_system, system_from_meta
from .system.presets import DEFAULT_OUTER_CLEARANCE_M, PAPER_OUTER_CLEARANCES, turbocharger


def parse_speeds(text: str, option: str = "--speeds") -> np.ndarray:
    """Rotor speeds [rpm] from ``"start:stop:count"`` (inclusive linspace) or a comma-separated list.

    Parameters
    ----------
    text : str
        The option's value, in rpm.
    option : str
        The option's name, for the messages.

    Returns
    -------
    ndarray
        Speeds [rpm].

    Raises
    ------
    ParameterError
        Naming the option and the two accepted forms.

    Examples
    --------
    >>> parse_speeds("10000:30000:3").tolist(), parse_speeds("5e4,1e5").tolist()
    ([10000.0, 20000.0, 30000.0], [50000.0, 100000.0])
    """

    name = f"{option} = {text!r}"
    try:
        if ":" in text:
            a, b, n = text.split(":")
            a, b, n = float(a), float(b), int(n)
            if n < 1:
                raise ValueError
        else:
            speeds = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise ParameterError(f"{name} is invalid: this command takes a speed grid, START:STOP:COUNT (rpm, COUNT >= 1) "
                             "or a comma list") from None
    if ":" in text:
        check_speeds_in_range(name, np.array([a, b]))  # (inf or nan named here, not passed to linspace)
        check_speed_count(name, n)  # before the grid is made (1e8 speeds: 800 MB)
        speeds = np.linspace(a, b, n)
    check_speeds_in_range(name, speeds)
    if np.unique(speeds).size < speeds.size:  # (a diagram or table over repeated speeds: rows twice, a 0-wide grid)
        twice = next(float(v) for v in speeds if np.count_nonzero(speeds == v) > 1)
        raise ParameterError(f"{name} repeats {twice:g} rpm: give distinct speeds")
    return speeds


def _given(value, default):
    """An option's value, or ``default`` when it was not given (an empty text is a value: it is checked and refused
    where it is parsed, not replaced by the default)."""
    return default if value is None else value


def check_method_speeds(option, text, speeds, letters):
    """Refuse, before any folder is made, speeds that the methods ``letters`` cannot take (film methods need speeds
    > 0; :func:`frbmodel.linear.campbell.check_speeds`), naming the option and its value."""

    for letter in letters:
        try:
            get_method(letter).check_speeds(speeds)
        except ParameterError as exc:
            raise ParameterError(f"{option} = {text!r}: {exc}") from None


def load_from_args(args):
    """The system of a command: ``--system FILE`` or the Table 2 system, with ``--outer-clearance`` and
    ``--film-model`` applied.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``outer_clearance`` [m] (or None) and optionally ``system`` (a path) and
        ``film_model``.

    Returns
    -------
    Turbocharger

    Examples
    --------
    >>> args = build_parser().parse_args(["equilibrium", "--outer-clearance", "40e-6"])
    >>> [b.outer.clearance for b in load_from_args(args).bearings]
    [4e-05, 4e-05]
    """

    if getattr(args, "system", None) is not None and not str(args.system).strip():
        raise ParameterError("--system = '' is invalid: give the path of a system file (frb system --out FILE "
                             "writes one), or leave --system out for the Table 2 system")
    if getattr(args, "system", None):
        tc = load_system(args.system)
        if args.outer_clearance is not None:
            tc = tc.with_outer_clearance(args.outer_clearance)
    else:
        tc = turbocharger() if args.outer_clearance is None else turbocharger(outer_clearance=args.outer_clearance)
    if getattr(args, "film_model", None):
        tc = tc.with_(film_model=args.film_model)
    return tc


def _refuse_with_fmu(args, names):
    """Options that cannot apply to an FMU-based command: the FMUs take their system from the SSP parameter set."""
    given = [f"--{n.replace('_', '-')}" for n in names if getattr(args, n, None) not in (None, False)]
    if given:
        raise ParameterError(f"{', '.join(given)} cannot apply with an SSP: the FMUs take the system from the SSP "
                             f"parameter set (--parameter-set, now {args.parameter_set!r}); choose a parameter set or "
                             "write your own (frb system + frb build-fmus)")


def _spring_args(p):
    """The spring stiffnesses of methods A, B, E [N/m]."""
    p.add_argument("--k", type=float, default=None, help="spring stiffness of methods A, E [N/m] (1e6)")
    p.add_argument("--kx", type=float, default=None, help="horizontal spring of method B [N/m] (1e6)")
    p.add_argument("--ky", type=float, default=None, help="vertical spring of method B [N/m] (2e6)")


def _system_args(p):
    p.add_argument("--outer-clearance", type=float, default=None, metavar="M",
                   help=f"radial clearance of both outer films [m] (default {DEFAULT_OUTER_CLEARANCE_M * 1e6:g}e-6)")
    p.add_argument("--system", metavar="FILE", help="system description (.toml or .json, see `frb system`)")
    p.add_argument("--film-model", choices=["short", "short_corrected"], default=None,
                   help="film model (default: the system's, 'short')")


def cmd_campbell(args):
    """``frb campbell``: Campbell diagram of one method (from the library or the FMUs), saved and summarised."""

    speeds = parse_speeds(args.speeds)
    check_method_speeds("--speeds", args.speeds, speeds, [args.method])
    fmax = args.fmax  # (bounded by NUMERIC_OPTIONS)
    if args.mode_shapes is not None and args.from_fmu:
        raise ParameterError("--mode-shapes needs the library model: it cannot be combined with --from-fmu")
    mode_rpm = args.mode_shapes  # (bounded by NUMERIC_OPTIONS, before any work)
    if mode_rpm is not None and not speeds.min() <= mode_rpm <= speeds.max():  # (was refused after the diagram)
        raise ParameterError(f"--mode-shapes = {mode_rpm:g} rpm is outside --speeds {args.speeds} "
                             f"({speeds.min():g} ... {speeds.max():g} rpm): the shapes are the diagram's modes, "
                             "give a speed inside its grid")
    if args.parameter_set is not None and not args.from_fmu:
        raise ParameterError(f"--parameter-set {args.parameter_set} applies only with --from-fmu (an SSP's parameter "
                             "set); without it the system is --system / --outer-clearance")
    if args.from_fmu:
        args.parameter_set = _given(args.parameter_set, "co36")
        _refuse_with_fmu(args, ("outer_clearance", "system", "film_model", "k", "kx", "ky", "oil",
                                "supply_temperature", "supply_pressure"))
        _check_ssp(args.from_fmu, args.parameter_set)  # (the user's SSP and set named, before the folder is made)
        out = writable_dir(args.out)
        cd = campbell_from_fmu(args.from_fmu, speeds, args.method, args.parameter_set, progress=True)
        tc, kw = None, {}
    else:
        tc = load_from_args(args)  # (a system the checks refuse is refused before the folder exists)
        supply = _oil_supply_from_args(args, tc)
        out = writable_dir(args.out)
        kw = {k: getattr(args, k) for k in ("k", "kx", "ky") if getattr(args, k) is not None}
        try:
            cd = campbell(tc, args.method, speeds, whirl=not args.no_whirl, progress=True, oil_supply=supply, **kw)
        except KeyboardInterrupt as exc:
            if getattr(exc, "result", None) is None:
                raise
            return _save_interrupted_campbell(exc, out, fmax)
    paths = cd.save(out, fmax_hz=fmax)
    print(f"method {cd.method}: {cd.meta.get('method_title', cd.meta.get('source', ''))}; {speeds.size} speeds")
    if "oil_supply" in cd.meta:
        o = cd.meta["oil_supply"]
        print(f"  thermal model: {o['oil']['name']}, supply {o['supply_temperature_K']:g} K, "
              f"{o['supply_pressure_Pa']:g} Pa; the films' viscosities at each speed's operating point")
    if not args.no_whirl:
        for _, r in cd.onsets_dataframe().iterrows():
            s = r["onset [rpm]"]
            text = ((f"{s:,.0f} rpm" + ("" if r["inside grid"] else " (outside the speed grid)")) if np.isfinite(s)
                    else "already past it at the grid start" if r["past onset at grid start"] else "none in range")
            print(f"  film whirl onset {r['film']:>17}: {text}")
        print(f"  onsets: {cd.meta.get('whirl_onset_source', '')}")
    ur = cd.unstable_ranges()
    if len(ur):
        print("unstable modes (D < -round-off bound):")
        print(ur.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    else:
        print("no unstable mode in the speed range")
    print(f"max. simultaneously unstable modes: {int(cd.n_unstable.max())}")
    if cd.n_neutral.max():
        print(f"neutral modes (|D| <= round-off bound, undamped): up to {int(cd.n_neutral.max())} at one speed")
    paths.append(_critical_table(cd, None if args.from_fmu else tc, out / f"campbell_{cd.method}_critical.csv", kw))
    if mode_rpm is not None:
        paths += save_mode_shapes(cd, mode_rpm, out, fmax)
    print("wrote:\n  " + "\n  ".join(str(p) for p in paths))
    print(f"results in {out.resolve()}")


def _save_interrupted_campbell(exc, out, fmax):
    """Write the speeds a Ctrl-C / SIGTERM left of a Campbell diagram (``exc.result``); the exit code 130 / 143."""
    cd = exc.result
    paths = cd.save(out, fmax_hz=fmax)
    code = 143 if isinstance(exc, Terminated) else 130
    print(f"\nfrb campbell: interrupted ({'SIGTERM' if code == 143 else 'Ctrl-C'}) after {cd.speeds_rpm.size} of "
          f"{cd.meta['speeds_requested']} speeds (up to {cd.speeds_rpm[-1]:,.0f} rpm); those are written, marked "
          f"'interrupted':\n  " + "\n  ".join(str(p) for p in paths), file=sys.stderr)
    return code


def _critical_table(cd, system, path, kw):
    """Print the 1X crossings of a Campbell diagram (:func:`frbmodel.linear.unbalance.critical_speeds`) and write
    them."""

    cs = critical_speeds(cd, system, **kw)
    _print_critical(cs)
    cs.to_csv(path, index=False)
    return path


def _print_critical(cs):
    """Print a critical-speed table (speeds in rpm, amplitudes in µm)."""
    if not len(cs):
        print("no critical speed in the speed range")
        return
    tab = cs[["source", "speed [rpm]", "mode", "kind", "precession", "damping [-]", "location"]].copy()
    tab["amplitude [um]"] = cs["amplitude [m]"] * 1e6
    print("critical speeds (1X crossings of the Campbell branches; response peaks):")
    fmt = {"speed [rpm]": "{:,.0f}".format, "damping [-]": lambda x: f"{0.0 if abs(x) < 5e-5 else x:.4f}",
           "amplitude [um]": "{:.4g}".format}
    print(tab.to_string(index=False, na_rep="", formatters=fmt))


def _unbalance_methods(text, kw):
    """Method letters of ``--method`` (one or a comma list) and the spring options each takes."""

    methods = [get_method(x) for x in text.split(",") if x.strip()] or [get_method(text)]
    letters = [m.letter for m in methods]
    twice = next((x for k, x in enumerate(letters) if x in letters[:k]), None)
    if twice:  # (the same response computed and drawn twice)
        raise ParameterError(f"--method {text} repeats method {twice}: give each method once")
    unused = [k for k in kw if not any(k in m.parameters for m in methods)]
    if unused:
        takers = ", ".join(m.letter for m in METHODS.values() if unused[0] in m.parameters)
        takes = "; ".join(f"method {m.letter} takes " + (", ".join(f"--{p}" for p in m.parameters) or "no spring")
                          for m in methods)
        raise ParameterError(f"--{unused[0]} = {kw[unused[0]]!r} is invalid for method {text}: it sets a spring of "
                             f"method{'s' if ',' in takers else ''} {takers} ({takes})")
    return [(m.letter, {k: v for k, v in kw.items() if k in m.parameters}) for m in methods]


def cmd_unbalance(args):
    """``frb unbalance``: unbalance response (Bode, polar, film orbits) and critical speeds of one or more methods."""

    speeds = parse_speeds(args.speeds)
    kw = {k: getattr(args, k) for k in ("k", "kx", "ky") if getattr(args, k) is not None}
    methods = _unbalance_methods(args.method, kw)
    check_method_speeds("--speeds", args.speeds, speeds, [letter for letter, _ in methods])
    tc = load_from_args(args)
    unbalance = _parse_unbalance(args.unbalance or ["turbine_wheel:1e-6:0"], tc)
    supply = _oil_supply_from_args(args, tc)
    names = _locations(args)
    bad = [n for n in names or [] if n not in location_names(tc)]
    if bad:
        raise ParameterError(f"--locations {bad[0]!r} is unknown; valid: {', '.join(location_names(tc))}")
    out = writable_dir(args.out)
    results, paths = [], []
    for letter, kw_m in methods:
        ur = unbalance_response(tc, letter, speeds, unbalance, peak_names=names, progress=True, oil_supply=supply,
                                **kw_m)
        paths += ur.save(out, names=names)
        print(f"method {letter}: {ur.meta['method_title']}; {speeds.size} speeds; unbalance "
              + ", ".join(f"{u['disc']} {u['m e [kg m]']:g} kg m at {u['phase [rad]']:g} rad" for u in ur.unbalance))
        if supply is not None:
            print(f"thermal operating point at every speed: {_supply_text(supply)}")
        _print_critical(ur.critical_speeds())
        results.append(ur)
    if len(results) > 1:
        import matplotlib.pyplot as plt

        fig = bode_figure(results, names)
        paths.append(out / f"unbalance_bode_{''.join(r.method for r in results)}.png")
        fig.savefig(paths[-1], dpi=130, bbox_inches="tight")
        plt.close(fig)
    print("wrote:\n  " + "\n  ".join(str(p) for p in paths))
    print(f"results in {out.resolve()}")


def cmd_equilibrium(args):
    """``frb equilibrium``: static equilibrium of both bearings at one speed, printed (and written as CSV)."""

    tc = load_from_args(args)  # (--speed-rpm is bounded by NUMERIC_OPTIONS)
    supply = _oil_supply_from_args(args, tc)
    if supply is not None:
        tc = at_operating_point(tc, args.speed_rpm, supply, args.method)
    out = writable_dir(args.out) if args.out is not None else None
    eq = equilibrium(tc, args.method, args.speed_rpm)
    if supply is not None:
        print(f"thermal operating point: {_supply_text(supply)}; film viscosities [Pa s]: " + ", ".join(
                  f"{b.name} inner {b.inner.viscosity:.5g}, outer {b.outer.viscosity:.5g}" for b in tc.bearings))
    print(eq)
    if out is not None:
        p = out / f"equilibrium_{eq.method}_{args.speed_rpm:.0f}rpm.csv"
        eq.to_dataframe().to_csv(p, index=False)
        print(f"wrote {p.resolve()}")


def cmd_system(args):
    """``frb system``: write the system description to a .toml or .json file."""
    tc = load_from_args(args)
    p = tc.save(args.out)
    print(f"wrote {Path(p).resolve()} (edit it and pass it with --system)")


def cmd_paper_figures(args):
    """``frb paper-figures``: regenerate the paper's linear figures 4-11."""

    tc = load_from_args(args)
    writable_dir(args.out)
    paths = paper_figures(tc, args.out, n_speeds=args.n_speeds, progress=True)
    print("wrote:\n  " + "\n  ".join(str(p) for p in paths))
    print(f"results in {Path(args.out).resolve()}")


def _locations(args):
    """The names of ``--locations NAME,NAME`` (None when not given; a text that names none is refused)."""
    if args.locations is None:
        return None
    names = [x.strip() for x in args.locations.split(",") if x.strip()]
    if not names:  # (it drew the default locations)
        raise ParameterError(f"--locations = {args.locations!r} names no location: give a comma list of names, e.g. "
                             "turbine_wheel,compressor_wheel")
    return check_distinct(f"--locations = {args.locations!r}", names)  # (a repeated location was drawn twice)


def _parse_unbalance(items, system):
    """The :class:`Unbalance` list of ``--unbalance DISC:AMOUNT[:PHASE]`` (repeatable), each checked on ``system``
    (the disc's own bound, each disc once: :func:`frbmodel.nonlinear.runup.unbalance_arrays`) before any folder."""

    out = []
    for it in items or []:
        fields = it.split(":")
        try:
            if not 2 <= len(fields) <= 3:  # a 4th field was dropped without a word
                raise ValueError
            disc, amount, *phase = fields
            amount, phase = float(amount), float(phase[0]) if phase else 0.0
        except ValueError:
            raise ParameterError(f"--unbalance {it!r} is invalid: use DISC:AMOUNT[:PHASE] (2 or 3 fields, "
                                 f"{len(fields)} given) with AMOUNT in kg m and PHASE in rad, e.g. "
                                 "turbine_wheel:1e-6:0") from None
        try:
            out.append(Unbalance(disc, amount, phase))
            unbalance_arrays(system.rotor, out)
        except ParameterError as exc:
            raise ParameterError(f"--unbalance {it!r}: {exc}") from None
    return out


#: the named speed profiles of ``frb runup --profile`` (or a FILE.csv)
PROFILES = ("ramp", "exponential", "constant", "up-down", "torque")
#: default ``frb runup --speeds`` [rpm] (START:END; constant and torque profiles take its START)
RUNUP_SPEEDS = "20000:250000"
#: figure titles of the runs by :attr:`frbmodel.nonlinear.runup.SpeedProfile.direction` (else "run-up")
RUN_TITLES = {"constant": "constant-speed run", "down": "run-down", "up-down": "run-up and run-down",
              "mixed": "run with rising and falling speed"}


def _profile_arg(text):
    """``--profile``: a named profile or a path ending in .csv."""
    if text in PROFILES or text.lower().endswith(".csv"):
        return text
    raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from {', '.join(PROFILES)}, or a FILE.csv)")


def _profile(args):

    if args.profile.lower().endswith(".csv"):
        given = [o for o, v in (("--speeds", args.speeds), ("--drive-torque", args.drive_torque)) if v is not None]
        if given:  # (they were ignored: the table is the speed)
            raise ParameterError(f"{given[0]} cannot be combined with --profile {args.profile}: the table "
                                 "prescribes the speed at every time")
        prof = SpeedProfile.from_csv(args.profile)
        if args.duration is not None and args.duration > prof.t[-1]:
            raise ParameterError(f"--duration = {args.duration!r} s is invalid with --profile {args.profile}: valid "
                                 f"range up to the profile's last time, {prof.t[-1]:g} s")
        return prof
    if args.profile != "torque" and args.drive_torque is not None:
        raise ParameterError(f"--drive-torque = {args.drive_torque!r} N m applies only with --profile torque (the "
                             f"--profile {args.profile} prescribes the speed)")
    duration = 1.0 if args.duration is None else args.duration
    if args.profile in ("torque", "constant"):
        a = _start_speed(_given(args.speeds, RUNUP_SPEEDS.split(":")[0]), args.profile)
        if args.profile == "torque":
            return SpeedProfile.torque(args.drive_torque or 0.0, a, duration)
        return SpeedProfile.constant(a, duration)
    a, b = _speed_pair(_given(args.speeds, RUNUP_SPEEDS))
    if args.profile == "ramp":
        return SpeedProfile.ramp(a, b, duration)
    if args.profile == "exponential":
        return SpeedProfile.exponential(a, b, duration)
    return SpeedProfile.up_down(a, b, duration / 2)


def _start_speed(text, profile):
    """The one speed [rpm] of ``--speeds`` for ``--profile constant`` (the speed held) or ``torque`` (the start
    speed): START, or START:END with END = START; another END is refused (it was ignored)."""
    fields = text.split(":")
    if len(fields) == 1:
        try:
            return float(fields[0])
        except ValueError:
            raise ParameterError(f"--speeds = {text!r} is invalid: give the speed in rpm, e.g. 20000") from None
    a, b = _speed_pair(text)
    if a != b:
        what = "holds one speed" if profile == "constant" else "starts at START and the drive torque sets the speed"
        raise ParameterError(f"--speeds = {text!r} is invalid with --profile {profile}: the run {what}, so END "
                             f"would be ignored; give --speeds {fields[0]}")
    return a


def _speed_pair(text):
    """``--speeds START:END`` [rpm] of the run-ups, bifurcations and comparisons: exactly two fields (a COUNT, as
    campbell's START:STOP:COUNT takes, is refused rather than dropped)."""
    fields = text.split(":")
    try:
        if len(fields) != 2:
            raise ValueError
        a, b = (float(x) for x in fields)
    except ValueError:
        extra = (" (a range, not a grid: no COUNT)" if len(fields) == 3 else "")
        raise ParameterError(f"--speeds = {text!r} is invalid: this command takes a speed range, START:END in "
                             f"rpm{extra}") from None
    return a, b


def cmd_runup(args):
    """``frb runup``: monolithic nonlinear run-up or run-down, streamed to a folder, with figures; exit code."""

    tc = load_from_args(args)
    prof = _profile(args)
    duration = float(prof.t[-1]) if args.duration is None else args.duration
    check_output_rate(args.rate, duration)

    rtol, atol = check_tolerances(tc, args.rtol, args.atol, ("--rtol", "--atol"))
    check_drive_torque(tc, prof, "--drive-torque")
    supply = check_runup_oil(_with_ring_capacity(args, _oil_supply_from_args(args, tc)), prof, args.integrator, None,
                             ("--integrator", "--profile"), tc)
    unbalance = _parse_unbalance(args.unbalance, tc)
    out = writable_dir(args.out)
    kind = RUN_TITLES.get(prof.direction, "run-up")
    print(f"{kind}: {prof.description}, film model {tc.film_model}, results stream to {out.resolve()}")
    if supply is not None:
        lag = supply.model.ring_heat_capacity_J_K
        print(f"  thermal model: {_supply_text(supply)}; " + ("film temperatures quasi-static in rotor speed" if lag
              is None else f"rings' temperatures as states (m_R c_R = {lag:g} J/K), films quasi-static"))

    def run_at(tighten, folder):
        return runup(tc, profile=prof, duration=duration, unbalance=unbalance,
                     output_rate_hz=args.rate, rtol=rtol * tighten, atol=atol * tighten, out_dir=folder,
                     progress=True, integrator=args.integrator, oil_supply=supply)

    run, code = _stoppable("runup", lambda: run_at(1.0, out), out)
    if "wall_time_s" in run.meta:
        work = ", ".join(f"{run.meta[k]} {k.replace('_', ' ')}" for k in ("solver_steps", "rhs_evaluations",
                                                                          "jacobian_evaluations") if k in run.meta)
        print(f"wall time {run.meta['wall_time_s']:.1f} s ({run.meta.get('integrator', 'lsoda')}: {work}), "
              f"{run.time.size} samples")
    if prof.direction == "up-down" and not args.no_figure:
        write_up_down_halves(run, tc, out, make_dir=writable_dir)
    _finish_run(args, run, lambda: tc, out, xscale="log" if args.profile == "exponential" else "linear", title=kind)
    if args.check_convergence and code == 0:
        print("convergence check: the same run with rtol and atol tightened tenfold")
        check_convergence(run, lambda folder: run_at(0.1, folder), out, "tolerances x0.1", runner=_cli_runner)
    return code


def cmd_bifurcation(args):
    """``frb bifurcation``: Hopf points and limit-cycle branches vs speed (continuation), tables and diagram."""

    tc = load_from_args(args)
    lo, hi = sorted(check_speed(f"--speeds {name}", v) for name, v in zip(("START", "END"), _speed_pair(args.speeds)))
    if args.hopf_only:  # (they were ignored: no branch is followed)
        given = [f"--{n.replace('_', '-')}" for n in ("start", "max_points", "segments", "runs")
                 if getattr(args, n) is not None]
        if given:
            raise ParameterError(f"{', '.join(given)} cannot be combined with --hopf-only: "
                                 f"{'it applies' if len(given) == 1 else 'they apply'} to the limit-cycle branches, "
                                 "which --hopf-only does not follow")
    try:
        text = "hopf" if args.start is None else args.start
        start = [s if s == "hopf" else float(s) for s in (x.strip() for x in text.split(","))]
    except ValueError:
        raise ParameterError(f"--start = {args.start!r} is invalid: 'hopf' or a speed in rpm, or a comma-separated "
                             "list of them (e.g. 25000,60000)") from None
    start = check_starts(start, (lo, hi), "--start", "--speeds")
    runs = _load_runs(args.runs, tc)  # (before hours of continuation: a wrong folder is refused now)
    supply = _oil_supply_from_args(args, tc)
    out = writable_dir(args.out)
    hps = hopf_points(tc, (lo, hi), restabilizing=True, oil_supply=supply)
    if supply is not None:
        print(f"thermal model: {_supply_text(supply)}; every speed at its own operating point")
    print(f"Hopf points of the full model, {lo:.0f} ... {hi:.0f} rpm (where a mode of the equilibrium loses or "
          "regains stability with rising speed):")
    for hp in hps:
        print(f"  {hp.speed_rpm:10.1f} rpm  {hp.frequency_hz:8.2f} Hz  ({hp.frequency_hz * 60 / hp.speed_rpm:.3f} X)  "
              f"{'regains' if hp.restabilizing else 'loses'}")
    hopf_dataframe(hps).to_csv(out / "hopf_points.csv", index=False)
    if args.hopf_only:
        print(f"wrote:\n  {out / 'hopf_points.csv'}\nresults in {out.resolve()}")
        return 0
    points = []
    partial = out / "branch_partial.csv"
    partial.write_text("speed [rpm],frequency [Hz],turbine wheel orbit radius [um],stable\n")

    def stream(p):
        points.append(p)
        with open(partial, "a") as fh:
            fh.write(f"{p.speed_rpm:.6f},{1 / p.period:.6f},{p.turbine_radius_m * 1e6:.6f},{p.stable}\n")

    try:
        bd = continuation(tc, (lo, hi), start, max_points=40 if args.max_points is None else args.max_points,
                          progress=True, on_point=stream, segments=args.segments or 1, oil_supply=supply)
        code = 0
    except KeyboardInterrupt as exc:
        code = 143 if isinstance(exc, Terminated) else 130
        print(f"\nfrb bifurcation: interrupted; the {len(points)} points computed are kept in {out.resolve()}",
              file=sys.stderr)
        bd = BifurcationDiagram(points, [], {"status": "interrupted", "branches": [len(points)],
                                             **({"oil_supply": supply.to_dict()} if supply else {})})
    bd.meta.setdefault("status", "finished")
    save_bifurcation_diagram(bd, tc, out, (lo, hi), runs, oil_supply=supply)
    partial.unlink()
    tab = bd.bifurcation_table()
    print("bifurcation points:" if len(tab) else "no bifurcation points on the branches")
    if len(tab):
        print(tab.to_string(index=False, float_format=lambda x: f"{x:.6g}"))
    print(f"results in {out.resolve()} (branch.csv, bifurcations.csv, branch.nc, bifurcation.png/.html)")
    return code


def _load_runs(text, system):
    """``[(folder, run-up result)]`` of ``--runs`` (comma-separated folders), loaded; a ParameterError names a
    folder without one, or with a run of another system than ``system`` (its envelope was drawn behind branches it
    cannot be compared with)."""

    folders = [d for d in (text or "").split(",") if d]
    check_distinct(f"--runs = {text!r}", [str(Path(d).resolve()) for d in folders])  # (its envelope drawn twice)
    return [(d, _same_system_run(d, system, "--runs")) for d in folders]


def _on_sigterm(signum, frame):
    raise Terminated()


def _stoppable(command, fn, out):
    """(result, exit code) of a long run that streams into ``out``: a :class:`RunStopped` (the run ended early,
    its samples kept) gives exit code 3, Ctrl-C 130 and SIGTERM 143 — the partial result is read back from
    ``out``, where the recorder marked it ``interrupted``."""

    try:
        return fn(), 0
    except RunStopped as exc:
        print(f"frb {command}: stopped: {exc}", file=sys.stderr)
        return exc.result, 3
    except KeyboardInterrupt as exc:
        code = 143 if isinstance(exc, Terminated) else 130
        print(f"\nfrb {command}: interrupted ({'SIGTERM' if code == 143 else 'Ctrl-C'}); what was computed is kept in "
              f"{out.resolve()}", file=sys.stderr)
        return RunupResult.load(out), code


def _cli_runner(fn, folder):
    """The rerun of a convergence check as a long run of the CLI (:func:`_stoppable`): its result."""
    return _stoppable("convergence check", fn, folder)[0]


def _finish_run(args, run, system, out, **figure_kw):
    """``runup.nc`` (the run as netCDF, :meth:`RunupResult.to_xarray`), composite figures (unless --no-figure or
    too few samples; ``system()`` gives the Turbocharger) and the closing line naming the output folder."""
    print(f"wrote {run.to_netcdf(out / 'runup.nc').resolve()} (netCDF: xarray.open_dataset)")
    if not args.no_figure and run.time.size >= MIN_FIGURE_SAMPLES:
        write_composites(run, system(), out, **figure_kw)
    elif not args.no_figure:  # (they were left out without a word)
        longer = "a longer --duration or a higher --rate" if hasattr(args, "duration") else "a longer --stop-time"
        print(f"no figures: {run.time.size} samples recorded, the spectrogram figures need at least "
              f"{MIN_FIGURE_SAMPLES} ({longer})")
    print(f"results in {out.resolve()}")


#: the fewest samples of a run whose composite figures are drawn (the spectrogram's segments)
MIN_FIGURE_SAMPLES = 64


#: results folders claimed by the running command (:mod:`frbmodel.core.manifest`), finished by :func:`main`
_CLAIMS = []
#: the running command line (named in the manifests)
_COMMAND = ["frb"]


def writable_dir(path, option="--out", claim=True):
    """Create folder ``path`` and check that files can be written there — before any computing starts. With
    ``claim``, the folder is this command's results folder: the files the previous command wrote there and nobody
    changed since are removed, and the command's own are listed in ``frb_manifest.json`` when it ends
    (:mod:`frbmodel.core.manifest`).

    Parameters
    ----------
    path : str or Path
        The folder (created with its parents).
    option : str
        Command-line option that gave it, named in the error.

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        Naming the option, the path and the reason.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     print(writable_dir(Path(tmp) / "a" / "b", claim=False).is_dir())
    True
    """
    import tempfile

    if not str(path).strip():  # (Path("") is the current folder: the results went there)
        raise ParameterError(f"{option} = {str(path)!r} is invalid: give a folder (e.g. {option} results/run)")
    p = Path(path)
    created = next((q for q in [*reversed(p.absolute().parents), p.absolute()] if not q.exists()), None)
    try:
        p.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=p, prefix=".frb_write_check_"):
            pass
    except OSError as exc:
        raise ParameterError(f"{option} = {str(path)!r} is not a writable folder: {exc.strerror or exc}") from None
    if claim and not any(c.folder.resolve() == p.resolve() for c in _CLAIMS):
        _CLAIMS.append(claim_folder(p, " ".join(_COMMAND), created))
    return p


def cmd_compare(args):
    """``frb compare``: run-ups vs method-J stability per outer clearance (figures and onset table)."""

    tc = load_from_args(args)
    cl = check_distinct(f"--clearances = {args.clearances!r}", [check_positive("--clearances", x, "m")
                                                            for x in args.clearances.split(",")], "m")
    try:  # (each against the system's films and its own result folder, before the folder is made)
        cl = check_clearances(tc, cl)
    except ParameterError as exc:
        raise ParameterError(f"--clearances = {args.clearances!r}: {exc}") from None
    a, b = _speed_pair(args.speeds)
    writable_dir(args.out)  # (after every check: a refused option leaves no folder)
    table, paths = compare(tc, cl, (a, b), args.duration, args.profile, out_dir=args.out, progress=True,
                           fmax_hz=args.fmax, check_convergence=args.check_convergence)
    print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print(f"results in {Path(args.out).resolve()}")


def parse_orders(text: str) -> tuple:
    """Order lines of ``frb plot --orders``: comma list of positive multiples k of the rotor frequency.

    Parameters
    ----------
    text : str or None
        E.g. ``"0.5,1,2"``; ``"none"`` (or empty) for no order lines; None: the default ``"0.5,1"``.

    Returns
    -------
    tuple of float
        The orders k [-], as given.

    Examples
    --------
    >>> parse_orders("0.5,1,2"), parse_orders("none")
    ((0.5, 1.0, 2.0), ())
    """
    if text is None:
        text = DEFAULT_ORDERS
    if text.strip().lower() in ("", "none"):
        return ()
    orders = [check_positive("--orders", x.strip()) for x in text.split(",") if x.strip()]
    return tuple(check_distinct(f"--orders = {text!r}", orders))  # (a repeated order line was drawn twice)


#: the default order lines of ``frb plot --orders`` (0.5X and 1X)
DEFAULT_ORDERS = "0.5,1"
#: the ``frb plot`` options that only one kind of results folder takes (the others are refused, not ignored)
PLOT_OPTIONS = {"runup": ("xscale", "orbits", "orbit_times", "revolutions", "waterfall", "orders"),
                "unbalance": ("locations",), "bifurcation": ("runs",)}
PLOT_KINDS = {"runup": "a run-up folder (frb runup, frb cosim)", "unbalance": "an unbalance-response folder "
              "(frb unbalance)", "bifurcation": "a bifurcation folder (frb bifurcation)"}


def _plot_kind_options(args, out, kind):
    """Refuse the ``frb plot`` options that the folder ``out`` of ``kind`` (a key of :data:`PLOT_OPTIONS`) has no
    use for: each applies to one kind of folder only (they were ignored)."""
    for other, names in PLOT_OPTIONS.items():
        given = [f"--{n.replace('_', '-')}" for n in names if other != kind and getattr(args, n, None) not in
                 (None, False)]
        if given:
            takers = ", ".join(f"--{n.replace('_', '-')}" for n in names)
            raise ParameterError(f"{', '.join(given)} cannot apply to {out}, {PLOT_KINDS[kind]}: {takers} "
                                 f"need{'s' if len(names) == 1 else ''} {PLOT_KINDS[other]}")


def cmd_plot(args):
    """Re-render the figures of a results folder written by frb runup / frb cosim (finished, stopped or
    interrupted) or by frb unbalance."""

    out = Path(args.dir)
    if out.is_file():  # (the figures are written into DIR: a file there was a traceback, "File exists")
        raise ParameterError(f"DIR = {args.dir!r} is a file; give the results folder that holds it "
                             f"(frb plot {str(out.parent)!r})")
    _CLAIMS.append(extend(out, " ".join(_COMMAND)))  # the figures it draws belong to the run whose folder it is
    orders = parse_orders(args.orders)
    if (out / "branch.nc").exists():
        _plot_kind_options(args, out, "bifurcation")
        return replot_bifurcation(args, out)
    if out.is_dir() and not (out / "runup.csv").exists() and any(out.glob("unbalance_*.json")):
        _plot_kind_options(args, out, "unbalance")
        locations = _locations(args)
        print("wrote:\n  " + "\n  ".join(str(p) for p in replot_unbalance(out, locations)))
        print(f"results in {out.resolve()}")
        return
    _plot_kind_options(args, out, "runup")
    run = RunupResult.load(out)
    if run.time.size < 64:
        raise ParameterError(f"{out}: {run.time.size} samples recorded; the figures need at least 64")
    system = system_from_meta(run.meta, out / "runup.json", "the Campbell overlay")

    recorded = SpeedProfile(run.time, run.speed_rpm, np.zeros_like(run.time), "recorded speed")
    title = f"{RUN_TITLES.get(recorded.direction, 'run-up')} ({run.status})"
    windows = _orbit_windows(args, run)  # every option checked before the composites are redrawn
    write_composites(run, system, out, xscale=args.xscale or "linear", title=title, orders=orders)
    write_orbits(windows, out, data=True)
    if args.waterfall:
        write_waterfalls(run, out, orders=orders)
    print(f"results in {out.resolve()}")


def replot_bifurcation(args, out):
    """``frb plot DIR`` of a folder written by ``frb bifurcation``: the diagram drawn again from ``branch.nc`` (with
    the Campbell lines of the system it holds and the runs of ``--runs``)."""

    bd = BifurcationDiagram.load(out)
    lo, hi = bd.meta.get("speed_range_rpm", [min(p.speed_rpm for p in bd.points), max(p.speed_rpm for p in bd.points)])
    system = system_from_meta(bd.meta, out / "branch.nc", "the Campbell lines")
    runs = _load_runs(getattr(args, "runs", None), system)
    save_bifurcation_diagram(bd, system, out, (lo, hi), runs)
    print(f"results in {out.resolve()} (bifurcation.png/.html)")
    return 0


def parse_time_windows(text: str) -> list:
    """Time windows of ``frb plot --orbit-times``: ``"T0:T1"`` or a comma list of them, in seconds.

    Parameters
    ----------
    text : str

    Returns
    -------
    list of (float, float)
        Start and end [s], start < end, each window once (a repeated window was drawn and written twice).

    Examples
    --------
    >>> parse_time_windows("1.1:1.5,0:0.2")
    [(1.1, 1.5), (0.0, 0.2)]
    """
    out = []
    for item in text.split(","):
        try:
            a, b = (float(x) for x in item.split(":"))
        except ValueError:
            raise ParameterError(f"--orbit-times {item!r} is invalid: use T0:T1 [s] (or a comma list)") from None
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise ParameterError(f"--orbit-times {item!r} is invalid: valid range T0 < T1 (finite) [s]")
        out.append((a, b))
    return check_distinct(f"--orbit-times = {text!r}", out, "s")


def _orbit_windows(args, run):
    """The orbit windows of ``frb plot --orbits / --orbit-times / --revolutions`` (:func:`orbit_windows`), each
    error naming its option; ``--revolutions`` without ``--orbits`` is refused (it would be ignored)."""
    if args.revolutions is not None and not args.orbits:
        raise ParameterError(f"--revolutions {args.revolutions:g} applies only with --orbits SPEEDS (the half-width "
                             "of each speed window); --orbit-times windows are given in seconds")
    revolutions = 20.0 if args.revolutions is None else args.revolutions  # (bounded by NUMERIC_OPTIONS)
    speeds = parse_speeds(args.orbits, "--orbits") if args.orbits else ()
    times = parse_time_windows(args.orbit_times) if args.orbit_times else ()
    windows = []
    for option, value, kw in (("--orbits", args.orbits, {"speeds_rpm": speeds}),
                              ("--orbit-times", args.orbit_times, {"time_windows": times})):
        try:
            windows += orbit_windows(run, revolutions=revolutions, **kw) if value else []
        except ParameterError as exc:
            raise ParameterError(f"{option} {value}: {exc}") from None
    return windows


def _oil_from_args(args, system):
    """The oil of ``frb losses``: ``--oil NAME``, else the system file's ``[oil]`` (None: constant viscosities);
    ``--supply-temperature`` / ``--supply-pressure`` without an oil, or an oil with a method other than J or with
    ``--run``, are refused."""

    oil = OIL(args.oil) if args.oil is not None else system.oil
    if oil is None:
        given = [o for o, v in (("--supply-temperature", args.supply_temperature),
                                ("--supply-pressure", args.supply_pressure)) if v is not None]
        if given:
            raise ParameterError(f"{given[0]} needs an oil: give --oil NAME or an [oil] table in --system (without an "
                                 "oil the films keep their constant viscosities)")
    elif any(not get_method(x).needs_films for x in str(getattr(args, "method", "J")).split(",") if x.strip()):
        source = f"--oil {args.oil!r}" if args.oil is not None else f"the [oil] table of --system {args.system}"
        raise ParameterError(f"--method {args.method} cannot be combined with an oil ({source}): methods A, B and E "
                             "have linear springs without oil films; use film methods (C, D, F, G, I, J)")
    elif getattr(args, "run", None):
        raise ParameterError("--run cannot be combined with an oil: a run-up's recorded losses are at the films' "
                             "constant viscosities; leave --oil (or the system's [oil]) out to overlay them")
    return oil


def _oil_args(p, what):
    """``--oil``, ``--supply-temperature`` (one value [K]) and ``--supply-pressure`` of a command that takes one
    oil supply (:class:`frbmodel.linear.thermal.OilSupply`); ``what`` says what the thermal model changes."""
    p.add_argument("--oil", default=None, metavar="NAME",
                   help=f"thermal model with this oil (SAE 0W-20, SAE 5W-30, SAE 10W-40, SAE 15W-40, ISO VG 46; or an "
                        f"[oil] table in --system): {what}")
    p.add_argument("--supply-temperature", type=float, default=None, metavar="K",
                   help="oil supply temperature [K] (default 363.15; needs an oil)")
    p.add_argument("--supply-pressure", type=float, default=None, metavar="PA",
                   help="oil supply pressure above ambient [Pa] (default 3e5; needs an oil)")


def _oil_supply_from_args(args, system):
    """The :class:`OilSupply` of ``--oil`` (else the system file's ``[oil]``) at ``--supply-temperature`` [K] and
    ``--supply-pressure`` [Pa]; None without an oil (the supply options are then refused, as is a method other
    than J with an oil)."""

    oil = _oil_from_args(args, system)
    if oil is None:
        return None
    t_s = 363.15 if args.supply_temperature is None else args.supply_temperature
    t_s = check_temperature("--supply-temperature", t_s, T_MIN_K, oil.max_temperature_K)
    p_s = SUPPLY_PRESSURE_PA if args.supply_pressure is None else args.supply_pressure
    # (the feed holes against the system's rings, before any folder: the check ran inside the first balance)
    return check_oil_supply(OilSupply(oil, t_s, check_supply_pressure("--supply-pressure", p_s)),
                            bearings=system.bearings)


def _with_ring_capacity(args, supply):
    """``supply`` with ``--ring-heat-capacity`` [J/K] in its thermal model (refused without an oil)."""
    if args.ring_heat_capacity is None:
        return supply
    if supply is None:
        raise ParameterError("--ring-heat-capacity needs an oil: give --oil NAME or an [oil] table in --system")
    return OilSupply(supply.oil, supply.supply_temperature_K, supply.supply_pressure_Pa,
                     replace(supply.model, ring_heat_capacity_J_K=args.ring_heat_capacity))


def _supply_text(supply):
    """``"<oil>, supply <T> K, <p> Pa"`` of an OilSupply, for the console."""
    return f"{supply.oil.name}, supply {supply.supply_temperature_K:g} K, {supply.supply_pressure_Pa:g} Pa"


def _supply_from_args(args, oil):
    """Supply temperatures [K] (each checked against the oil's range) and pressure [Pa] of ``frb losses``."""

    text = _given(args.supply_temperature, "333.15,363.15,393.15")
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise ParameterError(f"--supply-temperature = {text!r} is invalid: give a temperature [K] or a comma list "
                             "(e.g. 333.15,363.15)") from None
    temps = [check_temperature("--supply-temperature", v, T_MIN_K, oil.max_temperature_K) for v in values]
    check_distinct(f"--supply-temperature = {text!r}", temps, "K")
    p_s = SUPPLY_PRESSURE_PA if args.supply_pressure is None else args.supply_pressure
    return temps, check_supply_pressure("--supply-pressure", p_s)


def cmd_losses(args):
    """Bearing journal torque, power loss and ring-speed ratio at the static equilibrium over speed (CSV + figure),
    optionally with the recorded losses of a run-up / co-simulation folder; with an oil (``--oil`` or the system
    file's) at the thermal operating point, with the film temperatures
    (:func:`frbmodel.linear.thermal.thermal_losses`)."""
    import matplotlib.pyplot as plt


    tc = load_from_args(args)
    oil = _oil_from_args(args, tc)
    if args.onsets and oil is None:
        raise ParameterError("--onsets needs an oil: give --oil NAME or an [oil] table in --system (the onsets are "
                             "computed at each supply temperature's thermal operating points)")
    ramp = _runup_ramp_from_args(args)
    if args.onsets and args.method != "J":
        raise ParameterError(f"--onsets cannot be combined with --method {args.method}: the onsets are those of the "
                             "thermal Campbell diagram of method J (the full ring torque balance); use --method J")
    temps, p_s = _supply_from_args(args, oil) if oil is not None else (None, None)
    if oil is not None:  # (the thermal model's feed holes against the rings: it ran inside the first balance)
        check_oil_supply(OilSupply(oil, temps[0], p_s), bearings=tc.bearings)
    speeds = parse_speeds(args.speeds)
    check_method_speeds("--speeds", args.speeds, speeds, [args.method])
    run = _same_system_run(args.run, tc) if args.run is not None else None
    out = writable_dir(args.out)
    if oil is None:
        table = with_ring_speed_ratio(bearing_losses(tc, speeds, args.method))
        stem, fig = f"bearing_losses_{args.method}", plot_bearing_losses(table, run,
                                                                          title=f"Bearing power loss, {tc.name}")
        cols = ["speed [rpm]", "bearing", "RSR [-]", "journal torque [N m]", "power loss [W]", "power loss inner [W]",
                "power loss outer [W]"]
    else:
        table = thermal_losses(tc, speeds, oil, temps, p_s, method=args.method)
        stem = "thermal_losses" if args.method == "J" else f"thermal_losses_{args.method}"
        fig = plot_thermal_losses(table, None if args.method == "J" else f"{oil.name}, supply {p_s:g} Pa, method "
                                  f"{args.method} (RSR: {METHODS[args.method].rsr})")
        cols = ["supply temperature [K]", "speed [rpm]", "bearing", "RSR [-]", "inner film temperature [K]",
                "outer film temperature [K]", "ring temperature [K]", "power loss [W]"]
    p_csv, p_png = out / f"{stem}.csv", out / f"{stem}.png"
    table.to_csv(p_csv, index=False)
    fig.savefig(p_png, dpi=130)
    plt.close(fig)
    print(table[cols].to_string(index=False, float_format=lambda x: f"{x:.5g}"))
    paths = [p_csv, p_png] + (_write_onsets(tc, oil, temps, p_s, speeds, out, ramp) if args.onsets else [])
    print("wrote:\n  " + "\n  ".join(str(p) for p in paths))
    print(f"results in {out.resolve()}")


def _same_system_run(folder, system, option="--run"):
    """The run of ``frb losses --run DIR`` (or of ``option``), refused if it was computed for another system than
    ``system`` (its losses were drawn beside curves they cannot be compared with)."""
    run = RunupResult.load(folder)
    theirs = {k: v for k, v in run.meta.get("system", {}).items() if k != "name"}
    ours = {k: v for k, v in system.to_dict().items() if k != "name"}
    if theirs and theirs != ours:
        diff = ", ".join(k for k in ours if theirs.get(k) != ours[k])
        raise ParameterError(f"{option} {folder}: the run was computed for another system (they differ in {diff}): "
                             "its records cannot be compared with these results; give the run's system (--system, "
                             f"--outer-clearance, --film-model) or leave {option} out")
    return run


def _runup_ramp_from_args(args):
    """``(start [rpm], end [rpm], time [s])`` of ``frb losses --runup-onsets`` (None without it); the flag needs
    ``--onsets``, the ramp options need the flag."""
    given = [o for o, v in (("--runup-speeds", args.runup_speeds), ("--runup-duration", args.runup_duration))
             if v is not None]
    if not args.runup_onsets:
        if given:
            raise ParameterError(f"{given[0]} needs --runup-onsets (the run-up beside the linear onsets)")
        return None
    if not args.onsets:
        raise ParameterError("--runup-onsets needs --onsets (the run-up onsets are drawn beside the linear ones)")
    text = _given(args.runup_speeds, "20000:250000")
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise ParameterError(f"--runup-speeds = {text!r} is invalid: give START:STOP [rpm], e.g. 20000:250000") \
            from None
    if not 0.0 < lo < hi <= 1e6:
        raise ParameterError(f"--runup-speeds = {text!r} is invalid: valid range 0 < START < STOP <= 1e6 rpm")
    duration = 1.0 if args.runup_duration is None else args.runup_duration  # (bounded by NUMERIC_OPTIONS)
    try:  # (before the thermal tables and the linear onsets: a 1e-9 s ramp was refused after them)
        check_output_rate(RUNUP_RATE_HZ, duration)
    except ParameterError as exc:
        raise ParameterError(f"--runup-duration = {duration:g} s: {exc}") from None
    return lo, hi, duration


def _write_onsets(tc, oil, temps, p_s, speeds, out, ramp=None):
    """``frb losses --onsets``: whirl onsets versus supply temperature (:func:`frbmodel.studies.thermal.
    onsets_vs_supply`, Campbell grid = ``--speeds``) as whirl_onsets.csv, whirl_onsets_modes.csv and the figure;
    with a ``ramp`` (start [rpm], end [rpm], time [s]) also one run-up per supply temperature
    (:func:`frbmodel.studies.thermal.runup_onsets_vs_supply`): whirl_onsets_runup.csv and squares in the figure."""
    import matplotlib.pyplot as plt


    films, modes = onsets_vs_supply(tc, oil, temps, p_s, speeds_rpm=speeds, progress=True)
    runups = None if ramp is None else runup_onsets_vs_supply(tc, oil, temps, p_s, speed_range_rpm=ramp[:2],
                                                              duration_s=ramp[2])
    paths = [out / "whirl_onsets.csv", out / "whirl_onsets_modes.csv", out / "whirl_onsets.png"]
    films.to_csv(paths[0], index=False)
    modes.to_csv(paths[1], index=False)
    if runups is not None:
        paths.append(out / "whirl_onsets_runup.csv")
        runups.to_csv(paths[-1], index=False)
    fig = plot_onsets_vs_supply(films, modes, runups=runups)
    fig.savefig(paths[2], dpi=130)
    plt.close(fig)
    print("film whirl onsets (exact, each at the temperatures of its speed):")
    cols = ["supply temperature [K]", "film", "onset [rpm]", "constant-viscosity onset [rpm]", "RSR at onset [-]",
            "film temperature at onset [K]"]
    print(films[cols].to_string(index=False, float_format=lambda x: f"{x:.5g}"))
    return paths


def cmd_warmup(args):
    """Compile (or load) the numba kernels once, with a progress bar (CI and images call it on purpose)."""

    wall = warmup(progress=True)
    print(f"numba kernels ready in {wall:.1f} s (cached next to the package: {warmup_marker().parent})")


#: commands that run compiled kernels (a first run compiles them: the CLI says so first)
KERNEL_COMMANDS = ("campbell", "equilibrium", "losses", "runup", "compare", "cosim", "linearize", "sweep",
                   "paper-figures", "unbalance")


def _first_run_notice(args):
    """On the first run after an install or an update, compile the kernels with a visible message and a bar; the
    system file (``--system``, with ``--outer-clearance`` / ``--film-model``), an SSP's path and an ``--oil`` name
    are checked before, so that a mistyped one is named at once, not after the ~40 s of compiling."""

    if args.command not in KERNEL_COMMANDS or kernels_ready():
        return
    if hasattr(args, "outer_clearance"):
        load_from_args(args)  # (read again by the command; milliseconds)
    if isinstance(getattr(args, "oil", None), str):
        OIL(args.oil)  # an unknown oil name
    if isinstance(getattr(args, "ssp", None), str) and not Path(args.ssp).exists():
        raise ParameterError(f"SSP = {args.ssp!r} does not exist")
    print("frb: compiling the numba kernels (first run only, ~40 s on 2 cores; `frb warmup` does it on purpose)",
          file=sys.stderr, flush=True)
    warmup(progress=True)


def cmd_build_fmus(args):
    """``frb build-fmus``: build the FMUs and the SSP into a folder."""

    find_source(args.src)  # a missing source tree is named before any --out folder is created
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise ParameterError(f"--out = {args.out!r} is not a writable folder: it is a file")
    writable_dir(args.out)  # (e.g. /proc/x: named here, not a FileNotFoundError from the build)
    build_fmus(args.out, args.src, rotor_file=args.rotor_file, linearization=args.linearization)
    print(f"results in {Path(args.out).resolve()}")


def cmd_cosim(args):
    """``frb cosim``: co-simulated run-up of an SSP system (rotor speed from the parameter set's ramp, a drive torque
    or a CSV speed profile), streamed to a folder, with figures; exit code."""

    if Path(args.ssp).exists() and is_system_ssp(args.ssp):
        return _cosim_system(args)
    if args.coupling_tol is not None and not args.adaptive:
        raise ParameterError(f"--coupling-tol {args.coupling_tol:g} applies only with --adaptive")
    tol = COUPLING_TOL if args.coupling_tol is None else args.coupling_tol  # (bounded by NUMERIC_OPTIONS)
    profile, overrides = None, {}
    if args.profile is not None:
        given = [f"{o} {v}" for o, v in (("--speed-source", args.speed_source), ("--drive-torque", args.drive_torque))
                 if v is not None]
        if given:
            raise ParameterError(f"--profile {args.profile} and {' / '.join(given)} are mutually exclusive: the "
                                 "profile prescribes the rotor speed (the rotor FMU's speed_in)")
        profile = SpeedProfile.from_csv(args.profile)
    else:
        source = args.speed_source or "ramp"
        overrides = {"rotor": {"speed_source": ("String", source)}}
        if source == "torque":
            overrides["rotor"]["drive_torque"] = ("Real", check_finite("--drive-torque", args.drive_torque or 0.0,
                                                                       "N m"))
        elif args.drive_torque is not None:
            raise ParameterError("--drive-torque applies only with --speed-source torque")
    _check_ssp(args.ssp, args.parameter_set)
    out = writable_dir(args.out)
    trace = (lambda line: print(line, file=sys.stderr)) if args.trace_fmi else None
    kw = dict(progress=True, rollback=args.rollback, unvalidated_step=args.unvalidated_step, overrides=overrides,
              profile=profile, adaptive=args.adaptive, tolerance=tol)
    if profile is not None:
        print(f"rotor speed: {profile.description}")
    run, code = _stoppable("cosim", lambda: cosimulate(
        args.ssp, args.parameter_set, args.stop_time, args.step, out, trace=trace, **kw), out)
    if "wall_time_s" in run.meta:
        m = run.meta
        steps = (f"adaptive macro step {m['shortest_step_s']:g} ... {m['longest_step_s']:g} s (tolerance "
                 f"{m['coupling_tol']:g}), {m['steps_taken']} steps taken, {m['rejected_steps']} rejected"
                 if m.get("adaptive") and m.get("steps_taken") else f"macro step {m['step_size_s']:g} s")
        print(f"wall time {m['wall_time_s']:.1f} s ({m['fmi_time_s'] / max(m['wall_time_s'], 1e-9):.0%} in FMI "
              f"calls), {steps}, {run.time.size} samples")
    kind = "run-up" if profile is None else RUN_TITLES.get(profile.direction, "run-up")
    _finish_run(args, run, lambda: system_from_meta(run.meta), out,
                title=f"co-simulated {kind} ({args.parameter_set})")
    if args.check_convergence and code == 0 and args.adaptive:
        m = run.meta  # the path defect is O(h³): tolerance / 8 asks for about half the step
        print(f"convergence check: the same co-simulation with half the longest step ({m['max_step_s'] / 2:g} s) "
              f"and the coupling tolerance / 8 ({tol / 8:g})")
        check_convergence(run, lambda folder: cosimulate(
            args.ssp, args.parameter_set, args.stop_time, args.step, folder,
            **{**kw, "tolerance": tol / 8, "max_step": m["max_step_s"] / 2}), out, "max step / 2, tolerance / 8",
            runner=_cli_runner)
    elif args.check_convergence and code == 0:
        h = run.meta["step_size_s"] / 2
        print(f"convergence check: the same co-simulation with half the macro step ({h:g} s)")
        check_convergence(run, lambda folder: cosimulate(
            args.ssp, args.parameter_set, args.stop_time, h, folder, **kw), out, "macro step / 2", runner=_cli_runner)
    return code


#: frb cosim options of the bearing + rotor split that a system with the turbocharger FMU has no use for
_SPLIT_ONLY = (("rollback", "--rollback"), ("speed_source", "--speed-source"), ("profile", "--profile"),
               ("drive_torque", "--drive-torque"), ("adaptive", "--adaptive"), ("coupling_tol", "--coupling-tol"),
               ("check_convergence", "--check-convergence"), ("unvalidated_step", "--unvalidated-step"))


def _check_ssp(path, parameter_set):
    """Read the SSP ``path`` (archive, SSD, FMUs, the parameter set) before any folder is made: a missing or
    broken SSP or an unknown set is a one-line error, with nothing written."""

    with read_ssp(path) as ssp:
        ssp.parameters(parameter_set)


def _cosim_system(args):
    """``frb cosim`` of an SSP with the turbocharger FMU (e.g. build/engine_turbocharger.ssp): the fixed-step
    Jacobi master, the FMU's own record at 20 kHz, the composite figures."""

    given = [opt for attr, opt in _SPLIT_ONLY if getattr(args, attr, None) not in (None, False)]
    if given:
        raise ParameterError(f"{' / '.join(given)} applies to the bearing + rotor split; {args.ssp} holds the "
                             "turbocharger FMU, which integrates itself with error control at any macro step (set its "
                             "speed_source and drive_torque in the SSP's parameter set)")
    _check_ssp(args.ssp, args.parameter_set)
    out = writable_dir(args.out)
    trace = (lambda line: print(line, file=sys.stderr)) if args.trace_fmi else None
    master = SystemMaster(args.ssp, args.parameter_set, args.stop_time, args.step, trace=trace)
    print(f"system {args.ssp} ({args.parameter_set}): fixed-step Jacobi master, macro step {master.step_size:g} s, "
          f"stop time {master.stop_time:g} s")
    run, code = _stoppable("cosim", lambda: master.run(out, progress=True), out)
    if run is None:
        return code
    m = run.meta
    print(f"wall time {m.get('wall_time_s', float('nan')):.1f} s "
          f"({m.get('fmi_time_s', 0) / max(m.get('wall_time_s', 1e-9), 1e-9):.0%} in FMI calls), "
          f"{m.get('master', {}).get('steps_taken', 0)} macro steps, {run.time.size} samples of the turbocharger's "
          "record")
    _finish_run(args, run, lambda: system_from_meta(run.meta), out,
                title=f"turbocharger FMU in {Path(args.ssp).name} ({args.parameter_set})")
    if not args.no_figure and run.time.size >= 2:
        import pandas as pd  # (heavy: only for the figure)

        fig = system_run_figure(run, pd.read_csv(out / "signals.csv"),
                                title=f"{Path(args.ssp).name} ({args.parameter_set}), frb cosim")
        fig.savefig(out / "system_run.png", dpi=130, bbox_inches="tight")
        print(f"wrote {(out / 'system_run.png').resolve()}")
    return code


def cmd_linearize(args):
    """``frb linearize``: global state matrix from the FMUs at one operating point; prints its modes."""

    _check_ssp(args.ssp, args.parameter_set)  # (--speed-rpm is bounded by NUMERIC_OPTIONS)
    out = writable_dir(args.out) if args.out is not None else None
    A, tc = linearize(args.ssp, args.speed_rpm, args.method, args.parameter_set)
    md = modes_from_state(A, A.shape[0] // 2)
    print(f"global A from the FMUs: {A.shape[0]} states, method {args.method.upper()} operating point at "
          f"{args.speed_rpm:.0f} rpm ({args.parameter_set})")
    print(f"{'f [Hz]':>10} {'damping [-]':>12} {'Re(lambda) [1/s]':>17} {'stability':>10}")
    for lam, st in zip(md.eigenvalues, md.stability):
        print(f"{lam.imag / (2 * np.pi):10.2f} {-lam.real / abs(lam):12.4f} {lam.real:17.2f} {st:>10}")
    if out is not None:
        p = out / f"A_{args.method.upper()}_{args.speed_rpm:.0f}rpm.csv"
        np.savetxt(p, A, delimiter=",", header=f"global state matrix A [SI], {A.shape[0]} states, method "
                   f"{args.method.upper()} at {args.speed_rpm:.0f} rpm, set {args.parameter_set}, SSP {args.ssp}")
        print(f"wrote {p.resolve()}")


#: ``frb sweep`` options that only some analyses take (given for another, they were ignored)
SWEEP_OPTIONS = {"methods": ("campbell",), "duration": ("runup", "cosim"), "max_points": ("bifurcation",),
                 "ssp": ("cosim",)}


def _sweep_params(items):
    """``{name: [values]}`` of the repeatable ``--param NAME=V1,V2,...`` (SI); a name given twice is refused (the
    second replaced the first)."""
    params = {}
    for item in items:
        try:
            name, vals = item.split("=", 1)
            values = [float(v) for v in vals.split(",")]
        except ValueError:
            raise ParameterError(f"--param {item!r} is invalid: use NAME=V1,V2,... with SI values") from None
        if name.strip() in params:
            raise ParameterError(f"--param {item!r}: {name.strip()} is given twice; give all its values in one "
                                 f"--param {name.strip()}=V1,V2,...")
        check_distinct(f"--param {item!r}", values)
        params[name.strip()] = values
    return params


def _sweep_cases(args):
    """The cases of ``frb sweep``: ``--example``, or the grid of ``--param`` with the analysis' options (an option
    the analysis has no use for is refused, naming the analyses that take it)."""
    options = ("param", "oil", "analysis", "methods", "speeds", "duration", "max_points", "ssp")
    if args.example:
        given = [f"--{n.replace('_', '-')}" for n in options if getattr(args, n) is not None]
        if given:
            raise ParameterError(f"{', '.join(given)} cannot be combined with --example {args.example}: the built-in "
                                 "study sets its own parameters and analyses (give --param NAME=V1,V2,... instead)")
        return example_cases(args.example)
    if not args.param:
        raise ParameterError("frb sweep needs --param NAME=V1,V2,... (or --example outer-clearance)")
    params = _sweep_params(args.param)
    analysis = args.analysis or "campbell"
    for name, takers in SWEEP_OPTIONS.items():
        if getattr(args, name) is not None and analysis not in takers:
            raise ParameterError(f"--{name.replace('_', '-')} cannot apply to --analysis {analysis}: it is an option "
                                 f"of --analysis {' / '.join(takers)}")
    if analysis == "campbell":
        speeds = parse_speeds(_given(args.speeds, "1000:250000:200"))
        methods = [m.strip().upper() for m in _given(args.methods, "J").split(",")]
        if len(set(methods)) < len(methods):  # (every case computed a diagram twice)
            raise ParameterError(f"--methods {args.methods} repeats a method: give each method once")
        opts = {"methods": methods,
                "speeds_rpm": (float(speeds[0]), float(speeds[-1]), int(speeds.size))}
    else:
        opts = {"speed_rpm": _speed_pair(_given(args.speeds, "1000:250000"))}
        if analysis in ("runup", "cosim"):
            opts["duration"] = 2.0 if args.duration is None else args.duration
        if analysis == "bifurcation":
            opts["max_points"] = 25 if args.max_points is None else args.max_points
        if analysis == "cosim":
            if not args.ssp:
                raise ParameterError("--analysis cosim needs --ssp build/turbocharger.ssp (frb build-fmus)")
            opts["ssp"] = str(Path(args.ssp).resolve())
    if args.oil is not None:
        opts["oil"] = args.oil
    return grid(params, analysis, **opts)


def cmd_sweep(args):
    """``frb sweep``: parameter study (on Dask or serial) and its stability map; exit code 4 if a case failed."""

    cases = _sweep_cases(args)
    if args.workers is not None and (args.serial or args.scheduler):
        raise ParameterError(f"--workers {args.workers} cannot be combined with "
                             f"{'--serial' if args.serial else '--scheduler'}: it sets the processes of the "
                             "LocalCluster frb sweep starts itself")
    scheduler = "serial" if args.serial else args.scheduler
    check_scheduler(scheduler)  # (before the folder is made: a wrong address leaves nothing behind)
    writable_dir(args.out, claim=False)  # (a study resumes in its folder: its index owns it)
    interrupted = None
    try:
        idx = run_study(cases, args.out, scheduler=scheduler, n_workers=args.workers,
                        retry_failed=args.retry_failed, progress=True)
    except KeyboardInterrupt as exc:  # finished cases are on disk: index them and draw the map from them
        interrupted = exc
        idx = write_index(cases, Path(args.out))
        print(f"\nfrb sweep: interrupted ({'SIGTERM' if isinstance(exc, Terminated) else 'Ctrl-C'}); the finished "
              "cases are kept, the same command resumes the study", file=sys.stderr)
    paths = plot_stability_map(args.out)
    sm = stability_map(args.out)
    n_fail = int((idx["status"] == "failed").sum())
    print(f"{int((idx['status'] == 'finished').sum())} finished, {n_fail} failed, "
          f"{int((idx['status'] == 'pending').sum())} pending of {len(idx)} cases")
    if len(sm):
        cols = [c for c in sm.columns if c.split(" [")[0] in PARAMETERS]
        print(sm[cols + ["method", "item", "onset [rpm]", "f at onset [Hz]"]].sort_values(cols + ["method", "item"])
              .to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print("wrote:\n  " + "\n  ".join(str(p) for p in [Path(args.out) / "index.csv", *paths]))
    print(f"results in {Path(args.out).resolve()}")
    if interrupted is not None:
        return 143 if isinstance(interrupted, Terminated) else 130
    return 4 if n_fail else 0


class _Formatter(argparse.HelpFormatter):
    """Help with the defaults shown (where there is one and the help text does not state it)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if action.default not in (None, False, argparse.SUPPRESS) and "default" not in text:
            text += " (default: %(default)s)"
        return text


def _add_campbell(sub):

    c = sub.add_parser("campbell", formatter_class=_Formatter,
                       help="holistic Campbell diagram for one method (CSV + PNG + HTML)")
    c.add_argument("--method", default="J", type=str.upper, choices=list(METHODS), help="bearing model (Table 1)")
    c.add_argument("--speeds", default="10000:250000:100", metavar="GRID",
                   help="speed grid [rpm]: START:STOP:COUNT or a comma list")
    c.add_argument("--out", default="results/campbell", help="output folder")
    c.add_argument("--fmax", type=float, default=None, help="upper frequency limit of the plots [Hz]")
    c.add_argument("--no-whirl", action="store_true", help="skip the film whirl curves")
    c.add_argument("--mode-shapes", metavar="SPEED", type=float, default=None,
                   help="also write mode_shapes_<method>_<rpm>.png/.html/.csv: the shapes of the modes at SPEED "
                        "[rpm] (below --fmax if given)")
    _spring_args(c)
    c.add_argument("--from-fmu", metavar="SSP", default=None,
                   help="assemble the linear system from the FMUs of this SSP (methods F, G, I, J)")
    c.add_argument("--parameter-set", default=None, help="SSP parameter set for --from-fmu (default co36)")
    _oil_args(c, "every speed at its thermal operating point (film viscosities, whirl curves, exact onsets)")
    _system_args(c)
    c.set_defaults(func=cmd_campbell)


def _add_unbalance(sub):
    u = sub.add_parser("unbalance", formatter_class=_Formatter,
                       help="unbalance response (Bode, polar, film orbits) and critical speeds (CSV + PNG + HTML)")
    u.add_argument("--method", default="J", type=str.upper,
                   help="bearing model (Table 1: A B C D E F G I J), or a comma list such as A,J for one Bode figure "
                        "of all")
    u.add_argument("--speeds", default="1000:250000:200", metavar="GRID",
                   help="speed grid [rpm]: START:STOP:COUNT or a comma list")
    u.add_argument("--unbalance", action="append", metavar="DISC:KGM[:RAD]",
                   help="unbalance of a wheel, e.g. turbine_wheel:1e-6:0 (repeatable; default turbine_wheel:1e-6:0)")
    u.add_argument("--locations", default=None, metavar="NAMES",
                   help="comma list of the locations drawn and searched for peaks (default: the wheels), e.g. "
                        "'turbine_wheel,turbine journal'")
    _spring_args(u)
    _oil_args(u, "every speed, its 1X crossings and response peaks at their own thermal operating point")
    u.add_argument("--out", default="results/unbalance", help="output folder")
    _system_args(u)
    u.set_defaults(func=cmd_unbalance)


def _add_bifurcation(sub):
    b = sub.add_parser("bifurcation", formatter_class=_Formatter,
                       help="Hopf points, limit-cycle branches vs speed (continuation), bifurcation diagram")
    b.add_argument("--speeds", default="1000:250000", metavar="RANGE", help="speed range [rpm]: START:END")
    b.add_argument("--start", default=None,
                   help="'hopf' (default): a branch from each Hopf point in the range; or a speed [rpm]: the branch "
                        "through the orbit the whirl settles on there (both directions); or a comma-separated list "
                        "of these (e.g. 25000,60000)")
    b.add_argument("--max-points", type=int, default=None, help="points per branch and direction at most (default 40)")
    b.add_argument("--segments", type=int, default=None,
                   help="shooting segments per orbit (multiple shooting, e.g. 4, for strongly unstable branches; "
                        "default 1)")
    b.add_argument("--runs", default=None, metavar="DIR[,DIR]",
                   help="run-up / run-down folders whose turbine-wheel orbit envelopes are drawn behind the branches "
                        "(and the first one's spectrogram behind the branch frequencies)")
    b.add_argument("--hopf-only", action="store_true", help="only list the Hopf points")
    b.add_argument("--out", default="results/bifurcation", help="output folder")
    _system_args(b)
    _oil_args(b, "every speed of the Hopf points and the branches at its thermal operating point (quasi-static "
                 "temperatures)")
    b.set_defaults(func=cmd_bifurcation)


def _add_equilibrium(sub):

    e = sub.add_parser("equilibrium", formatter_class=_Formatter,
                       help="static equilibrium of both bearings (methods C, D, F, G, I, J)")
    e.add_argument("--method", default="J", type=str.upper, choices=list(METHODS), help="bearing model (Table 1)")
    e.add_argument("--speed-rpm", type=float, default=150e3, help="rotor speed [rpm]")
    e.add_argument("--out", default=None, help="also write a CSV into this folder")
    _oil_args(e, "the films' viscosities at the thermal operating point of --speed-rpm")
    _system_args(e)
    e.set_defaults(func=cmd_equilibrium)


def _add_system(sub):
    s = sub.add_parser("system", formatter_class=_Formatter,
                       help="write the system description (default: Table 2) to a .toml/.json file")
    s.add_argument("--out", default="turbocharger.toml")
    _system_args(s)
    s.set_defaults(func=cmd_system)


def _add_runup(sub):

    r = sub.add_parser("runup", formatter_class=_Formatter,
                       help="nonlinear run-up (monolithic reference) + spectrogram composite figures")
    r.add_argument("--speeds", default=None, metavar="RANGE",
                   help=f"speed range [rpm]: START:END (up-down: START:TOP; constant: the speed, torque: the start "
                        f"speed; default {RUNUP_SPEEDS})")
    r.add_argument("--duration", type=float, default=None,
                   help="simulated time [s] (default: 1; with a CSV profile its last time)")
    r.add_argument("--profile", type=_profile_arg, default="ramp", metavar="{" + ",".join(PROFILES) + "}|FILE.csv",
                   help="speed profile; 'up-down': START -> TOP -> START, half the duration each way; 'torque': the "
                        "spin is a state driven by --drive-torque and braked by the films (starts at START of "
                        "--speeds); FILE.csv: header 'time [s], speed [rpm]', one row per point from t = 0, the speed "
                        "linear in between (without --speeds)")
    r.add_argument("--drive-torque", type=float, default=None,
                   help="net drive torque about +z [N m] (--profile torque; default 0: the films brake the rotor)")
    r.add_argument("--unbalance", action="append", metavar="DISC:KGM[:RAD]",
                   help="unbalance of a wheel, e.g. turbine_wheel:1e-6:0 (repeatable)")
    r.add_argument("--rate", type=float, default=20e3, help="output sampling rate [Hz]")
    r.add_argument("--rtol", type=float, default=DEFAULT_RTOL, help="integrator relative tolerance [-]")
    r.add_argument("--atol", type=float, default=DEFAULT_ATOL_M,
                   help="integrator absolute tolerance on displacements [m]")
    r.add_argument("--integrator", choices=INTEGRATORS, default=INTEGRATORS[0],
                   help="'rodas': compiled Rosenbrock method (rotor Jacobian exact, film columns by differences); "
                        "'radau': compiled Radau IIA (CyRK); 'lsoda': scipy's LSODA calling the compiled right-hand "
                        "side from Python (the former path, slowest)")
    r.add_argument("--check-convergence", action="store_true",
                   help="rerun with rtol and atol tightened tenfold and label the onsets that move by > 1 %% as seeded "
                        "by round-off")
    r.add_argument("--no-figure", action="store_true")
    r.add_argument("--out", default="results/runup")
    _oil_args(r, "the films' viscosities follow the rotor speed (quasi-static temperatures of the thermal operating "
                 "points; torque-driven: a table up to the speed the drive could reach)")
    r.add_argument("--ring-heat-capacity", type=float, default=None, metavar="J/K",
                   help="m_R c_R of each ring [J/K] (e.g. 2.736: 7.2 g of bronze): the rings' temperatures as states "
                        "that lag the speed (ramps and exponential profiles; needs an oil); default: quasi-static")
    _system_args(r)
    r.set_defaults(func=cmd_runup)


def _add_compare(sub):
    m = sub.add_parser("compare", formatter_class=_Formatter,
                       help="run-ups vs method-J stability per outer clearance (Figs. 12-14 + table)")
    m.add_argument("--clearances", default=",".join(f"{c * 1e6:g}e-6" for c in PAPER_OUTER_CLEARANCES),
                   help="outer clearances [m], comma list")
    m.add_argument("--speeds", default="1000:250000", metavar="RANGE", help="speed range [rpm]: START:END")
    m.add_argument("--duration", type=float, default=4.0, help="simulated time per run-up [s]")
    m.add_argument("--profile", choices=["ramp", "exponential"], default="exponential")
    m.add_argument("--fmax", type=float, default=1000.0, help="upper frequency of the figures [Hz]")
    m.add_argument("--out", default="results/compare")
    _system_args(m)
    m.add_argument("--check-convergence", action="store_true",
                   help="rerun each case with rtol and atol tightened tenfold; label onsets that move by > 1 %% as "
                        "seeded by round-off (doubles the time)")
    m.set_defaults(func=cmd_compare)


def _add_build_fmus(sub):
    bf = sub.add_parser("build-fmus", formatter_class=_Formatter,
                       help="build the turbocharger FMU, the bearing and rotor FMUs, and pack build/turbocharger.ssp")
    bf.add_argument("--out", default="build", help="output folder")
    bf.add_argument("--src", default=None, help="folder holding fmu_src/ and ssp/ (default: this checkout, else the "
                    "copies shipped in the installed package)")
    bf.add_argument("--rotor-file", default=None, metavar="FILE",
                    help="system file (frb system) the rotor FMU is built for: its discs, bearings and node count "
                         "define the rotor and turbocharger FMUs' variables (default: Table 2)")
    bf.add_argument("--linearization", action="store_true",
                    help="give the bearing and rotor FMUs their linearization outputs (nx, nu, ny, A_i_j ... D_i_j) "
                         "for frb linearize, which otherwise builds this variant itself")
    bf.set_defaults(func=cmd_build_fmus)


def _add_cosim(sub):
    cs = sub.add_parser("cosim", formatter_class=_Formatter,
                       help="co-simulated run-up of an SSP system (fmpy master)")
    cs.add_argument("ssp", help=".ssp archive or folder (see frb build-fmus)")
    cs.add_argument("--parameter-set", default="co36", help="co36, co40, co42 or co46")
    cs.add_argument("--stop-time", type=float, default=None,
                    help="simulated time [s] (default: from the SSP; with --profile the table's last time)")
    cs.add_argument("--step", type=float, default=None, help="macro step [s] (default: from the SSP, 1e-5)")
    cs.add_argument("--rollback", action="store_true",
                    help="retry discarded steps with half steps (the fixed macro step; --adaptive retries by itself)")
    cs.add_argument("--speed-source", choices=["ramp", "torque"], default=None,
                    help="rotor speed: the parameter set's ramp (default), or a state driven by --drive-torque and "
                         "braked by the bearings' film torques (starts at the set's speed_start)")
    cs.add_argument("--profile", default=None, metavar="FILE.csv",
                    help="rotor speed from a CSV table 'time [s], speed [rpm]' (linear in between) through the rotor "
                         "FMU's speed_in; excludes --speed-source and --drive-torque; the stop time defaults to the "
                         "table's last time")
    cs.add_argument("--drive-torque", type=float, default=None,
                    help="net drive torque about +z [N m] for --speed-source torque (default 0: the bearings brake "
                         "the rotor)")
    cs.add_argument("--adaptive", action="store_true",
                    help="error-controlled macro step: steps whose journal path defect exceeds --coupling-tol are "
                         "rolled back and retried shorter, quiet phases grow the step (up to 12.5 us); outputs at "
                         "the fixed output times")
    cs.add_argument("--coupling-tol", type=float, default=None, metavar="X",
                    help="--adaptive: largest journal path defect per macro step as a fraction of the inner "
                         "clearance (default: 2e-4)")
    cs.add_argument("--check-convergence", action="store_true",
                    help="rerun with half the macro step (--adaptive: half the longest step and the tolerance / 8) "
                         "and label the onsets that move by > 1 %% as not converged")
    cs.add_argument("--unvalidated-step", action="store_true",
                    help="allow a macro step outside the validated range 1e-7 ... 2e-5 s")
    cs.add_argument("--trace-fmi", action="store_true",
                    help="print every FMI call with its arguments and status, and every message the FMUs log")
    cs.add_argument("--no-figure", action="store_true")
    cs.add_argument("--out", default="results/cosim")
    cs.set_defaults(func=cmd_cosim)


def _add_linearize(sub):
    li = sub.add_parser("linearize", formatter_class=_Formatter,
                       help="global A matrix and modes from the FMUs' linearization mode")
    li.add_argument("ssp")
    li.add_argument("--speed-rpm", type=float, default=150e3)
    li.add_argument("--method", default="J", type=str.upper, choices=list("FGIJ"), help="operating point method")
    li.add_argument("--parameter-set", default="co36")
    li.add_argument("--out", default=None, help="write A as CSV into this folder")
    li.set_defaults(func=cmd_linearize)


def _add_sweep(sub):
    sw = sub.add_parser("sweep", formatter_class=_Formatter,
                       help="parameter study on Dask (stability map over clearance, viscosity, ...)")
    sw.add_argument("--example", choices=["outer-clearance"], help="built-in study: outer clearance 36-46 um")
    sw.add_argument("--param", action="append", metavar="NAME=V1,V2",
                    help="swept parameter (repeatable; SI): outer_clearance, inner_clearance, viscosity_turbine, "
                         "viscosity_compressor, viscosity_scale, ring_mass, unbalance_turbine, unbalance_compressor, "
                         "supply_temperature [K], supply_pressure [Pa] (these two with --oil)")
    sw.add_argument("--oil", default=None, metavar="NAME",
                    help="thermal model with this oil (SAE 0W-20, SAE 5W-30, SAE 10W-40, SAE 15W-40, ISO VG 46): "
                         "every case at its supply temperature (default 363.15 K) and pressure (3e5 Pa); campbell "
                         "(film methods), runup, hopf and bifurcation")
    sw.add_argument("--analysis", choices=["campbell", "runup", "cosim", "hopf", "bifurcation"], default=None,
                    help="'campbell' (default): the Campbell diagrams' onsets; 'hopf': the Hopf points of the full "
                         "model (linear onsets) in --speeds START:END; two swept "
                         "parameters give a stability chart; 'bifurcation': the limit-cycle branches from those Hopf "
                         "points (each case's diagram in cases/<id>/, its bifurcation points in the map)")
    sw.add_argument("--max-points", type=int, default=None,
                    help="bifurcation: points per branch and direction (default 25)")
    sw.add_argument("--methods", default=None, help="campbell: methods, comma list (default J)")
    sw.add_argument("--speeds", default=None, metavar="GRID|RANGE",
                    help="campbell: START:STOP:COUNT (default 1000:250000:200); the other analyses: START:END "
                         "(default 1000:250000) [rpm]")
    sw.add_argument("--duration", type=float, default=None, help="runup, cosim: simulated time [s] (default 2)")
    sw.add_argument("--ssp", default=None, help="SSP for --analysis cosim")
    sw.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler (tcp://host:port)")
    sw.add_argument("--workers", type=int, default=None, help="LocalCluster worker processes (default: cores)")
    sw.add_argument("--serial", action="store_true", help="run in this process without Dask")
    sw.add_argument("--retry-failed", action="store_true", help="rerun cases that failed before")
    sw.add_argument("--out", default="results/sweep")
    sw.set_defaults(func=cmd_sweep)


def _add_paper_figures(sub):
    f = sub.add_parser("paper-figures", formatter_class=_Formatter,
                       help="regenerate the paper's linear figures 4-11")
    f.add_argument("--out", default="results/paper-figures")
    f.add_argument("--n-speeds", type=int, default=100, help="speeds per Campbell diagram")
    _system_args(f)
    f.set_defaults(func=cmd_paper_figures)


def _add_losses(sub):

    lo = sub.add_parser("losses", formatter_class=_Formatter,
                        help="bearing journal torque, power loss and RSR vs speed; with --oil the film temperatures "
                             "(CSV + PNG)")
    lo.add_argument("--speeds", default="10000:250000:49", metavar="GRID",
                    help="speed grid [rpm]: START:STOP:COUNT or a comma list")
    lo.add_argument("--method", default="J", type=str.upper, choices=[m for m in METHODS if m in "CDFGIJ"],
                    help="equilibrium method")
    lo.add_argument("--run", default=None, metavar="DIR", help="overlay the recorded losses of this run-up folder")
    lo.add_argument("--oil", default=None, metavar="NAME",
                    help="thermal operating point with this oil (SAE 0W-20, SAE 5W-30, SAE 10W-40, SAE 15W-40, "
                         "ISO VG 46; or an [oil] table in --system): film temperatures, viscosities, RSR, losses")
    lo.add_argument("--supply-temperature", default=None, metavar="K",
                    help="oil supply temperature(s) [K], one value or a comma list (default 333.15,363.15,393.15; "
                         "needs an oil)")
    lo.add_argument("--supply-pressure", type=float, default=None, metavar="PA",
                    help="oil supply pressure above ambient [Pa] (default 3e5; needs an oil)")
    lo.add_argument("--onsets", action="store_true",
                    help="with an oil, also the whirl onset speeds versus the supply temperature(s): each film's exact "
                         "onset and the Campbell modes' (grid = --speeds): whirl_onsets.csv, _modes.csv, .png")
    lo.add_argument("--runup-onsets", action="store_true",
                    help="with --onsets, also one run-up per supply temperature (quasi-static film temperatures) "
                         "and its sub-synchronous components' onsets [rpm] beside the linear ones: "
                         "whirl_onsets_runup.csv")
    lo.add_argument("--runup-speeds", default=None, metavar="START:STOP",
                    help="ramp of --runup-onsets [rpm] (default 20000:250000, the main job's)")
    lo.add_argument("--runup-duration", type=float, default=None, metavar="S",
                    help="ramp time of --runup-onsets [s] (default 1)")
    lo.add_argument("--out", default="results/losses", help="output folder")
    _system_args(lo)
    lo.set_defaults(func=cmd_losses)


def _add_warmup(sub):
    w = sub.add_parser("warmup", formatter_class=_Formatter,
                       help="compile the numba kernels once (first run only; for CI and container images)")
    w.set_defaults(func=cmd_warmup)


def _add_plot(sub):
    pl = sub.add_parser("plot", formatter_class=_Formatter,
                        help="re-render the figures of a run-up / co-simulation or unbalance-response results folder")
    pl.add_argument("dir", help="folder with runup.csv and runup.json, or with the unbalance_<M>.json/_dofs.csv files "
                                "of frb unbalance (then the Bode, polar and film-orbit figures are redrawn), or with "
                                "the branch.nc of frb bifurcation (then the diagram)")
    pl.add_argument("--xscale", choices=["linear", "log"], default=None, help="speed axis scale (default linear)")
    pl.add_argument("--orbits", metavar="SPEEDS", default=None,
                    help="also write orbits_<rpm>.png/.html/.csv/.nc at these speeds [rpm] (comma list or "
                         "start:stop:count; ± --revolutions about each): journal in ring, ring in housing (µm and ε), "
                         "wheels")
    pl.add_argument("--revolutions", type=float, default=None,
                    help="half-width of the --orbits windows in rotor revolutions (default 20)")
    pl.add_argument("--orbit-times", metavar="T0:T1", default=None,
                    help="also write orbits_t<t0>-<t1>s.png/.html/.csv/.nc over these time windows [s] (comma list), "
                         "e.g. the settled end of a constant-speed run")
    pl.add_argument("--waterfall", action="store_true",
                    help="also write the 3-D waterfall waterfall_<disc>.png/.html (amplitude in µm, order lines)")
    pl.add_argument("--orders", metavar="K", default=None,
                    help=f"order lines k × rotor frequency drawn on the spectrograms and waterfalls (comma list, "
                         f"e.g. 0.5,1,2; 'none' for none; default {DEFAULT_ORDERS})")
    pl.add_argument("--locations", default=None,
                    help="unbalance folders: locations drawn, comma list (default: the discs)")
    pl.add_argument("--runs", default=None, metavar="DIR[,DIR]",
                    help="bifurcation folders: run-up / run-down folders whose envelopes (and the first's "
                         "spectrogram) are drawn behind the branches")
    pl.set_defaults(func=cmd_plot)


def build_parser():
    """The ``frb`` argument parser with all subcommands.

    Returns
    -------
    argparse.ArgumentParser

    Examples
    --------
    >>> args = build_parser().parse_args(["runup", "--speeds", "250000:20000", "--duration", "2"])
    >>> args.command, args.speeds, args.duration, args.func.__name__
    ('runup', '250000:20000', 2.0, 'cmd_runup')
    """

    p = argparse.ArgumentParser(prog="frb", description="Rotordynamics of turbochargers on floating-ring bearings "
                                "(SI units inside; speeds on the command line in rpm).")
    p.add_argument("--version", action="version", version=f"frbmodel {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    _add_campbell(sub)
    _add_equilibrium(sub)
    _add_unbalance(sub)
    _add_system(sub)
    _add_runup(sub)
    _add_compare(sub)
    _add_build_fmus(sub)
    _add_cosim(sub)
    _add_linearize(sub)
    _add_sweep(sub)
    _add_paper_figures(sub)
    _add_plot(sub)
    _add_warmup(sub)
    _add_losses(sub)
    _add_bifurcation(sub)
    for name in HTML_COMMANDS:
        _html_arg(sub.choices[name])
    return p


#: the commands that write interactive HTML pages (they take ``--html``)
HTML_COMMANDS = ("campbell", "unbalance", "bifurcation", "runup", "compare", "cosim", "sweep", "plot")
#: ``--html`` choices: how the pages get plotly.js (:func:`frbmodel.plots.figures.write_html`)
HTML_MODES = {"folder": "directory", "self-contained": True}


def _html_arg(p):
    p.add_argument("--html", choices=list(HTML_MODES), default=None,
                   help="interactive pages: 'folder' (default) loads plotly.js from the one plotly.min.js written "
                        "beside them (small pages; copy the folder as a whole), 'self-contained' embeds it in every "
                        "page (+4.8 MB each; a page opens alone, e.g. mailed)")


def _html_mode(args):
    """How the command's pages get plotly.js (``--html``, :data:`HTML_MODES`); ``--html`` with ``--no-figure`` is
    refused (no page is written)."""
    mode = getattr(args, "html", None)
    if mode is not None and getattr(args, "no_figure", False):
        raise ParameterError(f"--html {mode} applies to the figures: with --no-figure no page is written")
    return HTML_MODES[mode or "folder"]


#: optional packages and the extra that installs them
EXTRAS = {"fmpy": "fmi", "pythonfmu": "fmi", "libcosimpy": "fmi", "dask": "dist", "distributed": "dist"}


def main(argv=None):
    """Entry point of ``frb``: parse the arguments, run the command and turn errors into exit codes.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code: 0 success, 2 bad input or a missing optional package (message on stderr), 3 a run stopped early
        (results kept), 4 a study with failed cases, 130 Ctrl-C, 143 SIGTERM.

    Notes
    -----
    Installs a SIGTERM handler (SIGTERM ends a run like Ctrl-C, keeping its results) and sets ``MPLBACKEND=Agg``
    unless set, so it is meant to be called once per process, as the ``frb`` script does.
    """
    import os
    import signal

    os.environ.setdefault("MPLBACKEND", "Agg")  # figures are written to files; the library never sets a backend
    args = build_parser().parse_args(argv)
    signal.signal(signal.SIGTERM, _on_sigterm)
    _COMMAND[:] = ["frb", *(sys.argv[1:] if argv is None else argv)]
    code = None
    try:
        code = _dispatch(args)
    finally:
        _finish_claims(code)
    return code


#: manifest status of a results folder by the command's exit code (None: an exception escaped)
CLAIM_STATUS = {0: "finished", 2: "refused", 3: "stopped", 4: "finished with failed cases", 130: "interrupted",
                143: "interrupted"}


def _finish_claims(code):
    """Write the manifests of the folders the command claimed (:func:`writable_dir`), with its outcome."""
    while _CLAIMS:
        c = _CLAIMS.pop()
        try:
            c.finish(CLAIM_STATUS.get(code, "failed"))
            if c.removed:
                print(f"removed {len(c.removed)} files of the previous run in {c.folder} that this one did not write "
                      "again (its frb_manifest.json listed them; files it did not write are kept)")
        except OSError as exc:  # (the folder was removed or made read-only meanwhile: the results still stand)
            print(f"frb: could not write {c.folder / 'frb_manifest.json'}: {exc.strerror or exc}", file=sys.stderr)


#: every numeric option of every command, by its argparse dest: (unit, valid range). A range is (lowest, highest):
#: floats must be finite and > lowest (and <= highest), integers >= lowest (and <= highest); None: no bound. A bound
#: that is a library constant is that constant, so the CLI and the API refuse the same values. A string names the
#: check that bounds the option where its range depends on the system or on other options (it runs inside the
#: command, before any work). :func:`check_numeric_options` applies the ranges before a command runs; a test requires
#: every float or int option of the parser to be listed here.
NUMERIC_OPTIONS = {
    "atol": ("m", "frbmodel.nonlinear.runup.check_tolerances (<= 1e-3 of the smallest film clearance)"),
    "rtol": ("-", "frbmodel.nonlinear.runup.check_tolerances (RTOL_RANGE)"),
    # (a fraction of the inner clearance per macro step: the run-up's atol bound, and on the main job the path defect
    # of the longest validated step, 20 us; a larger one asks for steps the step cap overrides: 10 had no effect)
    "coupling_tol": ("-", (0.0, MAX_COUPLING_TOL)),
    "drive_torque": ("N m", "frbmodel.nonlinear.runup.check_drive_torque (|T| <= J_p * 1e6 rpm / 1 ms)"),
    "duration": ("s", (0.0, None)),
    "fmax": ("Hz", (0.0, None)),
    # (MAX_SPRING_N_M: rigid supports there; stiffer springs lose the modes to round-off, 1e40 gave wrong ones)
    "k": ("N/m", (0.0, MAX_SPRING_N_M)),
    "kx": ("N/m", (0.0, MAX_SPRING_N_M)),
    "ky": ("N/m", (0.0, MAX_SPRING_N_M)),
    "max_points": ("-", (2, MAX_BRANCH_POINTS)),  # (the speed-grid bound: a branch's points are its diagram's speeds)
    "mode_shapes": ("rpm", "speed"),
    "n_speeds": ("-", (2, 10000)),  # (MAX_SPEED_COUNT: 1e8 speeds started a run of days)
    "outer_clearance": ("m", "the system's film checks (clearance / radius, roughness)"),
    "rate": ("Hz", "frbmodel.nonlinear.runup.check_output_rate (samples of the run)"),
    "revolutions": ("revolutions", (0.0, None)),
    "runup_duration": ("s", (0.0, None)),
    "segments": ("-", (1, MAX_SEGMENTS)),  # (4 serve strongly unstable branches; 1e6 held a million states per orbit)
    "speed_rpm": ("rpm", "speed"),
    "step": ("s", (0.0, None)),
    "stop_time": ("s", (0.0, None)),
    "supply_pressure": ("Pa", "frbmodel.linear.thermal.check_supply_pressure"),
    "ring_heat_capacity": ("J/K", (0.0, None)),
    "supply_temperature": ("K", "frbmodel.system.oil.check_temperature (the oil's range)"),
    "workers": ("-", (1, 256)),  # (the LocalCluster's processes: 100000 would have been started)
}


def check_numeric_options(args):
    """Refuse a numeric option outside its range of :data:`NUMERIC_OPTIONS` (one line naming the option, its value
    and the valid range), before the command starts."""

    for dest, (unit, rng) in NUMERIC_OPTIONS.items():
        value = getattr(args, dest, None)
        if value is None or isinstance(rng, str) and rng != "speed":
            continue
        option = "--" + dest.replace("_", "-")
        if rng == "speed":
            check_speed(option, check_positive(option, value, unit))
        elif isinstance(rng[0], int):
            if value < rng[0] or (rng[1] is not None and value > rng[1]):
                raise ParameterError(f"{option} = {value} is invalid: valid range >= {rng[0]}"
                                     + (f" and <= {rng[1]}" if rng[1] is not None else ""))
        else:
            v = check_positive(option, value, "" if unit == "-" else unit)
            if rng[1] is not None and v > rng[1]:
                shown = "" if unit == "-" else f" {unit}"
                raise ParameterError(f"{option} = {value!r}{shown} is invalid: valid range is finite and > {rng[0]:g} "
                                     f"and <= {rng[1]:g}{shown}")


def _dispatch(args):
    """Run the parsed command; its exit code (errors become messages and codes)."""
    try:
        check_numeric_options(args)  # (before the first-run notice and any folder)
        mode = _html_mode(args)
        _first_run_notice(args)
        with html_plotlyjs(mode):
            return args.func(args) or 0
    except FRBError as exc:
        print(f"frb {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as exc:
        top = (exc.name or "").split(".")[0]
        if top not in EXTRAS:
            raise
        print(f"frb {args.command}: error: this command needs the optional package {top!r}, which is not installed: "
              f"python -m pip install \"frbmodel[{EXTRAS[top]}]\" (or .[{EXTRAS[top]}] in a checkout)", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head` etc.: not an error of the computation
        sys.stderr.close()
        return 0
    except KeyboardInterrupt as exc:  # outside a long run: nothing to keep
        code = 143 if isinstance(exc, Terminated) else 130
        print(f"\nfrb {args.command}: interrupted", file=sys.stderr)
        return code


if __name__ == "__main__":
    sys.exit(main())
