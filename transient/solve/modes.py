"""Normal modes by block shift-invert Lanczos (lanczos.py) on a sparse factorization; ARPACK
(scipy eigsh) when the block method stalls."""
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..model.dofs import free_block
from .lanczos import TOL, NotConverged, block_lanczos
from .linsolve import factorize

DENSE_LIMIT = 600   # below this many free dofs a dense eigensolver is faster and exact
BLOCK = 16          # vectors per shift-invert step


@dataclass(frozen=True)
class Modes:
    frequencies: np.ndarray   # (n,) [Hz], ascending; negative for round-off negative eigenvalues
    shapes: np.ndarray        # (ndof, n) mass-normalized, zero on fixed dofs
    backend: str              # factorization used
    timings: dict             # factorization, eigensolver [s]


def frequencies_hz(eigenvalues):
    return np.sign(eigenvalues) * np.sqrt(np.abs(eigenvalues)) / (2 * np.pi)


def normal_modes(K, M, fixed=None, count=20, fmax=0.0, shift=-1.0, backend="auto", solve=None,
                 tol=TOL):
    """Lowest modes of (K, M) with the fixed dofs clamped.

    count : number of modes when fmax is 0 (otherwise ARPACK's first batch, if it runs).
    fmax : all modes up to this frequency [Hz] (the batch grows until one is above it).
    shift : shift frequency [Hz] of shift-invert, negative values meaning -(2 pi shift)^2, so that
        K - sigma M stays positive definite even with rigid-body modes.
    solve : optional callable applying (K - sigma M)^-1 on the free dofs (a factorization made
        elsewhere, e.g. lowrank.ContactSolver); otherwise K - sigma M is factorized here.
    tol : the block Lanczos' residual tolerance, relative to the largest theta (lanczos.TOL).
    """
    ndof = K.shape[0]
    free = np.arange(ndof) if fixed is None else np.flatnonzero(~np.asarray(fixed))
    # K may be an operator on the free dofs (lowrank.TangentStiffness): the shift-invert
    # needs only its solves, the dense eigensolver and ARPACK its matrix or products
    Kf = free_block(K, free) if sp.issparse(K) else K
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
        solve = factorize((Kf.tocsr() - sigma * Mf).tocsr(), backend, definite=sigma <= 0)
    timings["factorization"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lam_max = (2 * np.pi * fmax) ** 2 if fmax > 0 else None
    name = getattr(solve, "backend", "?")
    try:
        lam, vec, _ = block_lanczos(solve, Mf, sigma, lam_max, count, BLOCK, tol=tol)
    except NotConverged as exc:
        # a spectrum the block method does not resolve: ARPACK, one vector at a time
        lam, vec = _arpack(Kf, Mf, sigma, solve, count, fmax)
        name += f" (ARPACK; block Lanczos: {exc})"
    timings["eigensolver"] = time.perf_counter() - t0
    keep = frequencies_hz(lam) <= fmax if fmax > 0 else slice(0, count)
    lam, vec = lam[keep], vec[:, keep]
    return _modes(lam, vec, free, ndof, name, timings)


def _arpack(Kf, Mf, sigma, solve, count, fmax):
    """scipy eigsh in batches of count, doubled until one mode is above fmax."""
    n = Kf.shape[0]
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    v0 = np.random.default_rng(0).standard_normal(n)
    A = Kf if sp.issparse(Kf) else spla.LinearOperator(Kf.shape, matvec=Kf.__matmul__,
                                                         dtype=float)
    k = count
    while True:
        k = min(k, n - 2)
        lam, vec = spla.eigsh(A, k=k, M=Mf, sigma=sigma, OPinv=op, which="LM", v0=v0)
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
        if fmax <= 0 or frequencies_hz(lam[-1]) > fmax or k >= n - 2:
            return lam, vec
        k *= 2


def _modes(lam, vec, free, ndof, backend, timings):
    shapes = np.zeros((ndof, len(lam)))
    shapes[free] = vec
    return Modes(frequencies_hz(lam), shapes, backend, timings)

