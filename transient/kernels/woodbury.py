"""Exact contact corrections of an iteration operator through the Woodbury identity, for the
implicit kernels (Newmark, and the exponential scheme's implicit corrector).

A Jacobian J = S + U C^T diag(e) C (S the fixed operator, U = I or a diagonal) is solved with
the precomputed Z = S^-1 U C^T and G = C Z as
    J^-1 r = y - Z_A (I + diag(e_A) G_AA)^-1 diag(e_A) C_A y,   y = S^-1 r,
for the set A of rows that matter (the others, whose sum of |e_i| G_ii stays below
WOODBURY_REST, are left to the fixed-operator iteration, which they slow by at most that factor).

With friction the contact forces depend on the velocity too and the Jacobian is not
symmetric: coupled_rows and coupled_solve take the general form of an implicit step (see
there), of which the above is the frictionless case.
"""
import numpy as np

from ..jit import njit_fast
from .codes import FRICTIONLESS
from .friction import slip_tangent
from .laws import pressure
from .sparse import csr_row_dot

WOODBURY_REST = 0.1
# The friction's Newton iteration backtracks (halves its step) while the residual does not fall
# by the Armijo fraction ARMIJO of the step, down to MIN_STEP of the Newton step: on the
# saturating regularized sign, full steps overshoot and cycle (naive twins' hard system: no
# convergence in 50 iterations; one halving, then quadratic convergence).
ARMIJO = 1e-4
MIN_STEP = 1.0 / 32.0
# With friction the implicit steps iterate on the fixed point (no exact term) while the
# residual falls by this factor an iteration, and turn to Newton for the rest of the step once
# it does not: the friction's linear coupling (mu k_t w on every sliding point) fills
# coupled_rows' sum (pad_disc in its linear growth: 690 terms of about 0.1 each, 6.8 ms a step)
# where the fixed point converges as the explicit corrector does.
FIXED_POINT_RATE = 0.5


@njit_fast
def _largest(size, total, active):
    """The terms to correct exactly: the largest sizes first into active, until those left sum
    to at most WOODBURY_REST (total: the sum of size); returns their count."""
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
    return _largest(size, total, active)


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
def coupled_rows(code, params, gap, press, w, kt0, fr, slip, GQ, GV, cu, size, active):
    """The Jacobian's terms to correct exactly, for a step whose unknown x (n) moves the end
    state as q = qb + Dq x, v = vb + Dv x (Dq, Dv diagonal) and whose residual is
    R = P x + b - f(q, v), P diagonal, f the contact and friction forces. Then
        J = P + sum_c U_c V_c^T
    with, per contact point i, three candidate terms c = 3 i + kind (one, kind 0, without
    friction, fr[0] with no rows):
      kind 0, the gap: V = Dq C_i^T, U = e_i C_i^T + g_i (s_t Ct_i^T + s_c Cc_i^T), with
        e_i = w (k_t - k_t*) the tangent's move from the preload's and g_i = w k_t c the
        friction's change with the pressure;
      kinds 1 and 2, the slip along and across: V = Dv Ct_i^T or Dv Cc_i^T, U the matching
        column of [Ct_i^T Cc_i^T] H_i, H_i = d tau / d s = w p (c I + c' |s| e e^T).
    U_c = cu[c, 0] C_i^T + cu[c, 1] Ct_i^T + cu[c, 2] Cc_i^T. The size of a term bounds its
    diagonal entry of V^T P^-1 U: the sum of its parts' entries in absolute value (from
    GQ = C Dq P^-1 Cs^T and GV = [Ct; Cc] Dv P^-1 Cs^T, Cs = [C; Ct; Cc]); as in active_rows,
    the largest are taken until the others sum to at most WOODBURY_REST. Fills cu, size and
    active; returns the count taken."""
    m = gap.shape[0]
    stride = 3 if GV.shape[0] > 0 else 1         # GV is empty without friction
    total = 0.0
    for i in range(m):
        _, kt = pressure(code[i], params[i], gap[i])
        c = stride * i
        e = w[i] * (kt - kt0[i])
        cu[c, 0] = e
        cu[c, 1] = 0.0
        cu[c, 2] = 0.0
        size[c] = abs(e) * GQ[i, i]
        if stride == 3:
            for k in range(1, 3):
                cu[c + k, 0] = 0.0
                cu[c + k, 1] = 0.0
                cu[c + k, 2] = 0.0
                size[c + k] = 0.0
            if fr[3][i] != FRICTIONLESS and press[i] > 0.0:
                st = slip[0, i]
                sc = slip[1, i]
                ct, d = slip_tangent(fr[3][i], fr[4][i], fr[5][i], fr[6], fr[7], fr[8], st, sc)
                gq = w[i] * kt * ct
                cu[c, 1] = gq * st
                cu[c, 2] = gq * sc
                size[c] += abs(cu[c, 1] * GQ[i, m + i]) + abs(cu[c, 2] * GQ[i, 2 * m + i])
                s2 = st * st + sc * sc
                a = d / s2 if s2 > 0.0 else 0.0
                wp = w[i] * press[i]
                h00 = wp * (ct + a * st * st)
                h01 = wp * a * st * sc
                h11 = wp * (ct + a * sc * sc)
                cu[c + 1, 1] = h00
                cu[c + 1, 2] = h01
                cu[c + 2, 1] = h01
                cu[c + 2, 2] = h11
                size[c + 1] = abs(h00 * GV[i, m + i]) + abs(h01 * GV[i, 2 * m + i])
                size[c + 2] = abs(h11 * GV[m + i, 2 * m + i]) + abs(h01 * GV[m + i, m + i])
        for k in range(stride):
            total += size[c + k]
    return _largest(size[:stride * m], total, active)


