"""Euler–Bernoulli finite-element rotor with rotary inertia, gyroscopics and rigid discs
(docs/theory/equations-of-motion.md#equations-of-motion).

Node DoFs are ``[v, w, θx, θy]`` (x-displacement, y-displacement, rotation about x, rotation about y), with
θx = −∂w/∂z and θy = +∂v/∂z; x horizontal, y vertical up, z along the shaft, rotation CCW about +z.
The equation of motion (docs/theory/equations-of-motion.md#rotor, no rotor damping) is

    M q̈ + Ω G q̇ + (K + Ω̇ G) q = f,

with ``G`` the gyroscopic matrix per rad/s. :meth:`Rotor.eom_matrices` gives its three matrices at a speed,
:meth:`Rotor.acceleration_matrices` the precomputed M⁻¹, M⁻¹K, M⁻¹G of the compiled acceleration kernel
(:func:`frbmodel.physics.dynamics.rotor_acceleration`) and :meth:`Rotor.state_matrix` the first-order form
(:func:`first_order_state_matrix`). These are the only places the rotor's equation of motion is written.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from functools import cached_property

import numpy as np

from ..core.errors import ParameterError, check_real

DOF_PER_NODE = 4
GRAVITY = 9.81  # [m/s²], docs/theory/conventions.md#conventions


def first_order_state_matrix(minv_k, minv_c):
    """State matrix of ``M q̈ + C q̇ + K q = f`` in the state s = [q; q̇] (docs/theory/modal.md#modal-analysis).

    Parameters
    ----------
    minv_k, minv_c : ndarray (..., n, n)
        M⁻¹K and M⁻¹C; leading dimensions (stacks, e.g. one per speed) broadcast.

    Returns
    -------
    ndarray (..., 2n, 2n)
        A = [[0, I], [−M⁻¹K, −M⁻¹C]], so that ṡ = A s + [0; M⁻¹ f].

    Examples
    --------
    >>> first_order_state_matrix(np.array([[4.0]]), np.array([[0.5]]))
    array([[ 0. ,  1. ],
           [-4. , -0.5]])
    """
    minv_k, minv_c = np.asarray(minv_k, dtype=float), np.asarray(minv_c, dtype=float)
    n = minv_k.shape[-1]
    A = np.zeros(np.broadcast_shapes(minv_k.shape[:-2], minv_c.shape[:-2]) + (2 * n, 2 * n))
    A[..., :n, n:] = np.eye(n)
    A[..., n:, :n] = -minv_k
    A[..., n:, n:] = -minv_c
    return A


@dataclass(frozen=True)
class ShaftElement:
    """A uniform circular (optionally hollow) Euler–Bernoulli shaft element.

    Parameters
    ----------
    length : float
        Element length [m].
    outer_diameter : float
        Outer diameter [m].
    inner_diameter : float
        Bore diameter [m] (0 for a solid shaft).
    density : float
        Material density [kg/m³].
    youngs_modulus : float
        Young's modulus [Pa].

    Raises
    ------
    ParameterError
        A value that is not a finite real number in its range (strings are refused, not converted).

    Examples
    --------
    >>> e = ShaftElement(0.033, 0.011)
    >>> round(e.mass * 1e3, 2)      # [g]: 7860 kg/m³ · π/4 · (11 mm)² · 33 mm
    24.65
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0
    density: float = 7860.0
    youngs_modulus: float = 2.0e11

    def __post_init__(self):
        for name, unit in (("length", "m"), ("outer_diameter", "m"), ("density", "kg/m^3"),
                           ("youngs_modulus", "Pa")):
            object.__setattr__(self, name, check_real(f"shaft element {name}", getattr(self, name), unit, minimum=0.0))
        di = check_real("shaft element inner_diameter", self.inner_diameter, "m", minimum=0.0, inclusive=True)
        if di >= self.outer_diameter:
            raise ParameterError(f"shaft element inner_diameter = {di:g} m is invalid: valid range "
                                 f"0 <= inner_diameter < outer_diameter = {self.outer_diameter:g} m")
        object.__setattr__(self, "inner_diameter", di)

    @property
    def area(self) -> float:
        """Cross-section area [m²]."""
        return math.pi / 4.0 * (self.outer_diameter ** 2 - self.inner_diameter ** 2)

    @property
    def second_moment(self) -> float:
        """Diametral second moment of area I [m⁴] (polar = 2 I)."""
        return math.pi / 64.0 * (self.outer_diameter ** 4 - self.inner_diameter ** 4)

    @property
    def mass(self) -> float:
        """[kg]"""
        return self.density * self.area * self.length

    def matrices(self):
        """Element matrices of the Euler–Bernoulli element with rotary inertia
        (docs/theory/equations-of-motion.md#equations-of-motion).

        Returns
        -------
        M, K, G : ndarray (8, 8)
            Mass, stiffness and gyroscopic matrix (per rad/s) in DoF order [v1, w1, θx1, θy1, v2, w2, θx2, θy2].

        Examples
        --------
        >>> M, K, G = ShaftElement(0.1, 0.01).matrices()
        >>> bool(np.allclose(G, -G.T)), bool(np.allclose(K, K.T))
        (True, True)
        """
        l, E, rho = self.length, self.youngs_modulus, self.density
        A, I = self.area, self.second_moment
        kb = E * I / l ** 3 * np.array([[12, 6 * l, -12, 6 * l],
                                        [6 * l, 4 * l * l, -6 * l, 2 * l * l],
                                        [-12, -6 * l, 12, -6 * l],
                                        [6 * l, 2 * l * l, -6 * l, 4 * l * l]])
        mt = rho * A * l / 420.0 * np.array([[156, 22 * l, 54, -13 * l],
                                             [22 * l, 4 * l * l, 13 * l, -3 * l * l],
                                             [54, 13 * l, 156, -22 * l],
                                             [-13 * l, -3 * l * l, -22 * l, 4 * l * l]])
        mr = rho * I / (30.0 * l) * np.array([[36, 3 * l, -36, 3 * l],
                                              [3 * l, 4 * l * l, -3 * l, -l * l],
                                              [-36, -3 * l, 36, -3 * l],
                                              [3 * l, -l * l, -3 * l, 4 * l * l]])
        mb = mt + mr
        M = np.zeros((8, 8))
        K = np.zeros((8, 8))
        xz = [0, 3, 4, 7]  # v1, θy1, v2, θy2
        yz = [1, 2, 5, 6]  # w1, θx1, w2, θx2 (θx = −w')
        T = np.diag([1.0, -1.0, 1.0, -1.0])
        M[np.ix_(xz, xz)] = mb
        K[np.ix_(xz, xz)] = kb
        M[np.ix_(yz, yz)] = T @ mb @ T
        K[np.ix_(yz, yz)] = T @ kb @ T
        g = np.array([[0, 36, -3 * l, 0, 0, -36, -3 * l, 0],
                      [-36, 0, 0, -3 * l, 36, 0, 0, -3 * l],
                      [3 * l, 0, 0, 4 * l * l, -3 * l, 0, 0, -l * l],
                      [0, 3 * l, -4 * l * l, 0, 0, -3 * l, l * l, 0],
                      [0, -36, 3 * l, 0, 0, 36, 3 * l, 0],
                      [36, 0, 0, 3 * l, -36, 0, 0, 3 * l],
                      [3 * l, 0, 0, -l * l, -3 * l, 0, 0, 4 * l * l],
                      [0, 3 * l, l * l, 0, 0, -3 * l, -4 * l * l, 0]], dtype=float)
        G = rho * (2.0 * I) / (30.0 * l) * g
        return M, K, G

    def to_dict(self) -> dict:
        """The element as plain data [SI]."""
        return asdict(self)


@dataclass(frozen=True)
class Disc:
    """A rigid disc (wheel) at a node.

    Parameters
    ----------
    node : int
        Node index (0-based).
    mass : float
        [kg]
    polar_inertia : float
        I_p [kg m²]
    diametral_inertia : float
        I_d [kg m²]
    name : str
        e.g. ``"turbine_wheel"``.

    Raises
    ------
    ParameterError
        A mass or inertia that is not a finite real number in its range, a diametral inertia below half the polar
        one (impossible for a rigid body of revolution), or a node that is not an integer >= 0.

    Examples
    --------
    >>> Disc(0, 0.326, 8.1e-5, 7.7e-5, "turbine_wheel").mass
    0.326
    """

    node: int
    mass: float
    polar_inertia: float
    diametral_inertia: float
    name: str = "disc"

    def __post_init__(self):
        object.__setattr__(self, "mass", check_real(f"disc '{self.name}' mass", self.mass, "kg", minimum=0.0))
        object.__setattr__(self, "polar_inertia", check_real(
            f"disc '{self.name}' polar_inertia", self.polar_inertia, "kg m^2", minimum=0.0, inclusive=True))
        object.__setattr__(self, "diametral_inertia", check_real(
            f"disc '{self.name}' diametral_inertia", self.diametral_inertia, "kg m^2", minimum=0.0, inclusive=True))
        if isinstance(self.node, (bool, str)) or not isinstance(self.node, (int, np.integer, float)) \
                or int(self.node) != self.node or self.node < 0:
            raise ParameterError(f"disc '{self.name}' node = {self.node!r} is invalid: must be an integer >= 0")
        object.__setattr__(self, "node", int(self.node))
        # the principal moments of any rigid body obey I_a + I_b >= I_c; an axisymmetric one has I_a = I_b = I_d,
        # so 2 I_d >= I_p (equal for a flat disc); 1e-9 relative for inertias rounded in a data sheet
        if 2.0 * self.diametral_inertia < self.polar_inertia * (1.0 - 1e-9):
            raise ParameterError(
                f"disc '{self.name}' diametral_inertia = {self.diametral_inertia!r} kg m^2 is invalid with "
                f"polar_inertia = {self.polar_inertia!r} kg m^2: no rigid body of revolution has I_d < I_p / 2; "
                f"valid range >= {self.polar_inertia / 2:g} kg m^2 (were the two inertias swapped, or I_p given "
                "about another axis?)")

    def to_dict(self) -> dict:
        """The disc as plain data [SI]."""
        return asdict(self)


def check_names(what, names):
    """Raise :class:`ParameterError` unless ``names`` are distinct non-empty strings: unbalances, result columns
    and FMU variables are named by them (a repeated name made the FMU's variable names collide)."""
    for n in names:
        if not isinstance(n, str) or not n.strip():
            raise ParameterError(f"{what} name = {n!r} is invalid: give each {what} a non-empty name")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ParameterError(f"{what} names = {list(names)} are invalid: {', '.join(map(repr, repeated))} is used "
                             f"more than once; each {what} needs its own name (unbalances, results and FMU variables "
                             "are named by it)")


@dataclass(frozen=True)
class Rotor:
    """Shaft elements in series (node i to node i+1) plus rigid discs.

    Attributes ``M``, ``K``, ``G`` are the assembled global matrices (``4 * n_nodes`` square).

    Parameters
    ----------
    shaft : sequence of ShaftElement
        At least one element; element i joins node i and node i+1.
    discs : sequence of Disc
        Rigid discs at nodes 0 .. n_nodes − 1.

    Raises
    ------
    ParameterError
        No shaft element, an item that is not a ShaftElement / Disc, or a disc on a node the shaft lacks.

    Examples
    --------
    >>> r = Rotor([ShaftElement(0.1, 0.01)], [Disc(1, 1.0, 1e-3, 5e-4)])
    >>> r.M.shape
    (8, 8)
    """

    shaft: tuple
    discs: tuple = field(default_factory=tuple)

    def __post_init__(self):
        object.__setattr__(self, "shaft", tuple(self.shaft))
        object.__setattr__(self, "discs", tuple(self.discs))
        if len(self.shaft) < 1:
            raise ParameterError("rotor needs at least 1 shaft element; got 0")
        for what, items, cls in (("shaft", self.shaft, ShaftElement), ("discs", self.discs, Disc)):
            for i, item in enumerate(items):
                if not isinstance(item, cls):
                    raise ParameterError(f"rotor {what}[{i}] = {item!r:.60} is a {type(item).__name__}; expected a "
                                         f"{cls.__name__}")
        for d in self.discs:
            if d.node >= self.n_nodes:
                raise ParameterError(f"disc '{d.name}' node = {d.node} is invalid: valid range 0..{self.n_nodes - 1}")
        check_names("disc", [d.name for d in self.discs])

    @property
    def n_nodes(self) -> int:
        """Number of nodes (shaft elements + 1)."""
        return len(self.shaft) + 1

    @property
    def n_dof(self) -> int:
        """Number of DoFs, 4 per node."""
        return DOF_PER_NODE * self.n_nodes

    @cached_property
    def node_z(self) -> np.ndarray:
        """Axial node positions [m] (node 0 at z = 0)."""
        return np.concatenate([[0.0], np.cumsum([e.length for e in self.shaft])])

    @property
    def mass(self) -> float:
        """Total rotor mass [kg]."""
        return sum(e.mass for e in self.shaft) + sum(d.mass for d in self.discs)

    def disc(self, name: str) -> Disc:
        """The disc called ``name``.

        Parameters
        ----------
        name : str

        Returns
        -------
        Disc

        Raises
        ------
        ParameterError
            No disc of that name (the message lists the discs).
        """
        for d in self.discs:
            if d.name == name:
                return d
        raise ParameterError(f"disc name = {name!r} is unknown; rotor discs are {[d.name for d in self.discs]}")

    def check_unbalance(self, name, amount_kg_m, what=None):
        """``(disc, m e)`` of an unbalance of ``amount_kg_m`` [kg m] on the disc called ``name``, or a
        :class:`ParameterError` naming it, its value and the valid range 0 ... sqrt(m I_p) of the disc.

        The bound is the disc's own: its unbalance mass m_u at radius e_u is part of the disc, so m_u <= m and
        m_u e_u² <= I_p (the polar moment about the shaft axis holds every mass of the disc), hence
        m_u e_u <= sqrt(m I_p) — an unbalance above it needs more mass farther out than the disc has (10 kg m was
        accepted: 6.9e9 N at 250 krpm on a 0.5 kg rotor). (A bound by the rotor's weight is not one: 1 g mm at 250
        krpm is already 685 N, 134 times the Table 2 rotor's weight.)

        Parameters
        ----------
        name : str
            The disc's name.
        amount_kg_m : float
            m e [kg m], >= 0.
        what : str, optional
            The quantity's name for the message (default ``"unbalance of <name>"``).

        Returns
        -------
        (Disc, float)

        Examples
        --------
        >>> from frbmodel.system.presets import turbocharger
        >>> try:
        ...     turbocharger().rotor.check_unbalance("turbine_wheel", 10.0)
        ... except ParameterError as exc:
        ...     print(exc)  # doctest: +ELLIPSIS
        unbalance of turbine_wheel = 10.0 kg m is invalid: valid range 0 ... 0.00514 kg m = sqrt(m I_p) of the disc ...
        """
        disc = self.disc(name)
        what = what or f"unbalance of {name}"
        amount = check_real(what, amount_kg_m, "kg m", minimum=0.0, inclusive=True)
        top = math.sqrt(disc.mass * disc.polar_inertia)
        if amount > top:
            raise ParameterError(f"{what} = {amount_kg_m!r} kg m is invalid: valid range 0 ... {top:.3g} kg m = "
                                 f"sqrt(m I_p) of the disc ({disc.mass:g} kg, {disc.polar_inertia:g} kg m^2; a larger "
                                 "m e needs more mass farther from the axis than the disc has; 1e-6 kg m = 1 g mm)")
        return disc, amount

    @cached_property
    def _assembled(self):
        n = self.n_dof
        M, K, G = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
        for i, el in enumerate(self.shaft):
            me, ke, ge = el.matrices()
            sl = slice(4 * i, 4 * i + 8)
            M[sl, sl] += me
            K[sl, sl] += ke
            G[sl, sl] += ge
        for d in self.discs:
            j = 4 * d.node
            M[j, j] += d.mass
            M[j + 1, j + 1] += d.mass
            M[j + 2, j + 2] += d.diametral_inertia
            M[j + 3, j + 3] += d.diametral_inertia
            G[j + 2, j + 3] += d.polar_inertia
            G[j + 3, j + 2] -= d.polar_inertia
        for a in (M, K, G):
            a.setflags(write=False)
        return M, K, G

    @property
    def M(self) -> np.ndarray:
        """Mass matrix [kg, kg m, kg m²]."""
        return self._assembled[0]

    @property
    def K(self) -> np.ndarray:
        """Stiffness matrix [N/m, N, N m]."""
        return self._assembled[1]

    @property
    def G(self) -> np.ndarray:
        """Gyroscopic matrix per unit rotor speed (multiply by Ω [rad/s])."""
        return self._assembled[2]

    @cached_property
    def acceleration_matrices(self) -> tuple:
        """``(M⁻¹, M⁻¹K, M⁻¹G)`` (read-only, computed once): the constant matrices of the acceleration
        q̈ = M⁻¹f − (M⁻¹K + Ω̇ M⁻¹G) q − Ω M⁻¹G q̇ (:func:`frbmodel.physics.dynamics.rotor_acceleration`)."""
        minv = np.linalg.inv(self.M)
        out = (minv, minv @ self.K, minv @ self.G)
        for a in out:
            a.setflags(write=False)
        return out

    def eom_matrices(self, omega: float = 0.0, omega_dot: float = 0.0):
        """Matrices of the equation of motion M q̈ + C q̇ + K q = f at one rotor speed
        (docs/theory/equations-of-motion.md#rotor).

        Parameters
        ----------
        omega : float
            Rotor speed Ω [rad/s].
        omega_dot : float
            Rotor acceleration Ω̇ [rad/s²] (the spin-up term of d(I_p Ω θ)/dt).

        Returns
        -------
        M, C, K : ndarray (n_dof, n_dof)
            M; C = Ω G [N s/m ...]; K = K_shaft + Ω̇ G [N/m ...] (new arrays).

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)], [Disc(1, 1.0, 1e-3, 5e-4)])
        >>> M, C, K = r.eom_matrices(omega=100.0)
        >>> bool(np.allclose(C, 100.0 * r.G)), bool(np.array_equal(K, r.K))
        (True, True)
        """
        K = self.K + omega_dot * self.G if omega_dot else self.K.copy()
        return self.M.copy(), omega * self.G, K

    def state_matrix(self, omega: float = 0.0, omega_dot: float = 0.0) -> np.ndarray:
        """First-order state matrix of the free rotor, A = [[0, I], [−M⁻¹(K + Ω̇G), −Ω M⁻¹G]] in the state [q; q̇].

        Parameters
        ----------
        omega : float
            Rotor speed [rad/s].
        omega_dot : float
            Rotor acceleration [rad/s²].

        Returns
        -------
        ndarray (2 n_dof, 2 n_dof)

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)])
        >>> r.state_matrix(1000.0).shape
        (16, 16)
        """
        _, mk, mg = self.acceleration_matrices
        return first_order_state_matrix(mk + omega_dot * mg, omega * mg)

    def gravity_load(self, g: float = GRAVITY) -> np.ndarray:
        """Consistent nodal gravity load f_g = M a_g with a_g = −g on every w DoF.

        Parameters
        ----------
        g : float
            Gravitational acceleration [m/s²] along −y.

        Returns
        -------
        ndarray (n_dof,)
            [N, N m].

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)])
        >>> round(float(r.gravity_load(10.0)[1::4].sum()), 6) == round(-10.0 * r.mass, 6)
        True
        """
        return self.translation_load(0.0, -g)

    def translation_load(self, ax: float, ay: float) -> np.ndarray:
        """Consistent nodal load M T a of a uniform translational acceleration field a = (``ax``, ``ay``): a_x on
        every v DoF, a_y on every w DoF, nothing on the rotations (T holds the rigid translations).

        Gravity is ``translation_load(0, -g)``; a housing that accelerates by a_h loads the rotor, in the housing
        frame, with ``-translation_load(*a_h)`` (docs/theory/housing.md).

        Parameters
        ----------
        ax, ay : float
            Acceleration along x and y [m/s²].

        Returns
        -------
        ndarray (n_dof,)
            [N, N m].

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)])
        >>> f = r.translation_load(2.0, 0.0)
        >>> bool(np.isclose(f[0::4].sum(), 2.0 * r.mass, rtol=1e-12)), float(abs(f[1::4]).max())
        (True, 0.0)
        """
        a = np.zeros(self.n_dof)
        a[0::4] = ax
        a[1::4] = ay
        return self.M @ a

    def static_deflection(self, support_nodes, support_positions=None, g: float = GRAVITY) -> np.ndarray:
        """Static rotor DoFs q [m, rad] under the consistent gravity load with the lateral displacements (v, w)
        of the ``support_nodes`` prescribed.

        Parameters
        ----------
        support_nodes : sequence of int
            Nodes whose (v, w) are held (the journals).
        support_positions : sequence of (float, float), optional
            Prescribed (v, w) [m] per support node; default all zero.
        g : float
            Gravitational acceleration [m/s²] along −y.

        Returns
        -------
        ndarray (n_dof,)
            q, solving K q = f_g on the free DoFs. On two supports the rotor is statically determinate, so
            the support reactions K q − f_g do not depend on the prescribed positions.

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)])
        >>> q = r.static_deflection([0, 1], [(0.0, -1e-6), (0.0, -1e-6)], g=0.0)
        >>> bool(np.allclose(q[1::4], -1e-6)), bool(np.allclose(q[2::4], 0.0))   # weightless: rigid drop
        (True, True)
        """
        f = self.gravity_load(g)
        cons = np.array([4 * n + k for n in support_nodes for k in (0, 1)], dtype=int)
        free = np.setdiff1d(np.arange(self.n_dof), cons)
        q = np.zeros(self.n_dof)
        if support_positions is not None:
            q[cons] = np.asarray(support_positions, dtype=float).ravel()
        q[free] = np.linalg.solve(self.K[np.ix_(free, free)], f[free] - self.K[np.ix_(free, cons)] @ q[cons])
        return q

    def static_reactions(self, support_nodes, g: float = GRAVITY) -> np.ndarray:
        """Vertical support reactions [N] (positive = upward force on the shaft) at ``support_nodes``.

        The rotor on two point supports is statically determinate, so the reactions follow from the
        consistent gravity load with the support deflections held at zero (:meth:`static_deflection`).

        Parameters
        ----------
        support_nodes : sequence of int
            The supported nodes.
        g : float
            Gravitational acceleration [m/s²] along −y.

        Returns
        -------
        ndarray
            One reaction per support [N].

        Examples
        --------
        >>> r = Rotor([ShaftElement(0.1, 0.01)], [Disc(1, 1.0, 1e-3, 5e-4)])
        >>> w = r.static_reactions([0, 1])
        >>> round(float(w.sum()), 6) == round(r.mass * GRAVITY, 6)   # the supports carry the weight
        True
        """
        f = self.gravity_load(g)
        q = self.static_deflection(support_nodes, None, g)
        cons = np.array([4 * n + 1 for n in support_nodes])
        return self.K[cons] @ q - f[cons]

    def to_dict(self) -> dict:
        """The rotor as plain data ``{"shaft": [...], "discs": [...]}`` [SI]."""
        return {"shaft": [e.to_dict() for e in self.shaft], "discs": [d.to_dict() for d in self.discs]}

    @classmethod
    def from_dict(cls, d: dict) -> "Rotor":
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            ``{"shaft": [element dicts], "discs": [disc dicts]}`` [SI].

        Returns
        -------
        Rotor
        """
        return cls([ShaftElement(**e) for e in d["shaft"]], [Disc(**x) for x in d.get("discs", [])])
