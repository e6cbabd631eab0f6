"""The space of the contact rows on the dofs they touch: an orthonormal basis V and the rows in
it, for the low-rank update of the tangent (lowrank.ContactSolver)."""
import numpy as np

from .. import blas

ROW_SPACE_TOL = 1e-12


def factored_row_space(L, B, cols, tol=ROW_SPACE_TOL):
    """row_space of C E = L B[cols]^T (L (m, r), B (n, r) sparse) without the dense rows: with
    B[cols] = Q R, C E = (L R^T) Q^T, and the eigenvectors X of (L R^T)^T (L R^T) (r x r)
    above tol give V = Q X and Rm = L R^T X, the same cut as row_space (its k x k Gram has
    the same nonzero eigenvalues). The columns of B need not be independent."""
    with blas.every_core():         # products of a few hundred columns (an r x r eigh)
        Q, R = np.linalg.qr(B[cols].toarray())
        LR = L @ R.T
        lam, X = np.linalg.eigh(LR.T @ LR)
        X = X[:, lam > tol * max(lam.max(), 1e-300)]
        return LR @ X, Q @ X


def row_space(Cc, tol=ROW_SPACE_TOL):
    """Cc (m x k) = Rm V^T with V (k x rho) orthonormal: the eigenvectors of Cc^T Cc above
    tol of its largest eigenvalue. The eigenvalues of the Gram carry round-off of about 1e-16
    of the largest, so tol 1e-12 keeps singular values from 1e-6 of the largest: the part of
    C dropped is below 1e-6 of it (projected rows have such round-off directions)."""
    lam, V = np.linalg.eigh(Cc.T @ Cc)
    V = V[:, lam > tol * max(lam.max(), 1e-300)]
    return Cc @ V, V