@njit_fast
def _term_row(X, kind, i, m):
    """The row of GQ (kind 0) or GV (kinds 1, 2) that V_c^T P^-1 runs along."""
    return X[i] if kind <= 1 else X[m + i]


@njit_fast
def coupled_solve(y, Dq, Dv, P, C, Ct, Cc, GQ, GV, cu, active, n_active, uz):
    """y = P^-1 R on entry, J^-1 R = y - P^-1 U (I + V^T P^-1 U)^-1 V^T y on exit, for the
    n_active terms of coupled_rows (uz (n,) is scratch)."""
    m, n = C.shape
    stride = 3 if Ct.shape[0] > 0 else 1
    k = n_active
    H = np.empty((k, k))
    rhs = np.empty(k)
    for a in range(k):
        ca = active[a]
        ia = ca // stride
        kind = ca % stride
        s = 0.0
        if kind == 0:
            row = C[ia]
            for j in range(n):
                s += row[j] * Dq[j] * y[j]
            X = _term_row(GQ, 0, ia, m)
        else:
            row = Ct[ia] if kind == 1 else Cc[ia]
            for j in range(n):
                s += row[j] * Dv[j] * y[j]
            X = _term_row(GV, kind, ia, m)
        rhs[a] = s
        for b in range(k):
            cb = active[b]
            ib = cb // stride
            h = cu[cb, 0] * X[ib]
            if stride == 3:
                h += cu[cb, 1] * X[m + ib] + cu[cb, 2] * X[2 * m + ib]
            H[a, b] = h
        H[a, a] += 1.0
    z = np.linalg.solve(H, rhs)
    for j in range(n):
        uz[j] = 0.0
    for b in range(k):
        cb = active[b]
        ib = cb // stride
        c0 = z[b] * cu[cb, 0]
        if c0 != 0.0:
            row = C[ib]
            for j in range(n):
                uz[j] += c0 * row[j]
        if stride == 3:
            c1 = z[b] * cu[cb, 1]
            c2 = z[b] * cu[cb, 2]
            rt = Ct[ib]
            rc = Cc[ib]
            for j in range(n):
                uz[j] += c1 * rt[j] + c2 * rc[j]
    for j in range(n):
        y[j] -= uz[j] / P[j]


@njit_fast
def coupled_solve_sparse(y, h2, hv, C, Ct, Cc, Z, GQ, GV, cu, active, n_active):
    """coupled_solve on the full model (x = a, Dq = h2, Dv = hv scalars, C, Ct, Cc CSR
    triplets), P^-1 Cs^T given as Z = S^-1 [C; Ct; Cc]^T (n, 3m): y = S^-1 R on entry,
    J^-1 R on exit."""
    m = C[0].shape[0] - 1
    k = n_active
    H = np.empty((k, k))
    rhs = np.empty(k)
    for a in range(k):
        ca = active[a]
        ia = ca // 3
        kind = ca % 3
        if kind == 0:
            rhs[a] = h2 * csr_row_dot(C, ia, y)
            X = GQ[ia]
        else:
            rhs[a] = hv * csr_row_dot(Ct if kind == 1 else Cc, ia, y)
            X = _term_row(GV, kind, ia, m)
        for b in range(k):
            cb = active[b]
            ib = cb // 3
            H[a, b] = cu[cb, 0] * X[ib] + cu[cb, 1] * X[m + ib] + cu[cb, 2] * X[2 * m + ib]
        H[a, a] += 1.0
    z = np.linalg.solve(H, rhs)
    for b in range(k):
        cb = active[b]
        ib = cb // 3
        c0 = z[b] * cu[cb, 0]
        c1 = z[b] * cu[cb, 1]
        c2 = z[b] * cu[cb, 2]
        for j in range(y.shape[0]):
            y[j] -= c0 * Z[j, ib] + c1 * Z[j, m + ib] + c2 * Z[j, 2 * m + ib]


