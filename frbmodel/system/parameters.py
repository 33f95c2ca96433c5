"""System description: floating-ring bearings and the turbocharger (rotor + two bearings), with file I/O.

A system can be saved to and loaded from TOML or JSON (:meth:`Turbocharger.save`,
:func:`load_system`), so users can model their own turbocharger. All quantities are SI.

What a system file may contain is the schema :data:`SYSTEM` (allowed keys, their types and units, the required
ones, per table); :func:`check_section` checks a file's content against it before anything is built, so a
misspelt or unknown key, a missing one or a value of the wrong type is refused with its place in the file
(``bearings[0].inner.viscosty``), and the constructors then check the value ranges.
"""
from __future__ import annotations

import difflib
import json
import math
import numbers
import re
import tomllib
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_positive
from .films import Film, check_film_thickness, check_model
from .oil import Oil, oil_from_dict
from .rotor import GRAVITY, Disc, Rotor, ShaftElement, check_names

#: the largest gravitational acceleration a system takes [m/s²] (100 g; the FMUs' parameter gravity has the same)
MAX_GRAVITY = 1e3

# ------------------------------------------------------------------ the schema of a system file
REAL, INTEGER, STRING = "real number", "integer", "string"


@dataclass(frozen=True)
class Section:
    """The allowed content of one table of a system file.

    Parameters
    ----------
    title : str
        What the table describes (``"film"``), used in messages.
    keys : dict
        ``{key: kind}``; a kind is ``(REAL, unit)``, ``(INTEGER, unit)``, ``(STRING, "")``, a :class:`Section`
        (a sub-table) or a one-element list ``[Section]`` (an array of tables).
    required : tuple of str
        Keys that must be present (the others have defaults).
    """

    title: str
    keys: dict
    required: tuple = ()


FILM = Section("film", {"radius": (REAL, "m"), "length": (REAL, "m"), "clearance": (REAL, "m"),
                        "viscosity": (REAL, "Pa s")}, ("radius", "length", "clearance", "viscosity"))
SHAFT_ELEMENT = Section("shaft element", {"length": (REAL, "m"), "outer_diameter": (REAL, "m"),
                                          "inner_diameter": (REAL, "m"), "density": (REAL, "kg/m^3"),
                                          "youngs_modulus": (REAL, "Pa")}, ("length", "outer_diameter"))
DISC = Section("disc", {"node": (INTEGER, ""), "mass": (REAL, "kg"), "polar_inertia": (REAL, "kg m^2"),
                        "diametral_inertia": (REAL, "kg m^2"), "name": (STRING, "")},
               ("node", "mass", "polar_inertia", "diametral_inertia"))
ROTOR = Section("rotor", {"shaft": [SHAFT_ELEMENT], "discs": [DISC]}, ("shaft",))
BEARING = Section("bearing", {"node": (INTEGER, ""), "name": (STRING, ""), "ring_mass": (REAL, "kg"),
                              "ring_inertia": (REAL, "kg m^2"), "inner": FILM, "outer": FILM},
                  ("node", "ring_mass", "ring_inertia", "inner", "outer"))
#: the lubricant (optional): ``name`` of a named oil (:data:`frbmodel.system.oil.OILS`) or its datasheet numbers;
#: :func:`frbmodel.system.oil.oil_from_dict` checks which combination is given
OIL = Section("oil", {"nu40_m2_s": (REAL, "m^2/s"), "nu100_m2_s": (REAL, "m^2/s"), "density15_kg_m3": (REAL, "kg/m^3"),
                      "density_coefficient_1_K": (REAL, "1/K"), "specific_heat_J_kgK": (REAL, "J/(kg K)"),
                      "name": (STRING, "")})
#: the whole system file (``units`` is a free-text note for readers of the file)
SYSTEM = Section("system", {"name": (STRING, ""), "gravity": (REAL, "m/s^2"), "film_model": (STRING, ""),
                            "units": (STRING, ""), "rotor": ROTOR, "bearings": [BEARING], "oil": OIL},
                 ("rotor", "bearings"))


