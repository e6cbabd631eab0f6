"""Exponential integrator kernels on the reduced system (stepping.py has the system, the
state and the outputs): each mode's linear part, the contact linearized at the preload
included, is propagated exactly over a step; the forces, loads and contact remainder, are taken
linear in time between the step's ends and corrected explicitly (exponential_reduced) or solved
for by Newton (exponential_implicit)."""
import numpy as np

from ..jit import njit_fast
from .codes import NO_CONVERGENCE, NOT_FINITE, OK
from .stepping import (_external, _finite, _store, friction_energy, friction_pass,
                       modal_step_energies, remainder_dense)
from .woodbury import active_rows, woodbury_dense

IMPLICIT_TOL = 1e-3     # the implicit corrector's residual, relative to the step's motion


@njit_fast
def _propagate(coef, q0, v0, f0, f1, q, v):
    """(q, v) at the end of a step from (q0, v0) and forces f0, f1 at its ends, mode by mode."""
    for k in range(q.shape[0]):
        dF = f1[k] - f0[k]
        q[k] = coef[k, 0] * q0[k] + coef[k, 1] * v0[k] + coef[k, 4] * f0[k] + coef[k, 6] * dF
        v[k] = coef[k, 2] * q0[k] + coef[k, 3] * v0[k] + coef[k, 5] * f0[k] + coef[k, 7] * dF


@njit_fast
def _finish(state, t, f0, fstart, omega2, damp):
    """A chunk's end: the time, the forces at the start of the next step (carried, so that a
    run cut into chunks is the same run), and the acceleration they give."""
    state[3, 0] = t
    q, v, a = state[0], state[1], state[2]
    for k in range(q.shape[0]):
        fstart[k] = f0[k]
        a[k] = f0[k] - omega2[k] * q[k] - damp[k] * v[k]


@njit_fast
def exponential_reduced(state, acc, n_steps, every, dt, coef, damp, omega2, C, g0, w, kt0,
                        code, params, fr, patterns, sig, S, blocks, corrections, propagate,
                        fprev, fstart, out_t, out_s, out_g, out_p, out_e):
    """Exponential integrator on the reduced system: each mode's linear part (K_lin, damping)
    is propagated exactly over a step, the forces F = patterns s(t) + remainder(q) taken linear
    in time between the step's ends (first-order hold).

    coef (n, 8): per mode, the propagator [E11, E12, E21, E22] in columns 0-3, then the responses
    to F0 and to the ramp F1 - F0, [G0x, G0v, G1x, G1v], in columns 4-7
    (dynamics.schemes.exponential_coefficients).
    A predictor extrapolates F linearly from the previous step (fprev (n,): F at the start of
    the previous step, and fstart (n,): F at the start of the next one, both carried between
    chunks, so that where a run is cut changes nothing); F at the end point is evaluated at the
    predicted state, then `corrections` times more at the state propagated with it (one
    contact pass per evaluation). The step ends at the last state evaluated, or, if
    `propagate`, at a last propagation from the forces evaluated there (PEC for corrections = 0:
    on smooth contact as accurate as PECE at half the cost; on a stiff penalty closing the
    explicit force update is not: 11% energy drift on the bar impact, against 0.2% for PECE).
    With propagate, the gaps, pressures and contact energy stored are those of the last
    evaluation, a local error away from the final state. state, acc and outputs as in
    explicit_reduced; the acceleration left in the state is that of the forces carried.
    fr: the friction's arrays (stepping.friction_pass), its tractions part of the remainder,
    at each evaluation's velocity; state[6] and acc[3] carry its force and input power."""
    q, v = state[0], state[1]
    t = state[3, 0]
    n = q.shape[0]
    m = C.shape[0]
    rem = np.empty(n)
    fext = np.empty(n)
    f0 = np.empty(n)
    f1 = np.empty(n)
    q0 = np.empty(n)
    v0 = np.empty(n)
    svals = np.empty(patterns.shape[0])
    gap = np.empty(m)
    press = np.empty(m)
    fbuf = np.empty((blocks.shape[0] - 1, n))
    energy = np.empty(5)
    fext0 = np.empty(n)
    ff = np.empty(n)
    dq = np.empty(n)
    # the friction force at the step's start, carried in the state (with friction only: a
    # frictionless state may have fewer rows)
    ff0 = state[6] if fr[0].shape[0] > 0 else np.empty(n)
    _external(t, patterns, sig, svals, fext0)
    for k in range(n):
        f0[k] = fstart[k]
    row = 0
    for step in range(1, n_steps + 1):
        for k in range(n):
            q0[k] = q[k]
            v0[k] = v[k]
            f1[k] = 2.0 * f0[k] - fprev[k]          # linear extrapolation of the forces
        t += dt
        _external(t, patterns, sig, svals, fext)
        p_in = 0.0
        for it in range(corrections + 1):
            _propagate(coef, q0, v0, f0, f1, q, v)
            phi, lin = remainder_dense(C, g0, w, kt0, code, params, q, rem, gap, press, blocks,
                                       fbuf)
            p_in = friction_pass(fr, w, press, v, ff, rem)
            for k in range(n):
                f1[k] = fext[k] + rem[k]
        if propagate:
            _propagate(coef, q0, v0, f0, f1, q, v)
        modal_step_energies(q, v, q0, v0, fext0, fext, damp, omega2, lin, phi, dt, acc,
                            energy)
        for k in range(n):
            dq[k] = q[k] - q0[k]
        friction_energy(fr, acc, energy, ff0, ff, dq, p_in, dt)
        for k in range(n):
            fprev[k] = f0[k]
            f0[k] = f1[k]
            fext0[k] = fext[k]
        if not (_finite(q) and _finite(v) and _finite(energy)):
            _finish(state, t, f0, fstart, omega2, damp)
            return NOT_FINITE, step
        if step % every == 0:
            _store(row, t, q, S, gap, press, energy, out_t, out_s, out_g, out_p, out_e)
            row += 1
    _finish(state, t, f0, fstart, omega2, damp)
    return OK, n_steps


