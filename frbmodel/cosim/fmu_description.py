"""The parts of an FMU's modelDescription.xml that pythonfmu 0.7 does not write: valid ranges (``min``/``max``),
the real dependencies in ``ModelStructure`` (Outputs and InitialUnknowns) and constant outputs.

Each slave declares what it knows where it registers a variable (``fmu_src/_fmu_common.py``: the range of a
parameter or input, the inputs an output depends on); its ``to_xml`` hands those declarations to :func:`finish`.

FMI 2.0 (section 2.2.8): an ``<Unknown>`` without ``dependencies`` depends on *all* knowns, so a tool that analyses
dependencies sees an algebraic loop wherever two FMUs feed each other; ``dependencies=""`` says it depends on none.
At communication points the knowns are the inputs; in Initialization Mode also the parameters (``initial="exact"``).
"""
from __future__ import annotations

import math
from xml.etree.ElementTree import Element


def _index(root):
    """{variable name: (1-based index, ScalarVariable element)} of the model description ``root``."""
    return {sv.get("name"): (i, sv) for i, sv in enumerate(root.iter("ScalarVariable"), start=1)}


def _indices(names, index):
    return " ".join(str(i) for i in sorted(index[n][0] for n in names))


def set_ranges(root: Element, ranges: dict) -> Element:
    """``min``/``max`` on the ``<Real>`` of each variable of ``ranges`` (``{name: (low, high)}``, infinite bounds
    left out).

    Parameters
    ----------
    root : Element
        The ``fmiModelDescription`` element.
    ranges : dict

    Returns
    -------
    Element
        ``root`` (modified in place).

    Examples
    --------
    >>> from xml.etree.ElementTree import fromstring, tostring
    >>> root = fromstring('<m><ModelVariables><ScalarVariable name="c"><Real/></ScalarVariable></ModelVariables></m>')
    >>> tostring(set_ranges(root, {"c": (0.0, math.inf)}).find(".//Real")).decode()
    '<Real min="0" />'
    """
    index = _index(root)
    for name, (low, high) in ranges.items():
        real = index[name][1].find("Real")
        if real is None:
            continue
        for key, value in (("min", low), ("max", high)):
            if value is not None and math.isfinite(value):
                real.set(key, f"{float(value):.16g}")
    return root


def set_model_structure(root: Element, outputs: dict, initial: dict, parameters) -> Element:
    """Rewrite ``ModelStructure``: ``Outputs`` and ``InitialUnknowns`` with their dependencies.

    Parameters
    ----------
    root : Element
        The ``fmiModelDescription`` element.
    outputs : dict
        ``{output name: tuple of input names it depends on at communication points}`` (None: on all knowns).
    initial : dict
        ``{output name: tuple of input names it depends on in Initialization Mode}`` for the outputs with
        ``initial="calculated"``; they depend on the ``parameters`` as well.
    parameters : iterable of str
        The parameters (``initial="exact"``: knowns in Initialization Mode).

    Returns
    -------
    Element
        ``root`` (modified in place).
    """
    index = _index(root)
    structure = root.find("ModelStructure")
    for old in list(structure):
        structure.remove(old)
    params = list(parameters)
    for tag, table, extra in (("Outputs", outputs, ()), ("InitialUnknowns", initial, params)):
        if not table:
            continue
        node = Element(tag)
        for name in sorted(table, key=lambda n: index[n][0]):
            attrs = {"index": str(index[name][0])}
            deps = table[name]
            if deps is not None:
                attrs["dependencies"] = _indices(list(deps) + list(extra), index)
            node.append(Element("Unknown", attrs))
        structure.append(node)
    return root


def finish(root: Element, ranges: dict, outputs: dict, initial: dict, parameters) -> Element:
    """:func:`set_ranges` and :func:`set_model_structure` in one call (see there)."""
    return set_model_structure(set_ranges(root, ranges), outputs, initial, parameters)


__all__ = ["set_ranges", "set_model_structure", "finish"]
