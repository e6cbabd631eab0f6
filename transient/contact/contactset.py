"""All contact points of a run stacked: observation rows, initial gaps, weights and laws."""
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..kernels.laws import evaluate
from .laws import law_params


@dataclass(frozen=True)
class ContactSet:
    rows: sp.csr_matrix      # (P, ndof) gap observation of every point, pairs one after another;
    #                          None once released (`released`): C then rebuilds them from factors
    gap0: np.ndarray         # (P,) initial gaps [m]
    weights: np.ndarray      # (P,) w J [m^2]
    code: np.ndarray         # (P,) law code of each point
    params: np.ndarray       # (P, 4) law parameters of each point
    slices: dict             # pair name -> slice of its points
    factors: tuple = None    # (L (P, r), B (ndof, r) sparse) with C = L B^T, when every pair's
    #                          rows are factored (regularized rules: contact.pair.row_factors)

    @cached_property
    def C(self):
        """(P, ndof) CSR: the rows, or L B^T from the factors when they were released."""
        return self.rows if self.rows is not None else factored_rows(*self.factors)

    def released(self):
        """The same set without its explicit rows when the factors hold them: a regularized
        fine rule's rows are dense (points x interface dofs, about 1 GB at 141k dofs), and past
        the preload the stages read them only through the factors."""
        if self.factors is None or self.rows is None:
            return self
        return replace(self, rows=None)

    @property
    def n_points(self):
        return len(self.gap0)

    def laws(self, g):
        """Pressure p, tangent k_t and potential Phi at gaps g (P,)."""
        p, kt, phi = np.empty_like(g), np.empty_like(g), np.empty_like(g)
        evaluate(self.code, self.params, np.ascontiguousarray(g), p, kt, phi)
        return p, kt, phi

    def subset(self, keep, weights):
        """The points keep (sorted indices) with new weights; pairs stay contiguous."""
        bounds = {name: np.searchsorted(keep, [s.start, s.stop]) for name, s in self.slices.items()}
        factors = None if self.factors is None else (self.factors[0][keep], self.factors[1])
        rows = self.rows[keep] if self.rows is not None else factored_rows(*factors)
        return ContactSet(rows, self.gap0[keep], weights, self.code[keep],
                          self.params[keep], {name: slice(int(a), int(b))
                                              for name, (a, b) in bounds.items()}, factors)

    def observe(self, T):
        """C T (P, k) for a dense T (ndof, k): from the factors when held, L (B^T T), which
        reads r x ndof sparse entries instead of the P dense rows (pad_disc: 1.9 s -> 0.2)."""
        if self.factors is None:
            return np.asarray(self.C @ T)
        L, B = self.factors
        return L @ np.asarray(B.T @ T)

    def force(self, u):
        """Contact force C^T (w p) [N] at displacement u, with gaps, pressures and tangents."""
        g = self.C @ u + self.gap0
        p, kt, _ = self.laws(g)
        return self.C.T @ (self.weights * p), g, p, kt


def factored_rows(L, B):
    """L B^T (P, ndof) as CSR, on the dofs B touches only (L (P, r) dense, B (ndof, r) CSR)."""
    B = sp.csr_matrix(B)
    cols = np.flatnonzero(np.diff(B.indptr))
    dense = L @ B[cols].toarray().T
    P = dense.shape[0]
    rows = sp.csr_matrix((dense.ravel(), np.tile(cols, P), np.arange(P + 1) * len(cols)),
                         shape=(P, B.shape[0]))
    rows.eliminate_zeros()
    return rows


def stack(pairs, ndof):
    """The contact set of a run's pairs (empty when there are none)."""
    if not pairs:
        return ContactSet(sp.csr_matrix((0, ndof)), np.zeros(0), np.zeros(0),
                          np.zeros(0, np.int64), np.zeros((0, 4)), {})
    rows, gap0, w, code, params, slices = [], [], [], [], [], {}
    start = 0
    for pair in pairs:
        n = pair.rule.n_points
        c, prm = law_params(pair.spec.law, pair.k)
        rows.append(sp.csr_matrix(pair.observation(ndof)))
        gap0.append(pair.rule.gap0)
        w.append(pair.rule.weights)
        code.append(np.full(n, c, np.int64))
        params.append(np.tile(prm, (n, 1)))
        slices[pair.name] = slice(start, start + n)
        start += n
    C = sp.vstack(rows).tocsr()
    C.eliminate_zeros()
    factors = None
    if all(pair.factors is not None for pair in pairs):
        factors = (sla.block_diag(*[pair.factors[0] for pair in pairs]),
                   sp.hstack([pair.factors[1] for pair in pairs]).tocsr())
    return ContactSet(C, np.concatenate(gap0), np.concatenate(w), np.concatenate(code),
                      np.vstack(params), slices, factors)
