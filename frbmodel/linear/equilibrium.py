"""Static equilibria of the floating-ring bearings for methods C, D, F, G, I and J
(docs/theory/rings.md#coupled-static-equilibrium).

Per bearing X the inner film must carry the static reaction W_X and the outer film W_X plus the ring
weight. Because each film force depends only on its own relative position and speed, F (and D) solve each
film in closed form; G solves (28)–(31) as one coupled 4-unknown system (same answer, more work); I and J
add the ring speed as unknown (eq. (7), respectively the full torque balance (32)) and solve a 1-D root
in the ring speed with closed-form film solutions inside.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ConvergenceError, ParameterError, check_real, check_speed, check_system
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..core.units import rad_s_to_rpm, rpm_to_rad_s
from ..physics.bearing import ring_speed_ratio, static_ring_torque
from ..physics.film import check_model, film_coefficients, film_force, static_position_kernel
from ..plots.equilibrium import equilibrium_figure, equilibrium_figure_html
from ..plots.figures import write_html
from ..system.methods import get_method
from ..system.rotor import GRAVITY


@dataclass
class BearingEquilibrium:
    """Static state of one floating-ring bearing (from :func:`bearing_equilibrium`).

    Attributes
    ----------
    name : str
        Bearing name.
    r_inner : ndarray (2,)
        Journal centre minus ring centre [m].
    ring : ndarray (2,)
        Ring centre relative to the housing [m].
    eps_inner, eps_outer : float
        Eccentricity ratios of the inner and outer film [-].
    ring_speed : float
        Ring speed ω_FR [rad/s].
    ring_speed_ratio : float
        ω_FR / ω_R [-].
    rotor_speed : float
        ω_R [rad/s].
    iterations, evaluations : int
        Solver iterations and film evaluations.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger(36e-6)
    >>> eq = bearing_equilibrium(tc.bearings[0], tc.bearing_loads[0], 10472.0, "J")   # 100 krpm
    >>> round(eq.ring_speed_ratio, 3), eq.omega_inner == eq.rotor_speed + eq.ring_speed
    (0.198, True)
    """

    name: str
    r_inner: np.ndarray  # journal centre minus ring centre [m] (kept itself: it can be far below |ring|)
    ring: np.ndarray  # ring centre rel. housing [m]
    eps_inner: float
    eps_outer: float
    ring_speed: float  # [rad/s]
    ring_speed_ratio: float
    rotor_speed: float  # [rad/s]
    iterations: int
    evaluations: int

    @property
    def journal(self) -> np.ndarray:
        """Journal centre relative to the housing [m]."""
        return self.ring + self.r_inner

    @property
    def omega_inner(self) -> float:
        """Inner film speed sum ω_R + ω_FR [rad/s]."""
        return self.rotor_speed + self.ring_speed

    @property
    def omega_outer(self) -> float:
        """Outer film speed sum ω_FR [rad/s]."""
        return self.ring_speed


@dataclass
class EquilibriumResult(Result):
    """Equilibrium of both bearings at one speed (from :func:`equilibrium`).

    Attributes
    ----------
    method : str
        Method letter.
    speed_rpm : float
        Rotor speed [rpm].
    bearings : tuple of BearingEquilibrium
        In the system's bearing order (Table 2: turbine, compressor).
    cpu_time_s : float
        Time of the solve [s].
    meta : dict

    Examples
    --------
    >>> import frbmodel as frb
    >>> eq = frb.equilibrium(frb.turbocharger(36e-6), "J", 100e3)
    >>> list(eq.to_dataframe()["bearing"])
    ['turbine', 'compressor']
    """

    NC_GLOB = "equilibrium*.nc"  # (Result.load of a folder)
    method: str
    speed_rpm: float
    bearings: tuple
    cpu_time_s: float = 0.0
    meta: dict = field(default_factory=dict)

    @property
    def iterations(self) -> int:
        """Solver iterations of both bearings."""
        return sum(b.iterations for b in self.bearings)

    @property
    def evaluations(self) -> int:
        """Film evaluations of both bearings."""
        return sum(b.evaluations for b in self.bearings)

    def to_dataframe(self):
        """One row per bearing: positions [m], ε [-], ring speed [rad/s], RSR [-], solver counts (pandas)."""
        import pandas as pd

        rows = []
        for b in self.bearings:
            rows.append({"bearing": b.name, "method": self.method, "speed [rpm]": self.speed_rpm,
                         "journal x [m]": b.journal[0], "journal y [m]": b.journal[1],
                         "ring x [m]": b.ring[0], "ring y [m]": b.ring[1],
                         "eps_inner [-]": b.eps_inner, "eps_outer [-]": b.eps_outer,
                         "ring speed [rad/s]": b.ring_speed, "RSR [-]": b.ring_speed_ratio,
                         "iterations [-]": b.iterations, "evaluations [-]": b.evaluations})
        return pd.DataFrame(rows)

    def to_xarray(self):
        """The equilibrium as an :class:`xarray.Dataset` over ``bearing`` (× ``axis`` x, y), units in the attributes.

        Returns
        -------
        xarray.Dataset
        """
        import xarray as xr

        bs, ba = ("bearing",), ("bearing", "axis")
        b = self.bearings
        data = {"r_inner": variable(ba, [e.r_inner for e in b], "m", "journal centre minus ring centre"),
                "ring": variable(ba, [e.ring for e in b], "m", "ring centre relative to the housing"),
                "eps_inner": variable(bs, [e.eps_inner for e in b], "-", "inner film eccentricity ratio"),
                "eps_outer": variable(bs, [e.eps_outer for e in b], "-", "outer film eccentricity ratio"),
                "ring_speed": variable(bs, [e.ring_speed for e in b], "rad/s", "ring speed"),
                "ring_speed_ratio": variable(bs, [e.ring_speed_ratio for e in b], "-", "ring-speed ratio"),
                "rotor_speed": variable(bs, [e.rotor_speed for e in b], "rad/s", "rotor speed"),
                "iterations": variable(bs, [e.iterations for e in b], "-", "solver iterations"),
                "evaluations": variable(bs, [e.evaluations for e in b], "-", "film evaluations")}
        attrs = {"method": self.method, "speed_rpm": self.speed_rpm, "cpu_time_s": self.cpu_time_s, **self.meta}
        return xr.Dataset(data, {"bearing": [e.name for e in b], "axis": ["x", "y"]}, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The equilibrium from a dataset of :meth:`to_xarray`.

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        EquilibriumResult
        """
        meta = {k: decode_attr(v) for k, v in ds.attrs.items()}
        v = {k: ds[k].values for k in ds.data_vars}
        bearings = tuple(BearingEquilibrium(str(n), v["r_inner"][i].copy(), v["ring"][i].copy(),
                                            float(v["eps_inner"][i]), float(v["eps_outer"][i]),
                                            float(v["ring_speed"][i]), float(v["ring_speed_ratio"][i]),
                                            float(v["rotor_speed"][i]), int(v["iterations"][i]),
                                            int(v["evaluations"][i]))
                         for i, n in enumerate(ds["bearing"].values))
        return cls(str(meta.pop("method")), float(meta.pop("speed_rpm")), bearings, float(meta.pop("cpu_time_s")),
                   meta)

    def _figure_rows(self):
        """Positions and clearances per bearing for :mod:`frbmodel.plots.equilibrium` (clearances from
        ``meta["clearances_m"]``)."""
        clear = self.meta.get("clearances_m") or {}
        if set(clear) != {e.name for e in self.bearings}:
            raise ParameterError("this EquilibriumResult has no film clearances in meta['clearances_m'] (made by "
                                 "frbmodel.equilibrium): its figure draws the eccentricity vectors in them")
        return [{"name": e.name, "inner": e.r_inner, "outer": e.ring, "inner_clearance": clear[e.name][0],
                 "outer_clearance": clear[e.name][1]} for e in self.bearings]

    def plot(self, title=None):
        """Journal in ring and ring in housing of every bearing, in their clearance circles (matplotlib;
        :func:`frbmodel.plots.equilibrium.equilibrium_figure`)."""

        return equilibrium_figure(self._figure_rows(), title or self._title())

    def plot_html(self, path=None, title=None, include_plotlyjs=None):
        """The panels of :meth:`plot` as an interactive page, written to ``path`` (HTML) if given.

        Parameters
        ----------
        path : str or Path, optional
            The HTML file (not written if None).
        title : str, optional
            Figure title (default: method and speed).
        include_plotlyjs : {"directory", True}, optional
            As for :func:`frbmodel.plots.figures.write_html`: plotly.js beside the page, or embedded in it.

        Returns
        -------
        plotly.graph_objects.Figure
        """

        fig = equilibrium_figure_html(self._figure_rows(), title or self._title())
        if path is not None:
            write_html(fig, path, include_plotlyjs)
        return fig

    def _title(self):
        return f"method {self.method} equilibrium at {self.speed_rpm:,.0f} rpm"

    @property
    def stem(self) -> str:
        """File stem of :meth:`save`: ``equilibrium_<M>_<rpm>``."""
        return f"equilibrium_{self.method}_{self.speed_rpm:.0f}"

    def save(self, out_dir):
        """Write ``<stem>.csv`` (:meth:`to_dataframe`), ``<stem>.nc`` (:meth:`to_xarray`) and the figures
        ``<stem>.png`` / ``.html`` into ``out_dir`` (created if missing); returns the paths."""
        return self.save_files(out_dir, self.stem)

    def __str__(self):
        lines = [f"method {self.method} equilibrium at {self.speed_rpm:.0f} rpm "
                 f"({self.cpu_time_s * 1e3:.3f} ms, {self.iterations} iterations, {self.evaluations} evaluations)"]
        for b in self.bearings:
            lines.append(
                f"  {b.name:>10}: RSR {b.ring_speed_ratio:.5f}  eps_I {b.eps_inner:.4f}  eps_O {b.eps_outer:.4f}  "
                f"journal ({b.journal[0] * 1e6:+.3f}, {b.journal[1] * 1e6:+.3f}) um  "
                f"ring ({b.ring[0] * 1e6:+.3f}, {b.ring[1] * 1e6:+.3f}) um")
        return "\n".join(lines)


