"""The components path's synthesis basis X: each part's dense basis T_p on its own dofs, zero
elsewhere, held as the parts' blocks side by side.

Stored as one sparse matrix it would be the same entries, but every product with it (X q for
the preload and the fields, X^T f for loads, B^T X for the contact's rows, T^T H T for the loss)
would go through SciPy's single-threaded sparse loops over every stored entry. Held by part,
each is a dense BLAS product on the part's block, on every core the section allows.
"""
import numpy as np
import scipy.sparse as sp

from ..kernels.sparse import csr_dot
from ..transposed import Transposed

# a sparse row block R (m, n_p) is taken dense against a part's basis where at least this
# share of its (touched rows x touched dofs) holds entries: the compatible shapes' B^T, dense
# on the interface, go through BLAS; a contact rule's rows, a few dofs each, stay sparse
DENSE_SHARE = 0.1
DENSE_BYTES = 256e6        # and the dense copy of the block stays below this


class Synthesis:
    """X (ndof, N): the parts' bases T_p (n_p, w_p) on their dofs dofs_p, columns side by
    side in the parts' order. Supports X @ Y, X.T @ Y, R @ X for a sparse R, and the
    congruence T^T H T (congruence) of a sparse H, each by part."""

    __array_ufunc__ = None     # ndarray @ X defers to __rmatmul__, never an object array

    def __init__(self, ndof, dofs, bases):
        self.parts = tuple((np.asarray(d), np.asarray(T, dtype=np.float64))
                           for d, T in zip(dofs, bases))
        widths = [T.shape[1] for _, T in self.parts]
        self.offsets = np.concatenate([[0], np.cumsum(widths)]).astype(int)
        self.shape = (int(ndof), int(self.offsets[-1]))
        self.ndim = 2
        self.dtype = np.dtype(np.float64)
        # each dof's part (-1: in none, a fixed dof): the congruence's blocks of H
        self.owner = np.full(ndof, -1)
        for p, (d, _) in enumerate(self.parts):
            self.owner[d] = p

    def toarray(self):
        """X dense (ndof, N): for a small model, or a test."""
        out = np.zeros(self.shape)
        for p, (d, T) in enumerate(self.parts):
            out[d, self.columns(p)] = T
        return out

    def columns(self, p):
        """The slice of part p's columns."""
        return slice(self.offsets[p], self.offsets[p + 1])

    @property
    def T(self):
        return Transposed(self)

    def __matmul__(self, Y):
        """X Y (ndof, k), or (ndof,) for Y (N,)."""
        Y = np.asarray(Y)
        out = np.zeros((self.shape[0],) + Y.shape[1:], dtype=np.result_type(Y, np.float64))
        for p, (d, T) in enumerate(self.parts):
            out[d] = T @ Y[self.columns(p)]
        return out

    def transpose_times(self, Y):
        """X^T Y (N, k), or (N,) for Y (ndof,)."""
        Y = np.asarray(Y)
        return np.concatenate([T.T @ Y[d] for d, T in self.parts], axis=0)

    def __rmatmul__(self, R):
        """R X (m, N) dense for R (m, ndof), sparse or dense."""
        if not sp.issparse(R):
            R = np.asarray(R)
            out = np.zeros(R.shape[:-1] + (self.shape[1],), dtype=np.result_type(R, np.float64))
            for p, (d, T) in enumerate(self.parts):
                out[..., self.columns(p)] = R[..., d] @ T
            return out
        R = R.tocsc()
        out = np.zeros((R.shape[0], self.shape[1]))
        for p, (d, T) in enumerate(self.parts):
            out[:, self.columns(p)] = _block_times(R[:, d], T)
        return out

    def restricted(self, R):
        """(columns, R X[:, columns]) for a sparse R (m, ndof): the columns of the parts R
        touches, and the product on them alone (a pair's rows see two parts)."""
        R = R.tocsc()
        cols, blocks = [], []
        for p, (d, T) in enumerate(self.parts):
            Rp = R[:, d]
            if Rp.nnz:
                cols.append(np.arange(self.offsets[p], self.offsets[p + 1]))
                blocks.append(_block_times(Rp, T))
        if not cols:
            return np.zeros(0, dtype=int), np.zeros((R.shape[0], 0))
        return np.concatenate(cols), np.hstack(blocks)

    def congruence(self, H):
        """X^T H X (N, N) dense for a sparse H (ndof, ndof), a block per pair of parts that
        H couples (on one part each, for a loss assembled part by part)."""
        H = H.tocsr()
        G = np.zeros((self.shape[1], self.shape[1]))
        for p, (d, T) in enumerate(self.parts):
            Hp = H[d]
            for q in np.unique(self.owner[Hp.indices]):
                if q < 0:
                    continue
                dq, Tq = self.parts[q]
                G[self.columns(p), self.columns(q)] = T.T @ csr_dot(Hp[:, dq].tocsr(), Tq)
        return G



def _block_times(R, T):
    """R T for a sparse R (m, n_p) and a dense T (n_p, w): on the rows and dofs R touches,
    dense by BLAS where R is dense there (DENSE_SHARE), by csr_dot (both cores) otherwise."""
    R = R.tocsr()
    out = np.zeros((R.shape[0], T.shape[1]))
    if not R.nnz:
        return out
    rows = np.flatnonzero(np.diff(R.indptr))
    dofs = np.unique(R.indices)
    size = len(rows) * len(dofs)
    sub = R[rows][:, dofs]
    if R.nnz >= DENSE_SHARE * size and 8 * size <= DENSE_BYTES:
        out[rows] = sub.toarray() @ T[dofs]
    else:
        out[rows] = csr_dot(sub.tocsr(), np.ascontiguousarray(T[dofs]))
    return out
