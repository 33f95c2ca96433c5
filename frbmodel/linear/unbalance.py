"""Unbalance response (the steady-state 1X forced response of the linearized system) and critical speeds.

At each rotor speed Ω the linear system of a method (:func:`frbmodel.linear_system`: about the static equilibrium
at that speed for the film methods C–J, ring DoFs included for E–J, ring speed per the method) is driven by the
rotating unbalance forces. A disc with unbalance m e at angular position p (at rotation angle 0, from +x, CCW)
loads its node with f_x = m e Ω² cos(Ωt + p), f_y = m e Ω² sin(Ωt + p) — the constant-speed case of
:func:`frbmodel.physics.dynamics.add_unbalance_forces`, which the run-up uses. In complex form f = Re(F e^{iΩt}) with
F_x = m e Ω² e^{ip}, F_y = −i F_x, and the response q = Re(Q e^{iΩt}) solves

    (K(Ω) − Ω² M + i Ω C(Ω)) Q = F,

C(Ω) holding the bearing damping and the gyroscopic Ω G. Every orbit x + i y = r_f e^{iΩt} + r_b e^{−iΩt} has a
forward component r_f = (X + iY)/2 and a backward one r_b = (X̄ + iȲ)/2, semi-axes |r_f| + |r_b| and
||r_f| − |r_b||.

Critical speeds are where the 1X line f = Ω/2π crosses the damped Campbell branches (grid crossings refined by a
root solve on the eigenvalue of the tracked mode), and where the response amplitudes peak.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError, check_distinct, check_real, check_system, read_json
from ..core.progress import counter_bar, progress_enabled
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..core.units import rpm_to_rad_s
from ..core.version import __version__
from ..plots.figures import write_html
from ..plots.unbalance import (  # noqa: F401  (the figures, re-exported from where they were)
    PHASE_BREAK_DEG,
    POLAR_CLIP,
    RESULT_STYLES,
    bode_figure,
    default_films,
    phase_curve,
    response_figure,
    response_plotly,
)
from ..system.methods import get_method
from .campbell import campbell as campbell_diagram
from .critical import CRITICAL_COLUMNS, critical_speeds, linear_at, oil_supply_of, system_of  # noqa: F401
from .thermal import at_operating_point, check_oil_supply

#: default speed grid [rpm] (1 000 ... 250 000, 200 points)
DEFAULT_SPEEDS_RPM = (1e3, 250e3, 200)
#: the forcing, for the result files
FORCE_RULE = ("F_x = m e W^2 exp(i p), F_y = -i F_x on the disc node (f = Re(F exp(i W t)): a forward-rotating "
              "unbalance at angle W t + p from +x, CCW); response q = Re(Q exp(i W t)) of "
              "(K(W) - W^2 M + i W C(W)) Q = F")
_SIDES = ("inner", "outer")


def check_unbalance(system, unbalance):
    """Unbalances as ``(disc name, node, m e [kg m], phase [rad])`` tuples, or a :class:`ParameterError`.

    Parameters
    ----------
    system : Turbocharger
    unbalance : dict or sequence of Unbalance
        ``{disc_name: (m_e [kg m], phase [rad])}`` (a bare number is m e at phase 0), or
        ``[frbmodel.Unbalance(disc, amount, phase), ...]``.

    Returns
    -------
    tuple of (str, int, float, float)

    Examples
    --------
    >>> import frbmodel as frb
    >>> check_unbalance(frb.turbocharger(), {"compressor_wheel": (2e-6, 0.5)})
    (('compressor_wheel', 3, 2e-06, 0.5),)
    """
    if isinstance(unbalance, dict):
        items = list(unbalance.items())
    elif isinstance(unbalance, (list, tuple)) and all(hasattr(u, "disc") for u in unbalance):
        items = [(u.disc, (u.amount, u.phase)) for u in unbalance]
    else:
        raise ParameterError(f"unbalance = {unbalance!r} is invalid: give a dict {{disc name: (m e [kg m], phase "
                             "[rad])}, e.g. {'turbine_wheel': (1e-6, 0.0)}")
    if not items:
        raise ParameterError("unbalance = {} is invalid: give at least one disc, e.g. {'turbine_wheel': (1e-6, 0.0)}")
    names = [name for name, _ in items]
    check_distinct(f"unbalance discs {names}", names)  # (a list could give a disc twice: the two were summed)
    out = []
    for name, value in items:
        me, phase = (value, 0.0) if not isinstance(value, (tuple, list)) else (tuple(value) + (0.0,))[:2]
        if isinstance(value, (tuple, list)) and not 1 <= len(value) <= 2:
            raise ParameterError(f"unbalance[{name!r}] = {value!r} is invalid: expected (m e [kg m], phase [rad])")
        disc, me = system.rotor.check_unbalance(name, me, f"unbalance m e of {name}")  # (the disc's own bound)
        out.append((disc.name, disc.node, me, check_real(f"unbalance phase of {name}", phase, "rad")))
    if not any(u[2] > 0 for u in out):
        raise ParameterError(f"unbalance = {unbalance!r} is invalid: every m e is 0 (no response); valid range of "
                             "at least one m e: > 0 kg m")
    return tuple(out)


def unbalance_force(n_dof, unbalance, omega):
    """Complex amplitude F [N] of the rotating unbalance load, f(t) = Re(F e^{iΩt}).

    Parameters
    ----------
    n_dof : int
        Size of the system (rotor DoFs first, 4 per node).
    unbalance : sequence of (name, node, m e [kg m], phase [rad])
        As returned by :func:`check_unbalance`.
    omega : float
        Rotor speed Ω [rad/s].

    Returns
    -------
    ndarray (n_dof,) complex

    Examples
    --------
    >>> F = unbalance_force(8, [("w", 1, 1e-6, 0.0)], 1000.0)     # 1 g mm at 1000 rad/s: 1 N
    >>> F[4:6]
    array([1.+0.j, 0.-1.j])
    """
    F = np.zeros(n_dof, dtype=complex)
    for _, node, me, phase in unbalance:
        f = me * omega ** 2 * np.exp(1j * phase)
        F[4 * node] += f
        F[4 * node + 1] += -1j * f
    return F


def forced_response(ls, F, omega):
    """Steady-state complex amplitudes Q of ``M q̈ + C q̇ + K q = Re(F e^{iΩt})``.

    Parameters
    ----------
    ls : LinearSystem
        M, C, K at the speed Ω (C includes Ω G).
    F : ndarray (n,) complex
        Force amplitude [N, N m].
    omega : float
        Forcing (= rotor) angular frequency Ω [rad/s].

    Returns
    -------
    ndarray (n,) complex
        Q [m, rad]; inf where the dynamic stiffness is singular (an undamped system exactly at resonance).

    Examples
    --------
    >>> import frbmodel as frb
    >>> ls = frb.linear_system(frb.turbocharger(), "A", 0.0)
    >>> Q = forced_response(ls, unbalance_force(ls.M.shape[0], [("w", 0, 1e-6, 0.0)], 0.0), 0.0)
    >>> float(abs(Q).max())
    0.0
    """
    Z = ls.K - omega ** 2 * ls.M + 1j * omega * ls.C
    try:
        return np.linalg.solve(Z, F)
    except np.linalg.LinAlgError:
        return np.full(F.shape, np.inf + 0j)


def response_at(system, method, speed_rpm, unbalance, **kw):
    """Complex amplitudes of all DoFs at one speed.

    Parameters
    ----------
    system : Turbocharger
    method : str
        One of A, B, C, D, E, F, G, I, J.
    speed_rpm : float
        Rotor speed [rpm].
    unbalance : dict or sequence of Unbalance
        See :func:`check_unbalance`.
    **kw
        Spring stiffnesses of A, B, E [N/m].

    Returns
    -------
    Q : ndarray (n,) complex
        [m, rad], in the DoF order of ``ls``.
    ls : LinearSystem

    Examples
    --------
    >>> import frbmodel as frb
    >>> Q, ls = response_at(frb.turbocharger(), "J", 100e3, {"turbine_wheel": (1e-6, 0.0)})
    >>> ls.dof_labels[16], Q.shape
    ('ring_turbine.x', (20,))
    """
    m = get_method(method)
    unb = check_unbalance(system, unbalance)
    ls = linear_at(system, m, speed_rpm, kw)
    omega = rpm_to_rad_s(speed_rpm)
    return forced_response(ls, unbalance_force(ls.M.shape[0], unb, omega), omega), ls


def location_names(system, method="J"):
    """The locations an :class:`UnbalanceResponse` of ``system`` knows (its :attr:`UnbalanceResponse.names`).

    Parameters
    ----------
    system : Turbocharger
    method : str
        Method letter (checked; the names are the same for all methods, rings and films are NaN where undefined).

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> import frbmodel as frb
    >>> location_names(frb.turbocharger())[:6]
    ('turbine_wheel', 'compressor_wheel', 'node0', 'node1', 'node2', 'node3')
    """
    get_method(method)
    return _names(_layout(system, None))


def _layout(system, ring_dofs):
    """Where things are in the DoF vector: discs, bearings (node, ring DoFs, clearances), for the metadata."""
    return {"n_nodes": system.rotor.n_nodes,
            "discs": [{"name": d.name, "node": d.node} for d in system.rotor.discs],
            "bearings": [{"name": b.name, "node": b.node,
                          "ring_dofs": None if ring_dofs is None else [int(i) for i in ring_dofs[k]],
                          "inner_clearance_m": b.inner.clearance, "outer_clearance_m": b.outer.clearance}
                         for k, b in enumerate(system.bearings)]}


def _names(layout):
    """Location names of a layout: discs, nodes, then per bearing journal, ring, inner and outer film."""
    out = [d["name"] for d in layout["discs"]] + [f"node{i}" for i in range(layout["n_nodes"])]
    for b in layout["bearings"]:
        out += [f"{b['name']} {w}" for w in ("journal", "ring") + _SIDES]
    return tuple(out)


@dataclass
class UnbalanceResponse(Result):
    """Result of :func:`unbalance_response`: complex 1X amplitudes of every DoF at every speed.

    Locations (``names``): the discs (e.g. ``"turbine_wheel"``), the nodes ``"node<i>"``, per bearing
    ``"<bearing> journal"`` and ``"<bearing> ring"`` (relative to the housing), and the films ``"<bearing> inner"``
    (journal relative to ring) and ``"<bearing> outer"`` (ring relative to housing). Without ring DoFs the ring
    moves with the journal for method C (inner film rigid: its orbit is 0) and is undefined (NaN) for A, B (no
    films) and D (films in series).

    Attributes
    ----------
    method : str
    speeds_rpm : ndarray (n,)
        Rotor speeds [rpm], ascending.
    response : ndarray (n, n_dof) complex
        Q [m, rad]: q(t) = Re(Q e^{iΩt}) for each DoF of ``dof_labels``.
    dof_labels : list of str
    unbalance : list of dict
        ``{"disc", "node", "m e [kg m]", "phase [rad]"}`` per unbalanced disc.
    meta : dict
        System, method and options, layout of the DoFs (``meta["layout"]``), the forcing rule.
    critical : list of dict, optional
        Rows of the critical-speed table (read it with :meth:`critical_speeds`); None if not computed.

    Examples
    --------
    >>> import frbmodel as frb
    >>> ur = frb.unbalance_response(frb.turbocharger(), "A", [30e3, 60e3], {"turbine_wheel": (1e-6, 0.0)},
    ...                             critical=False)
    >>> [round(float(a) * 1e6, 3) for a in ur.major_axis("turbine_wheel")]      # [µm]
    [3.428, 2.973]
    >>> bool(np.allclose(ur.minor_axis("turbine_wheel"), ur.major_axis("turbine_wheel")))   # isotropic: circles
    True
    """

    method: str
    speeds_rpm: np.ndarray
    response: np.ndarray
    dof_labels: list
    unbalance: list
    meta: dict = field(default_factory=dict)
    critical: object = None

    def __post_init__(self):
        self.speeds_rpm = np.asarray(self.speeds_rpm, dtype=float).ravel()
        self.response = np.asarray(self.response, dtype=complex).reshape(self.speeds_rpm.size, -1)
        self.dof_labels = list(self.dof_labels)
        if self.response.shape[1] != len(self.dof_labels):
            raise ParameterError(f"UnbalanceResponse.response has {self.response.shape[1]} DoFs; dof_labels has "
                                 f"{len(self.dof_labels)}")

    # ------------------------------------------------------------------ locations
    @property
    def layout(self) -> dict:
        """Discs, nodes and bearings (node, ring DoFs, clearances [m]) of the analysed system."""
        return self.meta["layout"]

    @property
    def names(self) -> tuple:
        """Every location :meth:`orbit` knows: discs, nodes, journals, rings and films."""
        return _names(self.layout)

    @property
    def film_names(self) -> tuple:
        """The films, ``"<bearing> inner"`` / ``"<bearing> outer"`` per bearing."""
        return tuple(f"{b['name']} {s}" for b in self.layout["bearings"] for s in _SIDES)

    def _node_xy(self, node):
        return self.response[:, 4 * node], self.response[:, 4 * node + 1]

    def _bearing_xy(self, b, what):
        journal = self._node_xy(b["node"])
        nan = np.full(self.speeds_rpm.size, complex(math.nan, math.nan))
        zero = np.zeros(self.speeds_rpm.size, complex)
        if b["ring_dofs"] is not None:
            ring = (self.response[:, b["ring_dofs"][0]], self.response[:, b["ring_dofs"][1]])
        else:
            ring = journal if self.method == "C" else (nan, nan)
        if what == "journal":
            return journal
        if what in ("ring", "outer"):
            return ring
        if b["ring_dofs"] is not None:
            return journal[0] - ring[0], journal[1] - ring[1]
        return (zero, zero) if self.method == "C" else (nan, nan)

    def orbit(self, name):
        """Complex amplitudes (X, Y) of a location: x(t) = Re(X e^{iΩt}), y(t) = Re(Y e^{iΩt}).

        Parameters
        ----------
        name : str
            One of :attr:`names`.

        Returns
        -------
        X, Y : ndarray (n,) complex
            [m] per speed (film locations: relative motion [m]).
        """
        lay = self.layout
        for d in lay["discs"]:
            if d["name"] == name:
                return self._node_xy(d["node"])
        if isinstance(name, str) and name.startswith("node") and name[4:].isdigit() and \
                int(name[4:]) < lay["n_nodes"]:
            return self._node_xy(int(name[4:]))
        for b in lay["bearings"]:
            for what in ("journal", "ring") + _SIDES:
                if name == f"{b['name']} {what}":
                    return self._bearing_xy(b, what)
        raise ParameterError(f"location name = {name!r} is unknown; valid: {', '.join(self.names)}")

    def forward(self, name):
        """Forward-whirl component r_f = (X + iY)/2 [m] (complex, per speed) of ``name``'s orbit."""
        X, Y = self.orbit(name)
        return (X + 1j * Y) / 2

    def backward(self, name):
        """Backward-whirl component r_b = (X̄ + iȲ)/2 [m] of ``name``'s orbit: x + iy = r_f e^{iΩt} + r_b e^{−iΩt}."""
        X, Y = self.orbit(name)
        return (np.conj(X) + 1j * np.conj(Y)) / 2

    def major_axis(self, name):
        """Semi-major axis |r_f| + |r_b| [m] of the orbit of ``name`` (its largest radius), per speed."""
        return np.abs(self.forward(name)) + np.abs(self.backward(name))

    def minor_axis(self, name):
        """Semi-minor axis ||r_f| − |r_b|| [m] of the orbit of ``name``, per speed (0: a line)."""
        return np.abs(np.abs(self.forward(name)) - np.abs(self.backward(name)))

    def precession(self, name):
        """"forward" (|r_f| > |r_b|), "backward" or "" (line or undefined) per speed."""
        f, b = np.abs(self.forward(name)), np.abs(self.backward(name))
        return np.where(f > b, "forward", np.where(b > f, "backward", "")).astype(object)

    def phase(self, name, probe="x"):
        """Phase φ [rad] of a probe signal |A| cos(Ωt + φ), t = 0 when the rotation angle is 0.

        Parameters
        ----------
        name : str
        probe : {"x", "y", "forward"}
            The x or y displacement, or the forward component (the angle of the orbit point at t = 0).

        Returns
        -------
        ndarray (n,)
            In (−π, π] [rad].
        """
        X, Y = self.orbit(name)
        signals = {"x": X, "y": Y, "forward": (X + 1j * Y) / 2}
        if probe not in signals:
            raise ParameterError(f"probe = {probe!r} is invalid: 'x', 'y' or 'forward'")
        return np.angle(signals[probe])

    def clearance_fraction(self, film):
        """Semi-major axis of a film's relative orbit over its radial clearance [-], per speed.

        Parameters
        ----------
        film : str
            ``"<bearing> inner"`` (journal relative to ring, over c_i) or ``"<bearing> outer"`` (ring relative to
            the housing, over c_o).
        """
        for b in self.layout["bearings"]:
            for side in _SIDES:
                if film == f"{b['name']} {side}":
                    return self.major_axis(film) / b[f"{side}_clearance_m"]
        raise ParameterError(f"film = {film!r} is unknown; valid: {', '.join(self.film_names)}")

    def critical_speeds(self):
        """The critical-speed table (see :func:`critical_speeds` and :func:`response_peaks`).

        Returns
        -------
        pandas.DataFrame
            One row per 1X crossing of a Campbell branch (``source`` "1X crossing") and per response peak
            (``source`` "response peak"), sorted by speed; columns :data:`CRITICAL_COLUMNS`.
        """
        import pandas as pd

        if self.critical is None:
            raise ParameterError("this unbalance response was computed with critical=False: no critical speeds")
        return pd.DataFrame(self.critical, columns=list(CRITICAL_COLUMNS))

    # ------------------------------------------------------------------ tables and files
    def to_dataframe(self, names=None):
        """One row per speed: amplitudes, phases, semi-axes and whirl components of each location.

        Parameters
        ----------
        names : sequence of str, optional
            Locations (default: every one of :attr:`names`).

        Returns
        -------
        pandas.DataFrame
            ``speed [rpm]``, then per location ``<name> x amplitude [m]``, ``x phase [rad]``, ``y amplitude [m]``,
            ``y phase [rad]``, ``major semi-axis [m]``, ``minor semi-axis [m]``, ``forward [m]``, ``backward [m]``,
            and for the films ``major semi-axis / clearance [-]``.
        """
        import pandas as pd

        d = {"speed [rpm]": self.speeds_rpm}
        for name in names or self.names:
            X, Y = self.orbit(name)
            d.update({f"{name} x amplitude [m]": np.abs(X), f"{name} x phase [rad]": np.angle(X),
                      f"{name} y amplitude [m]": np.abs(Y), f"{name} y phase [rad]": np.angle(Y),
                      f"{name} major semi-axis [m]": self.major_axis(name),
                      f"{name} minor semi-axis [m]": self.minor_axis(name),
                      f"{name} forward [m]": np.abs(self.forward(name)),
                      f"{name} backward [m]": np.abs(self.backward(name))})
            if name in self.film_names:
                d[f"{name} major semi-axis / clearance [-]"] = self.clearance_fraction(name)
        return pd.DataFrame(d)

    def dofs_dataframe(self):
        """The raw complex amplitudes: ``speed [rpm]`` and ``<dof> re [m|rad]``, ``<dof> im [m|rad]`` per DoF."""
        import pandas as pd

        d = {"speed [rpm]": self.speeds_rpm}
        for k, lab in enumerate(self.dof_labels):
            unit = "rad" if lab.endswith((".thx", ".thy")) else "m"
            d[f"{lab} re [{unit}]"] = self.response[:, k].real
            d[f"{lab} im [{unit}]"] = self.response[:, k].imag
        return pd.DataFrame(d)

    def to_xarray(self):
        """The result as an :class:`xarray.Dataset` over speed × location (units in the attributes).

        Returns
        -------
        xarray.Dataset
            ``x_re``, ``x_im``, ``y_re``, ``y_im``, ``major_semi_axis``, ``minor_semi_axis``, ``forward``,
            ``backward`` [m]; ``clearance_fraction`` [-] over speed × film.
        """
        import xarray as xr

        names = list(self.names)
        orb = [self.orbit(n) for n in names]
        dims = ("speed", "location")
        data = {"x_re": (np.stack([o[0].real for o in orb], 1), "x amplitude, real part"),
                "x_im": (np.stack([o[0].imag for o in orb], 1), "x amplitude, imaginary part"),
                "y_re": (np.stack([o[1].real for o in orb], 1), "y amplitude, real part"),
                "y_im": (np.stack([o[1].imag for o in orb], 1), "y amplitude, imaginary part"),
                "major_semi_axis": (np.stack([self.major_axis(n) for n in names], 1), "orbit semi-major axis"),
                "minor_semi_axis": (np.stack([self.minor_axis(n) for n in names], 1), "orbit semi-minor axis"),
                "forward": (np.stack([np.abs(self.forward(n)) for n in names], 1), "forward whirl radius"),
                "backward": (np.stack([np.abs(self.backward(n)) for n in names], 1), "backward whirl radius")}
        ds = {k: variable(dims, v, "m", text) for k, (v, text) in data.items()}
        ds["clearance_fraction"] = variable(("speed", "film"), np.stack(
            [self.clearance_fraction(f) for f in self.film_names], 1), "-", "film orbit semi-major axis / clearance")
        ds["response_re"] = variable(("speed", "dof"), self.response.real, "SI", "complex amplitude of every DoF "
                                     "(m, rad), real part")
        ds["response_im"] = variable(("speed", "dof"), self.response.imag, "SI", "imaginary part")
        coords = {"speed": ("speed", self.speeds_rpm, {"units": "rpm", "long_name": "rotor speed"}),
                  "location": names, "film": list(self.film_names), "dof": list(self.dof_labels)}
        attrs = {**self.metadata(), "critical": self.critical}
        return xr.Dataset(ds, coords=coords, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The response from a dataset of :meth:`to_xarray` (e.g. ``unbalance_<M>.nc`` of :meth:`save`).

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        UnbalanceResponse
        """
        meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        for k in ("speeds_rpm", "force_rule", "frbmodel_version", "units", "dof_labels"):
            meta.pop(k, None)
        resp = ds["response_re"].values + 1j * ds["response_im"].values
        return cls(meta.pop("method"), ds["speed"].values, resp, [str(d) for d in ds["dof"].values],
                   meta.pop("unbalance"), meta, critical=meta.pop("critical", None))

    def metadata(self) -> dict:
        """What the result was computed with, JSON-ready (the content of :meth:`save`'s JSON)."""

        meta = dict(self.meta)
        meta.update({"method": self.method, "speeds_rpm": [float(s) for s in self.speeds_rpm],
                     "unbalance": self.unbalance, "dof_labels": self.dof_labels, "force_rule": FORCE_RULE,
                     "frbmodel_version": __version__,
                     "units": {"speed": "rpm", "amplitude": "m", "phase": "rad", "clearance fraction": "-"}})
        return meta

    def plot(self, names=None, films=None, title=None):
        """Bode (semi-major axis [µm], log scale; phase of x), film orbits over clearance, and polar plot.

        Parameters
        ----------
        names : sequence of str, optional
            Locations (default: the discs).
        films : sequence of str, optional
            Films for the clearance panel (default: those with a defined, non-zero orbit).
        title : str, optional

        Returns
        -------
        matplotlib.figure.Figure
        """
        return response_figure(self, names, films, title)

    def plot_html(self, path=None, names=None, films=None, include_plotlyjs=None):
        """Interactive plotly Bode, clearance and polar plot (hover: speed, amplitude, phase).

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there as HTML.
        names, films : sequence of str, optional
            As for :meth:`plot`.
        include_plotlyjs : {"directory", True}, optional
            ``"directory"``: plotly.js from ``plotly.min.js`` beside the file, one copy per folder (small file, shown
            offline); ``True``: embedded (self-contained, 4.8 MB larger). Default: ``"directory"``, or what
            :func:`frbmodel.plots.figures.html_plotlyjs` set. See :func:`frbmodel.plots.figures.write_html`.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        fig = response_plotly(self, names, films)
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def save(self, out_dir, stem=None, png=True, html=True, nc=True, names=None):
        """Write the tables, the metadata and the figures into ``out_dir``.

        Parameters
        ----------
        out_dir : str or Path
            Folder (created if missing).
        stem : str, optional
            File name stem (default ``unbalance_<method>``).
        png, html, nc : bool
            Write the PNG figure, the HTML figure, the netCDF dataset (:meth:`to_xarray`).
        names : sequence of str, optional
            Locations drawn in the figures (default: the discs).

        Returns
        -------
        list of Path
            ``<stem>.csv`` (:meth:`to_dataframe`), ``<stem>_dofs.csv`` (:meth:`dofs_dataframe`, read by
            :meth:`load`), ``<stem>_critical.csv``, ``<stem>.json`` and the figures / dataset.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stem = stem or f"unbalance_{self.method}"
        paths = [out / f"{stem}.csv", out / f"{stem}_dofs.csv"]
        self.to_dataframe().to_csv(paths[0], index=False)
        self.dofs_dataframe().to_csv(paths[1], index=False)
        if self.critical is not None:
            paths.append(out / f"{stem}_critical.csv")
            self.critical_speeds().to_csv(paths[-1], index=False)
        paths.append(out / f"{stem}.json")
        paths[-1].write_text(json.dumps(self.metadata(), indent=2, default=str))
        if png:
            import matplotlib.pyplot as plt

            fig = self.plot(names)
            paths.append(out / f"{stem}.png")
            fig.savefig(paths[-1], dpi=130, bbox_inches="tight")
            plt.close(fig)
        if html:
            paths.append(out / f"{stem}.html")
            self.plot_html(paths[-1], names)
        if nc:
            paths.append(self.to_netcdf(out / f"{stem}.nc"))
        return paths

    @classmethod
    def load(cls, path, *, stem=None):
        """Read a result written by :meth:`save`.

        Parameters
        ----------
        path : str or Path
            The folder.
        stem : str, optional
            File name stem (default: the only ``unbalance_*.json`` in the folder).

        Returns
        -------
        UnbalanceResponse

        Examples
        --------
        >>> import tempfile, frbmodel as frb
        >>> ur = frb.unbalance_response(frb.turbocharger(), "B", [20e3, 40e3], {"turbine_wheel": 1e-6},
        ...                             critical=False)
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     _ = ur.save(tmp, png=False, html=False, nc=False)
        ...     back = UnbalanceResponse.load(tmp)
        >>> bool(np.array_equal(back.response, ur.response)), back.method
        (True, 'B')
        """
        import pandas as pd

        out = Path(path)
        if stem is None:
            found = sorted(p.stem for p in out.glob("unbalance_*.json"))
            if len(found) != 1:
                raise ParameterError(f"folder = {str(path)!r} holds {len(found)} unbalance_*.json files; expected "
                                     "one (give stem=...)")
            stem = found[0]
        meta = read_json(out / f"{stem}.json", "unbalance-response metadata")
        df = pd.read_csv(out / f"{stem}_dofs.csv")
        labels = meta.pop("dof_labels")
        resp = np.column_stack([df[c].to_numpy() + 1j * df[c.replace(" re [", " im [")].to_numpy()
                                for c in df.columns if " re [" in c])
        crit = out / f"{stem}_critical.csv"
        critical = None
        if crit.exists():  # empty cells: NaN numbers, empty labels
            critical = pd.read_csv(crit)
            text = ["source", "kind", "precession", "location"]
            critical[text] = critical[text].astype(object).where(critical[text].notna(), "").astype(str)
        for k in ("speeds_rpm", "force_rule", "frbmodel_version", "units"):
            meta.pop(k, None)
        return cls(meta.pop("method"), df["speed [rpm]"].to_numpy(), resp, labels, meta.pop("unbalance"), meta,
                   critical=None if critical is None else critical.to_dict("records"))


def unbalance_response(system, method="J", speeds_rpm=None, unbalance=None, critical=True, peak_names=None,
                       progress: bool = False, oil_supply=None, **kw) -> UnbalanceResponse:
    """Steady-state 1X response of ``system`` to rotating unbalances, per speed, for bearing model ``method``.

    Parameters
    ----------
    system : Turbocharger
    method : {"A", "B", "C", "D", "E", "F", "G", "I", "J"}
    speeds_rpm : array_like, optional
        Rotor speeds [rpm] in any order (the result is ascending); default 1 000 ... 250 000, 200 points. > 0 for
        the film methods.
    unbalance : dict or sequence of Unbalance
        ``{disc_name: (m_e [kg m], phase [rad])}``, e.g. ``{"turbine_wheel": (1e-6, 0.0)}`` (1 g mm); default
        that one.
    critical : bool
        Also compute the critical-speed table: Campbell 1X crossings (:func:`critical_speeds`, refined) and
        response peaks (:func:`response_peaks`, refined).
    peak_names : sequence of str, optional
        Locations whose response peaks enter the table (default: the discs).
    progress : bool
        Show a progress bar over the speeds.
    oil_supply : OilSupply, optional
        The thermal model (film methods C, D, F, G, I, J): each speed's linear system is that of its own thermal
        operating point, solved with this method's equilibrium
        (:func:`frbmodel.linear.thermal.thermal_system` at that speed), and so are the Campbell diagram, the root
        search of each 1X crossing and of each response peak (every trial speed at its own operating point).
        ``meta`` records it (``oil_supply``) and the films' viscosities per speed (``film_viscosities_Pa_s``).
        None (default): the constant viscosities, bit for bit.
    **kw
        Spring stiffnesses of A, B, E: ``k``, ``kx``, ``ky`` [N/m].

    Returns
    -------
    UnbalanceResponse

    Raises
    ------
    ParameterError
        Not a system, an unknown method, option or disc, invalid speeds or unbalance, an oil supply with a method
        other than J.

    Examples
    --------
    >>> import frbmodel as frb
    >>> ur = frb.unbalance_response(frb.turbocharger(), "J", [60e3, 120e3], {"turbine_wheel": (1e-6, 0.0)},
    ...                             critical=False)
    >>> [round(float(a), 4) for a in ur.clearance_fraction("turbine outer")]
    [0.0078, 0.0131]
    """
    check_system(system)
    m = get_method(method)
    supply = check_oil_supply(oil_supply, m.letter, system.bearings)
    unb = check_unbalance(system, {"turbine_wheel": (1e-6, 0.0)} if unbalance is None else unbalance)
    speeds = np.sort(m.check_speeds(np.linspace(*DEFAULT_SPEEDS_RPM) if speeds_rpm is None else speeds_rpm))
    m.options(**kw)  # validate early
    t0 = time.perf_counter()
    rows, ls, mu = [], None, []
    with counter_bar(speeds.size, f"unbalance {m.letter}", progress_enabled(progress), unit="speed") as bar:
        for s in speeds:
            sys_s = at_operating_point(system, s, supply, m.letter)
            mu.append([f.viscosity for b in sys_s.bearings for f in (b.inner, b.outer)])
            ls = linear_at(sys_s, m, s, kw)
            omega = rpm_to_rad_s(s)
            rows.append(forced_response(ls, unbalance_force(ls.M.shape[0], unb, omega), omega))
            bar.update(1)
    meta = {"system_name": system.name, "system": system.to_dict(), "film_model": system.film_model,
            "method_title": m.title, "method_options": m.options(**kw), "layout": _layout(system, ls.ring_dofs),
            "source": "frbmodel.unbalance_response"}
    if supply is not None:
        meta.update(oil_supply=supply.to_dict(), film_viscosities_Pa_s=mu)
    ur = UnbalanceResponse(m.letter, speeds, np.array(rows), ls.dof_labels,
                           [{"disc": n, "node": node, "m e [kg m]": me, "phase [rad]": p} for n, node, me, p in unb],
                           meta)
    if critical:
        cd = campbell_diagram(system, m.letter, speeds, whirl=False, oil_supply=supply, **kw)
        rows = critical_speeds(cd, system, oil_supply=supply, **kw).to_dict("records")
        rows += response_peaks(ur, cd, system, peak_names, oil_supply=supply, **kw).to_dict("records")
        ur.critical = sorted(rows, key=lambda r: r["speed [rpm]"])
    ur.meta["cpu_time_s"] = time.perf_counter() - t0
    return ur


# ---------------------------------------------------------------------- critical speeds
def _amplitude_at(ur, system, m, name, unb, kw, oil_supply=None):
    """Semi-major axis [m] of ``name`` at one speed, as a function of the speed [rpm] (with an oil supply, at that
    speed's thermal operating point)."""
    def amp(speed_rpm):
        ls = linear_at(system, m, speed_rpm, kw, oil_supply)
        omega = rpm_to_rad_s(speed_rpm)
        Q = forced_response(ls, unbalance_force(ls.M.shape[0], unb, omega), omega)
        one = UnbalanceResponse(ur.method, [speed_rpm], Q[None, :], ur.dof_labels, ur.unbalance, ur.meta)
        return float(one.major_axis(name)[0])
    return amp


def _refine_peak(amp, lo, hi):
    """(speed [rpm], amplitude [m]) of the maximum of ``amp`` on [lo, hi] (bounded Brent on −log amp)."""
    from scipy.optimize import minimize_scalar

    r = minimize_scalar(lambda x: -math.log(max(amp(x), 1e-300)), bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-9 * hi})
    return float(r.x), amp(float(r.x))


def _nearest_mode(cd, speed_rpm):
    """(mode, kind, precession, damping) of the Campbell branch nearest to 1X at the grid speed nearest
    ``speed_rpm``; -1 and empty labels without a Campbell result."""
    if cd is None:
        return -1, "", "", math.nan
    k = int(np.argmin(np.abs(cd.speeds_rpm - speed_rpm)))
    d = np.abs(cd.frequencies_hz[k] - speed_rpm / 60.0)
    if not np.isfinite(d).any():
        return -1, "", "", math.nan
    j = int(np.nanargmin(d))
    return j, cd.mode_kind[k, j], cd.precession[k, j], float(cd.damping[k, j])


def response_peaks(ur, cd=None, system=None, names=None, refine=True, oil_supply=None, **kw):
    """Local maxima over speed of the orbit semi-major axes of an unbalance response.

    Parameters
    ----------
    ur : UnbalanceResponse
    cd : CampbellResult, optional
        Campbell diagram of the same system and method: each peak is labelled with the branch nearest to 1X.
    system : Turbocharger, optional
        Needed to refine (default: rebuilt from ``ur.meta["system"]``).
    names : sequence of str, optional
        Locations (default: the discs).
    refine : bool
        Refine each grid maximum by a bounded scalar search between its neighbouring grid speeds.
    oil_supply : OilSupply, optional
        The thermal model of ``ur`` (default: rebuilt from ``ur.meta["oil_supply"]``, None without one): each trial
        speed of the search at its own thermal operating point.
    **kw
        Spring stiffnesses of A, B, E [N/m] (default: ``ur.meta["method_options"]``).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CRITICAL_COLUMNS` with ``source`` "response peak", ``location`` and ``amplitude [m]``.

    Examples
    --------
    >>> import frbmodel as frb
    >>> ur = frb.unbalance_response(frb.turbocharger(), "A", np.linspace(1e3, 40e3, 40), critical=False)
    >>> pk = response_peaks(ur)                 # at the forward crossings of critical_speeds' example
    >>> sorted(set(pk["speed [rpm]"].round(0))), sorted(set(pk["location"]))
    ([7159.0, 19417.0], ['compressor_wheel', 'turbine_wheel'])
    """
    import pandas as pd

    m = get_method(ur.method)
    opts = {**ur.meta.get("method_options", {}), **kw} if m.parameters else {}
    system = system_of(ur, system) if refine else None
    supply = oil_supply_of(ur, oil_supply)
    unb = tuple((u["disc"], u["node"], u["m e [kg m]"], u["phase [rad]"]) for u in ur.unbalance)
    s, rows = ur.speeds_rpm, []
    for name in names or [d["name"] for d in ur.layout["discs"]]:
        a = ur.major_axis(name)
        with np.errstate(invalid="ignore"):
            idx = np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])) + 1
        for k in idx:
            speed, amp_k, refined = s[k], a[k], False
            if system is not None:
                x, amp_x = _refine_peak(_amplitude_at(ur, system, m, name, unb, opts, supply), s[k - 1], s[k + 1])
                if amp_x >= amp_k:
                    speed, amp_k, refined = x, amp_x, True
            j, kind, prec, damp = _nearest_mode(cd, speed)
            rows.append({"source": "response peak", "speed [rpm]": float(speed), "frequency [Hz]": float(speed) / 60,
                         "mode": j, "kind": kind, "precession": prec, "damping [-]": damp, "location": name,
                         "amplitude [m]": float(amp_k), "refined": refined})
    return pd.DataFrame(rows, columns=list(CRITICAL_COLUMNS)).sort_values("speed [rpm]", kind="stable") \
        .reset_index(drop=True)


# ---------------------------------------------------------------------- figures
