"""Block shift-invert Lanczos: the eigenpairs of (K, M) from a shift sigma up to a bound.

ARPACK's shift-invert (scipy eigsh) applies (K - sigma M)^-1 M to one vector at a time: each
step is a forward and back substitution through the whole factor (memory bound) and a sparse
product with M. Here each step applies it to
a block of b vectors, so the factor and M are read once for b vectors, and the
orthogonalization is matrix-matrix work.

With S = (K - sigma M)^-1 and Q M-orthonormal (Q^T M Q = I), the Krylov space of S M is built
block by block, fully re-orthogonalized (twice, classical Gram-Schmidt in the M inner
product), and T = Q^T M S M Q (block tridiagonal) gives the Ritz pairs: theta, y with
lambda = sigma + 1 / theta and x = Q y. The residual of a pair is the coupling of the last
block, ||S M x - theta x||_M = ||B_j y_j||; a pair is converged when it is below tol times the
largest theta, the norm of S M: a solve is exact only to some 1e-9 of it (PARDISO's perturbed
pivots), so a residual relative to each theta could not reach 1e-12 for the pairs far from the
shift (theta 64 times smaller at fmax than at the first mode of pad_disc), and the basis grew
without end.
Wanted are all lambda <= lam_max, that is theta >= 1 / (lam_max - sigma): the largest theta,
which shift-invert converges first, in order.

Against ARPACK on the same operator (scipy eigsh, what normal_modes ran before) it is faster
and closer to a tighter run (docs/performance.md, "Modes"). With drilled_cube's upper cube floating
(`transient modes`, contact.interface.k = 1e-3) one rigid theta is 1e6 times the elastic ones:
each block is orthonormalized level by level (m_orthonormalize), and each residual measured
against the thetas of its own scale (_reference); a basis that stops converging raises
NotConverged instead of growing (normal_modes then runs ARPACK).
"""
from contextlib import closing

import numpy as np

from .. import progress
from ..kernels.sparse import csr_dot

TOL = 1e-12
STALL = 8         # steps without a pair converging more before the basis is said stalled
OUTLIER = 1e3     # theta ratio beyond which a pair is not the scale of another's residual
BASIS_BYTES = 4e9     # default bound of the basis and M times it (2 N n floats)


