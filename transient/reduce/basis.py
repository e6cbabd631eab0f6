"""Reduced basis: normal modes of the preloaded structure up to fmax, plus static responses to
the contact point loads and the load patterns, M-orthonormalized and re-diagonalized.

The stiffness used is K_lin = K + C^T diag(w k_t*) C, linearized at the preload: in the reduced
coordinates q = T q_r, T^T M T = I and T^T K_lin T = diag(omega^2).
"""
import time
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..case.sizes import peak_rss_gb
from ..kernels.sparse import shares_pattern
from ..model.dofs import free_block, restrict
from .. import blas
from ..solve.lowrank import TangentStiffness, block_columns
from ..solve.modes import normal_modes


BY_COLUMNS_BYTES = 1.5e9   # K^-1 E dense (n x k) when the contact points outnumber their dofs

# the modes' residual, relative to the largest theta: the setup's solves (PARDISO's pivots, the
# low-rank update) are exact only to about 1e-9 of it, and the basis is re-diagonalized on the
# exact K_lin. Against 1e-12: pad_disc_long's Lanczos 6.0-6.4 -> 3.8-4.4 s (15 blocks, not 21),
# histories within 7e-8 (drilled_cube's energies) and 1e-9 (pad_disc's sensors)
MODES_TOL = 1e-9
COLUMN_BLOCK = 128     # columns of an n x s update formed at a time (fewer at scale:
#                        lowrank.block_columns)


@dataclass(frozen=True)
class Basis:
    """The basis T = X A: X (ndof, m) the modes and the static responses (zero on fixed dofs),
    A (m, n) their M-orthonormal, K-diagonal combinations. Kept as the two factors so that a
    later change of coordinates W (the sampled contact's) costs one n x m x n product on X
    instead of two on the ndof rows (T = X A, then T W)."""
    X: np.ndarray            # (ndof, m)
    A: np.ndarray            # (m, n)
    omega2: np.ndarray       # (n,) [rad^2/s^2], ascending
    n_modes: int             # normal modes below fmax in the basis
    n_static: int            # static vectors added (loads, the preload, friction's coupling
    #                          loads; before removing dependent directions)
    timings: dict
    n_contact_shapes: int = 0      # contact shapes kept (reduction.statics_tolerance)
    contact_flexibility: np.ndarray = None   # mu of contact_shapes, descending
    n_static_kept: int = 0         # static directions (contact shapes and loads) beyond the modes
    peaks: dict = None             # the process's peak memory after each of timings' parts [GB]
    mode_hz: np.ndarray = None     # (n_modes,) the frequencies of the modes, X's first columns

    @property
    def T(self):
        return self.expand()

    def expand(self, W=None):
        """T W (ndof, k), T itself when W is None; W (n, k) or (n,)."""
        return self.X @ (self.A if W is None else self.A @ W)

    def coordinates(self, y):
        """T^T y for y (ndof,): the reduced load of y, or the coordinates of M u for T^T M T = I."""
        return self.A.T @ (self.X.T @ y)