def _kind_name(value) -> str:
    """What a value read from TOML/JSON is, in the words of the messages."""
    if isinstance(value, bool):
        return "a boolean"
    for typ, name in ((numbers.Integral, "an integer"), (numbers.Real, "a real number"), (str, "a string"),
                      (dict, "a table"), ((list, tuple), "a list")):
        if isinstance(value, typ):
            return name
    return "null" if value is None else f"a {type(value).__name__}"


def _expected(kind) -> str:
    if isinstance(kind, Section):
        return f"a table ({kind.title})"
    if isinstance(kind, list):
        return f"a list of tables ({kind[0].title}s)"
    typ, unit = kind
    return f"{'an' if typ == INTEGER else 'a'} {typ}" + (f" [{unit}]" if unit else "")


def _fits(value, kind) -> bool:
    if isinstance(kind, Section):
        return isinstance(value, dict)
    if isinstance(kind, list):
        return isinstance(value, (list, tuple)) and all(isinstance(v, dict) for v in value)
    if isinstance(value, bool):
        return False
    return isinstance(value, {REAL: numbers.Real, INTEGER: numbers.Integral, STRING: str}[kind[0]])


def _unknown_key(key, where, section) -> ParameterError:
    valid = sorted(section.keys)
    close = difflib.get_close_matches(str(key), valid, n=1)
    place = f"in {where} ({section.title})" if where else "at the top level"
    hint = f", did you mean {close[0]!r}?" if close else ";"
    return ParameterError(f"unknown key {key!r} {place}{hint} valid keys: {', '.join(valid)}")


def check_section(d, section: Section = None, where: str = "") -> None:
    """Check plain data (a parsed system file) against the schema: keys, types, required keys, recursively.

    Parameters
    ----------
    d : dict
        The table, e.g. ``tomllib.load(f)``.
    section : Section, optional
        Its schema; default :data:`SYSTEM` (a whole system file).
    where : str
        Place of ``d`` in the file (``"bearings[0].inner"``), named in messages; ``""`` for the top level.

    Raises
    ------
    ParameterError
        ``d`` is not a table, holds a key the section does not know (the message names it, its place, the
        closest valid key and all valid keys), lacks a required key, or holds a value of the wrong type (the
        message names the key, the value and the expected type).

    Examples
    --------
    >>> film = {"radius": 5.5e-3, "length": 6.5e-3, "clearance": 34e-6, "viscosty": 4.9e-3}
    >>> try:
    ...     check_section(film, FILM, "bearings[0].inner")
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    unknown key 'viscosty' in bearings[0].inner (film), did you mean 'viscosity'? valid keys: clearance, ...
    """
    section = SYSTEM if section is None else section
    if not isinstance(d, dict):
        raise ParameterError(f"{where or 'the system description'} = {d!r:.60} is {_kind_name(d)}; expected "
                             f"{_expected(section)} with the keys {', '.join(sorted(section.keys))}")
    for key, value in d.items():
        if key not in section.keys:
            raise _unknown_key(key, where, section)
        kind, path = section.keys[key], f"{where}.{key}" if where else key
        if not _fits(value, kind):
            raise ParameterError(f"{path} = {value!r:.60} is {_kind_name(value)}; expected {_expected(kind)}"
                                 + (" (write numbers without quotes)" if isinstance(value, str) else ""))
        if isinstance(kind, Section):
            check_section(value, kind, path)
        elif isinstance(kind, list):
            for i, item in enumerate(value):
                check_section(item, kind[0], f"{path}[{i}]")
    missing = [k for k in section.required if k not in d]
    if missing:
        what = f"{where} ({section.title})" if where else "the system description"
        raise ParameterError(f"{what} lacks the required key{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(map(repr, missing))}; required: {', '.join(section.required)}")


