"""System description: floating-ring bearings and the turbocharger (rotor + two bearings), with file I/O.

A system can be saved to and loaded from TOML or JSON (:meth:`Turbocharger.save`,
:func:`load_system`), so users can model their own turbocharger. All quantities are SI.
"""
from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path

import numpy as np
import tomli_w

from .errors import ParameterError, check_positive
from .film import Film, check_model
from .rotor import GRAVITY, Rotor


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
    def from_dict(cls, d: dict) -> "FloatingRingBearing":
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            Keys as written by :meth:`to_dict` (``name`` optional).

        Returns
        -------
        FloatingRingBearing
        """
        return cls(node=d["node"], name=d.get("name", "bearing"), ring_mass=d["ring_mass"],
                   ring_inertia=d["ring_inertia"], inner=Film(**d["inner"]), outer=Film(**d["outer"]))


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

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger(outer_clearance=36e-6)
    >>> [round(float(w), 4) for w in tc.bearing_loads]   # static reactions [N], physics.md §10
    [5.3093, -0.1843]
    """

    rotor: Rotor
    bearings: tuple
    gravity: float = GRAVITY
    film_model: str = "short"
    name: str = "turbocharger"

    def __post_init__(self):
        object.__setattr__(self, "bearings", tuple(self.bearings))
        if len(self.bearings) != 2:
            raise ParameterError(f"number of bearings = {len(self.bearings)} is invalid: exactly 2 are supported")
        object.__setattr__(self, "gravity", check_positive("gravity", self.gravity, "m/s^2", allow_zero=True))
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
        bs = tuple(replace(b, outer=replace(b.outer, clearance=clearance)) for b in self.bearings)
        return replace(self, bearings=bs)

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict:
        """The system as plain data (SI units), the content of the files written by :meth:`save`.

        Returns
        -------
        dict
            ``name``, ``gravity`` [m/s²], ``film_model``, ``rotor`` (:meth:`Rotor.to_dict`), ``bearings``
            (two :meth:`FloatingRingBearing.to_dict`) and ``units`` (a note for readers of the file).
        """
        return {"name": self.name, "gravity": self.gravity, "film_model": self.film_model,
                "rotor": self.rotor.to_dict(), "bearings": [b.to_dict() for b in self.bearings],
                "units": "SI: m, kg, s, Pa, Pa s, kg m^2"}

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
            A section is missing or a value is out of its valid range (the message names it).
        """
        for key in ("rotor", "bearings"):
            if key not in d:
                raise ParameterError(f"system description lacks the required section '{key}'")
        return cls(rotor=Rotor.from_dict(d["rotor"]),
                   bearings=tuple(FloatingRingBearing.from_dict(b) for b in d["bearings"]),
                   gravity=d.get("gravity", GRAVITY), film_model=d.get("film_model", "short"),
                   name=d.get("name", "turbocharger"))

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
        path = Path(path)
        d = self.to_dict()
        if path.suffix.lower() == ".json":
            path.write_text(json.dumps(d, indent=2))
        elif path.suffix.lower() == ".toml":
            path.write_text(tomli_w.dumps(_toml_ready(d)))
        else:
            raise ParameterError(f"system file suffix = {path.suffix!r} is unknown; use .toml or .json")
        return path


def load_system(path) -> Turbocharger:
    """Read a system written by :meth:`Turbocharger.save` (or by hand) from TOML or JSON.

    Parameters
    ----------
    path : str or Path
        ``.toml`` (read by :mod:`tomllib`) or ``.json`` file with the keys of :meth:`Turbocharger.to_dict`.

    Returns
    -------
    Turbocharger

    Raises
    ------
    ParameterError
        The file does not exist, cannot be parsed, lacks a section or holds an invalid value.
    """
    path = Path(path)
    if not path.exists():
        raise ParameterError(f"system file = {str(path)!r} does not exist")
    text = path.read_text()
    if path.suffix.lower() == ".json":
        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ParameterError(f"system file = {str(path)!r} is not valid JSON: {exc}") from None
    elif path.suffix.lower() == ".toml":
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(f"system file = {str(path)!r} is not valid TOML: {exc}") from None
    else:
        raise ParameterError(f"system file suffix = {path.suffix!r} is unknown; use .toml or .json")
    return Turbocharger.from_dict(d)


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