def reduced_basis(K_lin, M, fixed, fmax, statics, solve, shift_hz, contact=None, tol=0.0,
                  coupling=None, Mf=None, solved=None):
    """Basis of the modes of (K_lin, M) up to fmax [Hz] and the responses to static loads.
    K_lin: sparse on the model dofs, or the tangent on the free dofs as an operator
    (lowrank.TangentStiffness, what the setup passes).

    statics (ndof, s): load vectors (load patterns, and K_lin u for a displacement u to
    represent, such as the preload). solve applies (K_lin - sigma M)^-1 on the free dofs,
    sigma = -(2 pi shift_hz)^2: the small shift keeps floating parts solvable.

    contact (C, stiffness (m,)): adds the responses to the contact point loads C^T, only the
    shapes of them that matter (`contact_shapes`, tol); C (m, ndof), or (m, nfree) already
    restricted to the free dofs (the factorization stage's).

    coupling: the loads of the modes Phi (nfree, n) that the basis must respond to beyond them
    (the friction forces their motion drives: reduce.stage.FrictionLoads, called with Phi and
    its eigenvalues, its width(omega2) columns), or None.
    Mf: M on the free dofs when the caller has it (the contact solver's), or None.
    solved: called after the last solve (the owner of the factors frees them), or None.
    """
    t0 = time.perf_counter()
    free = np.flatnonzero(~fixed)
    # the free blocks once: the modes, the projections and the reduced stiffness share them
    Kf = TangentStiffness(free_block(K_lin, free)) if sp.issparse(K_lin) else K_lin
    Mf = free_block(M, free) if Mf is None else Mf
    modes = normal_modes(Kf, Mf, None, count=40, fmax=fmax, shift=-shift_hz, solve=solve,
                         tol=MODES_TOL)
    t_modes = time.perf_counter() - t0
    peaks = {"modes": peak_rss_gb()}
    Phi = modes.shapes
    n, m = len(free), Phi.shape[1]
    columns, shapes, held = [], None, []
    omega2_modes = (2 * np.pi * modes.frequencies) ** 2
    width = (coupling.width(omega2_modes) if coupling is not None else 0) + statics.shape[1]
    n_static = width         # the friction's coupling loads are static directions asked too

    def into_basis(r):
        """X, allocated once the r contact shapes kept are known: they are solved into it."""
        held.append(np.empty((len(fixed), m + r + width)))
        return held[0][:n, m:m + r]
    mu = np.zeros(0)
    n_shapes = 0
    if contact is not None and len(contact[1]):
        C, stiffness = contact
        Cf = C if C is None or C.shape[1] == len(free) else restrict(C, cols=free)
        shapes, mu = contact_shapes(Cf, stiffness, solve, Phi, omega2_modes, tol,
                                    out=into_basis)
        C = Cf = contact = None          # a dense copy at scale: not held through the basis
        columns.append(shapes)
        n_shapes = shapes.shape[1]
    if coupling is not None:
        columns.append(np.atleast_2d(solve(np.asfortranarray(coupling(Phi, omega2_modes))).T).T)
    if statics.shape[1]:
        columns.append(np.atleast_2d(solve(np.asfortranarray(statics[free])).T).T)
    t_static = time.perf_counter() - t0 - t_modes
    peaks["statics"] = peak_rss_gb()
    if solved is not None:
        solved()
    # X in the making: its first n rows hold the free rows [Phi, S] (S a strided view, which
    # BLAS takes as is) until they are scattered to their dofs at the end, so that S and X are
    # one array, the contact shapes are solved into it, and M S and K S are never whole: an
    # n x s array is the setup's largest at scale (4x pad_disc, 1.2 GB: its peak was 8.02 GB
    # with S and M S, 7.64 GB with X and the shapes beside it, 7.14 GB now)
    X = held[0] if held else np.empty((len(fixed), m + sum(c.shape[1] for c in columns)))
    X[:n, :m] = Phi
    S = X[:n, m:]
    start, c = 0, None
    while columns:
        c = columns.pop(0)
        if c.base is not X:            # the shapes solved into X are in place already
            S[:, start:start + c.shape[1]] = c
        start += c.shape[1]
    shapes = c = None        # the pieces go as they are copied
    # no solve from here on: the products and eighs of a few hundred columns on every core
    with blas.every_core():
        # the static responses without what the modes already hold (twice, for round-off): on
        # a part free to move they are dominated by its rigid motion, 1e10 times their elastic
        # part, which the independence test below would otherwise take for round-off and drop
        # with them. By column blocks through one buffer: Phi P whole would be another n x s
        # array, and a new n x 128 array per block fresh memory each time.
        # M and K of one assembly: their products with a block read the pattern once
        shared = shares_pattern(Mf, Kf.K)
        MPhi, KPhi = Kf.with_mass(Mf, Phi, shared)
        width = block_columns(n, COLUMN_BLOCK)
        buf = np.empty((n, min(width, S.shape[1])))
        for _ in range(2):
            P = MPhi.T @ S
            for start in range(0, P.shape[1], width):
                block = slice(start, start + width)
                S[:, block] -= np.matmul(Phi, P[:, block], out=buf[:, :P[:, block].shape[1]])
        del buf
        # unit M-norm columns, then drop directions the others already span, then diagonalize
        # (the K Gram in the same pass over S, scaled and cut as S is below)
        G, GK = _grams(Mf, Kf, S, shared)
        norms = np.sqrt(np.maximum(np.diag(G), 0.0))
        scale = norms.max() if len(norms) else 0.0
        big = norms > 1e-12 * scale
        if not np.all(big):
            kept = np.flatnonzero(big)
            for to, col in enumerate(kept):       # in place, left to right: to <= col
                if to != col:
                    S[:, to] = S[:, col]
            X = X[:, :m + len(kept)]
            S, norms = X[:n, m:], norms[kept]
            G, GK = G[np.ix_(kept, kept)], GK[np.ix_(kept, kept)]
        S /= norms
        GK /= np.outer(norms, norms)
        lam, V = np.linalg.eigh(G / np.outer(norms, norms))
        keep = lam > 1e-12 * max(lam.max(), 1.0) if len(lam) else np.zeros(0, bool)
        Vs = V[:, keep] / np.sqrt(lam[keep])          # S Vs: M-orthonormal, M-orthogonal to Phi
        n_static_kept = int(keep.sum())
        # X^T K X in blocks, with X = [Phi, S Vs] never formed: S^T K S is the one big product
        KPS = (KPhi.T @ S) @ Vs
        Kr = np.block([[Phi.T @ KPhi, KPS], [KPS.T, Vs.T @ GK @ Vs]])
        omega2, W = sla.eigh(0.5 * (Kr + Kr.T))
        _to_dofs(X, free)
        A = np.vstack([W[:m], Vs @ W[m:]])
    timings = {"modes": t_modes, "statics": t_static,
               "orthonormalization": time.perf_counter() - t0 - t_modes - t_static}
    peaks["orthonormalization"] = peak_rss_gb()
    return Basis(X, A, np.maximum(omega2, 0.0), len(modes.frequencies), n_static,
                 timings, n_shapes, mu, n_static_kept, peaks, modes.frequencies)


