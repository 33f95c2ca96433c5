"""Benchmark of the FMI co-simulation (issues #4, #13 item 2): the main job's run-up monolithically, co-simulated at
the fixed 10 µs macro step and with the error-controlled (adaptive) step, in the same process.

Usage::

    python benchmarks/cosim.py [--duration 1.0] [--build build] [--unbalance 0] [--no-monolithic]

Builds the FMUs if needed, warms up (numba kernels, FMU extraction), then runs the 20k -> 250k rpm run-up at
c_o = 36 um (the SSP's co36 parameter set: method-J equilibrium start with the 5 % offset) and prints

* wall times and the ratio co-simulation / monolithic (issue #13 target <= 1.5);
* per macro step [ms]: total; inside FMI calls, per FMI function (doStep, getReal, setReal, the FMU state calls of
  the adaptive rollback); of that the FMI traffic, i.e. the calls' own cost: the number of calls times the cost of
  a call that moves one value and computes nothing (measured here on the same FMUs; a lower bound, since the
  per-value handling of the ~80 values per step is not in it), and the rest of the FMI time, the physics inside
  the FMUs (ring and rotor integration, film forces evaluated for the outputs, plus that per-value handling);
  outside FMI calls (the master's Python: exchange bookkeeping, error estimate, recorder);
* fixed vs adaptive: steps taken and rejected, the onsets of every sub-synchronous component at the turbine
  wheel and their differences (issue #13 acceptance: every onset within 1 %, fewer steps).
"""
from __future__ import annotations

import argparse
import time

from _cli import nonnegative, positive, run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb
from frbmodel.cosim.build import built_ssp
from frbmodel.cosim.master import CosimStopped, Master, cosimulate
from frbmodel.signals.spectral import spectrogram

#: FMI functions reported one by one; the others (instantiate, initialization, parameters) are set-up
STEP_FUNCTIONS = ("doStep", "getReal", "setReal", "getFMUstate", "setFMUstate", "freeFMUstate")


def _call_cost(ssp, n=3000):
    """Wall time [s] of one FMI call that moves one value and computes nothing: the mean of getReal(rotor_speed)
    and setReal(speed_in) on the rotor FMU, after initialization."""
    with Master(ssp, "co36") as m:
        m.initialize()
        get_vr, set_vr = m.rotor.vr(["rotor_speed"]), m.rotor.vr(["speed_in"])
        w = m.rotor.call("getReal", get_vr)
        t0 = time.perf_counter()
        for _ in range(n):
            m.rotor.call("getReal", get_vr)
            m.rotor.call("setReal", set_vr, w)
        return (time.perf_counter() - t0) / (2 * n)


def _cosim(ssp, duration, overrides, **kw):
    t0 = time.perf_counter()
    try:
        run, status = cosimulate(ssp, "co36", stop_time=duration, progress=False, overrides=overrides, **kw), "finished"
    except CosimStopped as exc:
        run, status = exc.result, f"stopped: {exc}"
    return run, time.perf_counter() - t0, status


def _split(name, run, wall, call_cost):
    """Print the per-step time split of a co-simulation."""
    m = run.meta
    steps = m["steps_taken"]
    calls = m["fmi_calls"]
    fmi = sum(w for _, w in calls.values())
    n_step_calls = sum(calls[f][0] for f in STEP_FUNCTIONS if f in calls)
    t_step_calls = sum(calls[f][1] for f in STEP_FUNCTIONS if f in calls)
    traffic = n_step_calls * call_cost
    per = 1e3 / steps
    print(f"\n{name}: {steps} steps ({m['rejected_steps']} rejected), wall {wall:.2f} s, {m['status']}")
    print(f"  {'total per step [ms]':<52}{wall * per:8.4f}")
    print(f"  {'inside FMI calls of the steps [ms]':<52}{t_step_calls * per:8.4f}   "
          f"({n_step_calls / steps:.1f} calls per step)")
    for f in STEP_FUNCTIONS:
        if f in calls:
            n, w = calls[f]
            print(f"    {f:<50}{w * per:8.4f}   ({n / steps:.2f} calls, {1e6 * w / n:.1f} us each)")
    print(f"  {'  of which FMI traffic (calls x call cost) [ms]':<52}{traffic * per:8.4f}")
    print(f"  {'  of which physics inside the FMUs [ms]':<52}{(t_step_calls - traffic) * per:8.4f}")
    print(f"  {'set-up FMI calls (instantiate, initialize) [ms]':<52}{(fmi - t_step_calls) * per:8.4f}")
    print(f"  {'outside FMI calls (master, recorder) [ms]':<52}{(wall - fmi) * per:8.4f}")


def _onsets(name, run):
    comps = spectrogram(run, "turbine_wheel").components()
    print(f"\n{name}: components at the turbine wheel (onset NaN: present from the start)")
    print(f"  {'comp':<6}{'dir':<10}{'onset [rpm]':>12}{'threshold [rpm]':>17}{'f at onset [Hz]':>17}"
          f"{'f first seen [Hz]':>19}")
    for c in comps:
        print(f"  {c.label:<6}{c.direction:<10}{c.onset_rpm:12.0f}{c.onset_threshold_rpm:17.0f}{c.onset_hz:17.2f}"
              f"{c.first_detection_hz:19.2f}")
    return comps


