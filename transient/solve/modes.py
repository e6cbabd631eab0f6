"""Normal modes by block shift-invert Lanczos (lanczos.py) on a sparse factorization; ARPACK
(scipy eigsh) when the block method stalls."""
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..model.dofs import free_block, shifted
from .lanczos import TOL, NotConverged, block_lanczos
from .mac import mac
from .linsolve import factorize

DENSE_LIMIT = 600   # below this many free dofs a dense eigensolver is faster and exact
BLOCK = 16          # vectors per shift-invert step


@dataclass(frozen=True)
class Modes:
    frequencies: np.ndarray   # (n,) [Hz], ascending; negative for round-off negative eigenvalues
    shapes: np.ndarray        # (ndof, n) mass-normalized, zero on fixed dofs
    backend: str              # factorization used
    timings: dict             # factorization, eigensolver [s]


def shift_sigma(shift):
    """The eigenvalue shift of a shift frequency [Hz]: -(2 pi shift)^2 for a negative one."""
    return np.sign(shift) * (2 * np.pi * shift) ** 2


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
        elsewhere, e.g. lowrank.ContactSolver); otherwise K - sigma M is factorized here. With
        K None, the solve alone defines the problem (a constrained one: solve.tied).
    tol : the block Lanczos' residual tolerance, relative to the largest theta (lanczos.TOL).
    """
    ndof = M.shape[0]
    free = np.arange(ndof) if fixed is None else np.flatnonzero(~np.asarray(fixed))
    # K may be an operator on the free dofs (lowrank.TangentStiffness): the shift-invert
    # needs only its solves, the dense eigensolver and ARPACK its matrix or products
    Kf = free_block(K, free) if sp.issparse(K) else K
    Mf = free_block(M, free)
    del K    # the caller's on all dofs: not held through the factorization and the Lanczos
    n = len(free)
    sigma = shift_sigma(shift)
    timings = {}
    if n <= DENSE_LIMIT and Kf is not None:
        t0 = time.perf_counter()
        lam, vec = sla.eigh(Kf.toarray(), Mf.toarray())
        timings["eigensolver"] = time.perf_counter() - t0
        keep = np.flatnonzero(frequencies_hz(lam) <= fmax) if fmax > 0 else np.arange(min(count, n))
        return _modes(lam[keep], vec[:, keep], free, ndof, "dense", timings)

    t0 = time.perf_counter()
    if solve is None:
        solve = factorize(shifted(Kf, Mf, sigma), backend, definite=sigma <= 0)
    timings["factorization"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lam_max = (2 * np.pi * fmax) ** 2 if fmax > 0 else None
    name = getattr(solve, "backend", "?")
    stalled = None
    try:
        lam, vec, _ = block_lanczos(solve, Mf, sigma, lam_max, count, BLOCK, tol=tol)
    except NotConverged as exc:
        stalled = str(exc)
    if stalled is not None:
        # a spectrum the block method does not resolve: ARPACK, one vector at a time, outside
        # the except clause, whose traceback holds the Lanczos' frame and basis (4 GB at 1M
        # dofs, else held beside the factors through all of ARPACK's solves)
        lam, vec = _arpack(Kf, Mf, sigma, solve, count, fmax)
        name += f" (ARPACK; block Lanczos: {stalled})"
    timings["eigensolver"] = time.perf_counter() - t0
    keep = frequencies_hz(lam) <= fmax if fmax > 0 else slice(0, count)
    lam, vec = lam[keep], vec[:, keep]
    return _modes(lam, vec, free, ndof, name, timings)


def _arpack(Kf, Mf, sigma, solve, count, fmax):
    """scipy eigsh in batches of count, doubled until one mode is above fmax."""
    n = Mf.shape[0]
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    v0 = np.random.default_rng(0).standard_normal(n)
    # shift-invert mode applies only OPinv and M: K may be an operator, or None (a
    # constrained problem that its solve alone defines)
    A = Kf if sp.issparse(Kf) else spla.LinearOperator(
        (n, n), matvec=Kf.__matmul__ if Kf is not None else op.matvec, dtype=float)
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



def receptance(modes, a, b, f, damping):
    """Transfer function from mass-normalized modes: the displacement along b per unit force
    along a [m/N] at frequencies f [Hz], each mode a damped oscillator of ratio `damping`:
    H(f) = sum_j (a . phi_j)(b . phi_j) / (w_j^2 - w^2 + 2 i zeta w_j w). a, b: (ndof,)
    observation rows (sensors: a node's dof along a direction)."""
    wj = 2 * np.pi * modes.frequencies
    w = 2 * np.pi * np.asarray(f, float)[:, None]
    participation = (a @ modes.shapes) * (b @ modes.shapes)
    return np.sum(participation / (wj ** 2 - w ** 2 + 2j * damping * wj * w), axis=1)


def mac_pairs(shapes_a, shapes_b, M):
    """For each mode of a, its partner among the modes of b by the modal assurance criterion in
    the mass (one to one, the assignment that maximizes the summed MAC), and the MAC:
    (partner index or -1, MAC) arrays of len(a). Shapes mass-normalized on the same dofs."""
    from scipy.optimize import linear_sum_assignment
    alike = mac(shapes_a, shapes_b, M)
    rows, cols = linear_sum_assignment(-alike)
    partner = np.full(shapes_a.shape[1], -1)
    partner[rows] = cols
    return partner, np.where(partner >= 0, alike[np.arange(len(partner)), partner], 0.0)
