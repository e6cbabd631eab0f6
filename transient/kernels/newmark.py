"""Implicit Newmark kernels (average acceleration: beta = 1/4, gamma = 1/2) with Newton
iterations on the accelerations; the system and outputs are those of stepping.py.

Each step solves R(a) = M a + c v(a) + K_lin q(a) - F(t) - remainder(q(a)) = 0 with
q = q_p + h2 a, v = v_p + dt/2 a, h2 = dt^2 / 4. The iteration operator S = M + dt/2 c + h2 K_lin
(the linear part at the preload) is factorized once, outside. Its Jacobian is
J = S + C^T diag(e) C, e_i = h2 w_i (k_t,i - k_t*,i): where contact tangents moved far from the
preload's (an impact closing, a deep penetration), the fixed operator alone would not converge,
so those rows are added exactly through the Woodbury identity with the precomputed
Z = S^-1 C^T and G = C Z:
    J^-1 r = y - Z_A (I + diag(e_A) G_AA)^-1 diag(e_A) C_A y,   y = S^-1 r,
for the set A of rows that matter (the others, whose sum of |e_i| G_ii stays below WOODBURY_REST,
are left to the fixed-operator iteration, which they slow by at most that factor: woodbury.py).
"""
import numpy as np

from ..jit import njit_fast
from .bookkeeping import close_step, energies, modal_step_end, step_buffers
from .sparse import csr_abs_matvec, csr_matvec, csr_row_dot, factor_solve
from .codes import OK
from .layout import A_ROW, Q_ROW, TIME_ROW, V_ROW
from .contact import block_buffers, contact_pass
from .friction import friction_pass_sparse
from .signals import external_forces
from .stepping import remainder_sparse
from .woodbury import (active_rows, coupled_rows, coupled_solve_sparse, friction_move,
                       move_start, newton_buffers, newton_coupled, newton_update, woodbury)


@njit_fast
def _corrected(qp, vp, a, dt, q, v):
    """Newmark's displacement and velocity from their predictors and the accelerations."""
    for k in range(q.shape[0]):
        q[k] = qp[k] + 0.25 * dt * dt * a[k]
        v[k] = vp[k] + 0.5 * dt * a[k]


@njit_fast
def _predicted(state, t, dt, h2, kept, patterns, sig, svals, fext):
    """A step's start at time t: kept = (q_old, v_old, qp, vp) the state there and Newmark's
    predictors from it (h2 = dt^2 / 4), the state moved to the first iterate (the
    accelerations kept), and the loads at the step's end; returns the time there."""
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    q_old, v_old, qp, vp = kept
    for k in range(q.shape[0]):
        q_old[k] = q[k]
        v_old[k] = v[k]
        qp[k] = q[k] + dt * v[k] + h2 * a[k]
        vp[k] = v[k] + 0.5 * dt * a[k]
    _corrected(qp, vp, a, dt, q, v)
    t += dt
    external_forces(t, patterns, sig, svals, fext)
    return t


@njit_fast
def _kept(n):
    """_predicted's (q_old, v_old, qp, vp) for n dofs."""
    return np.empty(n), np.empty(n), np.empty(n), np.empty(n)


@njit_fast
def _rayleigh(Mp, Mi, Md, Kp, Ki, Kd, beta, v, mv, kv):
    """The products of Rayleigh damping's two parts with v: M v, and K v where beta is not 0
    (M, K: CSR triplets)."""
    csr_matvec(Mp, Mi, Md, v, mv)
    if beta != 0.0:
        csr_matvec(Kp, Ki, Kd, v, kv)


