"""Sparse kernels on CSR triplets (indptr, indices, data): products, triangular solves, and the
columns of a CSR matrix taken by a map."""
import numpy as np

from numba import prange

from ..jit import njit, njit_fast, njit_parallel_ieee


@njit_parallel_ieee
def csr_block(indptr, indices, rows, new, datas):
    """The block of CSR matrices of one pattern (indptr, indices; data datas, a tuple) on the
    rows `rows` and the columns j with new[j] >= 0, renumbered new[j] (in row order):
    (indptr, indices, data (len(datas), nnz)), the rows in parallel (the M and K of one
    assembly taken in one pass: copies, no arithmetic)."""
    m = rows.shape[0]
    counts = np.zeros(m, indptr.dtype)
    for r in prange(m):
        i = rows[r]
        c = 0
        for k in range(indptr[i], indptr[i + 1]):
            if new[indices[k]] >= 0:
                c += 1
        counts[r] = c
    out_ptr = np.empty(m + 1, indptr.dtype)
    out_ptr[0] = 0
    for r in range(m):
        out_ptr[r + 1] = out_ptr[r] + counts[r]
    out_idx = np.empty(out_ptr[m], indices.dtype)
    out_data = np.empty((len(datas), out_ptr[m]))
    for r in prange(m):
        i = rows[r]
        p = out_ptr[r]
        for k in range(indptr[i], indptr[i + 1]):
            j = new[indices[k]]
            if j >= 0:
                out_idx[p] = j
                for d in range(len(datas)):
                    out_data[d, p] = datas[d][k]
                p += 1
    return out_ptr, out_idx, out_data


@njit
def csr_upper(indptr, indices, data):
    """The upper triangle (diagonal included) of a square CSR matrix, in its row and column
    order, as int32 (indptr, indices) and data: what PARDISO takes, in one pass and without
    SciPy's round trip through COO (0.15 s on pad_disc_long's 66554 dofs)."""
    n = indptr.shape[0] - 1
    out_ptr = np.empty(n + 1, np.int32)
    out_ptr[0] = 0
    count = 0
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            if indices[k] >= i:
                count += 1
        out_ptr[i + 1] = count
    out_idx = np.empty(count, np.int32)
    out_val = np.empty(count, np.float64)
    p = 0
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            if indices[k] >= i:
                out_idx[p] = indices[k]
                out_val[p] = data[k]
                p += 1
    return out_ptr, out_idx, out_val


@njit
def csr_combined(indptr, indices, a, b, beta):
    """The CSR triplet of A + beta B for A and B of one pattern (indptr, indices; data a and
    b), the entries that come out zero left out (as SciPy's sum leaves them). Counted first,
    so that the output is allocated once at its size (fresh memory is the cost here)."""
    m = indptr.shape[0] - 1
    zeros = 0
    for k in range(indices.shape[0]):
        if a[k] + beta * b[k] == 0.0:
            zeros += 1
    out_ptr = np.empty(m + 1, indptr.dtype)
    out_idx = np.empty(indices.shape[0] - zeros, indices.dtype)
    out_val = np.empty(indices.shape[0] - zeros, a.dtype)
    p = 0
    out_ptr[0] = 0
    for i in range(m):
        for k in range(indptr[i], indptr[i + 1]):
            v = a[k] + beta * b[k]
            if v != 0.0:
                out_idx[p] = indices[k]
                out_val[p] = v
                p += 1
        out_ptr[i + 1] = p
    return out_ptr, out_idx, out_val


@njit_parallel_ieee
def csr_matmat(indptr, indices, data, X, Y):
    """Y = A X for a CSR A and a C-ordered block X: rows in parallel, the same sums whatever
    the thread count. A row's entries go four at a time, (a0 x0 + a1 x1) + (a2 x2 + a3 x3)
    added to Y's row, then one at a time: each entry of Y is loaded and stored once per four
    of A's (the row at a time was bound by them: M times 128 columns on pad_disc, 137 -> 102
    ms). SciPy's product (single-threaded, each row summed in CSR order) differs by round-off."""
    n, s = Y.shape
    for i in prange(n):
        for c in range(s):
            Y[i, c] = 0.0
        k, end = indptr[i], indptr[i + 1]
        while k + 4 <= end:
            a0, a1, a2, a3 = data[k], data[k + 1], data[k + 2], data[k + 3]
            j0, j1, j2, j3 = indices[k], indices[k + 1], indices[k + 2], indices[k + 3]
            for c in range(s):
                Y[i, c] += (a0 * X[j0, c] + a1 * X[j1, c]) + (a2 * X[j2, c] + a3 * X[j3, c])
            k += 4
        while k < end:
            a = data[k]
            j = indices[k]
            for c in range(s):
                Y[i, c] += a * X[j, c]
            k += 1


