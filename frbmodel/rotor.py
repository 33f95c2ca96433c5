"""Euler–Bernoulli finite-element rotor with rotary inertia, gyroscopics and rigid discs (physics.md §7).

Node DoFs are ``[v, w, θx, θy]`` (x-displacement, y-displacement, rotation about x, rotation about y), with
θx = −∂w/∂z and θy = +∂v/∂z; x horizontal, y vertical up, z along the shaft, rotation CCW about +z.
The equation of motion is ``M q̈ + Ω G q̇ + K q = f``; ``G`` is the gyroscopic matrix per rad/s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, asdict
from functools import cached_property

import numpy as np

from .errors import ParameterError, check_positive

DOF_PER_NODE = 4
GRAVITY = 9.81  # [m/s²], physics.md §1


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
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0
    density: float = 7860.0
    youngs_modulus: float = 2.0e11

    def __post_init__(self):
        for name, unit in (("length", "m"), ("outer_diameter", "m"), ("density", "kg/m^3"),
                           ("youngs_modulus", "Pa")):
            object.__setattr__(self, name, check_positive(f"shaft element {name}", getattr(self, name), unit))
        di = check_positive("shaft element inner_diameter", self.inner_diameter, "m", allow_zero=True)
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
        """Element ``(M, K, G)`` (8 x 8) in DoF order [v1, w1, θx1, θy1, v2, w2, θx2, θy2]."""
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
    """

    node: int
    mass: float
    polar_inertia: float
    diametral_inertia: float
    name: str = "disc"

    def __post_init__(self):
        object.__setattr__(self, "mass", check_positive(f"disc '{self.name}' mass", self.mass, "kg"))
        object.__setattr__(self, "polar_inertia", check_positive(
            f"disc '{self.name}' polar_inertia", self.polar_inertia, "kg m^2", allow_zero=True))
        object.__setattr__(self, "diametral_inertia", check_positive(
            f"disc '{self.name}' diametral_inertia", self.diametral_inertia, "kg m^2", allow_zero=True))
        if int(self.node) != self.node or self.node < 0:
            raise ParameterError(f"disc '{self.name}' node = {self.node!r} is invalid: must be an integer >= 0")
        object.__setattr__(self, "node", int(self.node))

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Rotor:
    """Shaft elements in series (node i to node i+1) plus rigid discs.

    Attributes ``M``, ``K``, ``G`` are the assembled global matrices (``4 * n_nodes`` square).

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
        for d in self.discs:
            if d.node >= self.n_nodes:
                raise ParameterError(f"disc '{d.name}' node = {d.node} is invalid: valid range 0..{self.n_nodes - 1}")

    @property
    def n_nodes(self) -> int:
        return len(self.shaft) + 1

    @property
    def n_dof(self) -> int:
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
        for d in self.discs:
            if d.name == name:
                return d
        raise ParameterError(f"disc name = {name!r} is unknown; rotor discs are {[d.name for d in self.discs]}")

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

    def gravity_load(self, g: float = GRAVITY) -> np.ndarray:
        """Consistent nodal gravity load f_g = M a_g [N, N m] with a_g = −g on every w DoF."""
        a = np.zeros(self.n_dof)
        a[1::4] = -g
        return self.M @ a

    def static_reactions(self, support_nodes, g: float = GRAVITY) -> np.ndarray:
        """Vertical support reactions [N] (positive = upward force on the shaft) at ``support_nodes``.

        The rotor on two point supports is statically determinate, so the reactions follow from the
        consistent gravity load with the support deflections held at zero.
        """
        f = self.gravity_load(g)
        yz = np.sort(np.concatenate([np.arange(1, self.n_dof, 4), np.arange(2, self.n_dof, 4)]))
        cons = np.array([4 * n + 1 for n in support_nodes])
        free = np.setdiff1d(yz, cons)
        q = np.zeros(self.n_dof)
        q[free] = np.linalg.solve(self.K[np.ix_(free, free)], f[free])
        return self.K[np.ix_(cons, yz)] @ q[yz] - f[cons]

    def to_dict(self) -> dict:
        return {"shaft": [e.to_dict() for e in self.shaft], "discs": [d.to_dict() for d in self.discs]}

    @classmethod
    def from_dict(cls, d: dict) -> "Rotor":
        return cls([ShaftElement(**e) for e in d["shaft"]], [Disc(**x) for x in d.get("discs", [])])
