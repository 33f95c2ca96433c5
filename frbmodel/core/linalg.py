"""Small dense linear algebra in compiled code: LU factorization with partial pivoting and its solve, for the
compiled integrators that factor one matrix and solve with it several times (the ring integrator of the
co-simulation bearing, the Rosenbrock run-up integrator); numba's ``np.linalg.solve`` would factor anew each time.

>>> import numpy as np
>>> a = np.array([[0.0, 2.0], [4.0, 1.0]]); piv = np.zeros(2, dtype=np.int64)
>>> bool(lu_factor(a, piv))
True
>>> b = np.array([2.0, 9.0]); lu_solve(a, piv, b); b.tolist()   # [[0, 2], [4, 1]] x = [2, 9]
[2.0, 1.0]
"""
from __future__ import annotations

import math

from numba import njit

#: numba ``fastmath`` flags of the compiled loops of sums (matrix-vector products, LU, error norms): the compiler may
#: reorder a sum and fuse a multiply-add, so the loop runs on vector registers (the 16-DoF rotor's acceleration in
#: 0.11 µs instead of 0.33 µs, measured); never the flags that assume finite numbers, so NaN and inf checks stay
#: valid. Results change at round-off only.
SUM_FLAGS = {"reassoc": True, "contract": True}


@njit(cache=True, fastmath=SUM_FLAGS)
def lu_factor(a, piv):
    """LU factorization with partial pivoting of the square matrix ``a``, in place: the unit lower factor below the
    diagonal, the upper factor on and above it; row ``k`` was interchanged with row ``piv[k]``. Returns False (and a
    garbage ``a``) for a singular or non-finite matrix."""
    n = a.shape[0]
    for k in range(n):
        p, big = k, abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                p, big = i, abs(a[i, k])
        if not (0.0 < big < math.inf):  # also False for NaN
            return False
        piv[k] = p
        if p != k:
            for c in range(n):
                a[k, c], a[p, c] = a[p, c], a[k, c]
        for i in range(k + 1, n):
            m = a[i, k] / a[k, k]
            a[i, k] = m
            for c in range(k + 1, n):
                a[i, c] -= m * a[k, c]
    return True


@njit(cache=True, fastmath=SUM_FLAGS)
def lu_solve(lu, piv, b):
    """Solve A x = b in place (``b`` becomes x) with the factors of :func:`lu_factor`."""
    n = lu.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(1, n):
        s = b[i]
        for c in range(i):
            s -= lu[i, c] * b[c]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for c in range(i + 1, n):
            s -= lu[i, c] * b[c]
        b[i] = s / lu[i, i]
