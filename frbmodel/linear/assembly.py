"""Bearing coupling matrices (paper eqs. 17–27) and the global linear system (eq. 3 or 8).

The global DoF vector is the rotor's ``[v, w, θx, θy]`` per node, followed — for methods with ring
DoFs — by ``[x, y]`` of the turbine-side ring and then of the compressor-side ring.
The linear equation of motion is ``M q̈ + (C_b + Ω G) q̇ + (K + K_b) q = 0``, the rotor's part from
:meth:`frbmodel.system.rotor.Rotor.eom_matrices`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ParameterError, check_real, check_system
from ..core.units import rpm_to_rad_s
from ..physics.film import film_coefficients
from ..system.methods import get_method
from .equilibrium import bearing_equilibrium


@dataclass
class LinearSystem:
    """Matrices of the linearized system at one speed.

    Attributes
    ----------
    M, C, K : ndarray
        Mass [kg...], velocity (bearing damping + Ω G) [N s/m...] and stiffness [N/m...] matrices.
    dof_labels : list of str
    method : str
    speed_rpm : float
    equilibrium : tuple of BearingEquilibrium or None
    ring_dofs : list of (int, int) or None
        Global indices of (x, y) of each ring.
    n_rotor_dof : int
        Number of rotor DoFs (they come first).

    Examples
    --------
    >>> import frbmodel as frb
    >>> ls = frb.linear_system(frb.turbocharger(), "A", 0.0)
    >>> ls.dof_labels[:4], ls.n_rotor_dof
    (['node0.v', 'node0.w', 'node0.thx', 'node0.thy'], 16)
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    dof_labels: list
    method: str
    speed_rpm: float
    equilibrium: tuple | None
    ring_dofs: list | None
    n_rotor_dof: int

    def planes(self):
        """DoF indices of the two bending planes, for the complex-coordinate solve.

        Returns
        -------
        a, b : ndarray of int
            The x–z plane ``a`` = (v, θy, ring x) and the matching y–z plane ``b`` = (w, θx, ring y).
        sign : ndarray
            Maps b to (w, −θx, ring y), so that the complex coordinate ``a + i·sign·b`` is (v + i w, θy − i θx,
            x + i y).
        """
        nn = self.n_rotor_dof // 4
        a = [4 * i + k for i in range(nn) for k in (0, 3)]
        b = [4 * i + k for i in range(nn) for k in (1, 2)]
        sign = [1.0, -1.0] * nn
        for rx, ry in self.ring_dofs or []:
            a.append(rx)
            b.append(ry)
            sign.append(1.0)
        return np.array(a), np.array(b), np.array(sign)


def film_pair_matrix(k_inner, k_outer):
    """Journal/ring coupling of two films (paper eq. 27).

    Parameters
    ----------
    k_inner, k_outer : ndarray (2, 2)
        Inner and outer film matrix (stiffness [N/m] or damping [N s/m]).

    Returns
    -------
    ndarray (4, 4)
        [[K_I, −K_I], [−K_I, K_I + K_O]] on [journal x, journal y, ring x, ring y].

    Examples
    --------
    >>> film_pair_matrix(np.eye(2), 2 * np.eye(2))[:, 0] + 0.0     # + 0.0: print -0.0 as 0.0
    array([ 1.,  0., -1.,  0.])
    """
    return np.block([[k_inner, -k_inner], [-k_inner, k_inner + k_outer]])


def series_elementwise(a, b):
    """Element-wise series combination 1/x = 1/a + 1/b (method D, as written in the paper).

    Where one entry is 0 the series value is 0; where a + b = 0 with a·b ≠ 0 the result is infinite —
    the artefact docs/theory/parameters.md#interpretation-choices item 7 warns about; it is reported as an error.

    Parameters
    ----------
    a, b : ndarray
        Equal-shape coefficient matrices.

    Returns
    -------
    ndarray
        a b / (a + b) element-wise (0 where a b = 0).

    Examples
    --------
    >>> series_elementwise(np.array([2.0, 0.0]), np.array([2.0, 5.0])).tolist()
    [1.0, 0.0]
    """
    num = a * b
    den = a + b
    out = np.zeros_like(num)
    nz = num != 0.0
    if np.any(nz & (den == 0.0)):
        raise ParameterError("method D series combination is singular: an inner and an outer film coefficient "
                             "are equal and opposite (k_I + k_O = 0)")
    out[nz] = num[nz] / den[nz]
    return out


def bearing_matrices(bearing, eq, method, film_model="short", **kw):
    """Stiffness and damping of one bearing for ``method``.

    Parameters
    ----------
    bearing : FloatingRingBearing
    eq : BearingEquilibrium or None
        Its equilibrium (film methods only).
    method : str
        One of A, B, C, D, E, F, G, I, J.
    film_model : {"short", "short_corrected"}
    **kw
        Spring stiffnesses of methods A, B, E: ``k``, ``kx``, ``ky`` [N/m].

    Returns
    -------
    K, C : ndarray
        [N/m], [N s/m]: 2 x 2 on the journal for methods without ring DoFs, 4 x 4 on
        ``[journal x, journal y, ring x, ring y]`` for methods with ring DoFs.

    Examples
    --------
    >>> import frbmodel as frb
    >>> K, C = bearing_matrices(frb.turbocharger().bearings[0], None, "B")
    >>> K.tolist(), bool(C.any())
    ([[1000000.0, 0.0], [0.0, 2000000.0]], False)
    """
    m = get_method(method)
    opt = m.options(**kw)
    s = m.support
    if s == "isotropic_spring":
        return opt["k"] * np.eye(2), np.zeros((2, 2))
    if s == "orthotropic_spring":
        return np.diag([opt["kx"], opt["ky"]]), np.zeros((2, 2))
    if s == "ring_springs":
        k = opt["k"] * np.eye(2)
        return film_pair_matrix(k, k), np.zeros((4, 4))
    k_o, c_o = film_coefficients(bearing.outer, eq.ring, eq.omega_outer, film_model)
    if s == "outer_film":
        return k_o, c_o
    k_i, c_i = film_coefficients(bearing.inner, eq.r_inner, eq.omega_inner, film_model)
    if s == "series_films":
        return series_elementwise(k_i, k_o), series_elementwise(c_i, c_o)
    if s == "films":
        return film_pair_matrix(k_i, k_o), film_pair_matrix(c_i, c_o)
    raise AssertionError(s)


