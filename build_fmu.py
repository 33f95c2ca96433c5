"""Build the FMUs (build/fmus/FloatingRingBearing.fmu, TurbochargerRotor.fmu) and build/turbocharger.ssp.

Usage: python build_fmu.py [OUT_DIR]   (same as `frb build-fmus --out OUT_DIR`)
"""
import sys

from frbmodel.cosim.build import build_fmus
from frbmodel.errors import FRBError

if __name__ == "__main__":
    try:
        build_fmus(sys.argv[1] if len(sys.argv) > 1 else "build")
    except FRBError as exc:  # e.g. the FMU sources are missing: the message says what and how to fix it
        print(f"build_fmu.py: error: {exc}", file=sys.stderr)
        sys.exit(2)
