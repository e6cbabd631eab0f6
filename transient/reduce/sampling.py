"""Contact points sampled on the reduced dynamics: a few of a rich rule's points, with weights
that reproduce what the vibration sees of the contact (ECSW, the energy-conserving sampling and
weighting of Farhat et al., 2014, carried to the contact-linearized stiffness).

A reduced model built on a rich rule (the fine rule, regularized or not) sees the contact about
the preload through Kc = Cr^T diag(w k_t) Cr and the preload force Cr^T (w p). In the
coordinates y = Omega q of the linearized modes (Omega^2 = diag(omega2)), Kc~ = Omega^-1 Kc
Omega^-1: its diagonal is the relative shift of each eigenvalue that the contact makes, and its
column j the coupling of mode j to all others (second-order shifts). A subset of the points with
new weights w' >= 0 is asked to reproduce the columns of Kc~ of the modes in the band (below
fmax), and the preload displacement Omega^-1 Cr^T (w p) relative to |Omega q0|: the band's
frequencies and shapes then follow the rich rule's, and so do the histories.

Each point's contribution is one feature column z_i (k_t,i c~_i c~_iJ^T, p_i c~_i), c~ = Cr
Omega^-1, so the Gram matrix G = Z^T Z is known in closed form: G_il = (c~_i . c~_l)
(k_t,i k_t,l (c~_iJ . c~_lJ) + p_i p_l / s^2). Lawson-Hanson's active-set NNLS runs on it with
the columns formed only for the points it takes (memory N x m, not N^2, nor features x N), and
stops at the relative residual asked: the tolerance sets the number of points.
"""
import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..solve.preload import STALE


@dataclass(frozen=True)
class Sample:
    chosen: np.ndarray       # indices of the sampled points among the candidates
    weights: np.ndarray      # their weights w' >= 0
    residual: float          # relative residual of the features reproduced
    band: int                # modes whose stiffness columns are reproduced
    seconds: float


def _omega(omega2):
    """The modes' circular frequencies, the zero ones raised to the lowest positive."""
    return np.sqrt(np.maximum(omega2, omega2[omega2 > 0].min() if np.any(omega2 > 0) else 1.0))


def features(omega2, Cr, pressure, tangent, q0, band):
    """(c~, c~ of the band, k_t, p / s): what the Gram matrix of the points is made of."""
    omega = _omega(omega2)
    c = Cr / omega
    s = max(np.linalg.norm(omega * q0), 1e-300)
    return c, np.ascontiguousarray(c[:, :band]), tangent, pressure / s


def friction_terms(feats, omega2, Ct, Cc, m, dm, turn, pressure):
    """The friction's features as terms (s, L, R), each point's z_i = s_i L_i (x) R_i: the
    friction stiffness Ct^T diag(w m k_t) C on the band's columns and the friction preload in
    the scaled coordinates y = Omega q, and the friction damping along and across the sliding
    in y = Omega^1/2 q (Omega^-1/2 D Omega^-1/2: its diagonal is 2 zeta, the relative shift of a
    real part as Omega^-1 K Omega^-1's is of an eigenvalue). feats: the normal features
    (features), whose band rows, tangents and scaled pressures these share; m, dm, turn: the
    law at steady sliding (contactset.FrictionSet)."""
    _, cb, tangent, ps = feats
    band = cb.shape[1]
    omega = _omega(omega2)
    ct = Ct / omega
    root = np.sqrt(omega)
    ctd, ccd = Ct / root, Cc / root
    one = np.ones((len(pressure), 1))
    return [(m * tangent, ct, cb), (m * ps, ct, one),
            (pressure * dm, ctd, np.ascontiguousarray(ctd[:, :band])),
            (pressure * turn, ccd, np.ascontiguousarray(ccd[:, :band]))]


def gram_column(feats, j, terms=()):
    """Column j of the points' Gram matrix. Each feature array's products with its row j are
    made once: the friction's terms share ct and the band's rows (five products of N x n
    became four, and a N x band one two: they are memory-bound, 8.2 ms a column of
    pad_disc's 7734 candidates with friction on one core), the same arithmetic."""
    c, cb, kt, ps = feats
    dots = {}

    def dot(A):
        if id(A) not in dots:
            dots[id(A)] = A @ A[j]
        return dots[id(A)]
    g = dot(c) * (kt * kt[j] * dot(cb) + ps * ps[j])
    for t, L, R in terms:
        g += (t * t[j]) * dot(L) * dot(R)
    return g


def gram_target(feats, w, terms=()):
    """h = G w (the candidates' features against the rich rule's combination b = Z w)."""
    c, cb, kt, ps = feats
    Mf = (c * (w * kt)[:, None]).T @ cb
    F = c.T @ (w * ps)
    h = kt * np.einsum("ia,ab,ib->i", c, Mf, cb, optimize=True) + ps * (c @ F)
    for t, L, R in terms:
        h += t * np.einsum("ia,ab,ib->i", L, (L * (w * t)[:, None]).T @ R, R, optimize=True)
    return h


