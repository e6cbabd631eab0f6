"""Exact contact corrections of an iteration operator through the Woodbury identity, for the
implicit kernels (Newmark, and the exponential scheme's implicit corrector).

A Jacobian J = S + U C^T diag(e) C (S the fixed operator, U = I or a diagonal) is solved with
the precomputed Z = S^-1 U C^T and G = C Z as
    J^-1 r = y - Z_A (I + diag(e_A) G_AA)^-1 diag(e_A) C_A y,   y = S^-1 r,
for the set A of rows that matter (the others, whose sum of |e_i| G_ii stays below
WOODBURY_REST, are left to the fixed-operator iteration, which they slow by at most that factor).
"""
import numpy as np

from ..jit import njit_fast
from .laws import pressure

WOODBURY_REST = 0.1


@njit_fast
def active_rows(code, params, gap, w, kt0, h2, Gd, e, active):
    """Fills e and the rows to correct exactly (largest |e_i| G_ii first); returns their count."""
    m = gap.shape[0]
    size = np.empty(m)
    total = 0.0
    for i in range(m):
        _, kt = pressure(code[i], params[i], gap[i])
        e[i] = h2 * w[i] * (kt - kt0[i])
        size[i] = abs(e[i]) * Gd[i]
        total += size[i]
    if total <= WOODBURY_REST:
        return 0
    order = np.argsort(-size)
    n_active = 0
    for i in order:
        if total <= WOODBURY_REST:
            break
        active[n_active] = i
        n_active += 1
        total -= size[i]
    return n_active


@njit_fast
def woodbury(y, u, active, n_active, e, Z, G):
    """y -= Z_A (I + diag(e_A) G_AA)^-1 diag(e_A) u, u = C_A y."""
    H = np.empty((n_active, n_active))
    rhs = np.empty(n_active)
    for a in range(n_active):
        i = active[a]
        for b in range(n_active):
            H[a, b] = e[i] * G[i, active[b]]
        H[a, a] += 1.0
        rhs[a] = e[i] * u[a]
    z = np.linalg.solve(H, rhs)
    for a in range(n_active):
        i = active[a]
        for k in range(y.shape[0]):
            y[k] -= Z[k, i] * z[a]


@njit_fast
def woodbury_dense(y, C, u, active, n_active, e, Z, G):
    """woodbury for dense contact rows C (m, n): u = C_A y first (u is scratch)."""
    for j in range(n_active):
        row_c = C[active[j]]
        s = 0.0
        for k in range(y.shape[0]):
            s += row_c[k] * y[k]
        u[j] = s
    woodbury(y, u, active, n_active, e, Z, G)
