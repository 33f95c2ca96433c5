"""Build the FMUs (build/fmus/FloatingRingBearing.fmu, TurbochargerRotor.fmu) and build/turbocharger.ssp.

Usage: python build_fmu.py [OUT_DIR]   (same as `frb build-fmus --out OUT_DIR`)
"""
import sys

from frbmodel.cosim.build import build_fmus

if __name__ == "__main__":
    build_fmus(sys.argv[1] if len(sys.argv) > 1 else "build")
