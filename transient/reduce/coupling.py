"""The contact rows of the components path's coupling, a pair at a time.

In the parts' coordinates (their bases side by side) a pair's points see only the shapes of
its two parts: its rows are dense on those columns and zero on every other part's. They are
held that way, never as points x every part's columns, and where the rows are factored
(C = L B^T) as the pair's factor L_s and its shapes' rows B_s^T X on those columns, so that
the contact stiffness of the reduced coordinates is a sum of blocks that small, each through
its points' gram L_s^T D L_s (Cr^T diag(w k) Cr, and the steady sliding's Ct^T diag(w k m) Cr).
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator

from ..contact.blocks import pair_factors, points_gram

NORMAL, ALONG, ACROSS = 0, 1, 2


class PairRows:
    """Each pair's rows on the columns of its own parts: blocks[i] = (points' slice, columns,
    L_s, [normal, along, across] (r_s, columns)), the rows of a kind L_s @ Y_kind (the
    tangential ones with friction); L_s None where the rows are not factored: Y_kind are the
    rows themselves (points, columns). Through the factors the contact stiffness of a pair is
    Y^T (L_s^T D L_s) Y: its points' r_s x r_s gram first, then the columns', never a
    points x columns product on both sides."""

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
                self.blocks.append((s, c, Ls, [Y[r, c] for Y in BX]))
        else:
            rows = [contacts.C] + (list(contacts.tangential()) if f else [])
            for s in contacts.slices.values():
                # the columns of the parts the pair's rows (of any kind) touch
                c, Y = X.restricted(sp.vstack([R[s] for R in rows]))
                m = s.stop - s.start
                self.blocks.append((s, c, None,
                                    [Y[k * m:(k + 1) * m] for k in range(len(rows))]))

    def observe(self, q, kind=NORMAL):
        """(P,) the rows of that kind times the reduced coordinates q (N,)."""
        g = np.zeros(self.shape[0])
        for s, c, L, Y in self.blocks:
            g[s] = _left(L, Y[kind] @ q[c])
        return g

    def load(self, y, kind=NORMAL):
        """(N,) the rows' transpose times y (P,): the reduced force of tractions y."""
        f = np.zeros(self.shape[1])
        for s, c, L, Y in self.blocks:
            f[c] += Y[kind].T @ (y[s] if L is None else L.T @ y[s])
        return f

    def operator(self, kind=NORMAL):
        """The rows of that kind as a LinearOperator (P, N): R @ q and R.T @ y."""
        return LinearOperator(self.shape, matvec=lambda q: self.observe(q, kind),
                              rmatvec=lambda y: self.load(y, kind), dtype=float)

    def stiffness(self, Kr, wd, sliding=True):
        """Kr + the contact's tangent at the points' law stiffness wd (P,); sliding=False:
        its normal part alone, without the steady sliding's friction (symmetric)."""
        K = Kr.copy()
        for s, c, L, Y in self.blocks:
            normal = Y[NORMAL]
            block = normal.T @ _through(_points_gram(L, wd[s]), normal)
            if sliding and self.m is not None and np.any(self.m[s]):
                block += Y[ALONG].T @ _through(_points_gram(L, self.m[s] * wd[s]), normal)
            K[np.ix_(c, c)] += block
        return K

    def gram(self, d):
        """basis.contact_gram of every row stacked (sum over kinds of R^T diag(d) R, d's
        negative entries as zero), d (P,): the flexibility criterion's weights in the reduced
        coordinates."""
        n = self.shape[1]
        gram = np.zeros((n, n))
        for s, c, L, Y in self.blocks:
            G = _points_gram(L, np.maximum(d[s], 0.0))
            gram[np.ix_(c, c)] += sum(y.T @ _through(G, y) for y in Y)
        return gram


def _left(L, Y):
    """L Y, or Y where the rows are not factored (L None)."""
    return Y if L is None else L @ Y


def _points_gram(L, d):
    """L^T diag(d) L (r_s, r_s) of a pair's factored rows, the weights d themselves where the
    rows are plain (L None)."""
    return d if L is None else points_gram(L, d)


def _through(G, Y):
    """G Y for a points' gram G, diag(G) Y for plain rows' weights."""
    return G[:, None] * Y if G.ndim == 1 else G @ Y


def _seen(rows):
    """The columns where any of the rows is not zero."""
    return np.flatnonzero(np.logical_or.reduce([np.any(R != 0.0, axis=0) for R in rows]))