def rebase(basis, K0r, K_lin, M, fixed, u):
    """A Basis made on another tangent (a reference friction's: reduce.reference) for the
    tangent K_lin (lowrank.TangentStiffness on the free dofs) and the preload u (ndof,): u's
    M-orthogonal remainder beyond T joins the basis as one column (so that the preload is
    held exactly), and the whole is diagonalized again on K_lin. K0r: T^T K T of the
    structure without the contact's update (T^T K_lin T is K0r plus the update's Gram on the
    rows of T at the interface dofs: T itself, n x r, is never formed)."""
    t0 = time.perf_counter()
    free = np.flatnonzero(~fixed)
    n = len(basis.omega2)
    with blas.every_core():
        Kr = K0r + K_lin.update_gram(_rows_of(basis, free), n)
        r = u.copy()
        for _ in range(2):            # twice, for round-off
            r -= basis.expand(basis.coordinates(M @ r))
        norm = np.sqrt(max(float(r @ (M @ r)), 0.0))
        extra = norm > 1e-10 * np.sqrt(max(float(u @ (M @ u)), 0.0))
        X, A = basis.X, basis.A
        if extra:
            t = r / norm
            Kt = np.zeros_like(t)
            Kt[free] = K_lin @ t[free]
            TKt = basis.coordinates(Kt)
            Kr = np.block([[Kr, TKt[:, None]], [TKt[None, :], np.array([[t @ Kt]])]])
            X = np.hstack([X, t[:, None]])
            A = np.block([[A, np.zeros((A.shape[0], 1))], [np.zeros((1, n)), 1.0]])
        omega2, W = sla.eigh(0.5 * (Kr + Kr.T))
        A = A @ W
    timings = {"rebase": time.perf_counter() - t0}
    return Basis(X, A, np.maximum(omega2, 0.0), basis.n_modes, basis.n_static + 1, timings,
                 basis.n_contact_shapes, basis.contact_flexibility,
                 basis.n_static_kept + int(extra), {"rebase": peak_rss_gb()}, basis.mode_hz)


def structural_gram(basis, K_lin, fixed):
    """T^T K T of a Basis diagonalized on K_lin (lowrank.TangentStiffness): diag(omega^2)
    without the contact's update (rebase's K0r)."""
    with blas.every_core():
        rows = _rows_of(basis, np.flatnonzero(~fixed))
        return np.diag(basis.omega2) - K_lin.update_gram(rows, len(basis.omega2))


def _rows_of(basis, free):
    """rows(idx): the basis T = X A at the free dofs idx (indices among the free dofs)."""
    return lambda idx: basis.X[free[idx]] @ basis.A


