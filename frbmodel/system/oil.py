"""The lubricant: viscosity–temperature law from a datasheet (ASTM D341, Walther), density and specific heat
(docs/theory/thermal.md#oil).

A datasheet gives the kinematic viscosity at 40 °C and 100 °C (ASTM D445), the density at 15 °C and rarely more.
The Walther relation of ASTM D341,

    log10 log10(ν [mm²/s] + 0.7) = A − B log10 T [K],

through those two points gives ν(T); the density falls linearly with temperature, ρ(T) = ρ15 (1 − α (T − 288.15 K));
the dynamic viscosity of the films is μ = ρ ν [Pa s]. The named oils of :data:`OILS` are typical values of their
grades (the table's comments say where each number comes from).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..core.errors import ParameterError, check_real

__all__ = ["OIL", "OILS", "Oil", "check_no_oil", "check_temperature", "oil_from_dict", "walther_coefficients"]

#: datasheet temperatures of the two viscosities [K] (40 °C and 100 °C, ASTM D445 / ISO 3104)
T40_K, T100_K = 313.15, 373.15
#: reference temperature of the density [K] (15 °C, ISO 12185)
T15_K = 288.15
#: the temperatures at which the viscosity law is used [K]: −30 °C ... 200 °C, the range of the ASTM D341 chart
#: for lubricating oils; the law itself is also refused where it gives ν < 2 mm²/s (below that, D341's constant 0.7
#: alone is no longer accurate and the standard adds correction terms not implemented here)
T_MIN_K, T_MAX_K = 243.15, 473.15
#: smallest kinematic viscosity [mm²/s] at which the two-constant Walther form is used
NU_MIN_MM2_S = 2.0


def walther_coefficients(t1_K, nu1_mm2_s, t2_K, nu2_mm2_s):
    """The constants (A, B) of log10 log10(ν + 0.7) = A − B log10 T through two points.

    Parameters
    ----------
    t1_K, t2_K : float
        Temperatures [K], t1 < t2.
    nu1_mm2_s, nu2_mm2_s : float
        Kinematic viscosities [mm²/s] at t1 and t2, nu1 > nu2 > 0.

    Returns
    -------
    A, B : float
        Walther constants [-] (B > 0 for an oil that thins with temperature).

    Examples
    --------
    >>> a, b = walther_coefficients(313.15, 46.0, 373.15, 6.8)
    >>> round(b, 4)
    3.6844
    """
    w1 = math.log10(math.log10(nu1_mm2_s + 0.7))
    w2 = math.log10(math.log10(nu2_mm2_s + 0.7))
    b = (w1 - w2) / (math.log10(t2_K) - math.log10(t1_K))
    return w1 + b * math.log10(t1_K), b


def check_temperature(name, temperature_K, minimum_K=T_MIN_K, maximum_K=T_MAX_K):
    """Return ``float(temperature_K)`` if it is a finite number in ``minimum_K`` ... ``maximum_K``, else raise
    :class:`ParameterError` naming ``name``, the value and the valid range.

    Examples
    --------
    >>> check_temperature("supply temperature", 363.15)
    363.15
    >>> try:
    ...     check_temperature("supply temperature", 90.0)
    ... except ParameterError as exc:
    ...     print(exc)
    supply temperature = 90.0 K is invalid: valid range 243.15 ... 473.15 K (-30 ... 200 °C); temperatures are in K
    """
    nonfinite = isinstance(temperature_K, float) and not math.isfinite(temperature_K)  # (given the range below)
    t = temperature_K if nonfinite else check_real(name, temperature_K, "K")
    if not minimum_K <= t <= maximum_K:
        raise ParameterError(f"{name} = {t!r} K is invalid: valid range {minimum_K:g} ... {maximum_K:g} K "
                             f"({minimum_K - 273.15:.0f} ... {maximum_K - 273.15:.0f} °C); temperatures are in K")
    return t


def check_no_oil(system, what):
    """Refuse a ``system`` with an oil (a system file's ``[oil]`` table) where ``what`` runs at the films' constant
    viscosities: the oil would be ignored without a word."""
    oil = getattr(system, "oil", None)
    if oil is not None:
        raise ParameterError(f"system {getattr(system, 'name', '')!r} has an oil ({oil.name}, its [oil] table): {what} "
                             "runs at the films' constant viscosities and would ignore it; remove the [oil] table "
                             "(campbell, equilibrium, unbalance, runup, bifurcation, losses and sweep take an oil)")
    return system


@dataclass(frozen=True)
class Oil:
    """A lubricating oil from its datasheet values.

    Parameters
    ----------
    nu40_m2_s : float
        Kinematic viscosity at 40 °C [m²/s] (a datasheet's "mm²/s at 40 °C" × 1e-6).
    nu100_m2_s : float
        Kinematic viscosity at 100 °C [m²/s], 0 < nu100 < nu40.
    density15_kg_m3 : float
        Density at 15 °C [kg/m³], 600 ... 1200.
    density_coefficient_1_K : float
        Relative density decrease per kelvin α [1/K], 0 ... 2e-3 (mineral and synthetic oils: about 6e-4 ... 7e-4).
    specific_heat_J_kgK : float
        Specific heat c_p [J/(kg K)], 1000 ... 3000 (oils: about 1900 ... 2200 in the working range).
    name : str
        A label.

    Examples
    --------
    >>> oil = Oil(46e-6, 6.8e-6, 870.0, 6.5e-4, 2000.0, "ISO VG 46")
    >>> round(oil.kinematic_viscosity(313.15) * 1e6, 12), round(oil.kinematic_viscosity(373.15) * 1e6, 12)
    (46.0, 6.8)
    >>> round(oil.dynamic_viscosity(363.15) * 1e3, 3)   # [mPa s] at 90 °C
    7.094
    """

    nu40_m2_s: float
    nu100_m2_s: float
    density15_kg_m3: float
    density_coefficient_1_K: float = 6.5e-4
    specific_heat_J_kgK: float = 2000.0
    name: str = "oil"

    def __post_init__(self):
        nu40 = check_real("oil nu40_m2_s", self.nu40_m2_s, "m^2/s", minimum=0.0)
        nu100 = check_real("oil nu100_m2_s", self.nu100_m2_s, "m^2/s", minimum=0.0)
        if not NU_MIN_MM2_S * 1e-6 <= nu100 < nu40 <= 1e-2:
            raise ParameterError(
                f"oil viscosities nu40_m2_s = {nu40:g}, nu100_m2_s = {nu100:g} m^2/s are invalid: valid range "
                f"{NU_MIN_MM2_S:g}e-6 <= nu100 < nu40 <= 1e-2 m^2/s (an oil thins with temperature; give m^2/s, "
                "i.e. mm^2/s x 1e-6)")
        rho = check_real("oil density15_kg_m3", self.density15_kg_m3, "kg/m^3", minimum=0.0)
        alpha = check_real("oil density_coefficient_1_K", self.density_coefficient_1_K, "1/K", minimum=0.0,
                           inclusive=True)
        cp = check_real("oil specific_heat_J_kgK", self.specific_heat_J_kgK, "J/(kg K)", minimum=0.0)
        for what, v, lo, hi, unit in (("density15_kg_m3", rho, 600.0, 1200.0, "kg/m^3"),
                                      ("density_coefficient_1_K", alpha, 0.0, 2e-3, "1/K"),
                                      ("specific_heat_J_kgK", cp, 1000.0, 3000.0, "J/(kg K)")):
            if not lo <= v <= hi:
                raise ParameterError(f"oil {what} = {v:g} {unit} is invalid: valid range {lo:g} ... {hi:g} {unit}")
        if not isinstance(self.name, str):
            raise ParameterError(f"oil name = {self.name!r} is a {type(self.name).__name__}; expected a string")
        for f, v in (("nu40_m2_s", nu40), ("nu100_m2_s", nu100), ("density15_kg_m3", rho),
                     ("density_coefficient_1_K", alpha), ("specific_heat_J_kgK", cp)):
            object.__setattr__(self, f, v)
        _check_known_name(self)

    @property
    def walther(self):
        """(A, B) of log10 log10(ν [mm²/s] + 0.7) = A − B log10 T [K] through the two datasheet points."""
        return walther_coefficients(T40_K, self.nu40_m2_s * 1e6, T100_K, self.nu100_m2_s * 1e6)

    @property
    def max_temperature_K(self) -> float:
        """Highest temperature [K] of the viscosity law: 473.15 K or where ν falls to 2 mm²/s, whichever is lower."""
        a, b = self.walther
        t_nu_min = 10.0 ** ((a - math.log10(math.log10(NU_MIN_MM2_S + 0.7))) / b)
        return min(T_MAX_K, t_nu_min)

    def _check(self, temperature_K) -> float:
        return check_temperature(f"{self.name} temperature", temperature_K, T_MIN_K, self.max_temperature_K)

    def kinematic_viscosity(self, temperature_K) -> float:
        """ν(T) [m²/s] by ASTM D341 (Walther) through the two datasheet points.

        Parameters
        ----------
        temperature_K : float
            Oil temperature [K], in 243.15 K ... :attr:`max_temperature_K`.

        Returns
        -------
        float

        Raises
        ------
        ParameterError
            Temperature outside the valid range.
        """
        a, b = self.walther
        t = self._check(temperature_K)
        return (10.0 ** (10.0 ** (a - b * math.log10(t))) - 0.7) * 1e-6

    def density(self, temperature_K) -> float:
        """ρ(T) = ρ15 (1 − α (T − 288.15 K)) [kg/m³] (same temperature range as the viscosity)."""
        return self.density15_kg_m3 * (1.0 - self.density_coefficient_1_K * (self._check(temperature_K) - T15_K))

    def dynamic_viscosity(self, temperature_K) -> float:
        """μ(T) = ρ(T) ν(T) [Pa s]."""
        return self.density(temperature_K) * self.kinematic_viscosity(temperature_K)

    def to_dict(self) -> dict:
        """The oil as plain data (SI, the keys of the system file's ``[oil]`` table)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict, where: str = "oil") -> "Oil":
        """Inverse of :meth:`to_dict`, or ``{"name": ...}`` for one of :data:`OILS`; see :func:`oil_from_dict`."""
        return oil_from_dict(d, where)


def _check_known_name(oil):
    """Refuse an oil that has the name of one of :data:`OILS` but other numbers: its results would be labelled
    with the known oil's name. Every oil passes here, built in code or read from an ``[oil]`` table (the table's
    parser alone refused it). (The named oils themselves are built before :data:`OILS` exists.)"""
    known = globals().get("OILS", {}).get(oil.name)
    if known is None or oil == known:
        return
    mine, theirs = oil.to_dict(), known.to_dict()
    diff = [f"{k} = {v!r} (not {theirs[k]!r})" for k, v in mine.items() if v != theirs[k]]
    raise ParameterError(f"oil name = {oil.name!r} is a known oil, but {', '.join(diff)}: its results would be "
                         f"labelled {oil.name!r}; give another name for these numbers, or the known oil itself "
                         f"(frbmodel.OILS[{oil.name!r}], or name = {oil.name!r} alone in an [oil] table)")


# Named oils: typical values of their grades. The viscosity at 100 °C of each engine oil lies inside its SAE J300
# grade's published range (0W-20: 6.9 ... <9.3, 5W-30: 9.3 ... <12.5, 10W-40 and 15W-40: 12.5 ... <16.3 mm²/s) and the
# turbine oil's viscosity at 40 °C is the ISO 3448 mid-point of VG 46 (41.4 ... 50.6 mm²/s). The other numbers (ν at
# 40 °C of the engine oils, ν at 100 °C of the turbine oil, densities) are typical values of the grade, not taken from
# one product's datasheet; the density coefficient 6.5e-4 1/K and c_p = 2000 J/(kg K) are typical of mineral and
# synthetic oils (0.06 ... 0.07 % per K; 1.9 ... 2.2 kJ/(kg K)). Give a product's datasheet values as an [oil] table
# for a real oil.
OILS = {
    "SAE 0W-20": Oil(44e-6, 8.5e-6, 845.0, 6.5e-4, 2000.0, "SAE 0W-20"),
    "SAE 5W-30": Oil(64e-6, 11.0e-6, 852.0, 6.5e-4, 2000.0, "SAE 5W-30"),
    "SAE 10W-40": Oil(95e-6, 14.5e-6, 868.0, 6.5e-4, 2000.0, "SAE 10W-40"),
    "SAE 15W-40": Oil(110e-6, 14.8e-6, 880.0, 6.5e-4, 2000.0, "SAE 15W-40"),
    "ISO VG 46": Oil(46e-6, 6.8e-6, 870.0, 6.5e-4, 2000.0, "ISO VG 46"),
}
#: the keys an ``[oil]`` table may hold (either ``name`` alone, for one of :data:`OILS`, or the numbers)
OIL_KEYS = ("nu40_m2_s", "nu100_m2_s", "density15_kg_m3", "density_coefficient_1_K", "specific_heat_J_kgK", "name")


def OIL(name) -> Oil:
    """The named oil of :data:`OILS`, or a :class:`ParameterError` listing the names.

    Examples
    --------
    >>> OIL("SAE 5W-30").nu100_m2_s
    1.1e-05
    """
    if not isinstance(name, str) or name not in OILS:
        raise ParameterError(f"oil name = {name!r} is unknown; known oils: {', '.join(OILS)} (or give the numbers "
                             "nu40_m2_s, nu100_m2_s, density15_kg_m3, ... of an [oil] table)")
    return OILS[name]


def oil_from_dict(d, where="oil") -> Oil:
    """An :class:`Oil` from an ``[oil]`` table: ``{"name": "SAE 5W-30"}`` (a named oil) or the numbers of
    :meth:`Oil.to_dict` (``density_coefficient_1_K``, ``specific_heat_J_kgK`` and ``name`` optional).

    Raises
    ------
    ParameterError
        Not a table, an unknown key (the message lists the valid keys), a missing viscosity or density, or a value
        out of its range; the message starts with ``where``.

    Examples
    --------
    >>> oil_from_dict({"name": "ISO VG 46"}).nu40_m2_s
    4.6e-05
    >>> oil_from_dict({"nu40_m2_s": 46e-6, "nu100_m2_s": 6.8e-6, "density15_kg_m3": 870.0}).specific_heat_J_kgK
    2000.0
    """
    if not isinstance(d, dict):
        raise ParameterError(f"{where} = {d!r:.60} is a {type(d).__name__}; expected a table with the keys "
                             f"{', '.join(OIL_KEYS)}")
    unknown = [k for k in d if k not in OIL_KEYS]
    if unknown:
        raise ParameterError(f"unknown key {unknown[0]!r} in {where}; valid keys: {', '.join(OIL_KEYS)}")
    try:
        if set(d) == {"name"}:
            return OIL(d["name"])
        missing = [k for k in OIL_KEYS[:3] if k not in d]
        if missing:
            raise ParameterError(f"lacks {', '.join(missing)}: give name = one of {', '.join(OILS)}, or the numbers "
                                 f"({', '.join(OIL_KEYS[:3])} required)")
        return Oil(**d)  # (a known oil's name with other numbers is refused by Oil itself)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