def _compare(ref, other):
    """Each component of ``ref`` against the nearest of ``other`` (same direction, frequency at first detection
    within 10 %); an onset NaN in both (present from the start) agrees."""
    print("\nadaptive vs fixed 10 us: onset, threshold crossing, frequency at first detection")
    worst = 0.0
    for a in ref:
        match = [b for b in other if b.direction == a.direction
                 and abs(b.first_detection_hz / a.first_detection_hz - 1) < 0.1]
        if not match:
            print(f"  {a.label:<6}{a.direction:<10} no matching component")
            worst = float("inf")
            continue
        b = min(match, key=lambda x: abs(x.onset_threshold_rpm - a.onset_threshold_rpm))
        d = [100 * (b.onset_rpm / a.onset_rpm - 1), 100 * (b.onset_threshold_rpm / a.onset_threshold_rpm - 1),
             100 * (b.first_detection_hz / a.first_detection_hz - 1)]
        if (a.onset_rpm == a.onset_rpm) != (b.onset_rpm == b.onset_rpm):  # NaN in one run only
            worst = float("inf")
        worst = max([worst] + [abs(x) for x in d[:2] if x == x])
        print(f"  {a.label:<6}{a.direction:<10}{d[0]:+8.2f} %{d[1]:+8.2f} %{d[2]:+8.2f} %")
    extra = len(other) - len(ref)
    print(f"  largest onset difference {worst:.2f} % (acceptance <= 1 %)"
          + (f"; {extra} more component(s) in the adaptive run" if extra > 0 else ""))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=positive, default=1.0, help="simulated time [s] of the 20 -> 250 krpm ramp")
    ap.add_argument("--build", default="build")
    ap.add_argument("--unbalance", type=nonnegative, default=0.0,
                    help="turbine-wheel unbalance [kg m] (0.1 g mm = 1e-7)")
    ap.add_argument("--no-monolithic", action="store_true", help="skip the monolithic run")
    args = ap.parse_args(argv)
    ssp = built_ssp(args.build)
    tc = frb.turbocharger(36e-6)
    unb = [frb.Unbalance("turbine_wheel", args.unbalance, 0.0)] if args.unbalance else []
    overrides = {"rotor": {"turbine_wheel.unbalance": ("Real", args.unbalance)}} if args.unbalance else None
    frb.runup(tc, speed_rpm=(20e3, 21e3), duration=0.002, progress=False)  # warm-up: kernels, FMU extraction
    cosimulate(ssp, "co36", stop_time=0.002, progress=False)
    call_cost = _call_cost(ssp)
    t_mono = None
    if not args.no_monolithic:
        t0 = time.perf_counter()
        frb.runup(tc, speed_rpm=(20e3, 250e3), duration=args.duration, progress=False, unbalance=unb)
        t_mono = time.perf_counter() - t0
    fixed, t_fixed, s_fixed = _cosim(ssp, args.duration, overrides)
    adapt, t_adapt, s_adapt = _cosim(ssp, args.duration, overrides, adaptive=True)
    print(f"run-up 20k -> 250k rpm, {args.duration:g} s simulated, c_o = 36 um, turbine-wheel unbalance "
          f"{args.unbalance:g} kg m")
    if t_mono is not None:
        print(f"{'monolithic wall [s]':<46}{t_mono:10.2f}")
    print(f"{'co-simulation, fixed 10 us, wall [s]':<46}{t_fixed:10.2f}   ({s_fixed})")
    print(f"{'co-simulation, adaptive, wall [s]':<46}{t_adapt:10.2f}   ({s_adapt})")
    if t_mono is not None:
        print(f"{'ratio co-sim fixed / monolithic':<46}{t_fixed / t_mono:10.2f}   (target <= 1.5)")
        print(f"{'ratio co-sim adaptive / monolithic':<46}{t_adapt / t_mono:10.2f}")
    print(f"{'cost of a one-value FMI call [us]':<46}{call_cost * 1e6:10.2f}")
    stopped = [f"{n}: {s}" for n, s in (("fixed 10 us", s_fixed), ("adaptive", s_adapt)) if s != "finished"]
    if stopped:  # nothing to split per step or compare
        raise CosimStopped(f"the co-simulation did not finish ({'; '.join(stopped)})")
    _split("fixed 10 us", fixed, t_fixed, call_cost)
    _split(f"adaptive (tolerance {adapt.meta['coupling_tol']:g}, steps {adapt.meta['shortest_step_s'] * 1e6:.2f} ... "
           f"{adapt.meta['longest_step_s'] * 1e6:.2f} us, {adapt.meta['forced_steps']} forced)", adapt, t_adapt,
           call_cost)
    print(f"\nsteps taken: fixed {fixed.meta['steps_taken']}, adaptive {adapt.meta['steps_taken']} "
          f"({adapt.meta['steps_taken'] / fixed.meta['steps_taken']:.1%}), adaptive rejected "
          f"{adapt.meta['rejected_steps']}")
    _compare(_onsets("fixed 10 us", fixed), _onsets("adaptive", adapt))


if __name__ == "__main__":
    run_script(main)
