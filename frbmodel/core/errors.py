"""Exception types of frbmodel.

Every error raised for bad input names the quantity, its value and the valid range, so a user can fix
the input without reading the code.
"""
import math

import numpy as np


class FRBError(Exception):
    """Base class of all frbmodel errors.

    Examples
    --------
    >>> import frbmodel as frb
    >>> try:
    ...     frb.turbocharger(outer_clearance=-1e-6)
    ... except frb.FRBError as exc:
    ...     print(type(exc).__name__, isinstance(exc, ValueError))
    ParameterError True
    """


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
    disk with their status in ``runup.json``.

    Parameters
    ----------
    message : str
        What stopped the run, and when.
    result : object, optional
        The partial result (e.g. a :class:`~frbmodel.nonlinear.recorder.RunupResult`), or None.

    Examples
    --------
    >>> try:
    ...     raise RunupStopped("wall contact at t = 0.1 s", result="partial")
    ... except RunStopped as exc:
    ...     print(exc, "|", exc.result)
    wall contact at t = 0.1 s | partial
    """

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class RunupStopped(RunStopped):
    """The monolithic run-up stopped early (wall contact, integrator failure)."""


class CosimStopped(RunStopped):
    """The co-simulation stopped early (an FMU failed or rejected a step); the message names the FMU."""


def check_positive(name, value, unit="", allow_zero=False):
    """Return ``float(value)`` or raise :class:`ParameterError` naming ``name``, its value and the range.

    Lenient: anything ``float()`` accepts (also a numeric string) is converted; see :func:`check_real` for the
    strict check of API arguments.

    Parameters
    ----------
    name : str
        The quantity's name, used in the message.
    value : object
        The value to check.
    unit : str
        Unit for the message (e.g. ``"m"``).
    allow_zero : bool
        Accept 0 (range ``>= 0`` instead of ``> 0``).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``value`` is not a number, not finite, negative, or zero without ``allow_zero``.

    Examples
    --------
    >>> check_positive("viscosity", 0.005, "Pa s")
    0.005
    >>> check_positive("speed_rpm", 0, "rpm", allow_zero=True)
    0.0
    >>> try:
    ...     check_positive("outer_clearance", -1e-6, "m")
    ... except ParameterError as exc:
    ...     print(exc)
    outer_clearance = -1e-06 m is invalid: valid range is finite and > 0 m
    """
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


#: largest rotor speed accepted [rpm] by every analysis (linear and nonlinear); the model is verified over
#: 1 ... 250 krpm (README)
MAX_SPEED_RPM = 1e6


#: most speeds of one speed grid (Campbell diagrams, critical speeds, the CLI's --speeds): 25 rpm steps over 1 ... 250
#: krpm, finer than any branch tracking needs, and about a minute of Campbell diagram on the 2-core machine (400
#: speeds take ~1 s there); a grid of 1e8 speeds was accepted with an ETA of 29 h
MAX_SPEED_COUNT = 10_000


def check_speed_count(name, count):
    """Raise :class:`ParameterError` unless 1 <= ``count`` <= :data:`MAX_SPEED_COUNT` (speeds of one grid).

    Examples
    --------
    >>> try:
    ...     check_speed_count("--speeds = '1e4:2.5e5:100000000'", 100000000)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    --speeds = '1e4:2.5e5:100000000' has 100000000 speeds: valid range 1 ... 10000 speeds (25 rpm steps ...)
    """
    if not 1 <= count <= MAX_SPEED_COUNT:
        raise ParameterError(f"{name} has {count} speeds: valid range 1 ... {MAX_SPEED_COUNT} speeds "
                             "(25 rpm steps over 250 krpm: a finer grid resolves nothing more)")


def check_speeds_in_range(name, speeds_rpm):
    """Raise :class:`ParameterError` naming ``name`` and the first speed [rpm] of the array ``speeds_rpm`` that is
    not a number with |speed| <= :data:`MAX_SPEED_RPM` (the sign and zero are the caller's to check).

    Examples
    --------
    >>> try:
    ...     check_speeds_in_range("speeds_rpm", np.array([1e3, 2e6]))
    ... except ParameterError as exc:
    ...     print(exc)
    speeds_rpm contains 2000000.0 rpm: valid range |speed| <= 1e+06 rpm (the model is verified for 1 ... 250 krpm)
    """
    speeds_rpm = np.asarray(speeds_rpm, dtype=float)
    check_speed_count(name, speeds_rpm.size)
    bad = speeds_rpm[~(np.abs(speeds_rpm) <= MAX_SPEED_RPM)]  # (also NaN)
    if bad.size:
        raise ParameterError(f"{name} contains {float(bad[0])!r} rpm: valid range |speed| <= {MAX_SPEED_RPM:.0e} rpm "
                             "(the model is verified for 1 ... 250 krpm)")


def check_speed(name, speed_rpm):
    """Return ``float(speed_rpm)`` or raise :class:`ParameterError`: rotor speeds must be finite, > 0 and at most
    :data:`MAX_SPEED_RPM` rpm.

    Parameters
    ----------
    name : str
        The quantity's name, used in the message (e.g. ``"start speed"``).
    speed_rpm : float
        Rotor speed [rpm].

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If the speed is not a finite number in 0 < speed <= :data:`MAX_SPEED_RPM`.

    Examples
    --------
    >>> check_speed("start speed", 20e3)
    20000.0
    >>> try:
    ...     check_speed("end speed", 2e6)
    ... except ParameterError as exc:
    ...     print(exc)
    end speed = 2000000.0 rpm is invalid: valid range 0 < speed <= 1e+06 rpm (the model is verified for 1 ... 250 krpm)
    """
    v = check_positive(name, speed_rpm, "rpm")
    if v > MAX_SPEED_RPM:
        raise ParameterError(f"{name} = {speed_rpm!r} rpm is invalid: valid range 0 < speed <= {MAX_SPEED_RPM:.0e} rpm "
                             "(the model is verified for 1 ... 250 krpm)")
    return v


def _shown(value) -> str:
    """A value of a list for a message: a number as ``%g``, a tuple of numbers as ``A:B`` (a window), else ``str``."""
    if isinstance(value, tuple):
        return ":".join(_shown(v) for v in value)
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        return f"{value:g}"
    return str(value)


def check_distinct(name, values, unit=""):
    """``values`` if no value repeats, else a :class:`ParameterError` naming the first repeated one (the same case,
    curve, window or table rows would be computed or drawn twice). ``unit`` is written after a repeated number (or
    tuple of numbers), not after a word.

    Examples
    --------
    >>> check_distinct("--clearances = '36e-6,40e-6'", [36e-6, 40e-6], "m")
    [3.6e-05, 4e-05]
    >>> try:
    ...     check_distinct("--orbit-times = '0:1,0:1'", [(0.0, 1.0), (0.0, 1.0)], "s")
    ... except ParameterError as exc:
    ...     print(exc)
    --orbit-times = '0:1,0:1' repeats 0:1 s: give distinct values
    """
    values = list(values)
    twice = next((v for k, v in enumerate(values) if v in values[:k]), None)
    if twice is not None:
        numeric = not isinstance(twice, str)
        raise ParameterError(f"{name} repeats {_shown(twice)}{' ' + unit if unit and numeric else ''}: give distinct "
                             "values")
    return values


def check_finite(name, value, unit=""):
    """Return ``float(value)`` or raise :class:`ParameterError` if it is not a finite number.

    Parameters
    ----------
    name : str
        The quantity's name, used in the message.
    value : object
        The value to check (anything ``float()`` accepts).
    unit : str
        Unit for the message.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``value`` is not a number or is NaN or infinite.

    Examples
    --------
    >>> check_finite("gravity", -9.81, "m/s^2")
    -9.81
    >>> try:
    ...     check_finite("gravity", float("nan"), "m/s^2")
    ... except ParameterError as exc:
    ...     print(exc)
    gravity = nan m/s^2 is invalid: it must be finite
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} is not a number; expected a finite real number {unit}"
                             .strip()) from None
    if not (v == v and abs(v) != float("inf")):
        raise ParameterError(f"{name} = {value!r} {unit} is invalid: it must be finite".replace("  ", " "))
    return v