def m_orthonormalize(W, M, Qs, MQs, drop=1e-13):
    """W made M-orthogonal to the blocks Qs (MQs = M Qs), then M-orthonormal: returns (Wn, M Wn,
    C, R) with W = Q C + Wn R, Q the blocks side by side, up to the directions of W that Q
    spans to `drop` of W's M-norm (left out).

    The last two blocks first (most of a Krylov block is its recurrence coefficients), then
    every block once, and again only if a pass took more than half of a column's norm (DGKS:
    twice is enough); the basis is read once per pass, block by block (never copied whole).
    The Gram W^T M W resolves directions down to about 1e-8 of its largest eigenvalue only, and
    a block can span far more: the first solves of a floating part are its rigid motion, 1e6
    times their elastic part (drilled_cube's upper cube on a soft contact; with one Gram, the
    elastic directions came out 0.9 off orthogonal). So the strong directions are taken first,
    the rest projected against them and taken in turn, level by level. M Wn is formed from the
    projected block itself, not carried through the projections (carried, its error grew by
    10x a step)."""
    n, w = W.shape
    sizes = [Q.shape[1] for Q in Qs]
    C = np.zeros((sum(sizes), w))
    V = W
    # the recurrence's own blocks first: S M Q_j lies mostly on Q_j and Q_j-1
    if Qs:
        V, Hs = _project(V, Qs[-2:], MQs[-2:])
        C[len(C) - sum(sizes[-2:]):] += np.vstack(Hs)
    out, Mout, top0 = [], [], None
    for level in range(2 + int(np.ceil(-2 * np.log10(drop) / 8))):
        basis, Mbasis = Qs + out, MQs + Mout
        for _ in range(3):
            if not basis:
                break
            V, Hs = _project(V, basis, Mbasis, owned=V is not W)
            if level == 0 and Qs:
                # W's coefficients; a later level's on Qs are the round-off of these
                C += np.vstack(Hs[:len(Qs)])
            MV = csr_dot(M, V)
            G = V.T @ MV
            # projected away this pass, against what is left: again if over half of it went
            # (the M-norm before the pass is what is left plus what went, ||H||^2)
            went = sum(np.einsum("ij,ij->j", H, H) for H in Hs)
            if np.all(went <= np.diag(G)):
                break
        if not basis:
            MV = csr_dot(M, V)
            G = V.T @ MV
        lam, U = np.linalg.eigh(0.5 * (G + G.T))
        if top0 is None:
            # W's M-norms: what the projections took plus what is left
            top0 = max(float(np.max(np.diag(G) + np.einsum("ij,ij->j", C, C), initial=0.0)),
                       1e-300)
        top = float(lam.max(initial=0.0))
        if top <= drop ** 2 * top0:
            break
        strong = lam > max(1e-8 * top, drop ** 2 * top0)
        X = U[:, strong] / np.sqrt(lam[strong])
        Qn, MQn = V @ X, MV @ X
        # once more on these alone (their Gram is well conditioned now): orthonormal to round-off
        G2 = Qn.T @ MQn
        lam2, U2 = np.linalg.eigh(0.5 * (G2 + G2.T))
        X = U2[:, ::-1] / np.sqrt(lam2[::-1])
        out.append(Qn @ X)
        Mout.append(MQn @ X)
        if np.all(strong) or lam[~strong].max() <= drop ** 2 * top0:
            break
        V = V @ U[:, ~strong]
    Wn, MWn = _joined(out, n), _joined(Mout, n)
    return Wn, MWn, C, MWn.T @ W


def _project(V, Qs, MQs, owned=False):
    """V without its M-projections on the blocks Qs, classical Gram-Schmidt (every coefficient
    from the V given); returns (V, the coefficients per block). owned: V may be overwritten,
    else the first block's difference is a new array; the later ones are taken in place, each
    product Q H through one buffer (two fresh n x b arrays a block: 0.8 s of pad_disc_long's
    Lanczos went to these projections)."""
    Hs = [MQ.T @ V for MQ in MQs]
    buf = None
    for Q, H in zip(Qs, Hs):
        if not owned:
            V, owned = V - Q @ H, True
            continue
        if buf is None or buf.shape != (V.shape[0], H.shape[1]):
            buf = np.empty((V.shape[0], H.shape[1]))
        V -= np.matmul(Q, H, out=buf)
    return V, Hs


def _joined(blocks, n):
    """The blocks side by side; one block as it is (a copy of n x b per step otherwise)."""
    return blocks[0] if len(blocks) == 1 else np.hstack(blocks) if blocks else np.zeros((n, 0))


class NotConverged(RuntimeError):
    """The basis reached its bound before the wanted pairs converged."""


