"""Modal analysis: state space, eigenvalues, modal damping, precession, ring-mode classification, tracking.

Conventions (physics.md §9): λ = α + iβ with β > 0 kept; modal damping D = −α/|λ|; precession indicator
Ψ_j = Im(v̄_j · conj(w̄_j)) per node (> 0 forward, < 0 backward for CCW rotation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .rotor import first_order_state_matrix

#: eigenvalues with |Im λ| / |λ| below this are treated as over-damped (real) and left out
REAL_TOL = 1e-7
#: nodes whose amplitude² is below this fraction of the largest one carry no precession vote
NODE_AMP_TOL = 1e-4
#: |Ψ_j| / amplitude² below this is "planar" at that node and carries no vote
PSI_TOL = 1e-3


def state_matrix(M, C, K):
    """A = [[0, I], [−M⁻¹K, −M⁻¹C]] for ``M q̈ + C q̇ + K q = 0`` (:func:`frbmodel.rotor.first_order_state_matrix`).

    Examples
    --------
    >>> state_matrix(np.array([[2.0]]), np.array([[1.0]]), np.array([[8.0]]))
    array([[ 0. ,  1. ],
           [-4. , -0.5]])
    """
    Minv = np.linalg.inv(M)
    return first_order_state_matrix(Minv @ K, Minv @ C)


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
    return _select(lam, vec, n_dof)


def modes(M, C, K) -> Modes:
    """Under-damped modes of ``M q̈ + C q̇ + K q = 0``."""
    return modes_from_state(state_matrix(M, C, K), M.shape[0])


def _select(lam, vec, n_dof):
    keep = lam.imag > REAL_TOL * np.abs(lam)
    lam, vec = lam[keep], vec[:n_dof, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    norms = np.linalg.norm(vec, axis=0)
    norms[norms == 0.0] = 1.0
    return Modes(lam, vec / norms)


def isotropic_complex_form(M, C, K, a, b, sign, tol=1e-12):
    """Complex-coordinate matrices ``(Mc, Gc, Kc)`` of an undamped isotropic gyroscopic system, or None.

    For an axisymmetric rotor on isotropic, undamped supports the real equations split into two identical
    planes ``a`` and ``b`` coupled only by the gyroscopic matrix, and z = a + i·sign·b obeys
    ``Mc z̈ − i Gc ż + Kc z = 0`` with real symmetric ``Mc, Gc, Kc`` of half the size (the classical complex
    coordinates of rotordynamics). Returns None when the system is not of that form.
    """
    S = sign
    Maa, Kaa = M[np.ix_(a, a)], K[np.ix_(a, a)]
    Mbb, Kbb = S[:, None] * M[np.ix_(b, b)] * S[None, :], S[:, None] * K[np.ix_(b, b)] * S[None, :]
    Gab = C[np.ix_(a, b)] * S[None, :]
    Gba = S[:, None] * C[np.ix_(b, a)]
    scale_m, scale_k = np.abs(Maa).max(), np.abs(Kaa).max()
    scale_g = max(np.abs(Gab).max(), 1e-300)
    ok = (np.abs(Maa - Mbb).max() <= tol * scale_m and np.abs(Kaa - Kbb).max() <= tol * scale_k
          and np.abs(M[np.ix_(a, b)]).max() <= tol * scale_m and np.abs(K[np.ix_(a, b)]).max() <= tol * scale_k
          and np.abs(C[np.ix_(a, a)]).max() <= tol * scale_g and np.abs(C[np.ix_(b, b)]).max() <= tol * scale_g
          and np.abs(Gab + Gba).max() <= tol * scale_g and np.abs(Gab - Gab.T).max() <= tol * scale_g)
    return (Maa, Gab, Kaa) if ok else None


def batch_modes(systems):
    """Under-damped modes of a list of linear systems (objects with ``M``, ``C``, ``K``): the
    eigen-decompositions of all of them in one stacked LAPACK call on the state matrices."""
    if not systems:
        return []
    n = systems[0].M.shape[0]
    Minv = np.linalg.inv(systems[0].M)
    mk, mc = np.empty((len(systems), n, n)), np.empty((len(systems), n, n))
    for k, s in enumerate(systems):
        if s.M is not systems[0].M and not np.array_equal(s.M, systems[0].M):
            Minv = np.linalg.inv(s.M)
        mk[k], mc[k] = Minv @ s.K, Minv @ s.C
    lam, vec = np.linalg.eig(first_order_state_matrix(mk, mc))
    return [_select(lam[k], vec[k], n) for k in range(len(systems))]


def speed_modes(M, K, C0, G, omegas, planes=None):
    """Modes of ``M q̈ + (C0 + Ω G) q̇ + K q = 0`` at all speeds ``omegas`` [rad/s] (M, K, C0 constant).

    If the system is undamped and isotropic (methods A and E: axisymmetric rotor on isotropic springs) it is
    solved in complex coordinates z = a + i·sign·b (``planes = (a, b, sign)``) as a Hermitian-definite
    problem of half the size: exact, and the sign of each frequency is its precession. Otherwise the state
    matrices A0 + Ω A1 of all speeds go to one stacked eigen-decomposition.
    """
    omegas = np.asarray(omegas, dtype=float)
    n = M.shape[0]
    if planes is not None and not np.any(C0):
        a, b, sign = planes
        form = isotropic_complex_form(M, G, K, a, b, sign)
        if form is not None:
            try:
                return _isotropic_modes(form, omegas, n, a, b, sign)
            except np.linalg.LinAlgError:  # K not positive definite (free rotor): general path below
                pass
    Minv = np.linalg.inv(M)
    A = first_order_state_matrix(Minv @ K, Minv @ C0 + omegas[:, None, None] * (Minv @ G))
    lam, vec = np.linalg.eig(A)
    return [_select(lam[k], vec[k], n) for k in range(omegas.size)]


def _isotropic_modes(form, omegas, n_dof, a, b, sign):
    """Complex-coordinate solution of ``Mc z̈ − iΩΓ ż + Kc z = 0``.

    With z = e^{iωt} z0 and the state y = [z; ż] the problem is ω B y = [[0, −iKc], [iKc, ΩΓ]] y,
    B = diag(Kc, Mc). Scaling the first block, y = [i y1; y2], makes it real symmetric-definite:
    ω B y' = [[0, −Kc], [−Kc, ΩΓ]] y', solved for all speeds in one stacked real ``eigh`` after a
    Cholesky reduction with the speed-independent B. z0 = i y1' (a real shape: circular orbits).
    """
    Mc, Gam, Kc = form
    m = Mc.shape[0]
    B = np.zeros((2 * m, 2 * m))
    B[:m, :m], B[m:, m:] = Kc, Mc
    Linv = np.linalg.inv(np.linalg.cholesky(B))  # LinAlgError if K is not positive definite
    H0 = np.zeros((2 * m, 2 * m))
    H0[:m, m:] = -Kc
    H0[m:, :m] = -Kc
    H1 = np.zeros((2 * m, 2 * m))
    H1[m:, m:] = Gam
    H0t = Linv @ H0 @ Linv.T
    H1t = Linv @ H1 @ Linv.T
    w, x = np.linalg.eigh(H0t[None] + omegas[:, None, None] * H1t[None])
    order = np.argsort(np.abs(w), axis=1)
    w = np.take_along_axis(w, order, axis=1)
    x = np.take_along_axis(x, order[:, None, :], axis=2)
    z = Linv.T[:m] @ x  # (k, m, 2m) real displacement shapes (the factor i is a complex scale)
    z /= np.linalg.norm(z, axis=1, keepdims=True) * np.sqrt(2.0)
    # real-coordinate eigenvector of the eigenvalue i|ω| (z real): forward v̄ = z, w̄ = −i z;
    # backward v̄ = z, w̄ = +i z
    fwd = np.where(w > 0, -1.0, 1.0)[:, None, :]
    shapes = np.zeros((omegas.size, n_dof, 2 * m), dtype=complex)
    shapes[:, a] = z
    shapes[:, b] = sign[None, :, None] * (1j * fwd) * z
    lam = 1j * np.abs(w)
    return [Modes(lam[k], shapes[k]) for k in range(omegas.size)]


def precession_index(shapes, v_idx, w_idx):
    """Ψ per node and mode: 2 Im(v̄ conj(w̄)) / (|v̄|² + |w̄|²) ∈ [−1, 1] (+1: circular forward).

    ``shapes`` (..., n_dof, m); ``v_idx``, ``w_idx`` the DoF indices of x and y displacement per node.
    Returns ``(psi, amp2)`` each (..., n_nodes, m).
    """
    v = shapes[..., np.asarray(v_idx), :]
    w = shapes[..., np.asarray(w_idx), :]
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
    amax = amp2.max(axis=-2, keepdims=True)
    vote = (amp2 > NODE_AMP_TOL * amax) & (np.abs(psi) > PSI_TOL)
    pos = np.all((psi > 0) | ~vote, axis=-2)
    neg = np.all((psi < 0) | ~vote, axis=-2)
    anyv = np.any(vote, axis=-2)
    out = np.full(pos.shape, "mixed", dtype=object)
    out[anyv & pos] = "forward"
    out[anyv & neg] = "backward"
    return out


#: relative residual of a straight-line fit above which a shaft mode is called "bending"
BENDING_RESIDUAL = 0.25


def shape_class(shapes, v_idx, w_idx, z):
    """'cylindrical', 'conical' or 'bending' per mode from the shaft's lateral displacement pattern.

    The dominant whirl component of each node (forward r_f = (v̄ + i w̄)/2 or backward
    r_b = (conj v̄ + i conj w̄)/2, whichever carries more energy over the shaft) is phase-aligned to its
    largest node, giving a real deflection line x(z) at the node positions ``z`` [m]. If a straight line
    leaves a relative residual above ``BENDING_RESIDUAL`` the mode is "bending"; otherwise it is a rigid-shaft
    mode: "conical" if the line crosses zero inside the shaft, else "cylindrical". Works on (..., n_dof, m).
    """
    v = shapes[..., np.asarray(v_idx), :]
    w = shapes[..., np.asarray(w_idx), :]
    rf = 0.5 * (v + 1j * w)
    rb = 0.5 * (np.conj(v) + 1j * np.conj(w))
    use_f = np.sum(np.abs(rf) ** 2, axis=-2, keepdims=True) >= np.sum(np.abs(rb) ** 2, axis=-2, keepdims=True)
    r = np.where(use_f, rf, rb)
    k = np.argmax(np.abs(r), axis=-2)
    ref = np.take_along_axis(r, k[..., None, :], axis=-2)
    x = np.real(r * np.conj(ref) / np.where(np.abs(ref) > 0, np.abs(ref), 1.0))  # (..., n_nodes, m)
    z = np.asarray(z, dtype=float)
    V = np.column_stack([np.ones_like(z), z])  # least-squares straight line through the nodes
    P = V @ np.linalg.pinv(V)
    fit = np.einsum("ij,...jm->...im", P, x)
    resid = np.linalg.norm(x - fit, axis=-2) / np.maximum(np.linalg.norm(x, axis=-2), 1e-300)
    ends = fit[..., [0, -1], :]
    crosses = ends[..., 0, :] * ends[..., 1, :] < 0
    out = np.full(resid.shape, "cylindrical", dtype=object)
    out[crosses] = "conical"
    out[resid > BENDING_RESIDUAL] = "bending"
    return out


def ring_energy_fraction(shapes, M, ring_dofs):
    """Share of the modal kinetic energy u^H M u carried by the ring DoFs, per mode (..., m)."""
    if not ring_dofs:
        return np.zeros(shapes.shape[:-2] + shapes.shape[-1:])
    total = np.real(np.einsum("...im,ij,...jm->...m", np.conj(shapes), M, shapes))
    idx = np.array(ring_dofs).ravel()
    sr = shapes[..., idx, :]
    ring = np.real(np.einsum("...im,ij,...jm->...m", np.conj(sr), M[np.ix_(idx, idx)], sr))
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

    fast = _track_constant(eigenvalue_list, shape_list, w_lambda)
    if fast is not None:
        return fast
    last_shape = None  # (n_dof, n_tracks) unit-norm shapes of each track's last appearance
    last_lam = np.zeros(0, dtype=complex)
    assignment = []
    for lam, sh in zip(eigenvalue_list, shape_list):
        n_tr = last_lam.size
        cur = -np.ones(n_tr, dtype=int)
        used = np.zeros(lam.size, dtype=bool)
        if n_tr and lam.size:
            # shapes are unit norm, so MAC = |u_a^H u_b|²
            cost = 1.0 - np.abs(np.conj(last_shape).T @ sh) ** 2 \
                + w_lambda * np.abs(last_lam[:, None] - lam[None, :]) / np.abs(last_lam)[:, None]
            rmin = cost.argmin(axis=1)
            if n_tr <= lam.size and np.bincount(rmin, minlength=lam.size).max() == 1:
                r, c = np.arange(n_tr), rmin  # every track's best mode is distinct: that is the optimum
            else:
                r, c = linear_sum_assignment(cost)
            good = cost[r, c] < 1.5  # a poor match rather opens a new track
            r, c = r[good], c[good]
            cur[r] = c
            used[c] = True
            last_shape[:, r] = sh[:, c]
            last_lam[r] = lam[c]
        new = np.flatnonzero(~used)
        if new.size:
            last_shape = sh[:, new] if last_shape is None else np.concatenate([last_shape, sh[:, new]], axis=1)
            last_lam = np.concatenate([last_lam, lam[new]])
        assignment.append(np.concatenate([cur, new]))
    n_tracks = last_lam.size
    return [np.concatenate([a, -np.ones(n_tracks - a.size, dtype=int)]) for a in assignment]


def _track_constant(eigenvalue_list, shape_list, w_lambda):
    """Vectorised tracking when every step has the same modes count and each mode's best match at the next
    step is distinct (no ambiguity): all consecutive cost matrices in one batched product. None otherwise."""
    sizes = {lam.size for lam in eigenvalue_list}
    if len(sizes) != 1 or len(eigenvalue_list) < 2 or 0 in sizes:
        return None
    L = np.stack(eigenvalue_list)
    S = np.stack(shape_list)
    mac2 = np.abs(np.conj(S[:-1]).transpose(0, 2, 1) @ S[1:]) ** 2  # unit-norm shapes: MAC = |u^H v|²
    cost = 1.0 - mac2 + w_lambda * np.abs(L[:-1, :, None] - L[1:, None, :]) / np.abs(L[:-1, :, None])
    best = cost.argmin(axis=2)  # (steps-1, m): best next-step mode of each current mode
    m = L.shape[1]
    if np.any(np.sort(best, axis=1) != np.arange(m)[None, :]) or np.any(
            np.take_along_axis(cost, best[:, :, None], axis=2) >= 1.5):
        return None
    perm = [np.arange(m)]
    for b in best:
        perm.append(b[perm[-1]])
    return perm