def _loads(bearing, w, g):
    return (0.0, w), (0.0, w + bearing.ring_mass * g)


def _uncoupled(bearing, w, omega_r, model, g, rsr):
    f_i, f_o = _loads(bearing, w, g)
    omega_fr = rsr * omega_r
    r_i, eps_i, it_i = static_position_kernel(bearing.inner, *f_i, omega_r + omega_fr, model)
    r_o, eps_o, it_o = static_position_kernel(bearing.outer, *f_o, omega_fr, model)
    return BearingEquilibrium(bearing.name, r_i, r_o, eps_i, eps_o, omega_fr, rsr, omega_r, it_i + it_o, 2)


def _outer_only(bearing, w, omega_r, model, g, rsr):
    _, f_o = _loads(bearing, w, g)
    omega_fr = rsr * omega_r
    r_o, eps_o, it = static_position_kernel(bearing.outer, *f_o, omega_fr, model)
    return BearingEquilibrium(bearing.name, np.zeros(2), r_o, 0.0, eps_o, omega_fr, rsr, omega_r, it, 1)


def _coupled(bearing, w, omega_r, model, g, rsr):
    """Method G: solve F^I(r_I) = (0, W), F^O(r_O) = F^I + (0, m g) as one 4-unknown system (hybr)."""
    from scipy.optimize import root

    omega_fr = rsr * omega_r
    c_i, c_o = bearing.inner.clearance, bearing.outer.clearance
    scale_f = max(abs(w), bearing.ring_mass * g, 1e-6)
    zero = np.zeros(2)
    mg = np.array([0.0, bearing.ring_mass * g])
    target = np.array([0.0, w])

    # unknowns u (2 per film) map to r = c u / sqrt(1 + |u|^2): every trial point of the solver lies strictly
    # inside the clearance, so the Newton-type steps never ask for a film state with eps >= 1
    def to_r(u, c):
        return c * u / np.sqrt(1.0 + u @ u)

    def dr_du(u, c):
        q = 1.0 + u @ u
        return c * (np.eye(2) / np.sqrt(q) - np.outer(u, u) / q ** 1.5)

    def unpack(x):
        return to_r(x[:2], c_i), to_r(x[2:], c_o)

    def fun(x):
        r_i, r_o = unpack(x)
        f_i = film_force(bearing.inner, r_i, zero, omega_r + omega_fr, model)
        f_o = film_force(bearing.outer, r_o, zero, omega_fr, model)
        return np.concatenate([f_i - target, f_o - f_i - mg]) / scale_f

    def jac(x):
        r_i, r_o = unpack(x)
        k_i, _ = film_coefficients(bearing.inner, r_i, omega_r + omega_fr, model)
        k_o, _ = film_coefficients(bearing.outer, r_o, omega_fr, model)
        d_i, d_o = dr_du(x[:2], c_i), dr_du(x[2:], c_o)
        J = np.zeros((4, 4))
        J[:2, :2] = -k_i @ d_i
        J[2:, :2] = k_i @ d_i
        J[2:, 2:] = -k_o @ d_o
        return J / scale_f

    sol = root(fun, np.zeros(4), jac=jac, method="hybr", options={"xtol": 1e-13})
    if not sol.success or np.max(np.abs(sol.fun)) > 1e-9:
        raise ConvergenceError(f"method G equilibrium of the {bearing.name} bearing did not converge at "
                               f"{rad_s_to_rpm(omega_r):.0f} rpm: {sol.message} "
                               f"(residual {np.max(np.abs(sol.fun)):.3g})")
    r_i, r_o = unpack(sol.x)
    return BearingEquilibrium(bearing.name, r_i, r_o, float(np.hypot(*r_i) / c_i), float(np.hypot(*r_o) / c_o),
                              omega_fr, rsr, omega_r, int(sol.nfev), int(sol.nfev + sol.njev))


