"""Whirl onset speeds versus the oil supply temperature (issue #25 stage 2; theory:
docs/theory/thermal.md#whirl-onsets-versus-supply-temperature): per supply temperature the method-J Campbell
diagram with the thermal model (:func:`frbmodel.linear.campbell.campbell` with an
:class:`~frbmodel.linear.thermal.OilSupply`), its exact film whirl onsets (each at the temperatures of its own speed)
with the RSR, temperature and viscosity of the film there, and the speeds where the diagram's modes lose stability
(interpolated between the grid speeds)."""
from __future__ import annotations

import numpy as np

from ..core.errors import ParameterError, check_system
from ..linear.campbell import campbell
from ..linear.thermal import SUPPLY_PRESSURE_PA, OilSupply, thermal_losses
from ..linear.whirl import film_names, film_onset_speeds
from ..nonlinear.runup import check_output_rate, runup
from ..signals.spectral import spectrogram

__all__ = ["RUNUP_RAMP_RPM", "SUPPLY_TEMPERATURES_K", "onsets_vs_supply", "runup_onsets_vs_supply"]

#: default run-up of :func:`runup_onsets_vs_supply`: the main job's ramp, 20 -> 250 krpm [rpm] in 1 s
RUNUP_RAMP_RPM = (20e3, 250e3)

#: default supply temperatures [K]: 40 ... 120 °C in 20 K steps (a cold start to hot oil)
SUPPLY_TEMPERATURES_K = (313.15, 333.15, 353.15, 373.15, 393.15)


