"""The description of one oil film (geometry and lubricant) and the film models' names; the forces are
:mod:`frbmodel.physics.film`."""
from __future__ import annotations

from dataclasses import asdict, dataclass

from ..core.errors import ParameterError, check_real

__all__ = ["FILM_MODELS", "FILM_NAMES", "Film", "check_film", "check_film_thickness", "check_model"]

#: the smallest clearance / radius of a film: turbocharger bearings run at 1e-3 ... 1e-2 (Table 2: 6e-3); below
#: 1e-4 (0.55 µm on a 5.5 mm journal) the clearance is the size of the ground surfaces' roughness (~0.1-0.8 µm Ra),
#: so no hydrodynamic film forms (an outer clearance of 1e-12 m gave RSR 0 and "no unstable mode")
MIN_CLEARANCE_OF_RADIUS = 1e-4
#: names of the four films of the Table 2 system, in the order bearing 0 inner, outer, bearing 1 inner, outer (the
#: default labels when a result carries none)
FILM_NAMES = ("turbine inner", "turbine outer", "compressor inner", "compressor outer")

FILM_MODELS = ("short", "short_corrected")


@dataclass(frozen=True)
class Film:
    """Geometry and lubricant of one oil film.

    Parameters
    ----------
    radius : float
        Film radius R [m] (journal radius for the inner film, ring outer radius for the outer film).
    length : float
        Axial film length L [m].
    clearance : float
        Radial clearance c [m].
    viscosity : float
        Dynamic viscosity μ [Pa s].

    Examples
    --------
    >>> f = Film(radius=5.5e-3, length=6.5e-3, clearance=34e-6, viscosity=4.9e-3)
    >>> round(f.length_to_diameter, 4)
    0.5909
    """

    radius: float
    length: float
    clearance: float
    viscosity: float

    def __post_init__(self):
        for name, unit in (("radius", "m"), ("length", "m"), ("clearance", "m"), ("viscosity", "Pa s")):
            object.__setattr__(self, name, check_real(f"film {name}", getattr(self, name), unit, minimum=0.0))
        if self.clearance >= 0.1 * self.radius:
            raise ParameterError(
                f"film clearance = {self.clearance:g} m is invalid for radius {self.radius:g} m: the thin-film "
                f"(Reynolds) theory needs clearance < 0.1 * radius = {0.1 * self.radius:g} m")


    @property
    def length_to_diameter(self) -> float:
        """L/D [-]."""
        return self.length / (2.0 * self.radius)

    def to_dict(self) -> dict:
        """The film as plain data ``{radius, length, clearance, viscosity}`` [SI]."""
        return asdict(self)


def check_film(film, name="film") -> Film:
    """Return ``film`` if it is a :class:`Film`, else raise :class:`ParameterError` naming what was given.

    Parameters
    ----------
    film : Film
    name : str
        The argument's name, used in the message.

    Returns
    -------
    Film

    Examples
    --------
    >>> check_film(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)).clearance
    3.4e-05
    """
    if not isinstance(film, Film):
        raise ParameterError(f"{name} = {film!r:.80} is a {type(film).__name__}; expected a Film "
                             "(frbmodel.Film(radius, length, clearance, viscosity) or bearing.inner / bearing.outer)")
    return film


def check_model(film_model: str) -> str:
    """Return ``film_model`` if it is one of :data:`FILM_MODELS`, else raise :class:`ParameterError`.

    Parameters
    ----------
    film_model : str
        ``"short"`` or ``"short_corrected"``.

    Returns
    -------
    str

    Examples
    --------
    >>> check_model("short")
    'short'
    """
    if not isinstance(film_model, str) or film_model not in FILM_MODELS:
        raise ParameterError(f"film model = {film_model!r} is unknown; valid models are {', '.join(FILM_MODELS)}")
    return film_model


def check_film_thickness(film, where="film"):
    """``film`` if its clearance can carry a hydrodynamic film (at least :data:`MIN_CLEARANCE_OF_RADIUS` of its
    radius), else a :class:`ParameterError` naming ``where``, the value and the valid range. Applied to every system a
    user gives (presets, system files, ``with_outer_clearance``); a :class:`Film` itself checks only the thin-film
    theory's upper bound, so that mathematical limits (a rigid film as clearance -> 0) stay reachable in studies.

    Examples
    --------
    >>> check_film_thickness(Film(5.5e-3, 6.5e-3, 34e-6, 4.9e-3)).clearance
    3.4e-05
    """
    if film.clearance < MIN_CLEARANCE_OF_RADIUS * film.radius:
        raise ParameterError(
            f"{where} clearance = {film.clearance:g} m is invalid for radius {film.radius:g} m: valid range >= "
            f"{MIN_CLEARANCE_OF_RADIUS:g} * radius = {MIN_CLEARANCE_OF_RADIUS * film.radius:g} m (a thinner film "
            "is below the surfaces' roughness: no hydrodynamic film forms)")
    return film
