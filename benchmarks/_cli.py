"""What the benchmark scripts share: bad input is a clear message and exit status 2, never a traceback.

``positive``, ``nonnegative``, ``whole`` and ``count`` are argparse types (argparse prints ``argument --x: ...``
and exits with 2); :func:`run_script` runs a script's ``main`` and turns an frbmodel error (a refused parameter, a
stopped run) into one line on stderr and exit status 2.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from frbmodel.core.errors import FRBError


def _number(text, kind, ok, valid):
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number; valid range: {valid}") from None
    if not (math.isfinite(value) and ok(value)):
        raise argparse.ArgumentTypeError(f"{text!r} is invalid; valid range: {valid}")
    return value


def positive(text):
    """A finite float > 0 (e.g. a duration [s], a step [s])."""
    return _number(text, float, lambda v: v > 0, "finite and > 0")


def nonnegative(text):
    """A finite float >= 0 (e.g. an unbalance [kg m])."""
    return _number(text, float, lambda v: v >= 0, "finite and >= 0")


def whole(text):
    """An integer >= 0 (e.g. how many halvings)."""
    return _number(text, int, lambda v: v >= 0, "an integer >= 0")


def count(text):
    """An integer >= 1 (points, repeats, cases)."""
    return _number(text, int, lambda v: v >= 1, "an integer >= 1")


def run_script(main):
    """``main()``; an frbmodel error ends the script with its message and exit status 2."""
    try:
        main()
    except FRBError as exc:
        print(f"{Path(sys.argv[0]).name}: error: {exc}", file=sys.stderr)
        sys.exit(2)