def _grams(M, K, S, shared=None):
    """(S^T M S, S^T K S) for M sparse and K a lowrank.TangentStiffness, by column blocks of
    M S and K S (K.with_mass: one pass over the pattern and the block for both; shared as
    there): never an n x s product whole, and each block of S copied once. Each block's
    column is taken down to its diagonal block and mirrored (half the n s^2 flops: the Grams
    were 1.5 s of pad_disc's cea)."""
    s, width = S.shape[1], block_columns(S.shape[0], COLUMN_BLOCK)
    Gs = (np.empty((s, s)), np.empty((s, s)))
    for start in range(0, s, width):
        stop = min(start + width, s)
        part = np.ascontiguousarray(S[:, start:stop])
        products = list(K.with_mass(M, part, shared))
        for i, G in enumerate(Gs):
            G[:stop, start:stop] = S[:, :stop].T @ products[i]
            G[start:stop, :start] = G[:start, start:stop].T
            products[i] = None       # (two n x 128 blocks at once, 136 MB on pad_disc)
        part = None        # not held while the next block is copied (n x 128: 68 MB)
    return Gs


def _to_dofs(X, free, rows=4096):
    """X's first len(free) rows moved to the rows `free` (ascending), the others zeroed, in
    place: from the last row up, each to a row at or below its own (free[i] >= i), by pieces
    of at most `rows` rows so that NumPy's copy of an overlapping piece stays small."""
    n = len(free)
    shift = free - np.arange(n)
    ends = np.r_[np.flatnonzero(np.diff(shift)) + 1, n]
    for stop, start in zip(ends[::-1], np.r_[0, ends[:-1]][::-1]):
        d = int(shift[start])
        if d == 0:
            continue
        for top in range(stop, start, -rows):
            low = max(start, top - rows)
            X[low + d:top + d] = X[low:top]
    fixed = np.ones(X.shape[0], bool)
    fixed[free] = False
    X[fixed] = 0.0


def contact_shapes(C, stiffness, solve, Phi, omega2, tol, block=256, out=None):
    """The responses to the contact point loads that change the contact stiffness by tol or more.

    S = K^-1 C^T (n, m) are the responses to the m contact point loads; beyond the modes Phi
    (M-normalized, eigenvalues omega2) their flexibility at the points is
    F = C S - (C Phi) diag(omega2)^-1 (C Phi)^T. With D = diag(stiffness) the contact law's
    stiffness at each point (w k_t), the eigenvalues mu_i of D^1/2 F D^1/2 are the structural
    flexibility of each contact shape relative to the law's: a shape with mu_i < tol changes
    the stiffness of the two in series by less than tol, so it is dropped (tol = 0 keeps all).

    F is accumulated from solves of `block` loads at a time and the shapes kept, K^-1 C^T D^1/2
    u_i, solved for at the end: memory n x block and m x m, not n x m (a fine rule has
    thousands of points).

    C None: the solver's own rows, which its row space (solve.row_space) stands for.
    out: out(r) gives the (n, r) array the r shapes kept are solved into, on the paths by
    columns (the basis' own columns: no second n x r array), or None.

    Returns (shapes (n, r), mu (m,) descending).
    """
    known = getattr(solve, "row_space", None)
    if C is None:
        # the solver's own rows (lowrank.ContactSolver), held as their space: Rm V^T on cols
        return _contact_shapes_by_columns(None, stiffness, solve, Phi, omega2, tol, known.cols,
                                          out)
    m = C.shape[0]
    CT = C.T.tocsc()
    if tol <= 0:
        return np.atleast_2d(solve(np.asfortranarray(CT.toarray())).T).T, np.zeros(0)
    cols = np.unique(sp.csr_matrix(C).indices)
    # by columns needs K^-1 E (n x k) unless the solver holds the rows' space already
    held = known is not None and np.array_equal(known.cols, cols) and len(known.Rm) == m
    if len(cols) < m and (held or 8.0 * C.shape[1] * len(cols) <= BY_COLUMNS_BYTES):
        return _contact_shapes_by_columns(C, stiffness, solve, Phi, omega2, tol, cols, out)
    F = np.empty((m, m))
    for start in range(0, m, block):
        cols = slice(start, min(start + block, m))
        F[:, cols] = C @ solve(np.asfortranarray(CT[:, cols].toarray()))
    d = np.sqrt(np.maximum(stiffness, 0.0))
    CPhi = np.asarray(C @ Phi)
    F -= (CPhi / np.maximum(omega2, 1e-300)) @ CPhi.T
    F = 0.5 * (F + F.T) * d[:, None] * d[None, :]
    mu, U = sla.eigh(F, overwrite_a=True)
    mu, U = mu[::-1], U[:, ::-1]
    kept = mu >= tol
    if not np.any(kept):
        return np.zeros((C.shape[1], 0)), mu
    return np.atleast_2d(solve(np.asfortranarray(CT @ (d[:, None] * U[:, kept]))).T).T, mu