def _ring_speed_root(bearing, w, omega_r, model, g, residual_kind):
    """Methods I and J: 1-D Brent root in the ring speed; each evaluation solves both films in closed form."""
    from scipy.optimize import brentq

    f_i, f_o = _loads(bearing, w, g)
    counter = {"n": 0}

    def films(omega_fr):
        counter["n"] += 1
        r_i, eps_i, _ = static_position_kernel(bearing.inner, *f_i, omega_r + omega_fr, model)
        r_o, eps_o, _ = static_position_kernel(bearing.outer, *f_o, omega_fr, model)
        return r_i, eps_i, r_o, eps_o

    def residual(omega_fr):
        _, eps_i, _, eps_o = films(omega_fr)
        if residual_kind == "petroff":
            return ring_speed_ratio(bearing, eps_i, eps_o, "petroff", model) * omega_r - omega_fr
        return static_ring_torque(bearing, eps_i, eps_o, omega_r, omega_fr, model) / omega_r

    rsr6 = ring_speed_ratio(bearing)
    lo, hi = 0.5 * rsr6 * omega_r, min(1.2 * rsr6, 0.999) * omega_r
    try:
        r_lo, r_hi = residual(lo), residual(hi)
        if r_lo * r_hi > 0.0:
            lo, hi = 1e-3 * omega_r, 0.999 * omega_r
            r_lo, r_hi = residual(lo), residual(hi)
        if r_lo * r_hi > 0.0:
            raise ConvergenceError(
                f"method {'I' if residual_kind == 'petroff' else 'J'} ring speed of the {bearing.name} bearing: "
                f"no root in 0.001..0.999 x rotor speed at {rad_s_to_rpm(omega_r):.0f} rpm")
        omega_fr, res = brentq(residual, lo, hi, xtol=1e-12 * omega_r, rtol=1e-14, full_output=True)
    except ValueError as exc:  # a film solution failed inside (e.g. eps -> 1 at a tiny ring speed)
        raise ConvergenceError(f"ring speed solve of the {bearing.name} bearing failed at "
                               f"{rad_s_to_rpm(omega_r):.0f} rpm: "
                               f"{exc}") from exc
    r_i, eps_i, r_o, eps_o = films(omega_fr)
    return BearingEquilibrium(bearing.name, r_i, r_o, eps_i, eps_o, omega_fr, omega_fr / omega_r, omega_r,
                              int(res.iterations), 2 * counter["n"])


