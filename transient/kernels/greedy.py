"""Greedy orthogonal selection of rows (Orthogonal Maximum Sequence; pivoted QR on rows)."""
import numba
import numpy as np

from ..jit import njit_parallel


@njit_parallel
def _downdate(R, q, norms2, available):
    """norms2[i] -= (R[i] . q)^2 for the available rows, in one pass over R."""
    n, r = R.shape
    for i in numba.prange(n):
        if available[i]:
            d = 0.0
            for j in range(r):
                d += R[i, j] * q[j]
            norms2[i] -= d * d


@njit_parallel
def _row_norms2(R, out):
    n, r = R.shape
    for i in numba.prange(n):
        s = 0.0
        for j in range(r):
            s += R[i, j] * R[i, j]
        out[i] = s


@njit_parallel
def greedy_rows(R, m, tol, restart):
    """Indices of up to m rows of R (n, r) chosen greedily.

    At each step the row with the largest norm in the orthogonal complement of the rows already
    chosen is taken (as LAPACK's column pivoting does on R^T). A sweep ends when the largest
    remaining norm falls below tol times the largest initial one (the numerical rank); with
    `restart`, a new sweep starts from the original rows of those not chosen, until m rows.
    Returns (chosen, residual at each pick relative to the initial maximum).
    """
    n, r = R.shape
    m = min(m, n)
    chosen = np.empty(m, np.int64)
    residual = np.empty(m)
    available = np.ones(n, np.bool_)
    norms2 = np.empty(n)
    original = np.empty(n)
    _row_norms2(R, original)
    top = original.max()
    Q = np.zeros((min(m, r), r))
    k = 0
    while k < m:
        norms2[:] = original
        nq = 0
        while k < m and nq < r:
            p = -1
            best = -1.0
            for i in range(n):
                if available[i] and norms2[i] > best:
                    best = norms2[i]
                    p = i
            if p < 0 or best <= tol * tol * top:
                break
            q = R[p].copy()
            for _ in range(2):     # classical Gram-Schmidt twice: orthogonal to round-off
                for j in range(nq):
                    c = 0.0
                    for t in range(r):
                        c += Q[j, t] * q[t]
                    for t in range(r):
                        q[t] -= c * Q[j, t]
            s = np.sqrt((q * q).sum())
            if s <= tol * np.sqrt(top):
                break
            Q[nq] = q / s
            chosen[k] = p
            residual[k] = np.sqrt(max(best, 0.0) / top)
            available[p] = False
            _downdate(R, Q[nq], norms2, available)
            nq += 1
            k += 1
        if not restart or nq == 0:
            break
    return chosen[:k], residual[:k]
