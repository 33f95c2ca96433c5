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
    """An iterative solve (equilibrium, ring speed, ring integrator Newton loop) did not converge."""


class IntegrationError(FRBError, ArithmeticError):
    """A time integration blew up numerically (a state became non-finite): not bad input, but a step too large
    for the dynamics or the coupling."""


class RunStopped(FRBError):
    """A long run (run-up, co-simulation) ended before its end time: wall contact, integrator failure, an FMU
    failure or an interruption. ``.result`` holds what was computed up to there; the files written so far stay on
    disk with their status in ``runup.json``."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class RunupStopped(RunStopped):
    """The monolithic run-up stopped early (wall contact, integrator failure)."""


class CosimStopped(RunStopped):
    """The co-simulation stopped early (an FMU failed or rejected a step); the message names the FMU."""


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