def nnls_gram(column, h, bb, tol, max_points):
    """Lawson-Hanson NNLS on min |Z x - b|^2 given G = Z^T Z column by column, h = Z^T b and
    |b|^2, stopped when |Z x - b| <= tol |b| or at max_points. The passive set's Gram block is
    kept as a Cholesky factor, extended by one row per point taken and refactored only when a
    point leaves. Returns (indices, x on them, relative residual)."""
    N = len(h)
    cap = min(max_points, N)
    P = np.zeros(0, np.int64)
    # a column per point taken, written whole, and the factor in place (its leading k x k
    # block; growing it by np.block copied it whole at every point taken). Both double as
    # points are taken: sized for every candidate, a 1M-dof model's 64.6k asked 31 GiB.
    room = min(cap, 256)
    cols = np.empty((N, room), order="F")
    Lbuf = np.zeros((room, room))
    x = np.zeros(0)
    Gx = np.zeros(N)           # G x on every candidate, as the gradient h - G x needs it
    grad = h.copy()
    banned = np.zeros(N, bool)

    def residual(x):
        # x^T G_PP x from G x: a k x k gather of the columns at every point taken was 1.3 s of
        # 4x pad_disc's 11.5 s sampling (791 points)
        return np.sqrt(max(bb - 2 * h[P] @ x + x @ Gx[P], 0.0) / bb)

    res = 1.0
    while len(P) < cap:
        res = residual(x) if len(P) else 1.0
        if res <= tol and len(P):          # at least one point, whatever the tolerance
            break
        score = np.where(banned, -np.inf, grad)
        score[P] = -np.inf
        j = int(np.argmax(score))
        if score[j] <= 0:
            break
        g = column(j)
        k = len(P)
        L = Lbuf[:k, :k]
        l = sla.solve_triangular(L, g[P], lower=True) if k else np.zeros(0)
        d2 = g[j] - l @ l
        if d2 <= 1e-12 * g[j]:
            banned[j] = True          # already in the span of the points taken
            continue
        if k == room:
            room = min(2 * room, cap)
            cols, old = np.empty((N, room), order="F"), cols
            cols[:, :k] = old[:, :k]
            Lbuf = np.pad(Lbuf[:k, :k], (0, room - k))
        cols[:, k] = g
        P = np.append(P, j)
        Lbuf[k, :k] = l
        Lbuf[k, k] = np.sqrt(d2)
        L = Lbuf[:k + 1, :k + 1]
        x = np.append(x, 0.0)
        while True:
            z = sla.cho_solve((L, True), h[P])
            if np.all(z > 0):
                x = z
                break
            # step from x towards z until a weight reaches zero; those points leave
            neg = z <= 0
            alpha = np.min(x[neg] / (x[neg] - z[neg]))
            x = x + alpha * (z - x)
            keep = x > 1e-14 * max(x.max(), 1e-300)
            if np.all(keep):
                keep[np.argmin(x)] = False
            P, x = P[keep], x[keep]
            cols[:, :len(P)] = cols[:, np.flatnonzero(keep)]
            k = len(P)
            Lbuf[:k, :k] = np.linalg.cholesky(cols[P, :k])
            Lbuf[:k, k:] = 0.0
            L = Lbuf[:k, :k]
        Gx = cols[:, :len(P)] @ x
        grad = h - Gx
    res = residual(x) if len(P) else 1.0
    return P, x, float(res)


def sample(omega2, Cr, weights, pressure, tangent, q0, band, tol, max_points, friction=None):
    """The points and weights reproducing the rich rule's contact on the reduced dynamics.
    friction: (Ct, Cc, m, dm, turn) of the candidates (friction_terms), to reproduce its
    coupling too."""
    t0 = time.perf_counter()
    band = max(1, min(band, len(omega2)))
    feats = features(omega2, Cr, pressure, tangent, q0, band)
    terms = (() if friction is None else
             friction_terms(feats, omega2, *friction, pressure))
    h = gram_target(feats, weights, terms)
    bb = float(weights @ h)
    chosen, w, res = nnls_gram(lambda j: gram_column(feats, j, terms), h, bb, tol, max_points)
    order = np.argsort(chosen)
    return Sample(chosen[order], w[order], res, band, time.perf_counter() - t0)


class ReducedPreloadError(RuntimeError):
    pass


@dataclass(frozen=True)
class Sampled:
    contacts: object         # ContactSet of the points kept (the sampled ones, and the others)
    keep: np.ndarray         # their indices among the rich rule's points
    W: np.ndarray            # (n, n) the linearized modes with the sampled contact, in q
    omega2: np.ndarray       # their eigenvalues, ascending
    q: np.ndarray            # preload in the new coordinates (q_old = W q)
    gap: np.ndarray          # preload gaps, pressures and tangents of the points kept
    pressure: np.ndarray
    tangent: np.ndarray
    iterations: int          # Newton iterations of the reduced preload
    residual: float
    sample: Sample


