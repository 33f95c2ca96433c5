"""The paper's Table 2 turbocharger in SI units (docs/theory/parameters.md#table-2-in-si-units)."""
from __future__ import annotations

from ..core.errors import check_real
from .films import Film, check_film_thickness, check_model
from .parameters import FloatingRingBearing, Turbocharger
from .rotor import Disc, Rotor, ShaftElement

#: outer clearances [m] studied in the paper
PAPER_OUTER_CLEARANCES = (36e-6, 40e-6, 42e-6, 46e-6)
#: the outer clearance of the main job and of every default [m] (the paper's first case)
DEFAULT_OUTER_CLEARANCE_M = PAPER_OUTER_CLEARANCES[0]
#: speed range [rpm] of the paper's Campbell diagrams (Figs. 4-9)
PAPER_SPEED_RANGE_RPM = (10e3, 250e3)
#: default run-up: linear ramp from / to these rotor speeds [rpm] (the rotor FMU's ramp defaults)
RUNUP_SPEED_RPM = (20e3, 250e3)
#: duration of the default run-up ramp [s]
RUNUP_DURATION = 1.0


def table2_rotor() -> Rotor:
    """The rotor of the paper's Table 2.

    Returns
    -------
    Rotor
        3 shaft elements (33, 39, 33 mm, d = 11 mm, steel) with the turbine wheel at node 0 and the compressor
        wheel at node 3.

    Examples
    --------
    >>> r = table2_rotor()
    >>> r.n_nodes, [d.name for d in r.discs]
    (4, ['turbine_wheel', 'compressor_wheel'])
    """
    d = 11e-3
    shaft = [ShaftElement(l, d, 0.0, 7860.0, 2e11) for l in (33e-3, 39e-3, 33e-3)]
    discs = [Disc(0, 0.326, 8.1e-5, 7.7e-5, "turbine_wheel"), Disc(3, 0.118, 4.4e-5, 3.27e-5, "compressor_wheel")]
    return Rotor(shaft, discs)


def turbocharger(outer_clearance: float = DEFAULT_OUTER_CLEARANCE_M, film_model: str = "short",
                 inner_clearance: float = 34e-6, viscosity_turbine: float = 4.9e-3,
                 viscosity_compressor: float = 6.4e-3) -> Turbocharger:
    """The paper's Table 2 turbocharger.

    Parameters
    ----------
    outer_clearance : float
        Radial clearance of both outer films [m] (paper: 36e-6 ... 46e-6).
    film_model : {"short", "short_corrected"}
    inner_clearance : float
        Radial clearance of both inner films [m].
    viscosity_turbine, viscosity_compressor : float
        Oil viscosity of both films of the turbine / compressor bearing [Pa s].

    Returns
    -------
    Turbocharger

    Raises
    ------
    ParameterError
        An argument that is not a finite real number > 0 (a string such as ``"36e-6"`` is refused, not converted),
        or an unknown film model; the message names the argument, its value and the valid range.

    Notes
    -----
    The ring mass is 7.2e-3 kg: the table's "7.2 kg" is a typo (docs/theory/parameters.md#table-2-in-si-units: a steel
    ring of these dimensions weighs 7.4 g, and 7.2 g reproduces the table's polar inertia).

    Examples
    --------
    >>> tc = turbocharger(outer_clearance=46e-6)
    >>> tc.bearings[0].outer.clearance
    4.6e-05
    """
    outer_clearance, inner_clearance, viscosity_turbine, viscosity_compressor = (
        check_real(name, value, unit, minimum=0.0) for name, value, unit in (
            ("outer_clearance", outer_clearance, "m"), ("inner_clearance", inner_clearance, "m"),
            ("viscosity_turbine", viscosity_turbine, "Pa s"), ("viscosity_compressor", viscosity_compressor, "Pa s")))
    check_model(film_model)
    bearings = []
    for name, node, mu in (("turbine", 1, viscosity_turbine), ("compressor", 2, viscosity_compressor)):
        inner = check_film_thickness(Film(radius=5.5e-3, length=6.5e-3, clearance=inner_clearance, viscosity=mu),
                                     f"{name} inner film")
        outer = check_film_thickness(Film(radius=8e-3, length=9e-3, clearance=outer_clearance, viscosity=mu),
                                     f"{name} outer film")
        bearings.append(FloatingRingBearing(node=node, inner=inner, outer=outer, ring_mass=7.2e-3,
                                            ring_inertia=33.641e-8, name=name))
    return Turbocharger(rotor=table2_rotor(), bearings=tuple(bearings), film_model=film_model,
                        name=f"Table 2 turbocharger, c_o = {outer_clearance * 1e6:g} µm")
