"""Build the FMUs (build/fmus/FloatingRingBearing.fmu, TurbochargerRotor.fmu) and build/turbocharger.ssp.

Usage: python build_fmu.py [OUT_DIR]   (same as `frb build-fmus --out OUT_DIR`)
"""
import argparse
import sys

from frbmodel.core.errors import FRBError
from frbmodel.cosim.build import build_fmus

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description="Build the two FMUs and the SSP (same as `frb build-fmus`).")
    ap.add_argument("out_dir", nargs="?", default="build", help="output folder (default: build)")
    args = ap.parse_args()  # --help prints this; an unknown option exits with status 2
    try:
        build_fmus(args.out_dir)
    except FRBError as exc:  # e.g. the FMU sources are missing: the message says what and how to fix it
        print(f"build_fmu.py: error: {exc}", file=sys.stderr)
        sys.exit(2)