def sample_contact(contacts, candidate, omega2, Cr, q0, gap, pressure, tangent, band, tol,
                   max_points, newton_tol=1e-10, max_iter=50, tangential=None, given=None):
    """Sample the candidate points (bool mask) of a reduced model built on the rich rule, then
    re-solve the preload with the points kept and re-diagonalize the linearized stiffness.

    omega2, Cr, q0: the rich model's (its linearized modes diagonalize K + Cr^T diag(w k_t) Cr);
    gap, pressure, tangent: its preload state at every point. Points outside `candidate` are
    kept with their weights and left out of the features (their contribution is exact).
    tangential: (Ct, Cc) the rich model's tangential rows, with friction (contacts.friction):
    the points then reproduce the friction's coupling and damping too, and the reduced preload
    is the steady sliding one. given: the points and weights (a Sample) chosen already, on
    another preload of the same candidates (reduce.reference), or None to choose them here.
    """
    cand = np.flatnonzero(candidate)
    w = contacts.weights
    f = contacts.friction
    friction = (None if f is None else
                (tangential[0][cand], tangential[1][cand], f.m[cand], f.dm[cand], f.turn[cand]))
    s = given if given is not None else sample(omega2, Cr[cand], w[cand], pressure[cand],
                                               tangent[cand], q0, band, tol,
                                               max_points or len(cand), friction)
    weights = w.copy()
    weights[cand] = 0.0
    weights[cand[s.chosen]] = s.weights
    keep = np.flatnonzero(~candidate | (weights > 0))
    sub = contacts.subset(keep, weights[keep])
    # the structure alone, and the constant load balancing the rich rule's preload
    Kr = np.diag(omega2) - (Cr.T * (w * tangent)) @ Cr
    fr = Kr @ q0 - Cr.T @ (w * pressure)
    Ct = None
    if f is not None:
        fr -= tangential[0].T @ (w * pressure * f.m)
        Ct = tangential[0][keep]
    Ck = Cr[keep]
    q, g, p, kt, iterations, res = reduced_preload(Kr, fr, Ck, sub, q0, newton_tol, max_iter,
                                                   Ct)
    omega2_s, W = np.linalg.eigh(Kr + (Ck.T * (sub.weights * kt)) @ Ck)
    return Sampled(sub, keep, W, np.maximum(omega2_s, 0.0), W.T @ q, g, p, kt, iterations, res,
                   s)


def reduced_preload(Kr, fr, Cr, contacts, q, tol, max_iter, Ct=None, start=None,
                    blocks=None):
    """Newton on fr + Cr^T (w p(Cr q + g0)) - Kr q = 0 (dense: a reduced model); with the
    tangential rows Ct, plus the friction of steady sliding Ct^T (w p m), whose stiffness the
    tangent holds (dense and small here: exact Newton). start: (P,) the tangent the first step
    takes at least, with a backtracking line search (from the undeformed state, as
    solve_preload), or None (from a preload close by: plain Newton). blocks: with start, the
    rows a pair at a time (reduce.coupling.PairRows, whose operators Cr and Ct are), which
    form the tangent; None: the whole rows."""
    q = q.copy()
    scale = max(np.linalg.norm(fr), 1e-300)
    w = contacts.weights
    m = None if Ct is None else contacts.friction.m

    def residual(q):
        g = Cr @ q + contacts.gap0
        p, kt, _ = contacts.laws(g)
        r = fr + Cr.T @ (w * p) - Kr @ q
        if Ct is not None:
            r += Ct.T @ (w * p * m)
        return r, g, p, kt

    def tangent_at(d):
        if blocks is not None:
            return blocks.stiffness(Kr, w * d)
        tangent = Kr + (Cr.T * (w * d)) @ Cr
        if Ct is not None:
            tangent += (Ct.T * (w * m * d)) @ Cr
        return tangent

    r, g, p, kt = residual(q)
    held, factors = None, None
    for it in range(max_iter + 1):
        res = np.linalg.norm(r) / scale
        if res <= tol:
            return q, g, p, kt, it, float(res)
        if it < max_iter:
            d = kt if start is None or it else np.maximum(kt, start)
            try:
                if start is None:
                    dq = np.linalg.solve(tangent_at(d), r)
                else:
                    # from the undeformed state: the tangent (its P x n^2 product the cost
                    # of an iteration) kept while the laws' tangents move less than STALE
                    if held is None or np.max(np.abs(d - held)) > STALE * np.max(held):
                        with warnings.catch_warnings():
                            warnings.simplefilter("error", sla.LinAlgWarning)
                            factors = sla.lu_factor(tangent_at(d), check_finite=False)
                        held = d
                    dq = sla.lu_solve(factors, r, check_finite=False)
            except (np.linalg.LinAlgError, sla.LinAlgWarning):
                raise ReducedPreloadError(
                    "the preload tangent in the reduced coordinates is singular: too few "
                    "contact points or statics hold the parts") from None
            if start is None:
                q += dq
                r, g, p, kt = residual(q)
                continue
            step, norm = 1.0, np.linalg.norm(r)
            while True:
                trial = q + step * dq
                r, g, p, kt = residual(trial)
                if np.linalg.norm(r) < norm or step < 1e-6:
                    break
                step *= 0.5
            q = trial
    raise ReducedPreloadError(f"the preload in the reduced coordinates did not converge in "
                              f"{max_iter} Newton iterations (residual {res:.1e})")
