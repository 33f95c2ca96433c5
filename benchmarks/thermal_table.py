"""The thermal operating points of the Table 2 turbocharger (issue #25): the documentation's table of RSR, film and
ring temperatures and power loss at 50 ... 250 krpm for two supply temperatures, and its figure for three.

Usage::

    python benchmarks/thermal_table.py [--oil "SAE 5W-30"] [--supply-pressure 3e5] [--figure PATH]

Prints the Markdown table (docs/theory/thermal.md#results-for-the-table-2-turbocharger) and writes the figure
(default docs/img/thermal_operating_points.png).
"""
from __future__ import annotations

import argparse
import time

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from _cli import nonnegative, run_script  # noqa: E402  (benchmarks/ is the script's folder)

import frbmodel as frb  # noqa: E402
from frbmodel.plots.thermal import plot_thermal_losses  # noqa: E402

TABLE_SPEEDS_RPM = [50e3, 100e3, 150e3, 200e3, 250e3]
TABLE_SUPPLY_K = [333.15, 363.15]
FIGURE_SUPPLY_K = [333.15, 363.15, 393.15]


def markdown(table):
    """The table's rows as Markdown (K, W, RSR)."""
    lines = ["| supply [K] | speed [krpm] | bearing | RSR [-] | T inner [K] | T outer [K] | T ring [K] | "
             "μ inner [mPa s] | μ outer [mPa s] | power loss [W] |", "|" + "---|" * 10]
    for _, r in table.iterrows():
        lines.append(f"| {r['supply temperature [K]']:.2f} | {r['speed [rpm]'] / 1e3:.0f} | {r['bearing']} | "
                     f"{r['RSR [-]']:.4f} | {r['inner film temperature [K]']:.1f} | "
                     f"{r['outer film temperature [K]']:.1f} | {r['ring temperature [K]']:.1f} | "
                     f"{r['inner viscosity [Pa s]'] * 1e3:.2f} | {r['outer viscosity [Pa s]'] * 1e3:.2f} | "
                     f"{r['power loss [W]']:.1f} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--oil", default="SAE 5W-30", choices=list(frb.OILS), help="named oil")
    ap.add_argument("--supply-pressure", type=nonnegative, default=3e5,
                    help="supply pressure above ambient [Pa], 0 ... 2e6")
    ap.add_argument("--figure", default="docs/img/thermal_operating_points.png", help="figure file")
    args = ap.parse_args(argv)
    tc, oil = frb.turbocharger(), frb.OILS[args.oil]
    t0 = time.perf_counter()
    table = frb.thermal_losses(tc, TABLE_SPEEDS_RPM, oil, TABLE_SUPPLY_K, args.supply_pressure)
    wall = time.perf_counter() - t0
    print(f"{oil.name}, supply {args.supply_pressure:g} Pa, ThermalModel() defaults, Table 2 (outer clearance 36 um)")
    print(markdown(table))
    print(f"max |energy-balance residual| {np.abs(table['energy-balance residual [W]']).max():.2g} W, "
          f"max temperature residual {table['temperature residual [K]'].max():.2g} K, "
          f"evaluations {table['iterations [-]'].min()} ... {table['iterations [-]'].max()} per point, "
          f"{wall:.2f} s for {len(table)} points")
    fig_table = frb.thermal_losses(tc, np.linspace(10e3, 250e3, 25), oil, FIGURE_SUPPLY_K, args.supply_pressure)
    fig = plot_thermal_losses(fig_table)
    fig.savefig(args.figure, dpi=110)
    print(f"wrote {args.figure}")


if __name__ == "__main__":
    run_script(main)
