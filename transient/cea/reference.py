"""Complex modes of the full model by shift-invert Arnoldi (the reference of the reduced CEA).

The first-order pencil A z = lambda B z, A = [[0, I], [-K, -D]], B = [[I, 0], [0, M]], is
inverted about complex shifts sigma on the imaginary axis: (A - sigma B) z = b needs only
(K + sigma D + sigma^2 M) x = -b2 - (D + sigma M) b1, then y = b1 + sigma x, so one complex
sparse LU of n dofs per shift. ARPACK (scipy eigs) finds the eigenvalues nearest each shift.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..solve.linsolve import factorize_complex
from .modes import ComplexModes


def _near(M, D, K, sigma, k, v0):
    n = K.shape[0]
    solve = factorize_complex(sp.csr_matrix(K + sigma * D + sigma ** 2 * M, dtype=complex))
    DM = (D + sigma * M).tocsr()

    def op(z):
        b1, b2 = z[:n], M @ z[n:]
        x = solve(-b2 - DM @ b1)
        return np.concatenate([x, b1 + sigma * x])

    A = spla.LinearOperator((2 * n, 2 * n), matvec=op, dtype=complex)
    nu, Z = spla.eigs(A, k=k, which="LM", v0=v0, tol=1e-13)
    return sigma + 1.0 / nu, Z[:n]


def full_complex_modes(M, D, K, fmax, shifts=8, k=12):
    """Every complex mode with 0 <= frequency <= fmax [Hz] of sparse (n, n) M, D, K.

    Shifts i 2 pi f at `shifts` frequencies spread over [0, fmax]; each asks for the k nearest
    eigenvalues, doubled until the farthest lies beyond the spacing of the shifts (so the discs
    searched overlap and no eigenvalue between shifts is missed).
    """
    n = K.shape[0]
    M, D, K = (sp.csr_matrix(X) for X in (M, D, K))
    step = 2 * np.pi * fmax / shifts
    v0 = np.random.default_rng(0).standard_normal(2 * n) + 0j
    found, vectors = [], []
    for j in range(shifts):
        sigma = 1j * step * (j + 0.5)
        kj = k
        while True:
            kj = min(kj, 2 * n - 2)
            lam, Z = _near(M, D, K, sigma, kj, v0)
            if np.abs(lam - sigma).max() > step or kj >= 2 * n - 2:
                break
            kj *= 2
        found.append(lam)
        vectors.append(Z)
    lam, Z = np.concatenate(found), np.hstack(vectors)
    keep = (lam.imag >= 0) & (lam.imag <= 2 * np.pi * fmax)
    lam, Z = lam[keep], Z[:, keep]
    # one of each eigenvalue found from several shifts
    order = np.lexsort((lam.real, lam.imag))
    lam, Z = lam[order], Z[:, order]
    scale = np.abs(lam).max() if len(lam) else 1.0
    distinct = np.ones(len(lam), bool)
    distinct[1:] = np.abs(np.diff(lam)) > 1e-8 * scale
    lam, Z = lam[distinct], Z[:, distinct]
    big = np.argmax(np.abs(Z), axis=0)
    return ComplexModes(lam, Z / Z[big, np.arange(Z.shape[1])])