def _build(where, cls, **kw):
    """``cls(**kw)``, a range error prefixed with the place in the file."""
    try:
        return cls(**kw)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}" if where else str(exc)) from None


def _bearing(d, where):
    """FloatingRingBearing from a checked ``bearing`` table."""
    films = {f: _build(f"{where}.{f}", Film, **d[f]) for f in ("inner", "outer")}
    for f, film in films.items():
        check_film_thickness(film, f"{where}.{f}: film")
    return _build(where, FloatingRingBearing, node=d["node"], name=d.get("name", "bearing"),
                  ring_mass=d["ring_mass"], ring_inertia=d["ring_inertia"], **films)


@dataclass(frozen=True)
class FloatingRingBearing:
    """A floating-ring bearing: journal → inner film → ring → outer film → housing.

    Parameters
    ----------
    node : int
        Rotor node of the journal.
    inner, outer : Film
        Inner (journal–ring) and outer (ring–housing) films.
    ring_mass : float
        Ring mass m_FR [kg].
    ring_inertia : float
        Ring polar moment of inertia I_FR [kg m²].
    name : str
        ``"turbine"`` or ``"compressor"`` (any label).
    """

    node: int
    inner: Film
    outer: Film
    ring_mass: float
    ring_inertia: float
    name: str = "bearing"

    def __post_init__(self):
        object.__setattr__(self, "ring_mass", check_positive(f"{self.name} bearing ring_mass", self.ring_mass, "kg"))
        object.__setattr__(self, "ring_inertia",
                           check_positive(f"{self.name} bearing ring_inertia", self.ring_inertia, "kg m^2"))
        if int(self.node) != self.node or self.node < 0:
            raise ParameterError(f"{self.name} bearing node = {self.node!r} is invalid: must be an integer >= 0")
        # the ring's bore must be the inner film's outer surface, inside the outer film's radius
        if self.inner.radius + self.inner.clearance >= self.outer.radius:
            raise ParameterError(
                f"{self.name} bearing: inner film radius + clearance = "
                f"{self.inner.radius + self.inner.clearance:g} m must be < outer film radius = {self.outer.radius:g} m")

    def to_dict(self) -> dict:
        """The bearing as plain data (SI units), as written by :meth:`Turbocharger.save`.

        Returns
        -------
        dict
            ``node``, ``name``, ``ring_mass`` [kg], ``ring_inertia`` [kg m²] and the films ``inner``,
            ``outer`` (each :meth:`Film.to_dict`).
        """
        return {"node": self.node, "name": self.name, "ring_mass": self.ring_mass, "ring_inertia": self.ring_inertia,
                "inner": self.inner.to_dict(), "outer": self.outer.to_dict()}

    @classmethod
    def from_dict(cls, d: dict, where: str = "bearing") -> "FloatingRingBearing":
        """Inverse of :meth:`to_dict`; checked against the schema :data:`BEARING`.

        Parameters
        ----------
        d : dict
            Keys as written by :meth:`to_dict` (``name`` optional).
        where : str
            Name of the table in messages.

        Returns
        -------
        FloatingRingBearing

        Raises
        ------
        ParameterError
            An unknown or missing key, a value of the wrong type or out of its range (see :func:`check_section`).
        """
        check_section(d, BEARING, where)
        return _bearing(d, where)


