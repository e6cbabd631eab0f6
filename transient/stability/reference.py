"""Complex modes of the full model by shift-invert Arnoldi (the reference of the reduced CEA).

The first-order pencil A z = lambda B z, A = [[0, I], [-K, -D]], B = [[I, 0], [0, M]], is
inverted about complex shifts sigma on the imaginary axis: (A - sigma B) z = b needs only
(K + sigma D + sigma^2 M) x = -b2 - (D + sigma M) b1, then y = b1 + sigma x, so one complex
sparse LU of n dofs per shift. ARPACK (scipy eigs) finds the eigenvalues nearest each shift.
Floating parts' rigid modes are taken out first (stability.rigid): ARPACK does not converge on them.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..solve.linsolve import factorize_complex
from .modes import ComplexModes
from .rigid import floating

# ARPACK's restarts per call: a cluster that a call's count cuts through (repeated modes, as
# two identical parts make) can keep it from converging for n * 10 of them, its default
MAX_RESTARTS = 100
# eigenvalues asked of one shift at most (k doubles up to it): ARPACK keeps 2 k + 1 vectors of
# 2 n complex values
MAX_NEAR = 96


SHIFTS = 8          # shifts spread over [0, fmax]


# the damping ratio that a stiffness-proportional damping beta gives the band's top,
# beta pi fmax, beyond which the Arnoldi is not asked: the modes above it, overdamped from
# 1/(pi beta) Hz, spread into a cloud about the shifts in which ARPACK stalls (bar_impact
# resolved at 0.25, not within its bounds at 0.5)
MAX_TOP_DAMPING = 0.3


def top_damping(beta, fmax):
    """The damping ratio beta pi fmax of a stiffness-proportional damping at fmax [Hz]."""
    return beta * np.pi * fmax


class Unresolved(Exception):
    """The Arnoldi did not resolve the modes near a shift within its bounds."""


def full_complex_modes(M, D, K, fmax, rigid=(), shifts=SHIFTS, k=12):
    """Every complex mode with 0 <= frequency <= fmax [Hz] of sparse (n, n) M, D, K.

    Shifts i 2 pi f at `shifts` frequencies spread over [0, fmax]; each asks for the k nearest
    eigenvalues, doubled until the farthest lies beyond the spacing of the shifts (so the discs
    searched overlap and no eigenvalue of its band is missed), and keeps those of its band.
    rigid: each part's rigid motions on the free dofs (stability.rigid.rigid_motions), the ones
    found floating deflated. Raises Unresolved past MAX_RESTARTS or MAX_NEAR.
    """
    n = K.shape[0]
    M, D, K = (sp.csr_matrix(X) for X in (M, D, K))
    # a loss factor's i H holds the rigid motions K holds: each cell's stiffness does
    free = floating(M, D, sp.csr_matrix(K.real) if np.iscomplexobj(K.data) else K, rigid)
    step = 2 * np.pi * fmax / shifts
    v0 = free.project(np.random.default_rng(0).standard_normal(2 * n) + 0j)
    found, vectors = [], []
    lam, Z = free.modes()
    found.append(lam)
    vectors.append(Z)
    for j in range(shifts):
        lam, Z = _around(M, D, K, 1j * step * (j + 0.5), step, k, v0, free)
        # a real eigenvalue (overdamped motion) comes with round-off in its imaginary part
        lam = np.where(np.abs(lam.imag) <= 1e-10 * step * shifts, lam.real + 0j, lam)
        # each eigenvalue from the one shift whose band holds it: repeated modes stay repeated
        top = lam.imag <= step * shifts if j == shifts - 1 else lam.imag < step * (j + 1)
        band = (lam.imag >= step * j) & top
        found.append(lam[band])
        vectors.append(Z[:, band])
    lam, Z = np.concatenate(found), np.hstack(vectors)
    order = np.lexsort((lam.real, lam.imag))
    lam, Z = lam[order], Z[:, order]
    big = np.argmax(np.abs(Z), axis=0)
    return ComplexModes(lam, Z / Z[big, np.arange(Z.shape[1])])


def _around(M, D, K, sigma, radius, k, v0, free):
    """(eigenvalues, displacements) of the k or more eigenvalues nearest sigma, k doubled until
    the farthest lies beyond radius (or every one is found)."""
    n = K.shape[0]
    solve = factorize_complex(sp.csr_matrix(K + sigma * D + sigma ** 2 * M, dtype=complex))
    DM = (D + sigma * M).tocsr()

    def op(z):
        z = free.project(z)
        b1, b2 = z[:n], M @ z[n:]
        x = solve(-b2 - DM @ b1)
        return free.project(np.concatenate([x, b1 + sigma * x]))

    A = spla.LinearOperator((2 * n, 2 * n), matvec=op, dtype=complex)
    size = 2 * (n - free.rank)      # the eigenvalues left once the rigid modes are deflated
    where = f"near {sigma.imag / (2 * np.pi):.0f} Hz"
    kj = k
    while True:
        kj = min(kj, size - 2)
        if kj < 1:
            return np.zeros(0, complex), np.zeros((n, 0), complex)
        try:
            nu, Z = spla.eigs(A, k=kj, which="LM", v0=v0, tol=1e-13, maxiter=MAX_RESTARTS)
        except spla.ArpackNoConvergence:
            if kj >= min(MAX_NEAR, size - 2):
                raise Unresolved(f"ARPACK did not converge {where} in {MAX_RESTARTS} restarts "
                                 f"for {kj} eigenvalues") from None
        else:
            lam = sigma + 1.0 / nu
            if np.abs(lam - sigma).max() > radius or kj >= size - 2:
                return lam, Z[:n]
            if kj >= MAX_NEAR:
                raise Unresolved(f"more than {MAX_NEAR} eigenvalues lie within "
                                 f"{radius / (2 * np.pi):.0f} Hz of the shift {where}")
        kj *= 2