# ------------------------------------------------------------------ strict checks of API arguments
def _describe(value) -> str:
    """``repr`` of a value for a message, shortened."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _range_text(minimum, inclusive, unit) -> str:
    unit = f" {unit}" if unit else ""
    if minimum is None:
        return f"a finite real number{unit}"
    return f"a finite real number {'>=' if inclusive else '>'} {minimum:g}{unit}"


def check_real(name, value, unit="", minimum=None, inclusive=False):
    """Return ``float(value)`` for a real-number API argument, or raise :class:`ParameterError`.

    Stricter than :func:`check_positive`: a string (``"36e-6"``), a bool, ``None``, a complex number or a
    sequence is refused rather than converted, because an API argument of the wrong type is a mistake the user
    should see where it is made, not deep inside a computation.

    Parameters
    ----------
    name : str
        The argument's name, used in the message.
    value : object
        The value given: an ``int``, ``float``, NumPy real scalar or 0-d real array.
    unit : str
        Unit for the message (e.g. ``"m"``).
    minimum : float, optional
        Lower bound of the valid range (none if None).
    inclusive : bool
        ``value == minimum`` is valid.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        Naming ``name``, the value and the valid range.

    Examples
    --------
    >>> check_real("outer_clearance", 36e-6, "m", minimum=0.0)
    3.6e-05
    >>> try:
    ...     check_real("outer_clearance", "36e-6", "m", minimum=0.0)
    ... except ParameterError as exc:
    ...     print(exc)
    outer_clearance = '36e-6' is a str; expected a finite real number > 0 m (a number, not text)
    """
    if type(value) is float and math.isfinite(value) and (  # fast path for the common case
            minimum is None or value > minimum or (inclusive and value == minimum)):
        return value
    import numbers

    import numpy as np

    expected = _range_text(minimum, inclusive, unit)
    arr = value if isinstance(value, np.ndarray) and value.ndim == 0 else None
    if arr is not None and arr.dtype.kind in "iuf":
        value = arr.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        hint = " (a number, not text)" if isinstance(value, str) else ""
        raise ParameterError(f"{name} = {_describe(value)} is a {type(value).__name__}; expected {expected}{hint}")
    v = float(value)
    if not math.isfinite(v) or (minimum is not None and (v < minimum or (v == minimum and not inclusive))):
        raise ParameterError(f"{name} = {_describe(value)}{' ' + unit if unit else ''} is invalid: valid range is "
                             f"{expected}")
    return v


_KINDS = {"b": "booleans", "U": "text", "S": "text", "O": "objects (mixed or ragged)", "c": "complex numbers"}


def check_real_array(name, value, unit="", last_axis=None):
    """Return ``value`` as a float array of finite real numbers, or raise :class:`ParameterError`.

    Parameters
    ----------
    name : str
        The argument's name, used in the message.
    value : array_like
        Real numbers (no strings, no booleans, no complex numbers).
    unit : str
        Unit for the message.
    last_axis : int, optional
        Required length of the last axis (e.g. 2 for x-y vectors); a scalar is then refused.

    Returns
    -------
    ndarray of float

    Raises
    ------
    ParameterError
        Naming ``name``, its value and what is expected (type, shape, finiteness).

    Examples
    --------
    >>> check_real_array("e", [1e-6, 0.0], "m", last_axis=2)
    array([1.e-06, 0.e+00])
    >>> try:
    ...     check_real_array("e", [float("nan"), 0.0], "m", last_axis=2)
    ... except ParameterError as exc:
    ...     print(exc)
    e = [nan, 0.0] m is invalid: every entry must be a finite real number (entry (0,) is nan)
    """
    import numpy as np

    shape = f" of shape (..., {last_axis})" if last_axis else ""
    try:
        arr = np.asarray(value)
    except ValueError:  # ragged nesting
        arr = np.asarray(None)
    if arr.dtype.kind not in "iuf":
        raise ParameterError(f"{name} = {_describe(value)} is invalid: expected real numbers{shape} "
                             f"[{unit or '-'}], got {_KINDS.get(arr.dtype.kind, arr.dtype.name)}")
    if last_axis is not None and (arr.ndim == 0 or arr.shape[-1] != last_axis):
        raise ParameterError(f"{name} = {_describe(value)} has shape {arr.shape}; expected shape (..., {last_axis}) "
                             f"(x, y components) [{unit or '-'}]")
    arr = arr.astype(float)
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ParameterError(f"{name} = {_describe(value)}{' ' + unit if unit else ''} is invalid: every entry must "
                             f"be a finite real number (entry {idx} is {float(arr[idx])!r})")
    return arr


def check_system(system, name="system"):
    """Return ``system`` if it looks like a :class:`~frbmodel.system.parameters.Turbocharger`, else raise
    :class:`ParameterError` naming what was given.

    Parameters
    ----------
    system : object
        Needs ``rotor``, ``bearings``, ``bearing_loads``, ``film_model`` and ``gravity`` (duck typing).
    name : str
        The argument's name, used in the message.

    Returns
    -------
    object
        ``system`` itself.

    Examples
    --------
    >>> try:
    ...     check_system(36e-6)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    system = 3.6e-05 is a float; expected a Turbocharger (frb.turbocharger(...) or frb.load_system(path))
    """
    if not all(hasattr(system, a) for a in ("rotor", "bearings", "bearing_loads", "film_model", "gravity")):
        raise ParameterError(f"{name} = {_describe(system)} is a {type(system).__name__}; expected a Turbocharger "
                             "(frb.turbocharger(...) or frb.load_system(path))")
    return system


def renamed_keyword(old, new, since="0.1.0"):
    """Decorator: accept the keyword ``old`` as ``new`` for one more release, with a :class:`DeprecationWarning`.

    Parameters
    ----------
    old, new : str
        Old and new keyword names.
    since : str
        Version that renamed it (named in the warning).

    Returns
    -------
    callable
        The decorator.

    Examples
    --------
    >>> @renamed_keyword("model", "film_model")
    ... def f(film_model="short"):
    ...     return film_model
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     print(f(model="short_corrected"), w[0].category.__name__)
    short_corrected DeprecationWarning
    """
    import functools
    import warnings

    def decorate(func):
        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            if old in kwargs:
                if new in kwargs:
                    raise ParameterError(f"{func.__name__}() got both {old}= (deprecated) and {new}=; pass {new}= "
                                         "only")
                warnings.warn(f"{func.__name__}({old}=...) is deprecated since frbmodel {since} and will be removed "
                              f"in the next release; use {new}=...", DeprecationWarning, stacklevel=2)
                kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)

        return wrapper

    return decorate


def read_json(path, what="file"):
    """The JSON content of ``path``, or a :class:`ParameterError` naming the file, the line and column and what is
    wrong (a result folder written by an interrupted or foreign program, a file edited by hand).

    Parameters
    ----------
    path : str or Path
    what : str
        What the file is, for the message (e.g. ``"run-up metadata"``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "runup.json"
    ...     _ = p.write_text('{"status": ')
    ...     try:
    ...         read_json(p, "run-up metadata")
    ...     except ParameterError as exc:
    ...         print(str(exc).replace(str(p), "runup.json"))
    run-up metadata runup.json is not valid JSON: line 1, column 12: Expecting value
    """
    import json
    from pathlib import Path

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{what} {path} cannot be read: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise ParameterError(f"{what} {path} is not valid JSON: line {exc.lineno}, column {exc.colno}: "
                             f"{exc.msg}") from None
