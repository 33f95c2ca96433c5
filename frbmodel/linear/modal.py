"""Modal analysis: state space, eigenvalues, modal damping, precession, ring-mode classification, tracking.

Conventions (docs/theory/modal.md#modal-analysis): λ = α + iβ with β > 0 kept; modal damping D = −α/|λ|; precession
indicator
Ψ_j = Im(v̄_j · conj(w̄_j)) per node (> 0 forward, < 0 backward for CCW rotation).

Neutral modes. An eigen-solver returns the eigenvalues of a slightly perturbed matrix, so an undamped mode
(D = 0 exactly, e.g. every mode of methods A, B and E) comes out with |D| at round-off level and either sign.
Each mode therefore carries a round-off bound of its damping (:func:`damping_tolerance`); a mode with
|D| <= that bound is *neutral* (its sign is not determined by the computation), D < −bound is unstable and
D > bound is stable.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..core.errors import ParameterError, check_real_array
from ..system.rotor import first_order_state_matrix

#: eigenvalues with |Im λ| / |λ| below this are treated as over-damped (real) and left out
REAL_TOL = 1e-7
#: nodes whose amplitude² is below this fraction of the largest one carry no precession vote
NODE_AMP_TOL = 1e-4
#: |Ψ_j| / amplitude² below this is "planar" at that node and carries no vote
PSI_TOL = 1e-3
#: machine epsilon of float64
EPS = float(np.finfo(float).eps)


def damping_tolerance(A, lam, vec):
    """Round-off bound of the modal damping D = −Re λ/|λ| of each eigenvalue of a state matrix.

    LAPACK's ``geev`` (behind :func:`numpy.linalg.eig` and :func:`scipy.linalg.eig`) first balances A by a diagonal
    similarity, A_b = T⁻¹ A T (``gebal``, the same routine as :func:`scipy.linalg.matrix_balance`), and is then
    backward stable: its eigenvalues are exact for A_b + E with ‖E‖ ≲ p(N) ε ‖A_b‖. To first order an eigenvalue
    moves by |δλ| <= κ_b(λ) ‖E‖ with κ_b = ‖y_b‖ ‖x_b‖ / |y_b^H x_b| its condition number in the balanced
    coordinates (x_b, y_b right and left eigenvectors of A_b), so D moves by at most

        tol = N · ε · ‖A_b‖_F · κ_b(λ) / |λ|,

    with the growth factor p(N) taken as the state dimension N (Frobenius norm >= 2-norm). Measured on the Table 2
    system (100 speeds, 10 ... 250 krpm, outer clearance 36 and 46 µm): method B, where D = 0 exactly (an undamped
    gyroscopic system with M, K > 0 has imaginary eigenvalues), has computed |D| <= 1.9e-13 and |D| / tol <= 0.01;
    the film modes of methods C–J have |D| >= 3.9e-5 against tol <= 1.1e-7, so no film damping is taken for
    round-off.

    Parameters
    ----------
    A : ndarray (..., N, N)
        State matrices (a stack, e.g. one per speed).
    lam : complex ndarray (..., N)
        Their eigenvalues.
    vec : complex ndarray (..., N, N)
        Their right eigenvectors (columns), as returned with ``lam``.

    Returns
    -------
    ndarray (..., N)
        Bound on |δD| per eigenvalue [-] (inf where |λ| = 0).

    Examples
    --------
    >>> A = np.array([[0.0, 1.0], [-4.0, 0.0]])      # undamped oscillator, λ = ±2i
    >>> lam, vec = np.linalg.eig(A)
    >>> tol = damping_tolerance(A, lam, vec)
    >>> bool(np.all(np.abs(lam.real / np.abs(lam)) <= tol)), bool(np.all(tol < 1e-14))
    (True, True)
    """
    A = np.asarray(A)
    n = A.shape[-1]
    flat_a, flat_v = A.reshape(-1, n, n), np.asarray(vec).reshape(-1, n, n)
    flat_l = np.asarray(lam).reshape(-1, n)
    try:
        w_all = np.linalg.inv(flat_v)
    except np.linalg.LinAlgError:  # a defective eigenvalue in the stack: pseudo-inverse per matrix
        w_all = np.array([np.linalg.pinv(v) for v in flat_v])
    tol = np.empty(flat_l.shape)
    for k in range(flat_a.shape[0]):
        ab, T = sla.matrix_balance(flat_a[k])
        vb = np.linalg.solve(T, flat_v[k])  # right eigenvectors of A_b (T: a permutation times powers of 2)
        wb = w_all[k] @ T  # left eigenvectors of A_b (rows)
        kappa = np.linalg.norm(wb, axis=1) * np.linalg.norm(vb, axis=0) / np.abs(np.einsum("ij,ji->i", wb, vb))
        with np.errstate(divide="ignore"):
            tol[k] = n * EPS * np.linalg.norm(ab) * kappa / np.abs(flat_l[k])
    return tol.reshape(np.shape(lam))


def state_matrix(M, C, K):
    """State matrix A = [[0, I], [−M⁻¹K, −M⁻¹C]] of ``M q̈ + C q̇ + K q = 0``
    (:func:`frbmodel.system.rotor.first_order_state_matrix`).

    Parameters
    ----------
    M, C, K : ndarray (n, n)
        Mass, velocity and stiffness matrices [SI].

    Returns
    -------
    ndarray (2n, 2n)

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
    damping_tol : ndarray (m,)
        Round-off bound of each mode's damping D [-] (:func:`damping_tolerance`); 0 where D is exact by
        construction (the Hermitian solve of undamped isotropic systems). Default 0 (no bound known).

    Examples
    --------
    >>> md = modes(np.eye(1), np.zeros((1, 1)), 4.0 * np.eye(1))   # undamped oscillator, ω = 2 rad/s
    >>> md.eigenvalues, md.stability.tolist()
    (array([0.+2.j]), ['neutral'])
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    damping_tol: np.ndarray | None = None

    def __post_init__(self):
        if self.damping_tol is None:
            self.damping_tol = np.zeros(np.shape(self.eigenvalues))

    @property
    def frequencies_hz(self):
        """Damped natural frequencies Im λ / 2π [Hz]."""
        return self.eigenvalues.imag / (2.0 * np.pi)

    @property
    def damping(self):
        """Modal damping D = −Re λ / |λ| [-]."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)

    @property
    def stability(self):
        """"stable" (D > tol), "neutral" (|D| <= tol: round-off decides the sign) or "unstable" (D < −tol) per mode."""
        return stability_labels(self.damping, self.damping_tol)


def stability_labels(damping, damping_tol):
    """Stability of modes from their damping and its round-off bound.

    Parameters
    ----------
    damping, damping_tol : array_like
        Modal damping D [-] and its bound (NaN: mode absent).

    Returns
    -------
    ndarray of str (object)
        "stable" (D > tol), "neutral" (|D| <= tol), "unstable" (D < −tol) or "" (absent).

    Examples
    --------
    >>> stability_labels([0.1, -1e-14, -0.1, np.nan], [1e-10, 1e-10, 1e-10, np.nan]).tolist()
    ['stable', 'neutral', 'unstable', '']
    """
    d, t = np.asarray(damping, dtype=float), np.asarray(damping_tol, dtype=float)
    out = np.full(d.shape, "", dtype=object)
    with np.errstate(invalid="ignore"):
        out[d > t] = "stable"
        out[np.abs(d) <= t] = "neutral"
        out[d < -t] = "unstable"
    return out


def modes_from_state(A, n_dof):
    """Under-damped modes of a first-order system ṡ = A s whose first ``n_dof`` states are displacements.

    Parameters
    ----------
    A : ndarray (N, N)
        State matrix [SI].
    n_dof : int
        Number of displacement states (their eigenvector part is returned as the shape).

    Returns
    -------
    Modes
        With the round-off bound of each damping value (:func:`damping_tolerance`).

    Examples
    --------
    >>> md = modes_from_state(np.array([[0.0, 1.0], [-4.0, -0.4]]), 1)   # ω_n = 2, D = 0.1
    >>> round(float(md.damping[0]), 12), md.stability.tolist()
    (0.1, ['stable'])
    """
    A = check_real_array("A", A, "SI")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not 0 < int(n_dof) <= A.shape[0]:
        raise ParameterError(f"state matrix A of shape {A.shape} with n_dof = {n_dof!r} is invalid: expected a "
                             "square (N, N) matrix and 0 < n_dof <= N")
    lam, vec = sla.eig(A, check_finite=True)
    return _select(lam, vec, int(n_dof), damping_tolerance(A, lam, vec))


def modes(M, C, K) -> Modes:
    """Under-damped modes of ``M q̈ + C q̇ + K q = 0``.

    Parameters
    ----------
    M, C, K : array_like (n, n)
        Mass [kg ...], velocity (damping + gyroscopic) [N s/m ...] and stiffness [N/m ...] matrices.

    Returns
    -------
    Modes

    Raises
    ------
    ParameterError
        A matrix that is not real, finite or (n, n), or a singular M.

    Examples
    --------
    >>> md = modes([[2.0]], [[0.8]], [[8.0]])              # ω_n = 2 rad/s, D = 0.8 / (2 · 2 · 2) = 0.1
    >>> round(float(md.frequencies_hz[0] * 2 * np.pi), 6), round(float(md.damping[0]), 12)
    (1.989975, 0.1)
    """
    mats = [check_real_array(name, X, unit) for name, X, unit in (("M", M, "kg"), ("C", C, "N s/m"),
                                                                 ("K", K, "N/m"))]
    n = mats[0].shape[0] if mats[0].ndim == 2 else -1
    if any(X.shape != (n, n) for X in mats) or n < 1:
        raise ParameterError(f"M, C, K of shapes {[X.shape for X in mats]} are invalid: expected three square "
                             "matrices of the same size (n, n)")
    try:
        A = state_matrix(*mats)
    except np.linalg.LinAlgError:
        raise ParameterError("mass matrix M is singular: every DoF needs a mass or inertia") from None
    return modes_from_state(A, n)


def _select(lam, vec, n_dof, tol=None):
    keep = lam.imag > REAL_TOL * np.abs(lam)
    tol = np.zeros(lam.shape) if tol is None else tol
    lam, vec, tol = lam[keep], vec[:n_dof, keep], tol[keep]
    order = np.argsort(lam.imag)
    lam, vec, tol = lam[order], vec[:, order], tol[order]
    norms = np.linalg.norm(vec, axis=0)
    norms[norms == 0.0] = 1.0
    return Modes(lam, vec / norms, tol)


def isotropic_complex_form(M, C, K, a, b, sign, tol=1e-12):
    """Complex-coordinate matrices ``(Mc, Gc, Kc)`` of an undamped isotropic gyroscopic system, or None.

    For an axisymmetric rotor on isotropic, undamped supports the real equations split into two identical
    planes ``a`` and ``b`` coupled only by the gyroscopic matrix, and z = a + i·sign·b obeys
    ``Mc z̈ − i Gc ż + Kc z = 0`` with real symmetric ``Mc, Gc, Kc`` of half the size (the classical complex
    coordinates of rotordynamics).

    Parameters
    ----------
    M, C, K : ndarray (n, n)
        Mass, velocity (here: gyroscopic only) and stiffness matrices.
    a, b : ndarray of int
        DoF indices of the two planes (:meth:`frbmodel.linear.assembly.LinearSystem.planes`).
    sign : ndarray
        Sign of each b DoF in the complex coordinate.
    tol : float
        Relative tolerance of the symmetry checks.

    Returns
    -------
    tuple of ndarray or None
        ``(Mc, Gc, Kc)`` (half size), or None when the system is not of that form.

    Examples
    --------
    >>> M, K = np.eye(2), np.eye(2)                   # a point mass on isotropic springs, no gyroscopics
    >>> C = np.array([[0.0, 1e-3], [-1e-3, 0.0]])     # (a tiny skew coupling between the planes)
    >>> [X.tolist() for X in isotropic_complex_form(M, C, K, np.array([0]), np.array([1]), np.array([1.0]))]
    [[[1.0]], [[0.001]], [[1.0]]]
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
    """Under-damped modes of a list of linear systems, all in one stacked LAPACK call on the state matrices.

    Parameters
    ----------
    systems : sequence
        Objects with ``M``, ``C``, ``K`` (e.g. :class:`frbmodel.LinearSystem`) of one size.

    Returns
    -------
    list of Modes
        One per system, with the damping round-off bounds (:func:`damping_tolerance`).

    Examples
    --------
    >>> import frbmodel as frb
    >>> tc = frb.turbocharger()
    >>> out = batch_modes([frb.linear_system(tc, "J", s) for s in (50e3, 100e3)])
    >>> len(out), out[0].shapes.shape[0]
    (2, 20)
    """
    if not systems:
        return []
    n = systems[0].M.shape[0]
    Minv = np.linalg.inv(systems[0].M)
    mk, mc = np.empty((len(systems), n, n)), np.empty((len(systems), n, n))
    for k, s in enumerate(systems):
        if s.M is not systems[0].M and not np.array_equal(s.M, systems[0].M):
            Minv = np.linalg.inv(s.M)
        mk[k], mc[k] = Minv @ s.K, Minv @ s.C
    A = first_order_state_matrix(mk, mc)
    lam, vec = np.linalg.eig(A)
    tol = damping_tolerance(A, lam, vec)
    return [_select(lam[k], vec[k], n, tol[k]) for k in range(len(systems))]


