"""The system linearized at steady sliding: M, D, K of M a + D v + K q = 0 about the preload.
K is complex where materials have a loss factor: their structural damping i H, H = sum_m eta_m
K_m, which a run takes as a viscous damping instead (dynamics.system).

With g = C q + g0 the gap, p(g) the contact law (k_t = -dp/dg), Ct and Cc the tangential
observations along and across the sliding, and the friction force Ct^T (w p m(V - Ct v))
(contact.friction):
- K = K_lin + Ct^T diag(w m k_t) C: K_lin holds the normal contact tangent; the friction
  stiffness is not symmetric (the pressure a normal motion changes drags along t);
- D = the system's damping + Ct^T diag(w p m') Ct + Cc^T diag(w p m / V) Cc: the slope of the
  regularized law along the sliding (negative on a falling mu(v)) and the turning of the
  traction with a velocity across it.
Gyroscopic and convective terms of the imposed motion are left out (the disc's mesh does not
rotate; its rotation enters only through the sliding).
"""
import numpy as np
import scipy.sparse as sp

from ..contact.blocks import pair_factors, points_gram


def preload_pressure(system, state):
    """Pressure p and tangent k_t of every point at the state's displacement."""
    g = system.C @ state.q + system.contacts.gap0
    p, kt, _ = system.contacts.laws(np.asarray(g))
    return p, kt


def _friction_terms(system, p, kt):
    """(Kf, Df): the friction stiffness and damping on the system's coordinates, or None."""
    f = system.contacts.friction
    if f is None:
        return None, None
    w = system.contacts.weights
    C, Ct, Cc = system.C, system.Ct, system.Cc
    if system.reduced and system.shape_rows is not None:
        return _factored_terms(system, w * f.m * kt, w * p * f.dm, w * p * f.turn)
    if system.reduced:
        Kf = Ct.T @ ((w * f.m * kt)[:, None] * C)
        Df = Ct.T @ ((w * p * f.dm)[:, None] * Ct) + Cc.T @ ((w * p * f.turn)[:, None] * Cc)
        return Kf, Df
    Kf = Ct.T @ sp.diags(w * f.m * kt) @ C
    Df = Ct.T @ sp.diags(w * p * f.dm) @ Ct + Cc.T @ sp.diags(w * p * f.turn) @ Cc
    return Kf.tocsr(), Df.tocsr()


def _factored_terms(system, stiffness, along, across):
    """(Kf, Df) of a reduced system whose rows are factored, C = L Y (system.shape_rows): a
    pair at a time, through its points' gram, Ct^T diag(d) C = Yt^T (L_s^T diag(d) L_s) Y, a
    few hundred shapes squared per point instead of the reduced dofs squared; the pairs
    without friction (zero weights) left out."""
    Y, Yt, Yc = system.shape_rows
    n = system.n
    Kf, Df = np.zeros((n, n)), np.zeros((n, n))
    for rows, cols, L in pair_factors(system.contacts.factors[0]):
        if not (np.any(stiffness[rows]) or np.any(along[rows]) or np.any(across[rows])):
            continue
        Kf += Yt[cols].T @ (points_gram(L, stiffness[rows]) @ Y[cols])
        Df += (Yt[cols].T @ (points_gram(L, along[rows]) @ Yt[cols])
               + Yc[cols].T @ (points_gram(L, across[rows]) @ Yc[cols]))
    return Kf, Df


def linearized(system, state):
    """(M, D, K) of a prepared system (dynamics.system) at its initial state, the preload:
    dense for a reduced system (M = I), sparse on the free dofs for the full one."""
    p, kt = preload_pressure(system, state)
    Kf, Df = _friction_terms(system, p, kt)
    if system.reduced:
        n = system.n
        lossy = system.loss is not None
        M, K = np.eye(n), np.diag(system.omega2)
        D = np.diag(system.base_damp if lossy else system.damp)
        if Kf is not None:
            K, D = K + Kf, D + Df
        return M, D, (K + 1j * system.loss if lossy else K)
    M, K = system.M, system.K
    D = system.alpha * M + system.beta * K
    if Kf is not None:
        K, D = (K + Kf).tocsr(), (D + Df).tocsr()
    if system.loss is not None:
        K = (K + 1j * system.loss).tocsr()
    return M, sp.csr_matrix(D), K
