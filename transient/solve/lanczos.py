"""Block shift-invert Lanczos: the eigenpairs of (K, M) from a shift sigma up to a bound.

ARPACK's shift-invert (scipy eigsh) applies (K - sigma M)^-1 M to one vector at a time: each
step is a forward and back substitution through the whole factor (memory bound: pad_disc's
124 steps were 9 s of a 36 s setup) and a sparse product with M. Here each step applies it to
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

Not yet what normal_modes uses (it runs ARPACK): on drilled_cube with its upper cube left
floating (`transient modes`, contact.interface.k = 1e-3, one rigid mode whose theta is 1e6
times the elastic ones) the residuals did not reach tol and the basis grew for minutes. On
pad_disc_long it found the 37 modes in 9.4 s against ARPACK's 31 s on the same operator (load
2-3), and on drilled_cube its eigenvalues agree with a tighter run to 7e-16 where ARPACK's are
3.2e-9 off.
"""
import numpy as np

TOL = 1e-12
BASIS_BYTES = 4e9     # default bound of the basis and M times it (2 N n floats)


def m_orthonormalize(W, M, Qs, MQs):
    """W made M-orthogonal to the blocks Qs (MQs = M Qs; twice, for round-off), then
    M-orthonormal: returns (W, M W, C, R) with W_in = Q C + W R, Q the blocks side by side.
    M W is formed from the projected block itself, not carried through the projections
    (carried, its error grew by 10x a step). Directions of W that Q spans to 1e-10 of W's
    M-norm are left out."""
    C = np.zeros((sum(Q.shape[1] for Q in Qs), W.shape[1]))
    first = None
    for _ in range(2):
        if Qs:
            # block by block: the basis is never copied into one array
            H = np.vstack([MQ.T @ W for MQ in MQs])
            start = 0
            for Q in Qs:
                W = W - Q @ H[start:start + Q.shape[1]]
                start += Q.shape[1]
            C += H
            first = H if first is None else first
    MW = M @ W
    G = W.T @ MW
    lam, U = np.linalg.eigh(0.5 * (G + G.T))
    # W_in's M-norms: what the projections took plus what is left
    norms = np.diag(G) + (np.einsum("ij,ij->j", first, first) if first is not None else 0.0)
    keep = lam > 1e-20 * max(float(np.max(norms, initial=0.0)), 1e-300)
    U, lam = U[:, keep][:, ::-1], lam[keep][::-1]        # the strongest directions first
    # W = (W U / sqrt(lam)) (sqrt(lam) U^T): an M-orthonormal block and its coefficients
    R = np.sqrt(lam)[:, None] * U.T
    return W @ (U / np.sqrt(lam)), MW @ (U / np.sqrt(lam)), C, R


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
        done = res <= tol * np.abs(theta[0])
        # pairs converge in order from the largest theta (lambda nearest sigma): the first
        # open one must come after every wanted one (and, with lam_max, one beyond them)
        first_open = int(np.argmin(done)) if not done.all() else len(done)
        if lam_max is not None:
            need = int(np.sum(theta >= 1.0 / (lam_max - sigma))) + 1
        else:
            need = min(count, n)
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
        room = max_dim - N
        if Wn.shape[1] > room and max_dim == n:
            # the space is all but complete: what W adds beyond it is round-off
            Wn, MWn, cols[-1] = Wn[:, :room], MWn[:, :room], (C, R[:room])
        elif Wn.shape[1] > room:
            raise NotConverged(f"the modes did not converge: {first_open} of {need} "
                               f"eigenpairs in a basis of {N} vectors ({N * n * 16 / 1e9:.2g} GB)")
        Qj, MQj = Wn, MWn


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
