"""The contact rows of the components path's coupling, a pair at a time.

In the parts' coordinates (their bases side by side) a pair's points see only the shapes of
its two parts: its rows are dense on those columns and zero on every other part's. They are
formed and held that way, never as points x every part's columns, so the coupling's rows take
the pairs' blocks and the contact stiffness of the reduced coordinates is a sum of blocks that
small (Cr^T diag(w k) Cr, and the steady sliding's Ct^T diag(w k m) Cr).
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator

from ..contact.blocks import pair_factors
from .basis import contact_gram

NORMAL, ALONG, ACROSS = 0, 1, 2


class PairRows:
    """Each pair's rows on the columns of its own parts: blocks[i] = (points' slice, columns,
    [normal, along, across] dense (points, columns)), the tangential ones with friction."""

    def __init__(self, contacts, X):
        """X (ndof, N): the parts' bases side by side (reduce.synthesis.Synthesis)."""
        f = contacts.friction
        self.shape = (contacts.n_points, X.shape[1])
        self.m = None if f is None else f.m
        self.blocks = []
        if contacts.factors is not None:
            # C = L B^T: B^T X is small (compatible shapes x columns); a pair's points take
            # the factor columns of its own shapes
            L, B = contacts.factors
            BX = [b.T @ X for b in [B] + ([f.along, f.across] if f else [])]
            for s, r, Ls in pair_factors(L):
                c = _seen([Y[r] for Y in BX])
                self.blocks.append((s, c, [Ls @ Y[r, c] for Y in BX]))
        else:
            rows = [contacts.C] + (list(contacts.tangential()) if f else [])
            for s in contacts.slices.values():
                # the columns of the parts the pair's rows (of any kind) touch
                c, Y = X.restricted(sp.vstack([R[s] for R in rows]))
                m = s.stop - s.start
                self.blocks.append((s, c, [Y[k * m:(k + 1) * m] for k in range(len(rows))]))

    def observe(self, q, kind=NORMAL):
        """(P,) the rows of that kind times the reduced coordinates q (N,)."""
        g = np.zeros(self.shape[0])
        for s, c, rows in self.blocks:
            g[s] = rows[kind] @ q[c]
        return g

    def load(self, y, kind=NORMAL):
        """(N,) the rows' transpose times y (P,): the reduced force of tractions y."""
        f = np.zeros(self.shape[1])
        for s, c, rows in self.blocks:
            f[c] += rows[kind].T @ y[s]
        return f

    def operator(self, kind=NORMAL):
        """The rows of that kind as a LinearOperator (P, N): R @ q and R.T @ y."""
        return LinearOperator(self.shape, matvec=lambda q: self.observe(q, kind),
                              rmatvec=lambda y: self.load(y, kind), dtype=float)

    def stiffness(self, Kr, wd, sliding=True):
        """Kr + the contact's tangent at the points' law stiffness wd (P,); sliding=False:
        its normal part alone, without the steady sliding's friction (symmetric)."""
        K = Kr.copy()
        for s, c, rows in self.blocks:
            normal = rows[NORMAL]
            left = (normal + self.m[s, None] * rows[ALONG] if sliding and self.m is not None
                    else normal)
            K[np.ix_(c, c)] += (left.T * wd[s]) @ normal
        return K

    def gram(self, d):
        """basis.contact_gram of every row stacked (sum over kinds of R^T diag(d) R), d (P,):
        the flexibility criterion's weights in the reduced coordinates."""
        n = self.shape[1]
        gram = np.zeros((n, n))
        for s, c, rows in self.blocks:
            gram[np.ix_(c, c)] += contact_gram(np.vstack(rows), np.tile(d[s], len(rows)))
        return gram


def _seen(rows):
    """The columns where any of the rows is not zero."""
    return np.flatnonzero(np.logical_or.reduce([np.any(R != 0.0, axis=0) for R in rows]))
