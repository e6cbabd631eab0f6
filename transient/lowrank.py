"""Solves with K - sigma M + C^T diag(d) C for any diagonal d, from one sparse factorization.

Contact couples the interface dofs densely (regularized rows span the whole interface), which
makes factorizing K + C^T D C slow and memory hungry. With m contact points, the Woodbury
identity needs only A0 = K - sigma M factorized once, Z = A0^-1 C^T (m solves) and G = C Z:

    (A0 + C^T D C)^-1 b = y - Z (I + D G)^-1 D C y,   y = A0^-1 b,

so a new tangent D costs an m x m factorization, and a solve one sparse solve plus O(n m).
"""
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .linsolve import factorize

MAX_BYTES = 1.5e9     # Z = A0^-1 C^T dense; beyond this, factorize A0 + C^T D C directly
BLOCK = 256           # right-hand sides per solve when forming Z (bounds the solver's copies)


class ContactSolver:
    """Factorization of A0 = K - sigma M on the free dofs, updated by contact tangents.

    The update C^T D C has rank at most min(m, k), k the dofs the contact rows touch: with more
    points than interface dofs (a fine rule: 7734 points on 1194 dofs for pad_disc) it is
    written E (Cc^T D Cc) E^T, E the selection of those dofs and Cc = C E, and Woodbury runs on
    the k columns of E instead of the m rows of C.
    """

    def __init__(self, K, M, C, sigma, backend="auto"):
        self.A0 = (K - sigma * M).tocsr() if sigma else K.tocsr()
        self.C = C.tocsr()
        self.sigma = sigma
        self.backend = backend
        n, m = K.shape[0], C.shape[0]
        self.cols = np.unique(self.C.indices)
        k = len(self.cols)
        self.by_columns = k < m
        rank = min(m, k)
        self.lowrank = m > 0 and 8.0 * n * rank <= MAX_BYTES
        self.solve0 = factorize(self.A0, backend, definite=sigma <= 0)
        if self.lowrank:
            CT = self.C.T.tocsc()
            self.Z = np.empty((n, rank), order="F")
            for start in range(0, rank, BLOCK):
                stop = min(start + BLOCK, rank)
                if self.by_columns:
                    b = np.zeros((n, stop - start), order="F")
                    b[self.cols[start:stop], np.arange(stop - start)] = 1.0
                else:
                    b = np.asfortranarray(CT[:, start:stop].toarray())
                self.Z[:, start:stop] = np.atleast_2d(self.solve0(b).T).T
            if self.by_columns:
                self.G = self.Z[self.cols]
                self.Cc = self.C[:, self.cols].toarray()
            else:
                self.G = np.asarray(self.C @ self.Z)

    def solver(self, d):
        """solve(b) for (A0 + C^T diag(d) C) x = b; b (n,) or (n, k)."""
        d = np.asarray(d, float)
        if self.C.shape[0] == 0 or not np.any(d):
            return self.solve0
        if not self.lowrank:
            A = (self.A0 + self.C.T @ sp.diags(d) @ self.C).tocsr()
            return factorize(A, self.backend, definite=False)
        Z, solve0 = self.Z, self.solve0
        if self.by_columns:
            core = self.Cc.T @ (d[:, None] * self.Cc)
            lu = sla.lu_factor(np.eye(len(self.cols)) + core @ self.G)
            cols = self.cols

            def solve(b):
                y = solve0(b)
                return y - Z @ sla.lu_solve(lu, core @ y[cols])
            # the responses to unit loads on the touched dofs E without solving again:
            # (A0 + E core E^T)^-1 E = Z R, R = I - (I + core G)^-1 core G
            solve.on_columns = (cols, Z, lambda: np.eye(len(cols))
                                - sla.lu_solve(lu, core @ self.G))
        else:
            lu = sla.lu_factor(np.eye(len(d)) + d[:, None] * self.G)
            C = self.C

            def solve(b):
                y = solve0(b)
                Cy = C @ y
                return y - Z @ sla.lu_solve(lu, d[:, None] * Cy if Cy.ndim == 2 else d * Cy)
        solve.backend = getattr(self.solve0, "backend", "?") + "+woodbury"
        return solve
