"""Quasi-static film temperatures versus the rings' temperatures as states in a run-up (issue #25 item 3: "choose,
measure the difference, say why"; docs/theory/thermal.md#run-ups).

Usage::

    python benchmarks/thermal_ring_lag.py [--supply-temperature 363.15] [--durations 1,10]
                                          [--ring-heat-capacity 2.736]

For each ramp duration (20 -> 250 krpm, Table 2 turbocharger, SAE 5W-30 at 3e5 Pa):

- the rings' and films' temperatures at 100 / 175 / 250 krpm, quasi-static and lagged (``frbmodel.linear.thermal.
  ring_lag`` with m_R c_R = 7.2 g x 380 J/(kg K) = 2.736 J/K by default: bronze, assumed; Table 2 gives no ring
  material), and the lag of the viscosities;
- the sub-synchronous components of the turbine wheel's orbit (onset, vanishing speed) of the quasi-static run,
  of the lagged run, and of the quasi-static run with the initial journal offset changed by a relative 1e-9: the
  model's own sensitivity band inside the whirl (docs/validation/nonlinear.md), against which the lag's shift is
  read.

About 4 s per 1-s run and 40 s per 10-s run on the 2-core machine.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _cli import positive, run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb
from frbmodel.linear.thermal import OilSupply, ring_lag, thermal_losses
from frbmodel.physics.thermal import ThermalModel

SPEEDS_RPM = (100e3, 175e3, 250e3)
P0 = 0.05  # the run-up's default initial offset [of the clearance]


def temperature_rows(tc, supply, lagged, duration):
    """Ring, inner and outer film temperatures [K] of the turbine bearing at SPEEDS_RPM, quasi-static and lagged."""
    t = np.linspace(0.0, duration, 97)
    rpm = 20e3 + (250e3 - 20e3) * t / duration
    _, ring, inner, outer, mu, _ = ring_lag(tc, t, rpm, lagged)
    qs = thermal_losses(tc, list(SPEEDS_RPM), supply.oil, supply.supply_temperature_K, supply.supply_pressure_Pa)
    qs = qs[qs["bearing"] == tc.bearings[0].name]
    rows = []
    for s, (_, q) in zip(SPEEDS_RPM, qs.iterrows()):
        k = int(np.argmin(np.abs(rpm - s)))
        rows.append(f"| {duration:g} | {s / 1e3:.0f} | {q['ring temperature [K]']:.2f} / {ring[0, k]:.2f} | "
                    f"{q['inner film temperature [K]']:.2f} / {inner[0, k]:.2f} | "
                    f"{q['outer film temperature [K]']:.2f} / {outer[0, k]:.2f} | "
                    f"{100 * (mu[0, k] / q['inner viscosity [Pa s]'] - 1):+.2f} | "
                    f"{100 * (mu[1, k] / q['outer viscosity [Pa s]'] - 1):+.2f} |")
    return rows


def components(tc, duration, supply, perturbation=P0):
    """(wall [s], {component: (onset or "start", vanishes)} [krpm]) of one run-up."""
    t0 = time.perf_counter()
    run = frb.runup(tc, speed_rpm=(20e3, 250e3), duration=duration, oil_supply=supply, perturbation=perturbation)
    wall = time.perf_counter() - t0
    ct = frb.spectrogram(run, "turbine_wheel").components_table()
    out = {}
    for _, r in ct.iterrows():
        onset = "start" if np.isnan(r["onset [rpm]"]) else f"{r['onset [rpm]'] / 1e3:.1f}"
        end = "-" if np.isnan(r["vanishes at [rpm]"]) else f"{r['vanishes at [rpm]'] / 1e3:.1f}"
        out[r["component"]] = f"{r['f/f_rot at first detection [-]']:.2f} X: {onset} … {end}"
    return wall, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--supply-temperature", type=positive, default=363.15, help="oil supply temperature [K]")
    ap.add_argument("--durations", default="1,10", help="ramp durations [s], comma list")
    ap.add_argument("--ring-heat-capacity", type=positive, default=7.2e-3 * 380.0, help="m_R c_R [J/K]")
    args = ap.parse_args(argv)
    try:
        durations = [positive(x) for x in args.durations.split(",")]
    except argparse.ArgumentTypeError as exc:
        ap.error(f"--durations: {exc}")
    tc = frb.turbocharger()
    oil = frb.OILS["SAE 5W-30"]
    supply = OilSupply(oil, args.supply_temperature)
    lagged = OilSupply(oil, args.supply_temperature, model=ThermalModel(ring_heat_capacity_J_K=args.ring_heat_capacity))
    print(f"turbine bearing, supply {args.supply_temperature:g} K, m_R c_R = {args.ring_heat_capacity:g} J/K")
    print("| ramp [s] | speed [krpm] | ring [K] quasi-static / lagged | inner film [K] | outer film [K] | "
          "inner viscosity lag [%] | outer viscosity lag [%] |\n|---|---|---|---|---|---|---|")
    for d in durations:
        print("\n".join(temperature_rows(tc, supply, lagged, d)))
    frb.runup(tc, speed_rpm=(20e3, 25e3), duration=0.01)  # load the kernels (not timed)
    for d in durations:
        runs = {"quasi-static": components(tc, d, supply), "ring lag": components(tc, d, lagged),
                "quasi-static, offset +1e-9": components(tc, d, supply, P0 * (1 + 1e-9))}
        names = sorted({c for _, comp in runs.values() for c in comp})
        print(f"\n{d:g} s ramp: components of the turbine wheel's orbit, onset … vanishing [krpm]")
        print("| run | wall [s] | " + " | ".join(names) + " |\n" + "|---" * (len(names) + 2) + "|")
        for label, (wall, comp) in runs.items():
            print(f"| {label} | {wall:.1f} | " + " | ".join(comp.get(c, "") for c in names) + " |")


if __name__ == "__main__":
    run_script(main)