def _contact_shapes_by_columns(C, stiffness, solve, Phi, omega2, tol, cols, out=None):
    """contact_shapes when the m points touch only k < m dofs (a fine rule): with E the
    selection of those dofs, C = Cc E^T and F = Cc H Cc^T, H = E^T K^-1 E minus the modes'
    part (k x k, from k solves). With X = D^1/2 Cc and H = H^1/2 H^1/2, D^1/2 F D^1/2 = Y Y^T,
    Y = X H^1/2 (m x k): its singular values give mu and its left vectors the u_i, and the
    shapes are (K^-1 E) X^T u_i. When the solver is a ContactSolver, E is replaced by the
    basis E V of the rows' space it already solved for (Cc = Rm V^T; rho < k columns for a
    regularized rule)."""
    n, k = Phi.shape[0], len(cols)
    known = getattr(solve, "row_space", None)
    if known is not None and np.array_equal(known.cols, cols) and (
            C is None or len(known.Rm) == C.shape[0]):
        # the solver, built on these contact rows (lowrank.ContactSolver), has K^-1 E V = Z R
        # already, V a basis of the rows' space, and the rows in it, Cc = Rm: no solves here,
        # no n x k array
        V, Cc, R = known.V, known.Rm, known.R()
        H = known.G @ R

        def response(Y):
            return known.responses(R @ Y, None if out is None else out(Y.shape[1]))
    else:
        V = None
        Cc = sp.csr_matrix(C)[:, cols].toarray()
        E = np.zeros((n, k), order="F")
        E[cols, np.arange(k)] = 1.0
        KE = np.atleast_2d(solve(E).T).T
        H = KE[cols]

        def response(Y):
            return KE @ Y if out is None else np.matmul(KE, Y, out=out(Y.shape[1]))
    PhiE = Phi[cols] if V is None else V.T @ Phi[cols]
    H = H - (PhiE / np.maximum(omega2, 1e-300)) @ PhiE.T
    solves = V is not None and not known.held       # else a product with Z or K^-1 E
    return flexible_shapes(H, Cc, stiffness, tol, response, solves)


def contact_gram(Cc, stiffness):
    """X^T X with X = D^1/2 Cc: the rows Cc (m, k) dense weighted by the law's stiffness
    (m,), its negative entries as zero (flexible_shapes')."""
    X = np.sqrt(np.maximum(stiffness, 0.0))[:, None] * Cc
    return X.T @ X


def flexible_shapes(H, Cc, stiffness, tol, response, solves=False, gram=None):
    """The contact shapes of a flexibility H = E^T K^-1 E (k x k, beyond the modes) of the
    load basis E of the rows Cc (m x k: C = Cc E^T), the law's stiffness (m,) at the points:
    with Y = D^1/2 Cc H^1/2, mu the eigenvalues of Y Y^T; response(Z) gives K^-1 E Z, and the
    shapes kept (mu >= tol) are response(X^T u_i). solves: response solves (its products on
    one thread). gram: Cc^T D Cc when the caller forms it cheaper (Cc, stiffness unused).
    Returns (shapes (n, r), mu (k,) descending)."""
    lam, W = np.linalg.eigh(0.5 * (H + H.T))
    root = (W * np.sqrt(np.maximum(lam, 0.0))) @ W.T
    # Y Y^T and Y^T Y = H^1/2 X^T X H^1/2 share their eigenvalues mu: the k x k one is the
    # cheap one (m >= k), and X^T u_i = X^T Y v_i / sqrt(mu_i) = X^T X H^1/2 v_i / sqrt(mu_i)
    # the points x rho rows (0.40 GB at 1M dofs) are not held while the shapes are solved
    XtX = contact_gram(Cc, stiffness) if gram is None else gram
    mu, Q = np.linalg.eigh(root @ XtX @ root)
    mu, Q = np.maximum(mu[::-1], 0.0), Q[:, ::-1]
    kept = mu >= tol
    with nullcontext() if solves else blas.every_core():
        return response(XtX @ (root @ (Q[:, kept] / np.sqrt(mu[kept])))), mu
