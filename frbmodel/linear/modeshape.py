"""Mode shapes of a Campbell diagram's modes: the deflected, whirling rotor at one speed.

:func:`mode_shape` solves the eigenproblem of the same linear system the Campbell diagram used
(:func:`frbmodel.linear.assembly.linear_system` + :func:`frbmodel.linear.modal.modes`) at exactly the requested speed
and picks the eigenvector of the tracked mode. :class:`ModeShape` holds it normalised (:func:`normalise`: largest orbit
semi-major axis 1, its dominant whirl component real and positive) and gives the node amplitudes and phases, the
Euler–Bernoulli (Hermite cubic) deflection line between nodes, the orbit ellipses at the nodes and the ring orbits.

Sign convention (:mod:`frbmodel.system.rotor`): node DoFs ``[v, w, θx, θy]`` with θx = −∂w/∂z and θy = +∂v/∂z; x
horizontal, y vertical, rotation CCW about +z. A motion is ``x(t) = Re(v̂ e^{iφ})``, ``y(t) = Re(ŵ e^{iφ})`` with
φ = ω_d t (the decay/growth e^{σt} is left out); forward whirl is CCW about +z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ParameterError
from ..core.results import Result, decode_attr, netcdf_attrs, variable
from ..plots.figures import write_html
from ..plots.modeshape import plot_mode_shape, plot_mode_shape_html, plot_mode_shapes
from ..system.parameters import system_from_meta
from .assembly import linear_system
from .modal import modes


def hermite(xi, length):
    """Euler–Bernoulli (Hermite cubic) shape functions of a beam element.

    Parameters
    ----------
    xi : array_like
        Position along the element, 0 (first node) ... 1 (second node) [-].
    length : float
        Element length [m].

    Returns
    -------
    ndarray (4, n)
        N1..N4 multiplying (u1, u1', u2, u2'), u' the slope du/dz [-].

    Examples
    --------
    >>> hermite([0.0, 1.0], 2.0).round(12).tolist()      # nodal values: N1 = 1 at ξ = 0, N3 = 1 at ξ = 1
    [[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [0.0, 0.0]]
    """
    s = np.atleast_1d(np.asarray(xi, dtype=float))
    return np.array([1 - 3 * s**2 + 2 * s**3, length * (s - 2 * s**2 + s**3), 3 * s**2 - 2 * s**3,
                     length * (s**3 - s**2)])


def normalise(shape, n_nodes, ring_dofs=()):
    """Scale a mode shape: largest orbit semi-major axis (rotor nodes and rings) 1, its dominant whirl real > 0.

    The dominant whirl component of the largest orbit (forward r_f = (v + i w)/2 or backward
    r_b = (v̄ + i w̄)/2, whichever is larger) is made real and positive, so a circular orbit there has v real > 0.

    Parameters
    ----------
    shape : complex ndarray (n_dof,)
        Eigenvector displacement part; rotor DoFs first, 4 per node ``[v, w, θx, θy]``.
    n_nodes : int
        Number of rotor nodes.
    ring_dofs : sequence of (int, int)
        Indices of each ring's (x, y).

    Returns
    -------
    complex ndarray (n_dof,)

    Examples
    --------
    >>> normalise(np.array([0, 0, 0, 0, 2j, 2, 0, 0]), 2).round(12).tolist()   # node 1: circular forward
    [0j, 0j, 0j, 0j, (1+0j), -1j, 0j, 0j]
    """
    u = np.asarray(shape, dtype=complex)
    ix = np.concatenate([np.arange(n_nodes) * 4, [int(a) for a, _ in ring_dofs]]).astype(int)
    iy = np.concatenate([np.arange(n_nodes) * 4 + 1, [int(b) for _, b in ring_dofs]]).astype(int)
    major, _, _ = ellipse(u[ix], u[iy])
    k = int(np.argmax(major))
    v, w = u[ix[k]], u[iy[k]]
    rf, rb = 0.5 * (v + 1j * w), 0.5 * (np.conj(v) + 1j * np.conj(w))
    c = np.conj(rf) / abs(rf) if abs(rf) >= abs(rb) else rb / abs(rb)
    return u * c / major[k]


def ellipse(a, b):
    """Orbit ellipse of ``x = Re(a e^{iφ})``, ``y = Re(b e^{iφ})``.

    Parameters
    ----------
    a, b : complex or complex ndarray
        Complex amplitudes of x and y [m or normalised].

    Returns
    -------
    major, minor : ndarray
        Semi-axes [same unit as a, b] (minor >= 0).
    forward : ndarray of bool
        True where the orbit turns CCW about +z (forward whirl, with the rotor).

    Examples
    --------
    >>> major, minor, fwd = ellipse(1.0, -1j)            # x = cos φ, y = sin φ: circle, forward
    >>> float(major), float(minor), bool(fwd)
    (1.0, 1.0, True)
    """
    rf = 0.5 * (np.asarray(a) + 1j * np.asarray(b))
    rb = 0.5 * (np.conj(a) + 1j * np.conj(b))
    f, g = np.abs(rf), np.abs(rb)
    return f + g, np.abs(f - g), f > g


@dataclass
class ModeShape(Result):
    """One mode of a linear system at one speed, normalised (see :func:`normalise`).

    Attributes
    ----------
    method : str
        Method letter.
    speed_rpm : float
        Rotor speed [rpm].
    mode : int
        Tracked mode index of the Campbell diagram.
    eigenvalue : complex
        λ [1/s].
    shape : complex ndarray (n_dof,)
        Normalised displacement eigenvector (:func:`normalise`) [-, rotations 1/m]; rotor DoFs then the rings'
        (x, y).
    node_z : ndarray (n_nodes,)
        Axial node positions [m].
    discs : dict
        Disc name → node.
    bearings : dict
        Bearing name → node.
    ring_dofs : list of (int, int)
        Indices of each ring's (x, y) in ``shape`` (empty without ring DoFs), in the order of ``bearings``.
    ring_energy : ndarray (n_bearings,)
        Share of the modal kinetic energy u^H M u carried by each ring [-] (zeros without ring DoFs).
    kind, precession : str
        The Campbell diagram's labels of the mode at the nearest grid speed.
    meta : dict
        System name, method options.
    """

    NC_GLOB = "mode_shape*.nc"  # (Result.load of a folder)
    method: str
    speed_rpm: float
    mode: int
    eigenvalue: complex
    shape: np.ndarray
    node_z: np.ndarray
    discs: dict
    bearings: dict
    ring_dofs: list = field(default_factory=list)
    ring_energy: np.ndarray | None = None
    kind: str = ""
    precession: str = ""
    meta: dict = field(default_factory=dict)

    @property
    def frequency_hz(self) -> float:
        """Damped natural frequency Im λ / 2π [Hz]."""
        return float(self.eigenvalue.imag / (2 * math.pi))

    @property
    def damping(self) -> float:
        """Modal damping D = −Re λ / |λ| [-]."""
        return float(-self.eigenvalue.real / abs(self.eigenvalue))

    @property
    def n_nodes(self) -> int:
        """Number of rotor nodes."""
        return self.node_z.size

    def node_dofs(self):
        """Complex node amplitudes (v, w, θx, θy), each an ndarray (n_nodes,) [-, -, 1/m, 1/m]."""
        u = self.shape[:4 * self.n_nodes].reshape(-1, 4)
        return u[:, 0], u[:, 1], u[:, 2], u[:, 3]

    def deflection(self, z, phase=0.0):
        """Deflection line x(z), y(z) at ``phase`` φ of the period from the Hermite cubics between nodes.

        Parameters
        ----------
        z : array_like
            Axial positions within the shaft [m].
        phase : float
            φ [rad]; x = Re(v̂(z) e^{iφ}).

        Returns
        -------
        x, y : ndarray
            Normalised deflections [-].
        """
        xc, yc = self.complex_deflection(z)
        e = np.exp(1j * phase)
        return np.real(xc * e), np.real(yc * e)

    def complex_deflection(self, z):
        """Complex amplitudes v̂(z), ŵ(z) between the nodes (Hermite cubics, slopes θy and −θx) [-]."""
        z = np.atleast_1d(np.asarray(z, dtype=float))
        v, w, thx, thy = self.node_dofs()
        e = np.clip(np.searchsorted(self.node_z, z, side="right") - 1, 0, self.n_nodes - 2)
        length = self.node_z[e + 1] - self.node_z[e]
        N = hermite((z - self.node_z[e]) / length, 1.0)
        N[[1, 3]] *= length  # element lengths differ: scale the slope functions per point
        xc = N[0] * v[e] + N[1] * thy[e] + N[2] * v[e + 1] + N[3] * thy[e + 1]
        yc = N[0] * w[e] - N[1] * thx[e] + N[2] * w[e + 1] - N[3] * thx[e + 1]
        return xc, yc

    def ring_shapes(self):
        """Complex (x, y) amplitude of each ring [-]; an empty list without ring DoFs."""
        return [(self.shape[i], self.shape[j]) for i, j in self.ring_dofs]

    def node_forward(self):
        """True for each rotor node whose orbit turns with the rotor (forward whirl), ndarray (n_nodes,) of bool."""
        v, w, _, _ = self.node_dofs()
        return np.asarray(ellipse(v, w)[2])

    def ring_major_axes(self):
        """Orbit semi-major axis of each ring [-] (empty without ring DoFs)."""
        return np.array([float(ellipse(a, b)[0]) for a, b in self.ring_shapes()])

    def to_dataframe(self):
        """One row per rotor node and ring: amplitudes, phases and orbit of x and y.

        Returns
        -------
        pandas.DataFrame
            Columns: item (node<i> or ring_<bearing>), z [m], name (disc/bearing at the node), |x| [-],
            phase x [deg], |y| [-], phase y [deg], thx [1/m], thy [1/m] (complex magnitudes), major [-], minor [-],
            whirl (forward/backward), ring energy [-].
        """
        import pandas as pd

        v, w, thx, thy = self.node_dofs()
        names = {n: k for k, n in {**self.bearings, **self.discs}.items()}
        rows = [self._row(f"node{i}", self.node_z[i], names.get(i, ""), v[i], w[i], abs(thx[i]), abs(thy[i]), np.nan)
                for i in range(self.n_nodes)]
        for k, ((a, b), (bn, node)) in enumerate(zip(self.ring_shapes(), self.bearings.items())):
            rows.append(self._row(f"ring_{bn}", self.node_z[node], bn, a, b, np.nan, np.nan, self.ring_energy[k]))
        return pd.DataFrame(rows)

    @staticmethod
    def _row(item, z, name, a, b, tx, ty, ring_e):
        major, minor, fwd = ellipse(a, b)
        return {"item": item, "z [m]": z, "name": name, "|x| [-]": abs(a), "phase x [deg]": math.degrees(np.angle(a)),
                "|y| [-]": abs(b), "phase y [deg]": math.degrees(np.angle(b)), "|thx| [1/m]": tx,
                "|thy| [1/m]": ty, "major [-]": float(major), "minor [-]": float(minor),
                "whirl": "forward" if fwd else "backward", "ring energy [-]": ring_e}

    @property
    def title(self) -> str:
        """Short label: method, mode, speed, frequency, damping, kind."""
        return (f"{self.method} mode {self.mode} @ {self.speed_rpm / 1e3:.1f} krpm: {self.frequency_hz:.1f} Hz, "
                f"D = {self.damping:.3f}, {self.precession} {self.kind}")

    def plot(self, ax=None, n_phases=8, title=None):
        """2-D figure: x-deflection line at ``n_phases`` phases, orbit ellipses at the nodes, wheels marked.

        Parameters
        ----------
        ax : matplotlib Axes, optional
        n_phases : int
            Number of phases φ = 2π k / n_phases drawn.
        title : str, optional

        Returns
        -------
        matplotlib.figure.Figure
        """
        return plot_mode_shape(self, ax=ax, n_phases=n_phases, title=title)

    def plot_html(self, path=None, include_plotlyjs=None):
        """Interactive 3-D (plotly) figure of the whirling shaft; written to ``path`` if given.

        Parameters
        ----------
        path : str or Path, optional
            The HTML file.
        include_plotlyjs : {"directory", True}, optional
            ``"directory"``: plotly.js from ``plotly.min.js`` beside the file, one copy per folder (small file, shown
            offline); ``True``: embedded (self-contained, 4.8 MB larger). Default: ``"directory"``, or what
            :func:`frbmodel.plots.figures.html_plotlyjs` set. See :func:`frbmodel.plots.figures.write_html`.

        Returns
        -------
        plotly.graph_objects.Figure
        """
        return plot_mode_shape_html(self, path, include_plotlyjs=include_plotlyjs)

    def to_xarray(self):
        """The mode as an :class:`xarray.Dataset`: the complex shape over ``dof`` (real and imaginary part), the
        node positions over ``node``, the ring energy shares over ``bearing``; the scalars and the layout in the
        attributes.

        Returns
        -------
        xarray.Dataset
        """
        import xarray as xr

        energy = np.zeros(len(self.bearings)) if self.ring_energy is None else np.asarray(self.ring_energy)
        data = {"shape_re": variable(("dof",), self.shape.real, "-", "normalised eigenvector, real part (rotations "
                                     "1/m)"),
                "shape_im": variable(("dof",), self.shape.imag, "-", "imaginary part"),
                "node_z": variable(("node",), self.node_z, "m", "axial node position"),
                "ring_energy": variable(("bearing",), energy, "-", "share of the modal kinetic energy in the ring")}
        attrs = {"method": self.method, "speed_rpm": self.speed_rpm, "mode": self.mode,
                 "eigenvalue_re": self.eigenvalue.real, "eigenvalue_im": self.eigenvalue.imag, "discs": self.discs,
                 "bearings": self.bearings, "ring_dofs": [list(map(int, r)) for r in self.ring_dofs],
                 "kind": self.kind, "precession": self.precession, "has_ring_energy": self.ring_energy is not None,
                 **self.meta}
        return xr.Dataset(data, attrs=netcdf_attrs(attrs))

    @classmethod
    def from_xarray(cls, ds):
        """The mode from a dataset of :meth:`to_xarray`.

        Parameters
        ----------
        ds : xarray.Dataset

        Returns
        -------
        ModeShape
        """
        a = {k: decode_attr(v) for k, v in ds.attrs.items()}
        head = {k: a.pop(k) for k in ("method", "speed_rpm", "mode", "eigenvalue_re", "eigenvalue_im", "discs",
                                      "bearings", "ring_dofs", "kind", "precession", "has_ring_energy")}
        return cls(str(head["method"]), float(head["speed_rpm"]), int(head["mode"]),
                   complex(head["eigenvalue_re"], head["eigenvalue_im"]),
                   ds["shape_re"].values + 1j * ds["shape_im"].values, ds["node_z"].values.copy(), head["discs"],
                   head["bearings"], [tuple(r) for r in head["ring_dofs"]],
                   ds["ring_energy"].values.copy() if head["has_ring_energy"] else None, str(head["kind"]),
                   str(head["precession"]), a)

    @property
    def stem(self) -> str:
        """File stem of :meth:`save`: ``mode_shape_<M>_<rpm>_mode<k>``."""
        return f"mode_shape_{self.method}_{self.speed_rpm:.0f}_mode{self.mode}"

    def save(self, out_dir):
        """Write ``<stem>.csv`` (:meth:`to_dataframe`), ``<stem>.nc`` (:meth:`to_xarray`) and the figures
        ``<stem>.png`` / ``.html`` into ``out_dir`` (created if missing); returns the paths."""
        return self.save_files(out_dir, self.stem)


def _match_mode(cd, speed_rpm, mode, lam):
    """Index in ``lam`` of Campbell track ``mode`` at ``speed_rpm`` (eigenvalue interpolated along the track)."""
    s = cd.speeds_rpm
    if not 0 <= int(mode) < cd.n_modes:
        raise ParameterError(f"mode = {mode!r} is invalid: valid range 0..{cd.n_modes - 1}")
    col = cd.eigenvalues[:, int(mode)]
    ok = np.isfinite(col)
    if not ok.any() or not s[ok][0] <= speed_rpm <= s[ok][-1]:
        raise ParameterError(f"mode {mode} is not present at {speed_rpm:g} rpm in the Campbell diagram "
                             f"(present in {s[ok][0]:g}..{s[ok][-1]:g} rpm)" if ok.any() else
                             f"mode {mode} is absent at every speed of the Campbell diagram")
    target = np.interp(speed_rpm, s[ok], col[ok].real) + 1j * np.interp(speed_rpm, s[ok], col[ok].imag)
    return int(np.argmin(np.abs(lam - target))), int(np.argmin(np.abs(s - speed_rpm)))


def mode_shape(cd, speed_rpm, mode) -> ModeShape:
    """Shape of tracked mode ``mode`` of Campbell result ``cd`` at ``speed_rpm``, solved at exactly that speed.

    Parameters
    ----------
    cd : CampbellResult
        From :func:`frbmodel.linear.campbell` (its ``meta`` holds the system, method options).
    speed_rpm : float
        Rotor speed [rpm] within the range where the mode is present. Between grid speeds the mode is the
        eigenvalue nearest to the track's linearly interpolated one (near a crossing of two branches, choose a grid
        speed to be sure of the identity).
    mode : int
        Column of the Campbell arrays.

    Returns
    -------
    ModeShape

    Raises
    ------
    ParameterError
        No system in ``cd.meta``, a mode index out of range, or a speed outside the mode's range.

    Examples
    --------
    >>> import frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "A", [30e3], whirl=False)
    >>> ms = mode_shape(cd, 30e3, 0)
    >>> bool(np.isclose(ms.eigenvalue, cd.eigenvalues[0, 0]))
    True
    """
    system = system_from_meta(cd.meta, "this CampbellResult", "mode shapes (they need frbmodel.campbell(system, ...))")
    speed_rpm = float(speed_rpm)
    ls = linear_system(system, cd.method, speed_rpm, **cd.meta.get("method_options", {}))
    md = modes(ls.M, ls.C, ls.K)
    k, i = _match_mode(cd, speed_rpm, mode, md.eigenvalues)
    rotor = system.rotor
    rings = list(ls.ring_dofs or [])
    u = normalise(md.shapes[:, k], rotor.n_nodes, rings)
    total = float(np.real(np.conj(u) @ ls.M @ u))
    ring_e = np.array([float(np.real(np.conj(u[[a, b]]) @ ls.M[np.ix_([a, b], [a, b])] @ u[[a, b]])) / total
                       for a, b in rings]) if rings else np.zeros(len(system.bearings))
    return ModeShape(cd.method, speed_rpm, int(mode), complex(md.eigenvalues[k]), u, rotor.node_z.copy(),
                     {d.name: d.node for d in rotor.discs}, {b.name: b.node for b in system.bearings}, rings,
                     ring_e, str(cd.mode_kind[i, int(mode)]), str(cd.precession[i, int(mode)]),
                     {"system_name": system.name, "method_options": cd.meta.get("method_options", {})})


def modes_at(cd, speed_rpm, fmax_hz=None):
    """Tracked modes present at ``speed_rpm`` (nearest grid speed), below ``fmax_hz`` if given.

    Parameters
    ----------
    cd : CampbellResult
    speed_rpm : float
    fmax_hz : float, optional

    Returns
    -------
    list of int
    """
    i = int(np.argmin(np.abs(cd.speeds_rpm - speed_rpm)))
    f = cd.frequencies_hz[i]
    keep = np.isfinite(f) & (True if fmax_hz is None else f <= fmax_hz)
    return [int(j) for j in np.flatnonzero(keep)]


def save_mode_shapes(cd, speed_rpm, out_dir, fmax_hz=None):
    """Write the shapes of every mode present at ``speed_rpm`` (below ``fmax_hz``) as PNG, HTML and CSV.

    Parameters
    ----------
    cd : CampbellResult
    speed_rpm : float
        [rpm]
    out_dir : path
    fmax_hz : float, optional
        Only modes up to this frequency [Hz] (at the nearest grid speed).

    Returns
    -------
    list of Path
        ``mode_shapes_<method>_<rpm>.png``, ``.html`` (one 3-D figure per mode) and ``.csv`` (one row per mode
        and node/ring, with the mode, frequency [Hz], damping [-], precession and kind).
    """
    from pathlib import Path

    import pandas as pd

    out = Path(out_dir)
    shapes = [mode_shape(cd, speed_rpm, j) for j in modes_at(cd, speed_rpm, fmax_hz)]
    if not shapes:
        raise ParameterError(f"no mode at {speed_rpm:g} rpm" + ("" if fmax_hz is None else f" below {fmax_hz:g} Hz"))
    stem = out / f"mode_shapes_{cd.method}_{speed_rpm:.0f}"
    fig = plot_mode_shapes(shapes, title=f"method {cd.method}, {speed_rpm:,.0f} rpm: mode shapes "
                                         "(x deflection at 8 phases; node orbits red forward, blue backward)")
    fig.savefig(stem.with_suffix(".png"), dpi=110)
    import matplotlib.pyplot as plt


    plt.close(fig)
    write_html([plot_mode_shape_html(ms) for ms in shapes], stem.with_suffix(".html"))
    frames = []
    for ms in shapes:
        df = ms.to_dataframe()
        df.insert(0, "mode", ms.mode)
        df.insert(1, "frequency [Hz]", ms.frequency_hz)
        df.insert(2, "damping [-]", ms.damping)
        df.insert(3, "precession", ms.precession)
        df.insert(4, "kind", ms.kind)
        frames.append(df)
    pd.concat(frames, ignore_index=True).to_csv(stem.with_suffix(".csv"), index=False)
    return [stem.with_suffix(s) for s in (".png", ".html", ".csv")]


def unstable_mode_shapes(cd, precession="forward"):
    """Shape of each unstable range's mode at its least damped grid speed (:meth:`CampbellResult.unstable_ranges`).

    Parameters
    ----------
    cd : CampbellResult
    precession : str or None
        Keep only the ranges of this precession ("forward", "backward", "mixed"); None: all.

    Returns
    -------
    list of ModeShape
        In the order of the unstable ranges (by their start speed).

    Examples
    --------
    >>> import frbmodel as frb
    >>> cd = frb.campbell(frb.turbocharger(), "J", np.linspace(10e3, 250e3, 25), whirl=False)
    >>> [(ms.mode, ms.damping < 0) for ms in unstable_mode_shapes(cd)]
    [(3, True), (5, True), (1, True), (2, True)]
    """
    out = []
    for _, r in cd.unstable_ranges().iterrows():
        if precession is not None and r["precession"] != precession:
            continue
        j = int(r["mode"])
        inside = (cd.speeds_rpm >= r["from [rpm]"]) & (cd.speeds_rpm <= r["to [rpm]"])
        i = np.flatnonzero(inside)[np.nanargmin(cd.damping[inside, j])]
        out.append(mode_shape(cd, cd.speeds_rpm[i], j))
    return out


def _shape_items(system, ring_dofs):
    """The places a hover lists, along the shaft (by node; a disc before a journal at the same node, each ring after
    its journal): (label, x index, y index) in the displacement vector."""
    items = [(d.node, 0, d.name, 4 * d.node, 4 * d.node + 1) for d in system.rotor.discs]
    for k, b in enumerate(system.bearings):
        items.append((b.node, 1, f"{b.name} journal", 4 * b.node, 4 * b.node + 1))
        if ring_dofs:
            items.append((b.node, 2, f"{b.name} ring", int(ring_dofs[k][0]), int(ring_dofs[k][1])))
    return [(label, ix, iy) for _, _, label, ix, iy in sorted(items, key=lambda it: it[:2])]


def shape_hover_text(cd, shown=None):
    """Hover text of the mode shapes of a Campbell diagram's points: per disc, journal and ring (along the shaft)
    the orbit's semi-major axis (the largest orbit of the mode = 1), the phase of x [deg] relative to it and the
    whirl direction.

    The linear system of the diagram (its system, method and options from ``cd.meta``) is solved again at each grid
    speed (:func:`frbmodel.linear.assembly.linear_system`, :func:`frbmodel.linear.modal.modes`); each tracked mode is
    the eigenvalue equal to the diagram's, its eigenvector normalised by :func:`frbmodel.linear.modeshape.normalise`.

    Parameters
    ----------
    cd : CampbellResult
        With the system in ``cd.meta`` (from :func:`frbmodel.linear.campbell`).
    shown : (n, m) bool ndarray, optional
        Points that need a text (default: every present mode).

    Returns
    -------
    (n, m) ndarray of str or None
        ``"<br>"``-separated lines (``""`` where a mode is absent or not shown); None without a system.
    """
    if "system" not in (cd.meta or {}):
        return None

    system = system_from_meta(cd.meta)
    opts = cd.meta.get("method_options", {})
    shown = np.isfinite(cd.eigenvalues) if shown is None else shown & np.isfinite(cd.eigenvalues)
    out = np.full(cd.eigenvalues.shape, "", dtype=object)
    for i in np.flatnonzero(shown.any(axis=1)):
        ls = linear_system(system, cd.method, float(cd.speeds_rpm[i]), **opts)
        md = modes(ls.M, ls.C, ls.K)
        items = _shape_items(system, ls.ring_dofs)
        for j in np.flatnonzero(shown[i]):
            k = int(np.argmin(np.abs(md.eigenvalues - cd.eigenvalues[i, j])))
            u = normalise(md.shapes[:, k], system.rotor.n_nodes, list(ls.ring_dofs or []))
            lines = []
            for label, ix, iy in items:
                major, _, fwd = ellipse(u[ix], u[iy])
                lines.append(f"{label}: {float(major):.2f} ∠ {np.degrees(np.angle(u[ix])):.0f}° "
                             f"{'fwd' if fwd else 'bwd'}")
            out[i, j] = "<br>".join(lines)
    return out