def bearing_equilibrium(bearing, load, omega_rotor, method, film_model="short", gravity=GRAVITY):
    """Equilibrium of one bearing carrying a vertical load at one rotor speed
    (docs/theory/rings.md#coupled-static-equilibrium).

    Parameters
    ----------
    bearing : FloatingRingBearing
    load : float
        Static reaction W [N] the inner film carries (positive = upward force on the journal).
    omega_rotor : float
        Rotor speed [rad/s], > 0.
    method : str
        One of C, D, F, G, I, J.
    film_model : {"short", "short_corrected"}
    gravity : float
        [m/s²] along −y (ring weight).

    Returns
    -------
    BearingEquilibrium

    Raises
    ------
    ParameterError
        Method without film equilibrium, unknown film model, or a load / speed / gravity that is not a finite real
        number (speed <= 0).
    ConvergenceError
        The ring-speed or coupled solve failed.

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger(36e-6)
    >>> eq = bearing_equilibrium(tc.bearings[0], tc.bearing_loads[0], 1000.0, "F")
    >>> round(eq.ring_speed_ratio, 5)                  # method F uses eq. (6)
    0.19903
    """
    m = get_method(method)
    if m.equilibrium is None:
        raise ParameterError(f"method {m.letter} has no film equilibrium; equilibria exist for "
                             "C, D, F, G, I, J")
    omega_rotor = check_real("rotor speed omega_rotor", omega_rotor, "rad/s")
    if not omega_rotor > 0.0:
        raise ParameterError(f"rotor speed = {omega_rotor!r} rad/s is invalid for method {m.letter}: a linearized "
                             "film needs a rotor speed > 0")
    load = check_real("bearing load", load, "N")
    gravity = check_real("gravity", gravity, "m/s^2", minimum=0.0, inclusive=True)
    film_model = check_model(film_model)
    kind = m.equilibrium
    if kind in ("petroff", "torque"):
        return _ring_speed_root(bearing, load, omega_rotor, film_model, gravity, kind)
    rsr = ring_speed_ratio(bearing)
    solver = {"uncoupled": _uncoupled, "outer_film": _outer_only, "coupled": _coupled}[kind]
    return solver(bearing, load, omega_rotor, film_model, gravity, rsr)