def speed_modes(M, K, C0, G, omegas, planes=None):
    """Modes of ``M q̈ + (C0 + Ω G) q̇ + K q = 0`` at all speeds ``omegas`` [rad/s] (M, K, C0 constant).

    If the system is undamped and isotropic (methods A and E: axisymmetric rotor on isotropic springs) it is
    solved in complex coordinates z = a + i·sign·b (``planes = (a, b, sign)``) as a Hermitian-definite
    problem of half the size: exact, and the sign of each frequency is its precession. Otherwise the state
    matrices A0 + Ω A1 of all speeds go to one stacked eigen-decomposition.

    Parameters
    ----------
    M, K, C0, G : ndarray (n, n)
        Mass, stiffness, support damping and gyroscopic (per rad/s) matrices.
    omegas : array_like (k,)
        Rotor speeds [rad/s].
    planes : tuple, optional
        ``(a, b, sign)`` of :meth:`frbmodel.linear.assembly.LinearSystem.planes` (enables the complex-coordinate path).

    Returns
    -------
    list of Modes
        One per speed; the damping round-off bound is 0 on the exact Hermitian path.

    Examples
    --------
    >>> import frbmodel as frb
    >>> ls = frb.linear_system(frb.turbocharger(), "A", 0.0)
    >>> G = np.zeros_like(ls.M)
    >>> G[:16, :16] = frb.turbocharger().rotor.G
    >>> md = speed_modes(ls.M, ls.K, ls.C, G, [0.0, 100e3 * np.pi / 30], ls.planes())    # 0 and 100 krpm
    >>> round(float(md[1].frequencies_hz[0]), 1), set(md[1].stability)
    (60.2, {'neutral'})
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
    tol = damping_tolerance(A, lam, vec)
    return [_select(lam[k], vec[k], n, tol[k]) for k in range(omegas.size)]


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
    lam = 1j * np.abs(w)  # real ω of a Hermitian problem: D = 0 exactly, its round-off bound is 0
    return [Modes(lam[k], shapes[k], np.zeros(w.shape[1])) for k in range(omegas.size)]


def precession_index(shapes, v_idx, w_idx):
    """Precession indicator Ψ per node and mode: 2 Im(v̄ conj(w̄)) / (|v̄|² + |w̄|²) ∈ [−1, 1] (+1: circular
    forward).

    Parameters
    ----------
    shapes : complex ndarray (..., n_dof, m)
        Mode shapes.
    v_idx, w_idx : sequence of int
        DoF indices of the x and y displacement of each node.

    Returns
    -------
    psi, amp2 : ndarray (..., n_nodes, m)
        Ψ and the orbit amplitude |v̄|² + |w̄|² per node.

    Examples
    --------
    >>> psi, amp2 = precession_index(np.array([[1.0 + 0j], [-1j]]), [0], [1])   # v = cos βt, w = sin βt
    >>> float(psi[0, 0]), float(amp2[0, 0])
    (1.0, 2.0)
    """
    v = shapes[..., np.asarray(v_idx), :]
    w = shapes[..., np.asarray(w_idx), :]
    amp2 = np.abs(v) ** 2 + np.abs(w) ** 2
    psi = 2.0 * np.imag(v * np.conj(w))
    with np.errstate(invalid="ignore", divide="ignore"):
        psi_n = np.where(amp2 > 0, psi / np.where(amp2 > 0, amp2, 1.0), 0.0)
    return psi_n, amp2


def classify_precession(psi, amp2):
    """'forward', 'backward' or 'mixed' per mode from per-node Ψ (docs/theory/modal.md#modal-analysis).

    Nodes with negligible amplitude or a planar orbit do not vote. A mode whose voting nodes all have
    Ψ > 0 is forward, all Ψ < 0 backward, otherwise mixed (the paper's "combined precession").

    Parameters
    ----------
    psi, amp2 : ndarray (..., n_nodes, m)
        From :func:`precession_index`.

    Returns
    -------
    ndarray (..., m) of str

    Examples
    --------
    >>> classify_precession(np.array([[1.0, -1.0, 1.0], [1.0, -1.0, -1.0]]), np.ones((2, 3))).tolist()
    ['forward', 'backward', 'mixed']
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
    mode: "conical" if the line crosses zero inside the shaft, else "cylindrical".

    Parameters
    ----------
    shapes : complex ndarray (..., n_dof, m)
        Mode shapes.
    v_idx, w_idx : sequence of int
        DoF indices of the x and y displacement of each node.
    z : array_like (n_nodes,)
        Axial node positions [m].

    Returns
    -------
    ndarray (..., m) of str

    Examples
    --------
    >>> u = np.array([[1.0, 1.0], [0, 0], [1.0, 0.0], [0, 0], [1.0, -1.0], [0, 0]], dtype=complex)  # x at 3 nodes
    >>> shape_class(u, [0, 2, 4], [1, 3, 5], [0.0, 0.5, 1.0]).tolist()
    ['cylindrical', 'conical']
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
    """Share of the modal kinetic energy u^H M u carried by the ring DoFs.

    Parameters
    ----------
    shapes : complex ndarray (..., n_dof, m)
        Mode shapes.
    M : ndarray (n_dof, n_dof)
        Mass matrix [kg ...].
    ring_dofs : sequence of (int, int) or None
        Global (x, y) indices of each ring.

    Returns
    -------
    ndarray (..., m)
        Ring share [-] (0 without ring DoFs).

    Examples
    --------
    >>> float(ring_energy_fraction(np.array([[1.0], [1.0], [0.0]]), np.diag([1.0, 3.0, 1.0]), [(1, 2)])[0])
    0.75
    """
    if not ring_dofs:
        return np.zeros(shapes.shape[:-2] + shapes.shape[-1:])
    total = np.real(np.einsum("...im,ij,...jm->...m", np.conj(shapes), M, shapes))
    idx = np.array(ring_dofs).ravel()
    sr = shapes[..., idx, :]
    ring = np.real(np.einsum("...im,ij,...jm->...m", np.conj(sr), M[np.ix_(idx, idx)], sr))
    return ring / total


def mac(a, b):
    """Modal assurance criterion |a^H b|² / ((a^H a)(b^H b)) between the columns of a and b.

    Parameters
    ----------
    a : ndarray (n, p)
    b : ndarray (n, q)

    Returns
    -------
    ndarray (p, q)
        MAC values in [0, 1].

    Examples
    --------
    >>> mac(np.eye(2), np.array([[1.0], [1.0]])).ravel().tolist()
    [0.5, 0.5]
    """
    num = np.abs(np.conj(a).T @ b) ** 2
    den = np.outer(np.real(np.sum(np.conj(a) * a, axis=0)), np.real(np.sum(np.conj(b) * b, axis=0)))
    return num / den


def track(eigenvalue_list, shape_list, w_lambda=0.3):
    """Order modes consistently across a speed sweep (docs/theory/modal.md#modal-analysis tracking).

    Each step's modes are assigned to the tracks of the previous steps by minimising
    ``1 − MAC + w_λ |Δλ| / |λ|`` (Hungarian assignment); unmatched modes open new tracks.

    Parameters
    ----------
    eigenvalue_list : list of complex ndarray
        Eigenvalues per step.
    shape_list : list of complex ndarray (n_dof, m_k)
        Unit-norm mode shapes per step.
    w_lambda : float
        Weight of the relative eigenvalue change in the cost.

    Returns
    -------
    list of ndarray of int
        ``perm[k][t]`` = mode index at step k for track t (−1 = absent), all of equal length (the number of
        tracks).

    Examples
    --------
    >>> lam = [np.array([1j, 2j]), np.array([2.1j, 1.1j])]
    >>> sh = [np.eye(2, dtype=complex), np.eye(2, dtype=complex)[:, ::-1]]
    >>> [p.tolist() for p in track(lam, sh)]
    [[0, 1], [1, 0]]
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