def _film_rows(system, cd, sup, const):
    """One row per film: its exact thermal onset [rpm] and the film's state at the thermal operating point there."""
    rows = []
    for k, film in enumerate(film_names(system)):
        s = float(cd.whirl_onset_rpm[k])
        row = {"supply temperature [K]": sup.supply_temperature_K, "supply pressure [Pa]": sup.supply_pressure_Pa,
               "oil": sup.oil.name, "film": film, "onset [rpm]": s, "constant-viscosity onset [rpm]": float(const[k])}
        side = "inner" if k % 2 == 0 else "outer"
        if np.isfinite(s):
            r = thermal_losses(system, s, sup.oil, sup.supply_temperature_K, sup.supply_pressure_Pa,
                               sup.model).iloc[k // 2]
            row.update({"RSR at onset [-]": r["RSR [-]"], "ring speed at onset [rad/s]": r["ring speed [rad/s]"],
                        "film temperature at onset [K]": r[f"{side} film temperature [K]"],
                        "film viscosity at onset [Pa s]": r[f"{side} viscosity [Pa s]"],
                        "eps at onset [-]": r[f"eps {side} [-]"]})
        rows.append(row)
    return rows


def _mode_rows(cd, t_s):
    """The speeds where a mode of ``cd`` becomes unstable: modal damping D linearly interpolated to zero between the
    last stable and the first unstable grid speed (a mode unstable at the grid's first speed is flagged)."""
    rows = []
    s, d, f = cd.speeds_rpm, cd.damping, cd.frequencies_hz
    uns = cd.unstable
    for j in range(cd.n_modes):
        starts = np.flatnonzero(np.diff(np.concatenate([[0], uns[:, j].astype(int)])) == 1)
        for a in starts:
            if a == 0:
                speed, freq = s[0], f[0, j]
            else:
                w = d[a - 1, j] / (d[a - 1, j] - d[a, j])
                speed, freq = s[a - 1] + w * (s[a] - s[a - 1]), f[a - 1, j] + w * (f[a, j] - f[a - 1, j])
            rows.append({"supply temperature [K]": t_s, "mode": j, "kind": cd.mode_kind[a, j],
                         "precession": cd.precession[a, j], "onset [rpm]": float(speed),
                         "frequency at onset [Hz]": float(freq), "unstable at grid start": bool(a == 0)})
    return rows


def _supplies(oil, supply_temperatures_K, supply_pressure_Pa, model):
    """One OilSupply per supply temperature [K], every value checked before any work (a non-empty list)."""
    temps = np.atleast_1d(np.asarray(supply_temperatures_K, dtype=float))
    if temps.ndim != 1 or temps.size == 0:
        raise ParameterError(f"supply_temperatures_K = {supply_temperatures_K!r} is invalid: a non-empty list of "
                             "temperatures [K]")
    return [OilSupply(oil, t, supply_pressure_Pa, model) for t in temps]


def onsets_vs_supply(system, oil, supply_temperatures_K=SUPPLY_TEMPERATURES_K, supply_pressure_Pa=SUPPLY_PRESSURE_PA,
                     model=None, speeds_rpm=None, progress=False):
    """Linear whirl onsets of ``system`` at each oil supply temperature, with the thermal model at every speed.

    Parameters
    ----------
    system : Turbocharger
    oil : Oil
        The lubricant.
    supply_temperatures_K : sequence of float
        Supply temperatures [K] (each in the oil's range).
    supply_pressure_Pa : float
        Supply pressure above ambient [Pa].
    model : ThermalModel, optional
        Coefficients (default ``ThermalModel()``).
    speeds_rpm : array_like, optional
        Speed grid of the Campbell diagrams [rpm] (default that of :func:`campbell`); the film onsets are exact,
        searched over 500 ... 400 000 rpm whatever the grid.
    progress : bool
        Progress bars of the Campbell diagrams.

    Returns
    -------
    films : pandas.DataFrame
        One row per supply temperature and film: ``onset [rpm]`` (exact, :func:`film_onset_speeds` with the
        thermal model), ``constant-viscosity onset [rpm]`` (the system's own viscosities), and at the onset
        ``RSR at onset [-]``, ``ring speed at onset [rad/s]``, ``film temperature at onset [K]``,
        ``film viscosity at onset [Pa s]``, ``eps at onset [-]``.
    modes : pandas.DataFrame
        One row per supply temperature and mode that loses stability in the grid: ``onset [rpm]`` (interpolated
        between grid speeds), ``frequency at onset [Hz]``, kind, precession, ``unstable at grid start``.

    Examples
    --------
    >>> import frbmodel as frb
    >>> films, modes = onsets_vs_supply(frb.turbocharger(), frb.OILS["SAE 5W-30"], [333.15, 393.15],
    ...                                 speeds_rpm=[50e3, 150e3])
    >>> f = films[films["film"] == "turbine outer"]["onset [rpm]"].tolist()
    >>> bool(f[0] > f[1])                       # colder oil: the ring turns slower, the outer film whirls later
    True
    """
    import pandas as pd

    check_system(system)
    supplies = _supplies(oil, supply_temperatures_K, supply_pressure_Pa, model)
    const = film_onset_speeds(system)
    films, modes = [], []
    for sup in supplies:
        cd = campbell(system, "J", speeds_rpm, whirl=True, progress=progress, oil_supply=sup)
        films += _film_rows(system, cd, sup, const)
        modes += _mode_rows(cd, sup.supply_temperature_K)
    cols = ["supply temperature [K]", "mode", "kind", "precession", "onset [rpm]", "frequency at onset [Hz]",
            "unstable at grid start"]
    return pd.DataFrame(films), pd.DataFrame(modes, columns=cols)


#: output rate of the run-ups of :func:`runup_onsets_vs_supply` [Hz] (frb.runup's default)
RUNUP_RATE_HZ = 20e3


def runup_onsets_vs_supply(system, oil, supply_temperatures_K=SUPPLY_TEMPERATURES_K,
                           supply_pressure_Pa=SUPPLY_PRESSURE_PA, model=None, speed_range_rpm=RUNUP_RAMP_RPM,
                           duration_s=1.0, location="turbine_wheel"):
    """Sub-synchronous whirl components of one run-up per oil supply temperature (quasi-static film temperatures,
    :func:`frbmodel.nonlinear.runup.runup` with an :class:`~frbmodel.linear.thermal.OilSupply`): the run-up onsets
    beside the linear ones of :func:`onsets_vs_supply` (docs/theory/thermal.md#run-ups).

    Parameters
    ----------
    system : Turbocharger
    oil : Oil
    supply_temperatures_K : sequence of float
        Supply temperatures [K] (each in the oil's range; all checked before the first run).
    supply_pressure_Pa : float
        Supply pressure above ambient [Pa].
    model : ThermalModel, optional
    speed_range_rpm : (float, float)
        Linear ramp [rpm] (default the main job's 20 -> 250 krpm).
    duration_s : float
        Ramp time [s] (default 1).
    location : str
        The disc or journal whose orbit's spectrogram is tracked (default the turbine wheel).

    Returns
    -------
    pandas.DataFrame
        One row per supply temperature and sub-synchronous component (frequency ratio at first detection < 1) of
        :meth:`frbmodel.signals.spectral.SpectrogramResult.components_table`: its columns (``onset [rpm]``,
        ``f at onset [Hz]``, ``first detection [rpm]``, ``vanishes at [rpm]``, …) after ``supply temperature [K]``,
        ``supply pressure [Pa]``, ``oil``, ``ramp start [rpm]``, ``ramp end [rpm]``, ``ramp time [s]``.
    """
    import pandas as pd

    check_system(system)
    supplies = _supplies(oil, supply_temperatures_K, supply_pressure_Pa, model)
    lo, hi = (float(v) for v in speed_range_rpm)
    check_output_rate(RUNUP_RATE_HZ, duration_s)  # (1e-9 s was refused by the first run, after the others' work)
    frames = []
    for sup in supplies:
        run = runup(system, speed_rpm=(lo, hi), duration=duration_s, oil_supply=sup, output_rate_hz=RUNUP_RATE_HZ)
        tab = spectrogram(run, location).components_table()
        tab = tab[tab["f/f_rot at first detection [-]"] < 1.0].copy()
        head = {"supply temperature [K]": sup.supply_temperature_K, "supply pressure [Pa]": sup.supply_pressure_Pa,
                "oil": sup.oil.name, "ramp start [rpm]": lo, "ramp end [rpm]": hi, "ramp time [s]": float(duration_s)}
        for i, (k, v) in enumerate(head.items()):
            tab.insert(i, k, v)
        frames.append(tab)
    return pd.concat(frames, ignore_index=True)
