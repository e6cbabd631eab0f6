"""The left factor L of several pairs' factored rows (C = L B^T), held a pair at a time.

Each pair's points see only its own compatible shapes: stacked, L is block diagonal, and held
dense it is points x every pair's shapes, most of it zeros on a model of many pairs (a brake
corner's), every product with it reading them all (docs/performance.md). Held by pair, each
product is one BLAS call on a pair's block.
"""
import numpy as np

from ..transposed import Transposed


class PairFactors:
    """L (P, r) block diagonal: blocks[k] (p_k, r_k) dense on the points rows[k] and the
    shapes cols[k] (slices), the pairs in the contact set's order. Supports L @ Y, L.T @ Y,
    L[keep] (sorted rows, or a slice) and toarray."""

    __array_ufunc__ = None     # ndarray @ L is refused, never taken as an object array

    def __init__(self, blocks):
        self.blocks = [np.asarray(b) for b in blocks]
        rows = np.concatenate([[0], np.cumsum([b.shape[0] for b in self.blocks])])
        cols = np.concatenate([[0], np.cumsum([b.shape[1] for b in self.blocks])])
        self.rows = [slice(int(a), int(b)) for a, b in zip(rows[:-1], rows[1:])]
        self.cols = [slice(int(a), int(b)) for a, b in zip(cols[:-1], cols[1:])]
        self.shape = (int(rows[-1]), int(cols[-1]))
        self.ndim = 2
        self.dtype = np.dtype(np.float64)

    @property
    def T(self):
        return Transposed(self)

    def __iter__(self):
        """(points slice, shapes slice, L_k) of each pair."""
        return iter(zip(self.rows, self.cols, self.blocks))

    def __matmul__(self, Y):
        """L Y (P, k), or (P,) for Y (r,)."""
        Y = np.asarray(Y)
        out = np.empty((self.shape[0],) + Y.shape[1:], dtype=np.result_type(Y, np.float64))
        for rows, cols, L in self:
            out[rows] = L @ Y[cols]
        return out

    def transpose_times(self, y):
        """L^T y (r, k), or (r,) for y (P,)."""
        y = np.asarray(y)
        return np.concatenate([L.T @ y[rows] for rows, _, L in self], axis=0)

    def __getitem__(self, keep):
        """The rows keep (a slice, or sorted indices: a subset of the points), each pair's
        shapes kept whole, so that B's columns still match."""
        if isinstance(keep, slice):
            keep = np.arange(self.shape[0])[keep]
        keep = np.asarray(keep)
        starts = np.searchsorted(keep, [r.start for r in self.rows] + [self.shape[0]])
        return PairFactors([L[keep[a:b] - rows.start]
                            for rows, L, a, b in zip(self.rows, self.blocks, starts[:-1],
                                                     starts[1:])])

    def toarray(self):
        out = np.zeros(self.shape)
        for rows, cols, L in self:
            out[rows, cols] = L
        return out


def points_gram(L, d):
    """L^T diag(d) L (r, r) of a pair's factor L (p, r) and weights d (p,) on its points: a
    factored pair's contact stiffness or gram on its compatible shapes, C^T diag(d) C =
    B (L^T diag(d) L) B^T, never a points x dofs product."""
    return (L.T * d) @ L


def pair_factors(L):
    """(points slice, shapes slice, L_k) of each pair of a contact set's L: a PairFactors'
    blocks, or one pair's L whole."""
    if isinstance(L, PairFactors):
        return list(L)
    return [(slice(0, L.shape[0]), slice(0, L.shape[1]), L)]