@njit_fast
def exponential_implicit(state, acc, n_steps, every, dt, coef, damp, omega2, C, g0, w, kt0,
                         code, params, patterns, sig, S, blocks, Z, G, max_iter, fprev, fstart,
                         out_t, out_s, out_g, out_p, out_e):
    """The exponential integrator with the forces at the step's end taken implicitly.

    The end state is affine in the end forces, q = qb + D F1 with D = diag(G1x), so the step
    solves q = qb + D (fext + remainder(q)) by Newton: J = I + D C^T diag(e) C with
    e_i = w_i (k_t,i - k_t*,i). Rows whose tangent moved from the preload's are corrected
    exactly through Woodbury (Z = D C^T, G = C Z; woodbury.py), the others by fixed-point
    iteration, which is the evaluated corrector (PECE) when no row moved. exponential_reduced
    treats the remainder explicitly and diverges once contact stiffens far beyond the preload's
    tangent at a step set by accuracy (a hard tap on pad_disc: 4 kN); here it stays stable.
    Converged when the residual is below IMPLICIT_TOL of the step's motion (on pad_disc's tap
    the histories then agree with the evaluated corrector's to 4e-6, at one contact pass per
    step or two); NO_CONVERGENCE after max_iter iterations. Otherwise as exponential_reduced."""
    q, v = state[0], state[1]
    t = state[3, 0]
    n = q.shape[0]
    m = C.shape[0]
    rem = np.empty(n)
    fext = np.empty(n)
    fext0 = np.empty(n)
    f0 = np.empty(n)
    f1 = np.empty(n)
    q0 = np.empty(n)
    v0 = np.empty(n)
    qb = np.empty(n)
    y = np.empty(n)
    svals = np.empty(patterns.shape[0])
    gap = np.empty(m)
    press = np.empty(m)
    e = np.empty(m)
    u = np.empty(m)
    active = np.empty(m, np.int64)
    Gd = np.empty(m)
    for i in range(m):
        Gd[i] = G[i, i]
    fbuf = np.empty((blocks.shape[0] - 1, n))
    energy = np.empty(5)
    _external(t, patterns, sig, svals, fext0)
    for k in range(n):
        f0[k] = fstart[k]
    row = 0
    for step in range(1, n_steps + 1):
        for k in range(n):
            q0[k] = q[k]
            v0[k] = v[k]
            f1[k] = 2.0 * f0[k] - fprev[k]          # predictor: forces extrapolated
        t += dt
        _external(t, patterns, sig, svals, fext)
        _propagate(coef, q0, v0, f0, f1, q, v)
        for k in range(n):
            qb[k] = q[k] - coef[k, 6] * f1[k]
        converged = False
        for it in range(max_iter):
            phi, lin = remainder_dense(C, g0, w, kt0, code, params, q, rem, gap, press, blocks,
                                       fbuf)
            rnorm = 0.0
            motion = 0.0
            size = 0.0
            for k in range(n):
                f1[k] = fext[k] + rem[k]
                r = qb[k] + coef[k, 6] * f1[k] - q[k]
                y[k] = r
                rnorm += r * r
                motion += (q[k] - q0[k]) ** 2
                size += q[k] * q[k]
            if rnorm <= IMPLICIT_TOL * IMPLICIT_TOL * max(motion, 1e-20 * size, 1e-300):
                converged = True
                break
            n_active = active_rows(code, params, gap, w, kt0, 1.0, Gd, e, active)
            if n_active > 0:
                woodbury_dense(y, C, u, active, n_active, e, Z, G)
            for k in range(n):
                q[k] += y[k]
        # v from the forces found; q stays the state they were evaluated at (within the
        # tolerance of the propagated one), so a chunk restarting from it finds the same forces
        _propagate(coef, q0, v0, f0, f1, qb, v)
        modal_step_energies(q, v, q0, v0, fext0, fext, damp, omega2, lin, phi, dt, acc,
                            energy)
        for k in range(n):
            fprev[k] = f0[k]
            f0[k] = f1[k]
            fext0[k] = fext[k]
        if not (_finite(q) and _finite(v) and _finite(energy)):
            _finish(state, t, f0, fstart, omega2, damp)
            return NOT_FINITE, step
        if not converged:
            _finish(state, t, f0, fstart, omega2, damp)
            return NO_CONVERGENCE, step
        if step % every == 0:
            _store(row, t, q, S, gap, press, energy, out_t, out_s, out_g, out_p, out_e)
            row += 1
    _finish(state, t, f0, fstart, omega2, damp)
    return OK, n_steps
