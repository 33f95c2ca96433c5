"""frbmodel — rotordynamics of turbocharger rotors on floating-ring bearings.

Quick start::

    import numpy as np, frbmodel as frb
    tc = frb.turbocharger(outer_clearance=36e-6)          # the paper's Table 2 system, SI units
    eq = frb.equilibrium(tc, method="J", speed_rpm=150e3)  # static equilibrium of both bearings
    cd = frb.campbell(tc, method="J", speeds_rpm=np.linspace(10e3, 250e3, 100))
    cd.plot().savefig("campbell.png")

Every name below is importable from the top level; plotting libraries are imported only when a figure is made.
"""
from .core import kernel_cache as _kernel_cache  # noqa: F401, I001  (first: drops numba caches of changed kernels)
from .core.errors import (
    ConvergenceError,
    CosimStopped,
    FilmContactError,
    FRBError,
    IntegrationError,
    ParameterError,
    RunStopped,
    RunupStopped,
)
from .core.units import rad_s_to_rpm, rpm_to_rad_s
from .core.version import __version__
from .cycles.limitcycle import LimitCycle, limit_cycle
from .linear.assembly import LinearSystem, linear_system
from .linear.campbell import CampbellResult, campbell
from .linear.equilibrium import BearingEquilibrium, EquilibriumResult, equilibrium
from .linear.losses import bearing_losses
from .linear.modal import Modes, modes
from .linear.thermal import OilSupply, thermal_losses, thermal_system
from .linear.unbalance import UnbalanceResponse, unbalance_response
from .linear.whirl import film_onset_speeds
from .nonlinear.recorder import Recorder, RunupResult, RunupSchema
from .nonlinear.runup import SpeedProfile, Unbalance, runup
from .physics.bearing import ring_speed_ratio, ring_torque
from .physics.film import (
    FILM_MODELS,
    Film,
    film_coefficients,
    film_force,
    film_torques,
    static_eccentricity,
    static_position,
)
from .physics.losses import bearing_loss
from .physics.thermal import ThermalModel
from .signals.spectral import SpectrogramResult, spectrogram
from .signals.tracking import Component
from .system.methods import METHODS, Method, get_method
from .system.oil import OILS, Oil
from .system.parameters import FloatingRingBearing, Turbocharger, load_system
from .system.presets import PAPER_OUTER_CLEARANCES, turbocharger
from .system.rotor import Disc, Rotor, ShaftElement

__all__ = [
    "__version__", "BearingEquilibrium", "CampbellResult", "Component", "ConvergenceError", "CosimStopped", "Disc",
    "EquilibriumResult", "FILM_MODELS", "FRBError", "Film", "FilmContactError", "FloatingRingBearing",
    "IntegrationError", "LimitCycle", "LinearSystem", "METHODS", "Method", "Modes", "PAPER_OUTER_CLEARANCES",
    "OILS", "Oil", "OilSupply", "ParameterError", "ThermalModel", "thermal_losses", "thermal_system",
    "Recorder", "Rotor", "RunStopped", "RunupResult", "RunupSchema", "RunupStopped", "ShaftElement",
    "SpectrogramResult", "SpeedProfile", "Turbocharger", "Unbalance", "bearing_loss", "bearing_losses", "campbell",
    "equilibrium", "film_coefficients", "film_force", "film_onset_speeds", "film_torques", "get_method", "limit_cycle",
    "linear_system", "load_system", "modes", "rad_s_to_rpm", "ring_speed_ratio", "ring_torque", "rpm_to_rad_s",
    "runup", "spectrogram", "static_eccentricity", "static_position", "turbocharger",
    "UnbalanceResponse", "unbalance_response",
]