@dataclass(frozen=True)
class Turbocharger:
    """A rotor on two floating-ring bearings.

    Parameters
    ----------
    rotor : Rotor
    bearings : tuple of FloatingRingBearing
        (turbine side, compressor side).
    gravity : float
        g [m/s²], acting along −y.
    film_model : {"short", "short_corrected"}
        Film model used by equilibria, linearization and run-ups.
    name : str
    oil : Oil, optional
        The lubricant, used only by the thermal analyses (:func:`frbmodel.linear.thermal.thermal_losses`); every other
        analysis uses the films' constant viscosities. None (the default) for none.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger(outer_clearance=36e-6)
    >>> # static reactions [N]: docs/theory/parameters.md#table-2-in-si-units
    >>> [round(float(w), 4) for w in tc.bearing_loads]
    [5.3093, -0.1843]
    """

    rotor: Rotor
    bearings: tuple
    gravity: float = GRAVITY
    film_model: str = "short"
    name: str = "turbocharger"
    oil: Oil = None

    def __post_init__(self):
        object.__setattr__(self, "bearings", tuple(self.bearings))
        if self.oil is not None and not isinstance(self.oil, Oil):
            raise ParameterError(f"oil = {self.oil!r:.60} is a {type(self.oil).__name__}; expected an Oil "
                                 "(frbmodel.Oil(...) or frbmodel.OILS[name]) or None")
        if len(self.bearings) != 2:
            raise ParameterError(f"number of bearings = {len(self.bearings)} is invalid: exactly 2 are supported")
        object.__setattr__(self, "gravity", check_positive("gravity", self.gravity, "m/s^2", allow_zero=True))
        if self.gravity > MAX_GRAVITY:
            raise ParameterError(f"gravity = {self.gravity!r} m/s^2 is invalid: valid range 0 ... {MAX_GRAVITY:g} "
                                 "m/s^2 (100 g)")
        check_names("bearing", [b.name for b in self.bearings])
        check_model(self.film_model)
        nodes = [b.node for b in self.bearings]
        for b in self.bearings:
            if b.node >= self.rotor.n_nodes:
                raise ParameterError(f"{b.name} bearing node = {b.node} is invalid: "
                                     f"valid range 0..{self.rotor.n_nodes - 1}")
        if nodes[0] == nodes[1]:
            raise ParameterError(f"bearing nodes = {nodes} are invalid: the two bearings need different nodes")

    @cached_property
    def bearing_loads(self) -> np.ndarray:
        """Static vertical reactions W_X [N] at the bearings (positive = upward on the shaft)."""
        return self.rotor.static_reactions([b.node for b in self.bearings], self.gravity)

    def with_(self, **changes) -> "Turbocharger":
        """Copy with changed fields.

        Parameters
        ----------
        **changes
            Field values, e.g. ``film_model="short_corrected"``, ``gravity=0.0`` [m/s²].

        Returns
        -------
        Turbocharger
        """
        return replace(self, **changes)

    def with_outer_clearance(self, clearance: float) -> "Turbocharger":
        """Copy with both outer films' radial clearance changed.

        Parameters
        ----------
        clearance : float
            Radial clearance of both outer films [m].

        Returns
        -------
        Turbocharger
        """
        bs = tuple(replace(b, outer=check_film_thickness(replace(b.outer, clearance=clearance), f"{b.name} outer film"))
                   for b in self.bearings)
        return replace(self, bearings=bs)

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict:
        """The system as plain data (SI units), the content of the files written by :meth:`save`.

        Returns
        -------
        dict
            ``name``, ``gravity`` [m/s²], ``film_model``, ``rotor`` (:meth:`Rotor.to_dict`), ``bearings``
            (two :meth:`FloatingRingBearing.to_dict`), ``units`` (a note for readers of the file) and, only if the
            system has one, ``oil`` (:meth:`Oil.to_dict`).
        """
        d = {"name": self.name, "gravity": self.gravity, "film_model": self.film_model,
             "rotor": self.rotor.to_dict(), "bearings": [b.to_dict() for b in self.bearings],
             "units": "SI: m, kg, s, Pa, Pa s, kg m^2"}
        if self.oil is not None:
            d["oil"] = self.oil.to_dict()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Turbocharger":
        """Inverse of :meth:`to_dict`; every value is validated.

        Parameters
        ----------
        d : dict
            Needs ``rotor`` and ``bearings``; ``gravity``, ``film_model`` and ``name`` are optional.

        Returns
        -------
        Turbocharger

        Raises
        ------
        ParameterError
            An unknown (misspelt) or missing key, a value of the wrong type (checked against the schema
            :data:`SYSTEM` by :func:`check_section`) or out of its valid range; the message names the key and
            its place (``bearings[0].outer.clearance``).
        """
        check_section(d, SYSTEM)
        if not d.get("units", "SI").lstrip().upper().startswith("SI"):
            raise ParameterError(f"units = {d['units']!r} is invalid: a system file is in SI units (m, kg, s, Pa, "
                                 "Pa s, kg m^2), whatever this note says; give every value in SI and leave units out "
                                 "or write units = \"SI\"")
        r = d["rotor"]
        shaft = [_build(f"rotor.shaft[{i}]", ShaftElement, **e) for i, e in enumerate(r["shaft"])]
        discs = [_build(f"rotor.discs[{i}]", Disc, **x) for i, x in enumerate(r.get("discs", []))]
        return _build("", cls, rotor=_build("rotor", Rotor, shaft=shaft, discs=discs),
                      bearings=tuple(_bearing(b, f"bearings[{i}]") for i, b in enumerate(d["bearings"])),
                      gravity=d.get("gravity", GRAVITY), film_model=d.get("film_model", "short"),
                      name=d.get("name", "turbocharger"),
                      oil=oil_from_dict(d["oil"], "oil") if "oil" in d else None)

    def save(self, path) -> Path:
        """Write the system to a TOML (written by tomli-w) or JSON file.

        Parameters
        ----------
        path : str or Path
            File name ending in ``.toml`` or ``.json``.

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        ParameterError
            Unknown suffix, or a value that is not finite.

        Examples
        --------
        >>> import tempfile, frbmodel as frb
        >>> tc = frb.turbocharger(outer_clearance=40e-6)
        >>> with tempfile.TemporaryDirectory() as d:
        ...     frb.load_system(tc.save(f"{d}/tc.toml")) == tc
        True
        """
        import tomli_w  # (only for writing TOML: an FMU in a host's Python needs numpy, scipy and numba alone)

        path = Path(path)
        d = self.to_dict()
        if path.is_dir():
            raise ParameterError(f"system file {str(path)!r} cannot be written: it is a folder")
        if path.suffix.lower() in (".json", ".toml"):
            text = json.dumps(d, indent=2) if path.suffix.lower() == ".json" else tomli_w.dumps(_toml_ready(d))
            try:
                path.write_text(text)
            except OSError as exc:  # no such folder, a folder of that name, no permission
                raise ParameterError(f"system file {str(path)!r} cannot be written: {exc.strerror or exc}") from None
        else:
            raise ParameterError(f"system file suffix = {path.suffix!r} is unknown; use .toml or .json")
        return path


