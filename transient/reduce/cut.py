"""The modes of the pieces' fixed-cut modes coupled to the whole cut (reduce.pieces.cut_basis),
found without the coupled model's matrices.

The coupled model is Craig-Bampton's with every constraint mode: K_cb = diag(D, S),
M_cb = [[I, C], [C^T, Mh]], with D = omega2 - sigma the pieces' modes' shifted squared
frequencies, C their mass coupling with the cut (each piece's on the cut's dofs G it touches),
S and Mh the cut's condensation. Its size is the pieces' modes and the cut's dofs together:
formed dense, its two matrices and their eigensolver outgrow the client long before the cut's
own S and Mh do. Here both are applied by blocks: K_cb = L L^T with L = diag(D^1/2, R^T),
S = R^T R (one dense Cholesky of the cut's condensation), and the modes below top are the
largest eigenvalues 1/lambda of the symmetric L^-1 M_cb L^-T, which a block Lanczos converges
first (largest_pairs).

How many modes lie below top is known beforehand, from Sylvester's law of inertia: the
negative eigenvalues of K_cb - top M_cb, whose modal block D - top is diagonal, are those of
D - top and of its Schur complement on the cut, S - top Mh - top^2 C^T (D - top)^-1 C
(one dense LDL^T). The Lanczos is asked for that many pairs, largest 1/lambda first; the last
above top would mean that one below it was missed, and the search is made again.
"""
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import lapack

from ..solve.lanczos import BASIS_BYTES, NotConverged, _assemble, m_orthonormalize

# vectors per Lanczos step: each step reads the cut's dense factor and mass once for them all
BLOCK = 32
# the Lanczos basis grows by this fraction between two solutions of its projected problem
GROWTH = 0.2
# a search whose converged pairs, some converged already, did not grow over this many
# solutions of its projected problem, its basis past STALL times the wanted count, is said
# stalled (a tolerance below the solves' round-off)
STALLED = 3
STALL = 3
# the Ritz pairs' residual, relative to the largest 1/lambda: the cut's solves are a dense
# Cholesky's, exact to round-off, and the pairs converge that far in a few steps more
TOL = 1e-14
# a mode whose trace holds less than this squared of its strain energy (K_cb's) hardly moves
# the cut: its trace's direction is more the eigensolver's round-off (some 1e-14 of the mode)
# than the mode's, and its share of the mode's energy too small to matter
STILL = 1e-6
# how far above top the last of the counted modes may lie: the count's LDL^T and the Lanczos
# each place a mode within round-off of top on either side
SLACK = 1e-8
# searches made before a mode below top is said missed: each again with twice the block (a
# mode missed) and a tolerance 100 times looser (a search stalled on round-off)
ATTEMPTS = 3


def modes_below(S, Mh, couplings, top):
    """The count of the coupled model's eigenvalues below top: the negative ones of D - top
    and of Z = S - top Mh - top^2 sum_p C_p^T (D_p - top)^-1 C_p (Sylvester). couplings:
    (G, D_p (m_p,), C_p (m_p, len(G))) of each piece."""
    # S and Mh are symmetric: their transposes are the Fortran-ordered arrays LAPACK takes
    Z = np.array(S.T, order="F")
    Z -= top * Mh.T
    below = 0
    for G, d, C in couplings:
        below += int(np.count_nonzero(d < top))
        Z[np.ix_(G, G)] -= (top ** 2 * C.T / (d - top)) @ C
    # the wrapper's default workspace (one column) leaves dsytrf unblocked, 6x slower
    lwork, _ = lapack.dsytrf_lwork(len(Z), lower=1)
    ldu, ipiv, info = lapack.dsytrf(Z, lower=1, lwork=int(lwork), overwrite_a=1)
    if info < 0:
        raise ValueError(f"dsytrf: argument {-info} is invalid")
    return below + _negatives(ldu, ipiv)


def _negatives(ldu, ipiv):
    """The negative eigenvalues of D in dsytrf's lower L D L^T: its 1x1 blocks' signs, and a
    2x2 block's by its determinant (one of each sign when negative) and trace."""
    d, off = np.diag(ldu), np.diag(ldu, -1)
    count, k = 0, 0
    while k < len(d):
        if ipiv[k] > 0:
            count += int(d[k] < 0)
            k += 1
            continue
        a, b, c = d[k], off[k], d[k + 1]
        count += 1 if a * c < b * b else 2 * int(a + c < 0)
        k += 2
    return count


