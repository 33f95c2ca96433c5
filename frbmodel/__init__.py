"""frbmodel — rotordynamics of turbocharger rotors on floating-ring bearings.

Quick start::

    import numpy as np, frbmodel as frb
    tc = frb.turbocharger(outer_clearance=36e-6)          # the paper's Table 2 system, SI units
    eq = frb.equilibrium(tc, method="J", speed_rpm=150e3)  # static equilibrium of both bearings
    cd = frb.campbell(tc, method="J", speeds_rpm=np.linspace(10e3, 250e3, 100))
    cd.plot().savefig("campbell.png")
"""
__version__ = "0.1.0"

from .errors import ConvergenceError, FilmContactError, FRBError, ParameterError
from .film import (FILM_MODELS, Film, film_coefficients, film_force, film_torques, static_eccentricity,
                   static_position)
from .rotor import Disc, Rotor, ShaftElement
from .parameters import FloatingRingBearing, Turbocharger, load_system
from .presets import PAPER_OUTER_CLEARANCES, turbocharger
from .bearing import ring_speed_ratio, ring_torque
from .methods import METHODS, get_method
from .equilibrium import equilibrium, EquilibriumResult
from .linear import linear_system
from .modal import modes
from .whirl import film_onset_speeds
from .campbell import campbell, CampbellResult
from .runup import RunupResult, RunupStopped, SpeedProfile, Unbalance, runup
from .spectral import spectrogram

__all__ = [
    "__version__", "ConvergenceError", "FilmContactError", "FRBError", "ParameterError", "FILM_MODELS", "Film",
    "film_coefficients", "film_force", "film_torques", "static_eccentricity", "static_position", "Disc", "Rotor",
    "ShaftElement", "FloatingRingBearing", "Turbocharger", "load_system", "PAPER_OUTER_CLEARANCES", "turbocharger",
    "ring_speed_ratio", "ring_torque", "METHODS", "get_method", "equilibrium", "EquilibriumResult", "linear_system",
    "modes", "film_onset_speeds", "campbell", "CampbellResult", "RunupResult", "RunupStopped", "SpeedProfile",
    "Unbalance", "runup", "spectrogram",
]