@njit_parallel_ieee
def csr_matmat_pair(indptr, indices, a, b, X, YA, YB):
    """YA = A X and YB = B X for CSR A and B of one pattern (data a and b) and a C-ordered
    block X: csr_matmat's sums, term for term, for both, from one read of the pattern and of
    X's rows (M and K times 128 columns on pad_disc: 0.24 -> 0.16 s)."""
    n, s = YA.shape
    for i in prange(n):
        for c in range(s):
            YA[i, c] = 0.0
            YB[i, c] = 0.0
        k, end = indptr[i], indptr[i + 1]
        while k + 4 <= end:
            a0, a1, a2, a3 = a[k], a[k + 1], a[k + 2], a[k + 3]
            b0, b1, b2, b3 = b[k], b[k + 1], b[k + 2], b[k + 3]
            j0, j1, j2, j3 = indices[k], indices[k + 1], indices[k + 2], indices[k + 3]
            for c in range(s):
                x0, x1, x2, x3 = X[j0, c], X[j1, c], X[j2, c], X[j3, c]
                YA[i, c] += (a0 * x0 + a1 * x1) + (a2 * x2 + a3 * x3)
                YB[i, c] += (b0 * x0 + b1 * x1) + (b2 * x2 + b3 * x3)
            k += 4
        while k < end:
            ak, bk = a[k], b[k]
            j = indices[k]
            for c in range(s):
                YA[i, c] += ak * X[j, c]
                YB[i, c] += bk * X[j, c]
            k += 1


def csr_dot(A, X):
    """A @ X for a SciPy sparse A and a dense X (n,) or (n, s): by csr_matmat (both cores, the
    same sums on any thread count) when A is CSR, by SciPy otherwise."""
    if A.format != "csr":
        return A @ X
    X = np.asarray(X, dtype=np.float64)
    if X.ndim == 1:
        return csr_dot(A, X[:, None])[:, 0]
    Y = np.empty((A.shape[0], X.shape[1]))
    csr_matmat(A.indptr, A.indices, np.asarray(A.data, np.float64), np.ascontiguousarray(X), Y)
    return Y


def shares_pattern(A, B):
    """Whether sparse A and B are CSR of one pattern (the M and K of one assembly are)."""
    return (A.format == "csr" and B.format == "csr" and A.shape == B.shape
            and np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices))


def csr_dot_pair(A, B, X, shared=None):
    """(A @ X, B @ X) for sparse A and B and a dense block X (n, s), each csr_dot's to the last
    bit; in one pass (csr_matmat_pair) when they share their pattern. shared: that known
    already (shares_pattern), or None to test it."""
    if not (shares_pattern(A, B) if shared is None else shared):
        return csr_dot(A, X), csr_dot(B, X)
    X = np.ascontiguousarray(X, dtype=np.float64)
    YA, YB = np.empty((A.shape[0], X.shape[1])), np.empty((A.shape[0], X.shape[1]))
    csr_matmat_pair(A.indptr, A.indices, np.asarray(A.data, np.float64),
                    np.asarray(B.data, np.float64), X, YA, YB)
    return YA, YB


@njit_fast
def csr_matvec(indptr, indices, data, x, out):
    for i in range(out.shape[0]):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        out[i] = s


@njit_fast
def csr_row_dot(R, i, y):
    """Row i of a CSR triplet R times y."""
    Rp, Ri, Rd = R
    s = 0.0
    for j in range(Rp[i], Rp[i + 1]):
        s += Rd[j] * y[Ri[j]]
    return s


@njit_fast
def csr_abs_matvec(indptr, indices, data, x, out):
    """|A| |x|: the scale of the round-off in A x."""
    for i in range(out.shape[0]):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += abs(data[k] * x[indices[k]])
        out[i] = s


@njit_fast
def factor_solve(p_in, L, U, p_out, b, x, work):
    """x = A^-1 b from linsolve.triangular_factors: L z = b[p_in], U w = z, x = w[p_out].
    work (n,) is scratch; b and x may be the same array."""
    Lp, Li, Ld = L
    Up, Ui, Ud = U
    n = b.shape[0]
    for i in range(n):
        work[i] = b[p_in[i]]
    for i in range(n):                      # forward: the diagonal is the row's last entry
        s = work[i]
        end = Lp[i + 1] - 1
        for k in range(Lp[i], end):
            s -= Ld[k] * work[Li[k]]
        work[i] = s / Ld[end]
    for i in range(n - 1, -1, -1):          # backward: the diagonal is the row's first entry
        s = work[i]
        start = Up[i]
        for k in range(start + 1, Up[i + 1]):
            s -= Ud[k] * work[Ui[k]]
        work[i] = s / Ud[start]
    for i in range(n):
        x[i] = work[p_out[i]]
