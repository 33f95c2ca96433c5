"""Modal analysis: state space, eigenvalues, modal damping, precession, ring-mode classification, tracking.

Conventions (physics.md §9): λ = α + iβ with β > 0 kept; modal damping D = −α/|λ|; precession indicator
Ψ_j = Im(v̄_j · conj(w̄_j)) per node (> 0 forward, < 0 backward for CCW rotation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

#: eigenvalues with |Im λ| / |λ| below this are treated as over-damped (real) and left out
REAL_TOL = 1e-7
#: nodes whose amplitude² is below this fraction of the largest one carry no precession vote
NODE_AMP_TOL = 1e-4
#: |Ψ_j| / amplitude² below this is "planar" at that node and carries no vote
PSI_TOL = 1e-3


def state_matrix(M, C, K):
    """A = [[0, I], [−M⁻¹K, −M⁻¹C]] for ``M q̈ + C q̇ + K q = 0``."""
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -Minv @ K
    A[n:, n:] = -Minv @ C
    return A


@dataclass
class Modes:
    """Under-damped modes of one linear system, sorted by frequency.

    Attributes
    ----------
    eigenvalues : complex ndarray (m,)
        λ with Im λ > 0 [1/s].
    shapes : complex ndarray (n_dof, m)
        Displacement part of the eigenvectors, unit norm.
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray

    @property
    def frequencies_hz(self):
        return self.eigenvalues.imag / (2.0 * np.pi)

    @property
    def damping(self):
        """Modal damping D = −Re λ / |λ| [-]."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


def modes_from_state(A, n_dof):
    """Eigen-decomposition of a state matrix whose first ``n_dof`` states are displacements."""
    lam, vec = sla.eig(A, check_finite=True)
    keep = lam.imag > REAL_TOL * np.abs(lam)
    lam, vec = lam[keep], vec[:n_dof, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    norms = np.linalg.norm(vec, axis=0)
    norms[norms == 0.0] = 1.0
    return Modes(lam, vec / norms)


def modes(M, C, K) -> Modes:
    """Under-damped modes of ``M q̈ + C q̇ + K q = 0``."""
    return modes_from_state(state_matrix(M, C, K), M.shape[0])


def precession_index(shapes, v_idx, w_idx):
    """Ψ per node and mode: 2 Im(v̄ conj(w̄)) / (|v̄|² + |w̄|²) ∈ [−1, 1] (+1: circular forward).

    ``shapes`` (n_dof, m); ``v_idx``, ``w_idx`` the DoF indices of x and y displacement per node.
    Returns ``(psi, amp2)`` each (n_nodes, m).
    """
    v = shapes[np.asarray(v_idx)]
    w = shapes[np.asarray(w_idx)]
    amp2 = np.abs(v) ** 2 + np.abs(w) ** 2
    psi = 2.0 * np.imag(v * np.conj(w))
    with np.errstate(invalid="ignore", divide="ignore"):
        psi_n = np.where(amp2 > 0, psi / np.where(amp2 > 0, amp2, 1.0), 0.0)
    return psi_n, amp2


def classify_precession(psi, amp2):
    """'forward', 'backward' or 'mixed' per mode from per-node Ψ (physics.md §9).

    Nodes with negligible amplitude or a planar orbit do not vote. A mode whose voting nodes all have
    Ψ > 0 is forward, all Ψ < 0 backward, otherwise mixed (the paper's "combined precession").
    """
    out = []
    amax = amp2.max(axis=0)
    for j in range(psi.shape[1]):
        vote = (amp2[:, j] > NODE_AMP_TOL * amax[j]) & (np.abs(psi[:, j]) > PSI_TOL)
        p = psi[vote, j]
        if p.size == 0:
            out.append("mixed")
        elif np.all(p > 0):
            out.append("forward")
        elif np.all(p < 0):
            out.append("backward")
        else:
            out.append("mixed")
    return np.array(out, dtype=object)


def ring_energy_fraction(shapes, M, ring_dofs):
    """Share of the modal kinetic energy u^H M u carried by the ring DoFs, per mode (m,)."""
    if not ring_dofs:
        return np.zeros(shapes.shape[1])
    total = np.real(np.einsum("im,ij,jm->m", np.conj(shapes), M, shapes))
    idx = np.array(ring_dofs).ravel()
    ring = np.real(np.einsum("im,ij,jm->m", np.conj(shapes[idx]), M[np.ix_(idx, idx)], shapes[idx]))
    return ring / total


def mac(a, b):
    """Modal assurance criterion matrix |a^H b|² / ((a^H a)(b^H b)) between columns of a and b."""
    num = np.abs(np.conj(a).T @ b) ** 2
    den = np.outer(np.real(np.sum(np.conj(a) * a, axis=0)), np.real(np.sum(np.conj(b) * b, axis=0)))
    return num / den


def track(eigenvalue_list, shape_list, w_lambda=0.3):
    """Order modes consistently across a speed sweep (physics.md §9 tracking).

    Each step's modes are assigned to the tracks of the previous steps by minimising
    ``1 − MAC + w_λ |Δλ| / |λ|`` (Hungarian assignment); unmatched modes open new tracks.

    Returns ``perm``: list of index arrays, ``perm[k][t]`` = mode index at step k for track t (−1 = none),
    all of equal length (the number of tracks).
    """
    from scipy.optimize import linear_sum_assignment

    n_steps = len(eigenvalue_list)
    tracks_last_shape = []
    tracks_last_lam = []
    assignment = []
    for k in range(n_steps):
        lam, sh = eigenvalue_list[k], shape_list[k]
        cur = -np.ones(len(tracks_last_lam), dtype=int)
        used = np.zeros(lam.size, dtype=bool)
        if tracks_last_lam and lam.size:
            prev_sh = np.column_stack(tracks_last_shape)
            prev_lam = np.array(tracks_last_lam)
            cost = 1.0 - mac(prev_sh, sh) + w_lambda * np.abs(prev_lam[:, None] - lam[None, :]) / np.abs(
                prev_lam)[:, None]
            r, c = linear_sum_assignment(cost)
            for ri, ci in zip(r, c):
                if cost[ri, ci] < 1.5:  # a poor match rather opens a new track
                    cur[ri] = ci
                    used[ci] = True
                    tracks_last_shape[ri] = sh[:, ci]
                    tracks_last_lam[ri] = lam[ci]
        new = np.flatnonzero(~used)
        for ci in new:
            tracks_last_shape.append(sh[:, ci])
            tracks_last_lam.append(lam[ci])
        cur = np.concatenate([cur, new])
        assignment.append(cur)
    n_tracks = len(tracks_last_lam)
    return [np.concatenate([a, -np.ones(n_tracks - a.size, dtype=int)]) for a in assignment]
