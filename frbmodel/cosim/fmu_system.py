"""The rotor system a TurbochargerRotor FMU is built for ("baked" into the FMU at build time).

pythonfmu registers an FMU's variables when the slave is constructed, before any parameter is set, so the
variables of the rotor FMU (per-disc outputs ``<disc>.x/y``, per-bearing inputs and outputs
``<bearing>_bearing.*``, per-disc unbalance parameters, the sizes of the linearization matrices) must be fixed
when the FMU is built. ``frb build-fmus --rotor-file FILE`` therefore writes the system of FILE into the rotor
FMU's resources as :data:`RESOURCE` (:func:`write_rotor_system`); the slave builds its variables from it
(:func:`rotor_system`; without the file: the paper's Table 2 system). At run time the FMU's ``rotor_file``
parameter may select another system of the same *structure* (:func:`structure_differences`: node count, disc
names, bearing names and order) — other geometry, materials, masses, node positions, bearing nodes or gravity —
and anything else is refused at initialization with the differences named.
"""
from __future__ import annotations

import json
import re
import zipfile
from pathlib import Path

from ..core.errors import ParameterError
from ..system.oil import check_no_oil
from ..system.parameters import Turbocharger, load_system
from ..system.presets import turbocharger

#: file name of the built-in system inside the rotor FMU's resources folder
RESOURCE = "rotor_system.json"
_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def as_system(system):
    """A Turbocharger from a Turbocharger or a system file path."""

    return system if isinstance(system, Turbocharger) else load_system(system)


def check_names(system) -> None:
    """Refuse disc and bearing names that cannot be parts of FMI variable names.

    Parameters
    ----------
    system : Turbocharger

    Raises
    ------
    ParameterError
        A name that is not an identifier (letters, digits, underscores; not starting with a digit) — it becomes
        part of variable names such as ``<disc>.x`` — or two discs / bearings of the same name.
    """
    for kind, names in (("disc", [d.name for d in system.rotor.discs]), ("bearing", [b.name for b in system.bearings])):
        for n in names:
            if not _IDENTIFIER.match(n):
                raise ParameterError(f"{kind} name = {n!r} is invalid for an FMU: use letters, digits and underscores, "
                                     "not starting with a digit (it becomes part of FMI variable names)")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ParameterError(f"{kind} names {dup} occur more than once; FMU variables need unique names")


def write_rotor_system(system, folder) -> Path:
    """Write the system the rotor FMU is built for into ``folder`` (a build's project files).

    Parameters
    ----------
    system : Turbocharger or str or Path
        The system, or a system file written by ``frb system`` (TOML/JSON).
    folder : str or Path
        Existing folder; gets :data:`RESOURCE`.

    Returns
    -------
    Path
        The written file, to be passed to pythonfmu's builder as a project file of the rotor FMU.

    Raises
    ------
    ParameterError
        The file cannot be read or holds an invalid system, or a name unusable in FMI variable names.
    """
    return check_rotor_system(system).save(Path(folder) / RESOURCE)


def check_rotor_system(system):
    """The Turbocharger of ``system`` (or of a system file) if a rotor FMU can be built for it: names usable in FMI
    variable names, and no oil (the bearing FMUs take theirs from the SSP parameter set; it would be ignored)."""
    tc = check_no_oil(as_system(system), "the rotor FMU's system (the bearing FMUs take their oil from the SSP "
                      "parameter set, parameter oil)")
    check_names(tc)
    return tc


def rotor_system(resources=None):
    """The system a rotor FMU was built for, from its resources folder.

    Parameters
    ----------
    resources : str or Path, optional
        The FMU's resources folder (or, while pythonfmu builds the FMU, its staging folder).

    Returns
    -------
    Turbocharger
        The system of ``<resources>/rotor_system.json``; the paper's Table 2 system
        (:func:`frbmodel.system.presets.turbocharger`) when there is no such file.
    """

    path = Path(resources) / RESOURCE if resources else None
    return load_system(path) if path is not None and path.is_file() else turbocharger()


def rotor_system_of_fmu(fmu):
    """The system a rotor FMU was built for, read from the ``.fmu`` archive or its unzipped folder.

    Parameters
    ----------
    fmu : str or Path

    Returns
    -------
    Turbocharger
        As :func:`rotor_system`.
    """

    fmu = Path(fmu)
    if fmu.is_dir():
        return rotor_system(fmu / "resources")
    with zipfile.ZipFile(fmu) as z:
        name = f"resources/{RESOURCE}"
        if name not in z.namelist():
            return rotor_system(None)
        return Turbocharger.from_dict(json.loads(z.read(name).decode("utf-8")))


def structure(system) -> dict:
    """What fixes the rotor FMU's variables: node count, disc names, bearing names (in order).

    Parameters
    ----------
    system : Turbocharger

    Returns
    -------
    dict
        ``{"nodes": int, "discs": sorted list of str, "bearings": list of str}``.
    """
    return {"nodes": system.rotor.n_nodes, "discs": sorted(d.name for d in system.rotor.discs),
            "bearings": [b.name for b in system.bearings]}


def structure_differences(built_for, other) -> list:
    """How ``other`` differs in structure from the system a rotor FMU was built for.

    Parameters
    ----------
    built_for, other : Turbocharger

    Returns
    -------
    list of str
        One sentence per difference (empty when the FMU's variables fit ``other``).
    """
    a, b = structure(built_for), structure(other)
    what = {"nodes": "node count", "discs": "disc names", "bearings": "bearing names (in order)"}
    return [f"{what[k]} {b[k]} (the FMU was built for {a[k]})" for k in a if a[k] != b[k]]


__all__ = ["RESOURCE", "check_names", "write_rotor_system", "rotor_system", "rotor_system_of_fmu", "structure",
           "structure_differences"]