def equilibrium(system, method="J", speed_rpm=150e3) -> EquilibriumResult:
    """Static equilibrium of both floating-ring bearings.

    Parameters
    ----------
    system : Turbocharger
    method : {"C", "D", "F", "G", "I", "J"}
    speed_rpm : float
        Rotor speed [rpm], > 0.

    Returns
    -------
    EquilibriumResult
        Journal/ring positions [m], eccentricity ratios, ring speeds [rad/s] and RSR per bearing,
        iterations, evaluations and CPU time.

    Examples
    --------
    >>> import frbmodel as frb
    >>> eq = frb.equilibrium(frb.turbocharger(36e-6), method="J", speed_rpm=100e3)
    >>> round(eq.bearings[0].ring_speed_ratio, 3)
    0.198
    """
    check_system(system)
    speed_rpm = check_real("speed_rpm", speed_rpm, "rpm")
    if not speed_rpm > 0.0:
        raise ParameterError(f"speed_rpm = {speed_rpm!r} rpm is invalid for a film equilibrium: valid range > 0")
    check_speed("speed_rpm", speed_rpm)
    m = get_method(method)
    t0 = time.perf_counter()
    loads = system.bearing_loads
    res = tuple(bearing_equilibrium(b, loads[i], rpm_to_rad_s(speed_rpm), m.letter, system.film_model, system.gravity)
                for i, b in enumerate(system.bearings))
    clearances = {b.name: (b.inner.clearance, b.outer.clearance) for b in system.bearings}
    return EquilibriumResult(m.letter, speed_rpm, res, time.perf_counter() - t0, {"clearances_m": clearances})


def linear_rsr(system, speeds_rpm, methods="FIJ"):
    """Ring-speed ratios of the linear methods' equilibria, as the composite figure's RSR panel draws them.

    Parameters
    ----------
    system : Turbocharger
    speeds_rpm : (n,) array_like
        Rotor speeds [rpm].
    methods : str
        Method letters.

    Returns
    -------
    tuple
        (speeds [rpm] (n,), {method letter: RSR [-] (n, nb)}, bearing names), bearings in the system's order.

    Examples
    --------
    >>> import frbmodel as frb
    >>> s, rsr, names = linear_rsr(frb.turbocharger(), [50e3], "F")
    >>> names, round(float(rsr["F"][0, 0]), 5)
    (('turbine', 'compressor'), 0.19903)
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    by_method = {m: np.array([[b.ring_speed_ratio for b in equilibrium(system, m, s).bearings] for s in speeds])
                 for m in methods}
    return speeds, by_method, tuple(b.name for b in system.bearings)
