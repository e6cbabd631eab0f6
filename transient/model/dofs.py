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
