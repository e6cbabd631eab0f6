"""Normal modes by shift-invert Lanczos (scipy eigsh) on a sparse factorization."""
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from ..model.dofs import free_block
from .linsolve import factorize

DENSE_LIMIT = 600   # below this many free dofs a dense eigensolver is faster and exact


@dataclass(frozen=True)
class Modes:
    frequencies: np.ndarray   # (n,) [Hz], ascending; negative for round-off negative eigenvalues
    shapes: np.ndarray        # (ndof, n) mass-normalized, zero on fixed dofs
    backend: str              # factorization used
    timings: dict             # factorization, eigensolver [s]


def frequencies_hz(eigenvalues):
    return np.sign(eigenvalues) * np.sqrt(np.abs(eigenvalues)) / (2 * np.pi)


def normal_modes(K, M, fixed=None, count=20, fmax=0.0, shift=-1.0, backend="auto", solve=None):
    """Lowest modes of (K, M) with the fixed dofs clamped.

    count : number of modes when fmax is 0; otherwise the first batch size.
    fmax : all modes up to this frequency [Hz] (the batch grows until one is above it).
    shift : shift frequency [Hz] of shift-invert, negative values meaning -(2 pi shift)^2, so that
        K - sigma M stays positive definite even with rigid-body modes.
    solve : optional callable applying (K - sigma M)^-1 on the free dofs (a factorization made
        elsewhere, e.g. lowrank.ContactSolver); otherwise K - sigma M is factorized here.
    """
    ndof = K.shape[0]
    free = np.arange(ndof) if fixed is None else np.flatnonzero(~np.asarray(fixed))
    Kf = free_block(K, free)
    Mf = free_block(M, free)
    n = len(free)
    sigma = np.sign(shift) * (2 * np.pi * shift) ** 2
    timings = {}
    if n <= DENSE_LIMIT:
        t0 = time.perf_counter()
        lam, vec = sla.eigh(Kf.toarray(), Mf.toarray())
        timings["eigensolver"] = time.perf_counter() - t0
        keep = np.flatnonzero(frequencies_hz(lam) <= fmax) if fmax > 0 else np.arange(min(count, n))
        return _modes(lam[keep], vec[:, keep], free, ndof, "dense", timings)

    t0 = time.perf_counter()
    if solve is None:
        solve = factorize((Kf - sigma * Mf).tocsr(), backend, definite=sigma <= 0)
    timings["factorization"] = time.perf_counter() - t0
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    v0 = np.random.default_rng(0).standard_normal(n)
    k = count
    t0 = time.perf_counter()
    while True:
        k = min(k, n - 2)
        lam, vec = spla.eigsh(Kf, k=k, M=Mf, sigma=sigma, OPinv=op, which="LM", v0=v0)
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
        if fmax <= 0 or frequencies_hz(lam[-1]) > fmax or k >= n - 2:
            break
        k *= 2
    timings["eigensolver"] = time.perf_counter() - t0
    if fmax > 0:
        keep = frequencies_hz(lam) <= fmax
        lam, vec = lam[keep], vec[:, keep]
    return _modes(lam, vec, free, ndof, getattr(solve, "backend", "?"), timings)


def _modes(lam, vec, free, ndof, backend, timings):
    shapes = np.zeros((ndof, len(lam)))
    shapes[free] = vec
    return Modes(frequencies_hz(lam), shapes, backend, timings)

