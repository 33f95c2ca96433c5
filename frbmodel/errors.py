"""Exception types of frbmodel.

Every error raised for bad input names the quantity, its value and the valid range, so a user can fix
the input without reading the code.
"""


class FRBError(Exception):
    """Base class of all frbmodel errors."""


class ParameterError(FRBError, ValueError):
    """A parameter is out of its valid range (negative clearance, zero viscosity, unknown method...)."""


class FilmContactError(FRBError, ValueError):
    """A film's eccentricity ratio reached 1: the inner member touches its wall."""


class ConvergenceError(FRBError, RuntimeError):
    """An iterative solve (equilibrium, ring speed) did not converge."""


def check_positive(name, value, unit="", allow_zero=False):
    """Return ``float(value)`` or raise :class:`ParameterError` naming ``name``, its value and the range."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} is not a number; expected a finite real number "
                             f"{'>= 0' if allow_zero else '> 0'} {unit}".rstrip()) from None
    ok = v >= 0.0 if allow_zero else v > 0.0
    if not (ok and v == v and v != float("inf")):
        rng = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name} = {value!r} {unit} is invalid: valid range is finite and {rng} {unit}"
                             .replace("  ", " ").strip())
    return v


def check_finite(name, value, unit=""):
    """Return ``float(value)`` or raise :class:`ParameterError` if it is not a finite number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} is not a number; expected a finite real number {unit}"
                             .strip()) from None
    if not (v == v and abs(v) != float("inf")):
        raise ParameterError(f"{name} = {value!r} {unit} is invalid: it must be finite".replace("  ", " "))
    return v