@njit_fast
def friction_move(move, y, rnorm2, rprev2, newton, frac, friction):
    """The implicit steps' iteration before a Newton solve, with friction: a fixed-point step
    x -= y while the residual (rnorm2, squared) falls by FIXED_POINT_RATE, then Newton, whose
    last step (x_prev - delta) is halved while backtrack says so; move = (x, x_prev, delta).
    Returns (solve, newton, rprev2, frac): solve False when x was moved here and the
    iteration goes on, True when the caller takes a full Newton step from this residual
    (rprev2 then rnorm2, frac 1); without friction always Newton, never halved."""
    x, x_prev, delta = move
    if not newton:
        if rnorm2 <= FIXED_POINT_RATE * FIXED_POINT_RATE * rprev2:
            for k in range(x.shape[0]):
                x[k] -= y[k]
            return False, False, rnorm2, frac
        newton = True
        rprev2 = np.inf
    if friction and backtrack(rnorm2, rprev2, frac):
        frac *= 0.5
        for k in range(x.shape[0]):
            x[k] = x_prev[k] - frac * delta[k]
        return False, newton, rprev2, frac
    return True, newton, rnorm2, 1.0


@njit_fast
def move_start(friction):
    """An implicit step's iteration at its start: not converged, and friction_move's (rprev2,
    frac, newton), with friction the fixed point first, without it Newton at once."""
    return False, np.inf, 1.0, not friction


@njit_fast
def coupled_buffers(rows):
    """coupled_rows' buffers (cu, size, active) for up to rows terms."""
    return np.empty((rows, 3)), np.empty(rows), np.empty(rows, np.int64)


@njit_fast
def newton_buffers(x, m, friction):
    """An implicit step's buffers for its unknown x (n,) and m contact points: y (n,), the
    residual and then the Newton step; uz (n,), coupled_solve's scratch; move = (x, x_prev,
    delta) (friction_move, newton_update); coupled_rows' buffers for a term a point, three
    with friction."""
    n = x.shape[0]
    move = (x, np.empty(n), np.empty(n))
    return np.empty(n), np.empty(n), move, coupled_buffers((3 if friction else 1) * m)


@njit_fast
def newton_coupled(y, Dq, Dv, P, contact, fr, gap, press, slip, GQ, GV, coupled, uz, move):
    """The Newton step of a reduced implicit kernel: y = J^-1 r with the exact terms of
    coupled_rows (coupled: its buffers), then move = (x, x_prev, delta) by newton_update;
    contact as contact.contact_pass takes it."""
    C, g0, w, kt0, code, params = contact
    cu, size, active = coupled
    n_active = coupled_rows(code, params, gap, press, w, kt0, fr, slip, GQ, GV, cu, size, active)
    if n_active > 0:
        coupled_solve(y, Dq, Dv, P, C, fr[0], fr[1], GQ, GV, cu, active, n_active, uz)
    newton_update(move, y)


@njit_fast
def newton_update(move, y):
    """The full Newton step x -= y, kept (x_prev, delta) for friction_move's halving; move =
    (x, x_prev, delta)."""
    x, x_prev, delta = move
    for k in range(x.shape[0]):
        x_prev[k] = x[k]
        delta[k] = y[k]
        x[k] -= y[k]


@njit_fast
def backtrack(rnorm2, rprev2, alpha):
    """Whether to halve the last Newton step (of fraction alpha) again: its squared residual
    rnorm2 did not fall by ARMIJO alpha from rprev2, the step's start, and alpha is above
    MIN_STEP."""
    return alpha > MIN_STEP and rnorm2 > (1.0 - ARMIJO * alpha) ** 2 * rprev2