def coupled_traces(S, Mh, couplings, top, overwrite=False):
    """(U (g, k), R): the traces on the cut of the coupled model's modes below top (each of
    unit K_cb-norm), but those of the modes that hold the cut still (STILL; a symmetric part
    cut along its nodal lines has them), and R the upper Cholesky factor of S (S = R^T R) for
    the caller's further solves, in S's memory with overwrite. couplings as modes_below's."""
    count = modes_below(S, Mh, couplings, top)
    R = sla.cho_factor(S.T, lower=False, overwrite_a=overwrite)[0]
    g = len(S)
    if count == 0:
        return np.zeros((g, 0)), R
    scale = 1.0 / np.sqrt(np.concatenate([d for _, d, _ in couplings]))
    m = len(scale)
    at = np.cumsum([0] + [len(d) for _, d, _ in couplings])
    blocks = [(slice(at[i], at[i + 1]), G, C) for i, (G, _, C) in enumerate(couplings)]

    def apply(Y):
        """L^-1 M_cb L^-T Y, a block at a time."""
        Xq = scale[:, None] * Y[:m]
        Xg = sla.solve_triangular(R, Y[m:], lower=False, check_finite=False)
        F = np.empty_like(Y)
        F[:m], F[m:] = Xq, Mh @ Xg
        for rows, G, C in blocks:
            F[rows] += C @ Xg[G]
            F[m + G] += C.T @ Xq[rows]
        F[:m] *= scale[:, None]
        F[m:] = sla.solve_triangular(R, F[m:], trans="T", lower=False, check_finite=False)
        return F

    found = "none"
    for attempt in range(ATTEMPTS):
        try:
            mu, Y = largest_pairs(apply, m + g, count, BLOCK << attempt, attempt,
                                  TOL * 100.0 ** attempt)
        except NotConverged as exc:
            found = str(exc)
            continue
        lam = 1.0 / mu
        if len(lam) >= count and lam[count - 1] <= top * (1 + SLACK):
            # y = L^T x: the cut's rows of y are R x_cut, whose norm is the trace's share
            Y = Y[m:, :count]
            Y = Y[:, np.linalg.norm(Y, axis=0) > STILL]
            return sla.solve_triangular(R, Y, lower=False), R
        found = f"{np.sum(lam <= top)} of them, the last at {lam[-1] / top:.6g} top"
    raise NotConverged(f"the cut's coupled modes: {count} below top by their inertia, the "
                       f"Lanczos found {found}")


def largest_pairs(apply, n, count, block, seed, tol):
    """(mu (k,) descending, Y (n, k) orthonormal): the count largest eigenpairs of the symmetric
    operator apply (a block Y (n, b) to its product), or the k < count it has when its Krylov
    space closes first. A block Lanczos fully re-orthogonalized (solve.lanczos's
    m_orthonormalize); a pair is converged when its residual is below tol times the largest mu.
    The projected problem is solved for the count largest pairs alone, and only once the basis
    has grown by GROWTH since: solve.lanczos.block_lanczos solves it whole at every step,
    which took most of the time with a thousand modes wanted."""
    identity = sp.identity(n)
    Q = m_orthonormalize(np.random.default_rng(seed).standard_normal((n, min(block, n))),
                         identity, [], [])[0]
    Qs, cols, size, solve_at = [], [], 0, count + block
    bound = min(n, max(int(BASIS_BYTES / (8.0 * n)), count + 4 * block))
    done = []
    while True:
        Qs.append(Q)
        size += Q.shape[1]
        Q, _, C, R = m_orthonormalize(apply(Q), identity, Qs, Qs)
        if size + Q.shape[1] > n:
            # the whole space spanned: what the step adds beyond it is round-off
            Q, R = Q[:, :n - size], R[:n - size]
        cols.append((C, R))
        closed = Q.shape[1] == 0
        if size < solve_at and not closed:
            continue
        T = _assemble(cols)
        k = min(count, size)
        mu, Z = sla.eigh(0.5 * (T + T.T), subset_by_index=[size - k, size - 1])
        mu, Z = mu[::-1], Z[:, ::-1]
        residual = np.linalg.norm(R @ Z[size - Qs[-1].shape[1]:], axis=0)
        done.append(int(np.count_nonzero(residual <= tol * mu[0])))
        if closed or done[-1] == k:
            Y, start = np.zeros((n, k)), 0
            for B in Qs:
                Y += B @ Z[start:start + B.shape[1]]
                start += B.shape[1]
            return mu, Y
        if (size + Q.shape[1] > bound or size > STALL * count and len(done) > STALLED
                and 0 < done[-1] <= done[-1 - STALLED]):
            raise NotConverged(f"{done[-1]} of {count} pairs converged in a basis of {size} "
                               f"vectors")
        solve_at = size * (1 + GROWTH)