@njit_fast
def newmark_reduced(state, acc, n_steps, every, dt, damp, omega2, contact, fr, signals, blocks,
                    iteration, out):
    """Newmark on the reduced system (M = I, diagonal damping and K_lin): S is diagonal, and
    the Jacobian with the contact's and the friction's exact terms is that of
    woodbury.coupled_rows with x = a, P = S, Dq = dt^2/4, Dv = dt/2: GQ = C Dq S^-1 Cs^T and
    GV = [Ct; Cc] Dv S^-1 Cs^T (Cs = [C; Ct; Cc]; GQ = C Dq S^-1 C^T and GV empty without
    friction, fr's Ct with no rows); with friction, the fixed point first, then Newton with
    its steps halved while the residual does not fall (as exponential.exponential_implicit).
    Converged when the residual is below tol times the force
    scale (external, contact, elastic, inertial, and the momentum over a half step, which sets
    the scale in free flight); NO_CONVERGENCE after max_iter iterations. state, acc and
    outputs as in stepping.explicit_reduced; friction at the end velocity, the state's
    FRICTION_ROW and the SLIDING_ACC accumulator carrying its force and input power
    (friction.friction_energy)."""
    patterns, sig, S = signals
    GQ, GV, tol, max_iter = iteration
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    n = q.shape[0]
    friction = fr[0].shape[0] > 0
    rem, fext, fext_old, svals, gap, press, energy, ff, slip, dq, ff0 = step_buffers(
        state, contact, fr, signals)
    fbuf, ffbuf = block_buffers(blocks.shape[0] - 1, n)
    kept = _kept(n)
    q_old, v_old, qp, vp = kept
    start = (q_old, v_old, fext_old)
    y, uz, move, coupled = newton_buffers(a, gap.shape[0], friction)
    op = np.empty(n)
    h2 = 0.25 * dt * dt
    Dq = np.full(n, h2)
    Dv = np.full(n, 0.5 * dt)
    v_scale = 2.0 / dt if dt > 0.0 else 0.0     # momentum over a step: a force scale in flight
    for k in range(n):
        op[k] = 1.0 + 0.5 * dt * damp[k] + h2 * omega2[k]
    passed = (0.0, 0.0, 0.0)
    status, step = OK, 0
    for step in range(1, n_steps + 1):
        t = _predicted(state, t, dt, h2, kept, patterns, sig, svals, fext)
        converged, rprev, alpha, newton = move_start(friction)
        for it in range(max_iter):
            passed = contact_pass(contact, q, fr, v, rem, ff, gap, press, slip, blocks, fbuf,
                                  ffbuf)
            rnorm = 0.0
            fnorm = 0.0
            for k in range(n):
                f = fext[k] + rem[k]
                r = a[k] + damp[k] * v[k] + omega2[k] * q[k] - f
                rnorm += r * r
                fnorm += f * f + (omega2[k] * q[k]) ** 2 + a[k] * a[k] + (v_scale * v[k]) ** 2
                y[k] = r / op[k]
            if rnorm <= tol * tol * max(fnorm, 1e-300):
                converged = True
                break
            solve, newton, rprev, alpha = friction_move(move, y, rnorm, rprev, newton, alpha,
                                                        friction)
            if solve:
                newton_coupled(y, Dq, Dv, op, contact, fr, gap, press, slip, GQ, GV, coupled,
                               uz, move)
            _corrected(qp, vp, a, dt, q, v)
        modal_step_end(q, v, start, fext, damp, omega2, passed, dt, fr, ff0, ff, dq, acc, energy)
        status = close_step(step, every, t, state, S, gap, press, slip, energy, converged, out)
        if status != OK:
            break
    return status, step


