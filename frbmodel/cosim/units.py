"""Units of the FMUs' Real variables: unit algebra and the FMI 2.0 ``UnitDefinitions``.

Each slave declares the unit of every Real variable where it registers the variable (``unit=`` of the mixin's
``_param`` / ``_input`` / ``_output`` in ``fmu_src/_fmu_common.py``); the slave's ``to_xml`` then calls
:func:`declare_units`, so the unit attribute of each ``<Real>`` and the ``<UnitDefinitions>`` come from that one
declaration when pythonfmu writes modelDescription.xml. pythonfmu 0.7 itself has no unit support.

Unit names follow the FMI/Modelica convention: factors joined by ``.``, integer powers appended (``kg.m2``,
``m/s2``), one ``/`` with a parenthesized denominator of several factors (``m/(rad.s2)``), ``1`` for a
dimensionless quantity. Tokens are the SI base units of FMI's BaseUnit (kg, m, s, A, K, mol, cd, rad) and the
derived units N, Pa, J, W and Hz.
"""
from __future__ import annotations

import math
import re
from xml.etree.ElementTree import Element, SubElement

#: FMI 2.0 BaseUnit exponents, in the order used for generated unit names
BASE = ("kg", "m", "rad", "s", "A", "K", "mol", "cd")
#: derived units allowed as tokens: exponents of the base units
DERIVED = {"N": {"kg": 1, "m": 1, "s": -2}, "Pa": {"kg": 1, "m": -1, "s": -2}, "J": {"kg": 1, "m": 2, "s": -2},
           "W": {"kg": 1, "m": 2, "s": -3}, "Hz": {"s": -1}}
#: names used for a combination of exponents when it occurs (instead of a generated base-unit name)
PREFERRED = ("1", "m", "m/s", "m/s2", "rad", "rad/s", "rad/s2", "s", "kg", "kg.m", "kg.m2", "N", "N/m", "N.s/m",
             "N.m", "W", "Pa.s")
#: display units per unit: (name, factor) with display value = factor * value (FMI 2.0 DisplayUnit)
DISPLAY = {"rad/s": (("rpm", 30.0 / math.pi),), "m": (("um", 1e6),)}

_TOKEN = re.compile(r"^([A-Za-z]+)(-?\d+)?$")


def exponents(unit: str) -> dict:
    """Base-unit exponents of a unit name.

    Parameters
    ----------
    unit : str
        e.g. ``"N.s/m"``, ``"kg.m2"``, ``"m/(rad.s2)"``, ``"1"``.

    Returns
    -------
    dict
        ``{base unit: exponent}`` without zero entries (``{}`` for ``"1"``).

    Raises
    ------
    ValueError
        A token that is neither a base unit of :data:`BASE` nor a unit of :data:`DERIVED`, or a malformed name.

    Examples
    --------
    >>> exponents("N.s/m")
    {'kg': 1, 's': -1}
    """
    num, _, den = unit.partition("/")
    den = den[1:-1] if den.startswith("(") and den.endswith(")") else den
    out: dict = {}
    for part, sign in ((num, 1), (den, -1)):
        for tok in part.split(".") if part and part != "1" else ():
            m = _TOKEN.match(tok)
            if m is None or (m.group(1) not in BASE and m.group(1) not in DERIVED):
                raise ValueError(f"unit {unit!r}: {tok!r} is not a unit token; valid: {list(BASE) + list(DERIVED)} "
                                 "with an optional integer power")
            power = sign * int(m.group(2) or 1)
            for base, e in (DERIVED[m.group(1)] if m.group(1) in DERIVED else {m.group(1): 1}).items():
                out[base] = out.get(base, 0) + e * power
    return {b: e for b, e in out.items() if e}


def unit_name(exps: dict) -> str:
    """The name of the unit with base-unit exponents ``exps``: a :data:`PREFERRED` name if one fits, else a
    generated one (``m/(rad.s2)``).

    Parameters
    ----------
    exps : dict
        ``{base unit: exponent}``.

    Returns
    -------
    str
    """
    exps = {b: e for b, e in exps.items() if e}
    for name in PREFERRED:
        if exponents(name) == exps:
            return name

    def factors(sign):
        return [f"{b}{abs(exps[b]) if abs(exps[b]) != 1 else ''}" for b in BASE if sign * exps.get(b, 0) > 0]

    num, den = factors(1), factors(-1)
    text = ".".join(num) or "1"
    if den:
        text += "/" + (den[0] if len(den) == 1 else "(" + ".".join(den) + ")")
    return text


def ratio(numerator: str, denominator: str, time_power: int = 0) -> str:
    """Unit of ``numerator / denominator · s^time_power`` (e.g. an entry of a state-space matrix).

    Parameters
    ----------
    numerator, denominator : str
        Unit names.
    time_power : int
        Extra power of the second (−1 for a time derivative of the numerator).

    Returns
    -------
    str

    Examples
    --------
    >>> ratio("m", "rad", -2), ratio("m", "N", -1), ratio("N", "m")
    ('m/(rad.s2)', 's/kg', 'N/m')
    """
    exps = dict(exponents(numerator))
    for b, e in exponents(denominator).items():
        exps[b] = exps.get(b, 0) - e
    exps["s"] = exps.get("s", 0) + time_power
    return unit_name(exps)


def unit_definitions(units) -> Element:
    """The FMI 2.0 ``<UnitDefinitions>`` element for the unit names ``units`` (sorted, each once).

    Parameters
    ----------
    units : iterable of str

    Returns
    -------
    xml.etree.ElementTree.Element
    """
    defs = Element("UnitDefinitions")
    for name in sorted(set(units)):
        u = SubElement(defs, "Unit", {"name": name})
        SubElement(u, "BaseUnit", {b: str(e) for b, e in exponents(name).items()})
        for display, factor in DISPLAY.get(name, ()):
            SubElement(u, "DisplayUnit", {"name": display, "factor": repr(factor)})
    return defs


def declare_units(root: Element, units: dict) -> Element:
    """Put the units into a modelDescription tree: ``unit`` on the ``<Real>`` of every variable and the
    ``<UnitDefinitions>`` after the ``<CoSimulation>``/``<ModelExchange>`` element (FMI 2.0 element order).

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        ``fmiModelDescription`` as pythonfmu builds it.
    units : dict
        ``{variable name: unit name}``; every Real variable must have one.

    Returns
    -------
    xml.etree.ElementTree.Element
        ``root`` (modified in place).

    Raises
    ------
    ValueError
        A Real variable without a unit, or a unit name :func:`exponents` cannot read.
    """
    missing = []
    for sv in root.iter("ScalarVariable"):
        real = sv.find("Real")
        if real is None:
            continue
        unit = units.get(sv.get("name"))
        if unit is None:
            missing.append(sv.get("name"))
            continue
        exponents(unit)  # a malformed name fails at build time
        real.set("unit", unit)
    if missing:
        raise ValueError(f"Real variables without a declared unit: {missing[:10]}{' ...' if len(missing) > 10 else ''}")
    old = root.find("UnitDefinitions")
    if old is not None:
        root.remove(old)
    kinds = [i for i, el in enumerate(root) if el.tag in ("ModelExchange", "CoSimulation")]
    root.insert(kinds[-1] + 1 if kinds else 0, unit_definitions(units[n] for n in units))
    return root


__all__ = ["exponents", "unit_name", "ratio", "unit_definitions", "declare_units", "BASE", "DERIVED", "PREFERRED",
           "DISPLAY"]
