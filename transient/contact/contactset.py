"""All contact points of a run stacked: observation rows, initial gaps, weights and laws."""
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..kernels.laws import evaluate
from .laws import law_params
from .regularize import factored_rows


@dataclass(frozen=True)
class ContactSet:
    rows: sp.csr_matrix      # (P, ndof) gap observation of every point, pairs one after another;
    #                          None when the factors hold them: C then builds them on demand
    gap0: np.ndarray         # (P,) initial gaps [m]
    weights: np.ndarray      # (P,) w J [m^2]
    code: np.ndarray         # (P,) law code of each point
    params: np.ndarray       # (P, 4) law parameters of each point
    slices: dict             # pair name -> slice of its points
    factors: tuple = None    # (L (P, r), B (ndof, r) sparse) with C = L B^T, when every pair's
    #                          rows are factored (regularized rules: contact.pair.row_factors)

    @cached_property
    def C(self):
        """(P, ndof) CSR: the rows, or L B^T from the factors (formed on the first call: only
        the full system and the rows' fallbacks ask for them)."""
        return self.rows if self.rows is not None else factored_rows(*self.factors)

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
        """Contact force C^T (w p) [N] at displacement u, with gaps, pressures and tangents
        (through the factors when held: L (B^T u) and B (L^T w p))."""
        if self.factors is None:
            g = self.C @ u + self.gap0
        else:
            L, B = self.factors
            g = L @ (B.T @ u) + self.gap0
        p, kt, _ = self.laws(g)
        wp = self.weights * p
        f = self.C.T @ wp if self.factors is None else B @ (L.T @ wp)
        return f, g, p, kt


def stack(pairs, ndof):
    """The contact set of a run's pairs (empty when there are none)."""
    if not pairs:
        return ContactSet(sp.csr_matrix((0, ndof)), np.zeros(0), np.zeros(0),
                          np.zeros(0, np.int64), np.zeros((0, 4)), {})
    rows, gap0, w, code, params, slices = [], [], [], [], [], {}
    start = 0
    factored = all(pair.factors is not None for pair in pairs)
    for pair in pairs:
        n = pair.rule.n_points
        c, prm = law_params(pair.spec.law, pair.k)
        if not factored:
            rows.append(sp.csr_matrix(pair.observation(ndof)))
        gap0.append(pair.rule.gap0)
        w.append(pair.rule.weights)
        code.append(np.full(n, c, np.int64))
        params.append(np.tile(prm, (n, 1)))
        slices[pair.name] = slice(start, start + n)
        start += n
    C, factors = None, None
    if factored:
        # the rows are held as factors only: dense points x interface dofs otherwise
        factors = (sla.block_diag(*[pair.factors[0] for pair in pairs]),
                   sp.hstack([pair.factors[1] for pair in pairs]).tocsr())
    else:
        C = sp.vstack(rows).tocsr()
        C.eliminate_zeros()
    return ContactSet(C, np.concatenate(gap0), np.concatenate(w), np.concatenate(code),
                      np.vstack(params), slices, factors)