def system_from_meta(meta, what="this result", need="it"):
    """The :class:`Turbocharger` a result recorded in its metadata (``meta["system"]``, :meth:`Turbocharger.to_dict`).

    Parameters
    ----------
    meta : dict
        The result's metadata.
    what, need : str
        The result and what needs the system, for the message.

    Raises
    ------
    ParameterError
        No system recorded (e.g. a result computed from an FMU).

    Examples
    --------
    >>> from frbmodel.system.presets import turbocharger
    >>> system_from_meta({"system": turbocharger(40e-6).to_dict()}).bearings[0].outer.clearance
    4e-05
    """
    if not isinstance(meta.get("system"), dict):
        raise ParameterError(f"{what} has no system in its metadata (e.g. computed from an FMU): {need} cannot be done")
    return Turbocharger.from_dict(meta["system"])


def load_system(path) -> Turbocharger:
    """Read a system written by :meth:`Turbocharger.save` (or by hand) from TOML or JSON.

    Parameters
    ----------
    path : str or Path
        ``.toml`` (read by :mod:`tomllib`) or ``.json`` file with the keys of :meth:`Turbocharger.to_dict`
        (the schema :data:`SYSTEM`).

    Returns
    -------
    Turbocharger

    Raises
    ------
    ParameterError
        The file does not exist or cannot be read; it is not valid TOML/JSON (the message names the file, the
        line and the column and shows the line); or its content does not fit the schema or holds an invalid
        value (the message names the file and the key, see :meth:`Turbocharger.from_dict`).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if path.is_dir():
        raise ParameterError(f"system file = {str(path)!r} is a folder; expected a .toml or .json file")
    if suffix not in (".toml", ".json"):
        raise ParameterError(f"system file suffix = {path.suffix!r} is unknown; use .toml or .json")
    if not path.exists():
        raise ParameterError(f"system file = {str(path)!r} does not exist")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"system file = {str(path)!r} cannot be read: {exc}") from None
    try:
        d = json.loads(text, object_pairs_hook=_unique_keys) if suffix == ".json" else tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise _syntax_error(path, text, exc) from None
    except ParameterError as exc:
        raise ParameterError(f"system file {str(path)!r}: {exc}") from None
    try:
        return Turbocharger.from_dict(d)
    except ParameterError as exc:
        raise ParameterError(f"system file {str(path)!r}: {exc}") from None


def _unique_keys(pairs) -> dict:
    """A JSON object as a dict, or a ParameterError for a key given twice (json keeps the last one silently; TOML
    refuses a repeated key itself)."""
    d = {}
    for k, v in pairs:
        if k in d:
            raise ParameterError(f"key {k!r} is given twice in one table (values {d[k]!r:.40} and {v!r:.40}); give "
                                 "it once")
        d[k] = v
    return d


def _syntax_error(path, text, exc) -> ParameterError:
    """ParameterError naming the file, line and column of a TOML/JSON decoding error, showing the line."""
    msg = getattr(exc, "msg", None) or str(exc)
    line, col = getattr(exc, "lineno", None), getattr(exc, "colno", None)
    m = re.search(r"\s*\(at (?:line (\d+), column (\d+)|end of document)\)$", msg)
    if m:  # tomllib before Python 3.14 gives the position only in its message
        msg = msg[:m.start()]
        if m.group(1):
            line, col = int(m.group(1)), int(m.group(2))
    lines = text.splitlines() or [""]
    if line is None:  # at the end of the document (a truncated file)
        line, col = len(lines), len(lines[-1]) + 1
    kind = "JSON" if isinstance(exc, json.JSONDecodeError) else "TOML"
    shown = lines[line - 1] if 0 < line <= len(lines) else ""
    return ParameterError(f"system file {str(path)!r}, line {line}, column {col}: not valid {kind}: {msg}\n"
                          f"    {shown}\n    {' ' * (col - 1)}^")


def _toml_ready(v):
    """Copy of the system dictionary with plain Python scalars (numpy scalars converted), as tomli-w needs;
    a non-finite number raises :class:`ParameterError` (no system quantity may be NaN or infinite)."""
    if isinstance(v, dict):
        return {k: _toml_ready(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_toml_ready(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        raise ParameterError(f"value {v!r} cannot be written to TOML: it must be finite")
    return v


def check_bearing(bearing, name="bearing"):
    """Return ``bearing`` if it is a :class:`FloatingRingBearing`, else raise :class:`ParameterError` naming what was
    given (e.g. a bearing's name instead of the bearing).

    Examples
    --------
    >>> from frbmodel.system.presets import turbocharger
    >>> check_bearing(turbocharger().bearings[0]).name
    'turbine'
    """
    if not isinstance(bearing, FloatingRingBearing):
        raise ParameterError(f"{name} = {bearing!r:.80} is a {type(bearing).__name__}; expected a FloatingRingBearing "
                             "(e.g. frb.turbocharger().bearings[0], or system.bearings[k])")
    return bearing
