"""Run-up whirl components of the Table 2 turbocharger with the thermal model (issue #25 stage 2 item 3): one
20 -> 250 krpm run-up in 1 s per supply temperature (quasi-static film temperatures) and one at the constant Table 2
viscosities, the sub-synchronous components of the turbine wheel's orbit of each (docs/theory/thermal.md#run-ups).

Usage::

    python benchmarks/thermal_runup_onsets.py [--oil "SAE 5W-30"] [--supply-temperature 333.15,363.15,393.15]

Prints each run's wall time and its components table (onset, first detection, vanishing speed [rpm], frequencies
[Hz]); about 4 s per run on a 2-core machine.
"""
from __future__ import annotations

import argparse
import time

import pandas as pd
from _cli import run_script  # (benchmarks/ is the script's folder)

import frbmodel as frb


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--oil", default="SAE 5W-30", choices=list(frb.OILS), help="named oil")
    ap.add_argument("--supply-temperature", default="333.15,363.15,393.15",
                    help="supply temperatures [K], comma list")
    ap.add_argument("--supply-pressure", type=float, default=3e5, help="supply pressure above ambient [Pa]")
    args = ap.parse_args(argv)
    try:
        temps = [float(x) for x in args.supply_temperature.split(",")]
    except ValueError:
        ap.error(f"--supply-temperature = {args.supply_temperature!r} is invalid: a comma list of temperatures [K]")
    supplies = [None] + [frb.OilSupply(frb.OILS[args.oil], t, args.supply_pressure) for t in temps]  # checked first
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 20)
    tc = frb.turbocharger()
    for sup in supplies:
        t0 = time.perf_counter()
        run = frb.runup(tc, speed_rpm=(20e3, 250e3), duration=1.0, oil_supply=sup)
        wall = time.perf_counter() - t0
        label = "constant viscosities" if sup is None else f"{sup.oil.name}, supply {sup.supply_temperature_K:g} K"
        print(f"{label}: {run.status}, wall {wall:.1f} s")
        cols = ["component", "whirl direction", "onset [rpm]", "f at onset [Hz]", "first detection [rpm]",
                "vanishes at [rpm]", "f/f_rot at first detection [-]"]
        print(frb.spectrogram(run, "turbine_wheel").components_table()[cols].to_string(index=False,
                                                                                        float_format="{:.4g}".format))


if __name__ == "__main__":
    run_script(main)