def block_lanczos(solve, M, sigma, lam_max=None, count=None, block=16, max_dim=None, seed=0,
                  tol=TOL):
    """Eigenpairs of K x = lambda M x nearest above sigma: those with lambda <= lam_max and the
    first converged one above it, or the first `count`.

    solve(B) applies (K - sigma M)^-1 to a block B (n, b); M sparse (n, n) SPD. Returns
    (lam (k,) ascending, X (n, k) M-orthonormal, steps). Raises NotConverged when the basis
    would pass max_dim first (default: n, or what BASIS_BYTES holds); a Krylov space that
    closes (an invariant subspace) returns what it holds, exact.
    """
    n = M.shape[0]
    max_dim = min(n, max_dim or max(int(BASIS_BYTES / (16.0 * n)), 4 * block))
    rng = np.random.default_rng(seed)
    X0 = rng.standard_normal((n, min(block, n)))
    Qj, MQj, _, _ = m_orthonormalize(X0, M, [], [])
    Qs, MQs = [], []                     # the basis by blocks, and M times it
    N, cols, steps = 0, [], 0            # columns, T's block columns, steps
    best, since = 0, 0                   # most pairs converged so far, steps since it grew
    # the wanted count is known as the Ritz values converge: the bar's total follows it
    with closing(progress.work("modes", None, "mode")) as bar:
        while True:
            b = Qj.shape[1]
            Qs.append(Qj)
            MQs.append(MQj)
            N += b
            W = np.asarray(solve(np.asfortranarray(MQj)))
            if W.ndim == 1:
                W = W[:, None]
            steps += 1
            Wn, MWn, C, R = m_orthonormalize(W, M, Qs, MQs)
            cols.append((C, R))
            T = _assemble(cols)
            theta, Y = np.linalg.eigh(0.5 * (T + T.T))
            theta, Y = theta[::-1], Y[:, ::-1]
            # residual of each Ritz pair: the coupling to the next block times y's last block
            res = np.linalg.norm(R @ Y[-b:], axis=0)
            done = res <= tol * _reference(theta)
            # pairs converge in order from the largest theta (lambda nearest sigma): the first
            # open one must come after every wanted one (and, with lam_max, one beyond them)
            first_open = int(np.argmin(done)) if not done.all() else len(done)
            if lam_max is not None:
                need = int(np.sum(theta >= 1.0 / (lam_max - sigma))) + 1
            else:
                need = min(count, n)
            bar.advance(min(first_open, need), need)
            closed = Wn.shape[1] == 0 or N == n      # an invariant subspace
            if first_open >= need or closed:
                k = len(theta) if closed else first_open
                lam = sigma + 1.0 / theta[:k]
                order = np.argsort(lam)
                Y = Y[:, :k][:, order]
                X, start = np.zeros((n, k)), 0
                for Q in Qs:
                    X += Q @ Y[start:start + Q.shape[1]]
                    start += Q.shape[1]
                return lam[order], X, steps
            best, since = (first_open, 0) if first_open > best else (best, since + 1)
            if since >= STALL and N >= 2 * need + 4 * block:
                # the residuals sit on the solves' round-off: more vectors will not lower them
                raise NotConverged(f"the modes stalled: {first_open} of {need} eigenpairs "
                                   f"converged, none more in the last {since} steps ({N} vectors)")
            room = max_dim - N
            if Wn.shape[1] > room and max_dim == n:
                # the space is all but complete: what W adds beyond it is round-off
                Wn, MWn, cols[-1] = Wn[:, :room], MWn[:, :room], (C, R[:room])
            elif Wn.shape[1] > room:
                raise NotConverged(f"the modes did not converge: {first_open} of {need} "
                                   f"eigenpairs in a basis of {N} vectors "
                                   f"({N * n * 16 / 1e9:.2g} GB)")
            Qj, MQj = Wn, MWn


def _reference(theta, ratio=OUTLIER):
    """What each Ritz value's residual is measured against: the largest theta, the norm of the
    operator the solves apply, leaving out those over `ratio` times its own. A floating part's
    rigid mode (theta 1e6 times the elastic ones on drilled_cube's soft contact) is deflated
    once converged, and the later solves never see it: against its theta, the elastic pairs
    would be taken as converged at residuals of 1e-6 of their own."""
    t = np.abs(theta)                                   # descending
    first = np.searchsorted(-t, -ratio * t, side="left")    # the first theta_j <= ratio theta_i
    return t[np.minimum(first, len(t) - 1)]


def _assemble(cols):
    """T (N, N) from its block columns: column j holds C_j (on the blocks before and at j) and
    R_j (the coupling to block j + 1), the last R left out."""
    sizes = [C.shape[1] for C, _ in cols]
    N = sum(sizes)
    T = np.zeros((N, N))
    start = 0
    for j, (C, R) in enumerate(cols):
        b = sizes[j]
        T[:C.shape[0], start:start + b] = C
        if j + 1 < len(cols):
            T[start + b:start + b + R.shape[0], start:start + b] = R
        start += b
    return T