@njit_fast
def newmark_full(state, acc, n_steps, every, dt, K, M, alpha, beta, contact, fr, signals,
                 iteration, out):
    """Newmark on the free dofs of the full model: K (K_lin) and M CSR triplets, Rayleigh
    damping alpha M + beta K, C and S CSR triplets; factor = (p_in, L, U, p_out) of
    S = (1 + dt/2 alpha) M + (dt/2 beta + h2) K_lin (linsolve.triangular_factors). Without
    friction (fr as friction_pass_sparse's, Ct of no row; GV empty) Z = S^-1 C^T (n, m) and
    G = C Z (m, m) for active_rows; with it Z = S^-1 Cs^T (n, 3m), G = h2 C Z and GV =
    dt/2 [Ct; Cc] Z for coupled_rows, the fixed point first and then Newton with backtracking,
    as newmark_reduced. Otherwise as newmark_reduced."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    factor, Z, G, GV, tol, max_iter = iteration
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    n = q.shape[0]
    m = g0.shape[0]
    Kp, Ki, Kd = K
    Mp, Mi, Md = M
    Cp, Ci, Cd = C
    perm_in, L, U, perm_out = factor
    friction = fr[0][0].shape[0] > 1
    rem, fext, fext_old, svals, gap, press, energy, ff, slip, dq, ff0 = step_buffers(
        state, contact, fr, signals)
    kept = _kept(n)
    q_old, v_old, qp, vp = kept
    y, _, move, coupled = newton_buffers(a, m, friction)
    cu, size, active_terms = coupled
    ku = np.empty(n)
    kabs = np.empty(n)
    kv = np.empty(n)
    ma = np.empty(n)
    mv = np.empty(n)
    r = np.empty(n)
    work_n = np.empty(n)
    e = np.empty(m)
    u = np.empty(m)
    active = np.empty(m, np.int64)
    Gd = np.empty(m)
    for i in range(m):
        Gd[i] = G[i, i]
    h2 = 0.25 * dt * dt
    v_scale = 2.0 / dt if dt > 0.0 else 0.0     # momentum over a step: a force scale in flight
    csr_matvec(Mp, Mi, Md, v, mv)
    csr_matvec(Kp, Ki, Kd, v, kv)
    power_old = 0.0
    for k in range(n):
        power_old += alpha * v[k] * mv[k] + beta * v[k] * kv[k]
    phi = 0.0
    lin = 0.0
    p_in = 0.0
    status, step = OK, 0
    for step in range(1, n_steps + 1):
        t = _predicted(state, t, dt, h2, kept, patterns, sig, svals, fext)
        converged, rprev, frac, newton = move_start(friction)
        for it in range(max_iter):
            phi, lin = remainder_sparse(Cp, Ci, Cd, g0, w, kt0, code, params, q, rem, gap, press)
            p_in = friction_pass_sparse(fr, w, press, v, ff, rem, slip)
            csr_matvec(Kp, Ki, Kd, q, ku)
            csr_abs_matvec(Kp, Ki, Kd, q, kabs)
            csr_matvec(Mp, Mi, Md, a, ma)
            _rayleigh(Mp, Mi, Md, Kp, Ki, Kd, beta, v, mv, kv)
            rnorm = 0.0
            fnorm = 0.0
            for k in range(n):
                f = fext[k] + rem[k]
                r[k] = ma[k] + ku[k] + alpha * mv[k] - f
                if beta != 0.0:
                    r[k] += beta * kv[k]
                rnorm += r[k] * r[k]
                fnorm += f * f + kabs[k] * kabs[k] + ma[k] * ma[k] + (v_scale * mv[k]) ** 2
            if rnorm <= tol * tol * max(fnorm, 1e-300):
                converged = True
                break
            factor_solve(perm_in, L, U, perm_out, r, y, work_n)
            solve, newton, rprev, frac = friction_move(move, y, rnorm, rprev, newton, frac,
                                                       friction)
            if solve:
                if friction:
                    n_active = coupled_rows(code, params, gap, press, w, kt0, fr, slip, G, GV,
                                            cu, size, active_terms)
                    if n_active:
                        coupled_solve_sparse(y, h2, 0.5 * dt, C, fr[0], fr[1], Z, G, GV, cu,
                                             active_terms, n_active)
                else:
                    n_active = active_rows(code, params, gap, w, kt0, h2, Gd, e, active)
                    if n_active:
                        for j in range(n_active):
                            u[j] = csr_row_dot(C, active[j], y)
                        woodbury(y, u, active, n_active, e, Z, G)
                newton_update(move, y)
            _corrected(qp, vp, a, dt, q, v)
        csr_matvec(Kp, Ki, Kd, q, ku)
        _rayleigh(Mp, Mi, Md, Kp, Ki, Kd, beta, v, mv, kv)
        work = 0.0
        kin = 0.0
        strain = -lin
        power = 0.0
        for k in range(n):
            dq[k] = q[k] - q_old[k]
            work += 0.5 * (fext_old[k] + fext[k]) * dq[k]
            kin += 0.5 * v[k] * mv[k]
            strain += 0.5 * q[k] * ku[k]
            power += alpha * v[k] * mv[k]
            if beta != 0.0:
                power += beta * v[k] * kv[k]
            fext_old[k] = fext[k]
        energies(energy, kin, strain, phi, acc, work, 0.5 * dt * (power_old + power), fr, ff0,
                 ff, dq, p_in, dt)
        power_old = power
        status = close_step(step, every, t, state, S, gap, press, slip, energy, converged, out)
        if status != OK:
            break
    return status, step


@njit_fast
def factor_columns(factor, C, n):
    """Z = S^-1 C^T (n, m) for a CSR C (m, n), column by column through the factors."""
    p_in, L, U, p_out = factor
    Cp, Ci, Cd = C
    m = Cp.shape[0] - 1
    Z = np.zeros((n, m))
    b = np.empty(n)
    x = np.empty(n)
    work = np.empty(n)
    for i in range(m):
        b[:] = 0.0
        for k in range(Cp[i], Cp[i + 1]):
            b[Ci[k]] = Cd[k]
        factor_solve(p_in, L, U, p_out, b, x, work)
        Z[:, i] = x
    return Z