def mass_matrix(system, method="J"):
    """Global mass matrix of the linear system of ``method`` (speed-independent).

    Parameters
    ----------
    system : Turbocharger
    method : str
        One of A, B, C, D, E, F, G, I, J.

    Returns
    -------
    M : ndarray
        Rotor mass matrix, then ring masses [kg] on the rings' (x, y) DoFs for methods with ring DoFs, or lumped
        onto the journal for the methods whose ring moves with the journal (D, C: outer film / series films).
    ring_dofs : list of (int, int) or None
        Global indices of (x, y) of each ring (None without ring DoFs).

    Examples
    --------
    >>> import frbmodel as frb
    >>> M, ring_dofs = mass_matrix(frb.turbocharger(), "J")
    >>> M.shape, ring_dofs
    ((20, 20), [(16, 17), (18, 19)])
    """
    m = get_method(method)
    rotor = system.rotor
    n_r = rotor.n_dof
    n = n_r + (4 if m.ring_dofs else 0)
    M = np.zeros((n, n))
    M[:n_r, :n_r] = rotor.M
    ring_dofs = [] if m.ring_dofs else None
    for i, b in enumerate(system.bearings):
        if m.ring_dofs:
            rr = n_r + 2 * i
            ring_dofs.append((rr, rr + 1))
            M[rr, rr] = M[rr + 1, rr + 1] = b.ring_mass
        elif m.support in ("outer_film", "series_films"):  # ring moves with the journal: lump its mass
            j = 4 * b.node
            M[j, j] += b.ring_mass
            M[j + 1, j + 1] += b.ring_mass
    return M, ring_dofs


def _check_speed(m, speed_rpm):
    """``speed_rpm`` as a float, checked by the method (:meth:`frbmodel.system.methods.Method.check_speeds`)."""
    return float(m.check_speeds(check_real("speed_rpm", speed_rpm, "rpm"), "speed_rpm")[0])


def linear_system(system, method="J", speed_rpm=150e3, equilibria=None, **kw) -> LinearSystem:
    """Assemble the global linear system of ``system`` for ``method`` at ``speed_rpm``.

    Parameters
    ----------
    system : Turbocharger
    method : str
        One of A, B, C, D, E, F, G, I, J.
    speed_rpm : float
        Rotor speed [rpm]; > 0 for the film methods (C, D, F, G, I, J).
    equilibria : tuple of BearingEquilibrium, optional
        Reuse already-solved equilibria (else they are solved here).
    **kw
        Spring stiffnesses of methods A, B, E: ``k``, ``kx``, ``ky`` [N/m].

    Returns
    -------
    LinearSystem
        M [kg ...], C = C_b + Ω G [N s/m ...] and K = K_rotor + K_b [N/m ...] on the rotor DoFs followed by the
        rings' (x, y) for methods with ring DoFs.

    Raises
    ------
    ParameterError
        Not a system, an unknown method or option, a speed that is not a finite real number (> 0 for the film
        methods), or ``equilibria`` of the wrong length.

    Examples
    --------
    >>> import frbmodel as frb
    >>> ls = frb.linear_system(frb.turbocharger(), "J", 100e3)
    >>> ls.M.shape
    (20, 20)
    """
    check_system(system)
    m = get_method(method)
    speed_rpm = _check_speed(m, speed_rpm)
    if m.needs_films and equilibria is not None and len(equilibria) != len(system.bearings):
        raise ParameterError(f"equilibria has {len(equilibria)} entries; expected one BearingEquilibrium per bearing "
                             f"({len(system.bearings)})")
    rotor = system.rotor
    n_r = rotor.n_dof
    omega = rpm_to_rad_s(speed_rpm)
    M, ring_dofs = mass_matrix(system, m.letter)
    C = np.zeros_like(M)
    K = np.zeros_like(M)
    _, C[:n_r, :n_r], K[:n_r, :n_r] = rotor.eom_matrices(omega)
    labels = [f"node{i}.{d}" for i in range(rotor.n_nodes) for d in ("v", "w", "thx", "thy")]
    if m.needs_films and equilibria is None:
        loads = system.bearing_loads
        equilibria = tuple(bearing_equilibrium(b, loads[i], omega, m.letter, system.film_model, system.gravity)
                           for i, b in enumerate(system.bearings))
    for i, b in enumerate(system.bearings):
        eq = equilibria[i] if m.needs_films else None
        kb, cb = bearing_matrices(b, eq, m.letter, system.film_model, **kw)
        j = 4 * b.node
        idx = [j, j + 1]
        if m.ring_dofs:
            idx += list(ring_dofs[i])
            labels += [f"ring_{b.name}.x", f"ring_{b.name}.y"]
        K[np.ix_(idx, idx)] += kb
        C[np.ix_(idx, idx)] += cb
    return LinearSystem(M, C, K, labels, m.letter, speed_rpm, equilibria, ring_dofs, n_r)
