"""Sparse blocks on a subset of dofs (the free ones) without SciPy's fancy column indexing."""
import numpy as np
import scipy.sparse as sp


def restrict(A, rows=None, cols=None):
    """A[rows][:, cols] as CSR, rows and cols sorted index arrays (None: all)."""
    return restricted((A,), rows, cols)[0]


def restricted(mats, rows=None, cols=None):
    """[A[rows][:, cols] for A in mats] as CSR (restrict), data as float64: one pass over the
    pattern for matrices that share theirs (kernels.sparse.csr_block), as the M and K of one
    assembly do (pad_disc's free blocks: 0.27 s, one then the other, with SciPy's row
    indexing). SciPy's column indexing (csr_column_index2) took 0.3-1 s a call on pad_disc,
    nine calls a setup, and the same remapping in NumPy (a cumulative sum over the entries)
    as long."""
    from ..kernels.sparse import csr_block, shares_pattern
    mats = [sp.csr_matrix(A) for A in mats]
    m, n = mats[0].shape
    if (rows is None or len(rows) == m) and (cols is None or len(cols) == n):
        return mats
    if len(mats) > 1 and not all(shares_pattern(A, mats[0]) for A in mats[1:]):
        return [restricted((A,), rows, cols)[0] for A in mats]
    A = mats[0]
    new = np.full(n, -1, A.indices.dtype)
    new[np.arange(n) if cols is None else cols] = np.arange(n if cols is None else len(cols))
    indptr, indices, data = csr_block(A.indptr, A.indices,
                                      np.arange(m) if rows is None else np.asarray(rows), new,
                                      tuple(np.asarray(B.data, np.float64) for B in mats))
    out = []
    for B, values in zip(mats, data):
        C = sp.csr_matrix((values, indices, indptr),
                          shape=(len(indptr) - 1, n if cols is None else len(cols)))
        C.has_sorted_indices = B.has_sorted_indices
        out.append(C)
    return out


def free_block(A, free):
    """A on the free dofs, rows and columns (free sorted)."""
    return restrict(A, free, free)


def shifted(K, M, sigma):
    """K - sigma M as CSR. K and M of one assembly share their pattern: then their data are
    combined in one pass (SciPy's sum merges the two patterns entry by entry: 0.18 s on
    pad_disc's free dofs), the entries that cancel left out as SciPy leaves them out."""
    K, M = sp.csr_matrix(K), sp.csr_matrix(M)
    if not sigma:
        return K
    from ..kernels.sparse import csr_combined, shares_pattern
    if not (K.has_sorted_indices and M.has_sorted_indices and shares_pattern(K, M)):
        return (K - sigma * M).tocsr()
    indptr, indices, data = csr_combined(K.indptr, K.indices, K.data, M.data, -sigma)
    out = sp.csr_matrix((data, indices, indptr), shape=K.shape)
    out.has_sorted_indices = True
    return out


def rigid_motions(points, dofs, centre):
    """(len(dofs), 6) the rigid translations and rotations about centre (3,) of the model
    dofs `dofs`, of nodes at points (nn, 3): omega_a e_a x (x - centre) on each dof."""
    node, comp = dofs // 3, dofs % 3
    x = points[node] - centre
    R = np.zeros((len(dofs), 6))
    R[np.arange(len(dofs)), comp] = 1.0
    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3
        R[comp == a, 3 + axis] = -x[comp == a, b]
        R[comp == b, 3 + axis] = x[comp == b, a]
    return R
