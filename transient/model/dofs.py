"""Sparse blocks on a subset of dofs (the free ones) without SciPy's fancy column indexing."""
import numpy as np
import scipy.sparse as sp


def restrict(A, rows=None, cols=None):
    """A[rows][:, cols] as CSR, rows and cols sorted index arrays (None: all).

    The columns are taken by remapping A's column indices in one pass (kernels.sparse): SciPy's
    column indexing (csr_column_index2) took 0.3-1 s a call on pad_disc, nine calls a setup,
    and the same remapping in NumPy (a cumulative sum over the entries) as long."""
    A = sp.csr_matrix(A)
    if rows is not None and len(rows) != A.shape[0]:
        A = A[rows]
    if cols is None or len(cols) == A.shape[1]:
        return A
    from ..kernels.sparse import csr_take_columns
    new = np.full(A.shape[1], -1, A.indices.dtype)
    new[cols] = np.arange(len(cols))
    indptr, indices, data = csr_take_columns(A.indptr, A.indices, A.data, new)
    out = sp.csr_matrix((data, indices, indptr), shape=(A.shape[0], len(cols)))
    out.has_sorted_indices = A.has_sorted_indices
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
    if not (K.has_sorted_indices and M.has_sorted_indices and K.shape == M.shape
            and np.array_equal(K.indptr, M.indptr) and np.array_equal(K.indices, M.indices)):
        return (K - sigma * M).tocsr()
    from ..kernels.sparse import csr_combined
    indptr, indices, data = csr_combined(K.indptr, K.indices, K.data, M.data, -sigma)
    out = sp.csr_matrix((data, indices, indptr), shape=K.shape)
    out.has_sorted_indices = True
    return out
