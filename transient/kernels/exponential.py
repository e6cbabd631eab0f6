"""Exponential integrator kernels on the reduced system (stepping.py has the system, the
state and the outputs): each mode's linear part, the contact linearized at the preload
included, is propagated exactly over a step; the forces, loads and contact remainder, are taken
linear in time between the step's ends and corrected explicitly (exponential_reduced) or solved
for by Newton (exponential_implicit)."""
import numpy as np

from ..jit import njit_fast
from .bookkeeping import close_step, modal_step_end, step_buffers
from .codes import OK
from .layout import A_ROW, Q_ROW, TIME_ROW, V_ROW
from .contact import block_buffers, contact_pass
from .signals import external_forces
from .woodbury import friction_move, move_start, newton_buffers, newton_coupled

IMPLICIT_TOL = 1e-3     # the implicit corrector's residual, relative to the step's motion


@njit_fast
def _propagate(coef, q0, v0, f0, f1, q, v):
    """(q, v) at the end of a step from (q0, v0) and forces f0, f1 at its ends, mode by mode."""
    for k in range(q.shape[0]):
        dF = f1[k] - f0[k]
        q[k] = coef[k, 0] * q0[k] + coef[k, 1] * v0[k] + coef[k, 4] * f0[k] + coef[k, 6] * dF
        v[k] = coef[k, 2] * q0[k] + coef[k, 3] * v0[k] + coef[k, 5] * f0[k] + coef[k, 7] * dF


@njit_fast
def _predicted(q, v, f0, fprev, q0, v0, f1):
    """A step's start kept (q0, v0) and the forces at its end predicted, extrapolated linearly
    from those at its start (f0) and at the previous step's (fprev)."""
    for k in range(q.shape[0]):
        q0[k] = q[k]
        v0[k] = v[k]
        f1[k] = 2.0 * f0[k] - fprev[k]


@njit_fast
def _carried(fprev, f0, f1):
    """The forces handed on at a step's end: the previous step's start, and the next one's."""
    for k in range(f0.shape[0]):
        fprev[k] = f0[k]
        f0[k] = f1[k]


@njit_fast
def _finish(state, f0, fstart, omega2, damp):
    """A chunk's end: the forces at the start of the next step (carried, so that a run cut
    into chunks is the same run), and the acceleration they give."""
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    for k in range(q.shape[0]):
        fstart[k] = f0[k]
        a[k] = f0[k] - omega2[k] * q[k] - damp[k] * v[k]


@njit_fast
def exponential_reduced(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks,
                        corrector, carry, out):
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
    fr: the friction's arrays (contact.contact_pass), its tractions part of the remainder,
    at each evaluation's velocity; the state's FRICTION_ROW and the SLIDING_ACC accumulator
    carry its force and input power."""
    no_iteration = (np.empty((0, 0)), np.empty((0, 0)), 0)
    return _steps(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks, corrector,
                  no_iteration, carry, out)


@njit_fast
def exponential_implicit(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks,
                         iteration, carry, out):
    """The exponential integrator with the forces at the step's end taken implicitly.

    The end state is affine in the end forces x, q = qb + D x and v = vb + Dv x with
    D = diag(G1x), Dv = diag(G1v), so the step solves R(x) = x - fext - f(q, v) = 0 (f the
    contact remainder and the friction) by Newton: J = I + U V^T as in woodbury.coupled_rows
    (P = I, Dq = D), from GQ = C D Cs^T and GV = [Ct; Cc] Dv Cs^T (Cs = [C; Ct; Cc]; GQ =
    C D C^T and GV empty without friction). The terms whose tangent moved from the preload's,
    and with friction the slip's and the pressure's, are corrected exactly, the others by
    fixed-point iteration, which is the evaluated corrector (PECE) when none is taken. With
    friction, whose linear coupling makes most points' terms count in coupled_rows' sum even
    where the explicit corrector converges, the step iterates on the fixed point while the
    residual falls by FIXED_POINT_RATE an iteration, and by Newton once it does not; there a
    step whose residual does not fall is halved (woodbury.backtrack): Newton alone overshoots
    the saturating regularized sign and cycles.
    exponential_reduced treats the remainder explicitly and diverges once contact stiffens far
    beyond the preload's tangent at a step set by accuracy (a hard tap on pad_disc: 4 kN), or
    once friction sticks (its tangent w p mu / v_eps); here it stays stable. Converged when the
    residual's motion D R is below IMPLICIT_TOL of the step's (on pad_disc's tap the histories
    then agree with the evaluated corrector's to 4e-6, at one contact pass per step or two),
    and with friction Dv R below IMPLICIT_TOL of the velocity's change; NO_CONVERGENCE after
    max_iter iterations. q stays the last state evaluated, v is propagated with the forces
    found there. Otherwise as exponential_reduced."""
    return _steps(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks, (0, False),
                  iteration, carry, out)


@njit_fast
def _steps(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks, corrector,
           iteration, carry, out):
    """The steps of both kernels, which differ only in how a step finds the forces at its end:
    exponential_reduced's explicit corrector (corrector = (corrections, propagate)) where
    iteration's max_iter is 0, else exponential_implicit's Newton (iteration = (GQ, GV,
    max_iter); corrector unused)."""
    coef, damp, omega2 = modal
    patterns, sig, S = signals
    corrections, propagate = corrector
    GQ, GV, max_iter = iteration
    fprev, fstart = carry
    q, v = state[Q_ROW], state[V_ROW]
    t = state[TIME_ROW, 0]
    n = q.shape[0]
    implicit = max_iter > 0
    friction = fr[0].shape[0] > 0
    rem, fext, fext0, svals, gap, press, energy, ff, slip, dq, ff0 = step_buffers(
        state, contact, fr, signals)
    fbuf, ffbuf = block_buffers(blocks.shape[0] - 1, n)
    f0 = np.empty(n)
    f1 = np.empty(n)
    q0 = np.empty(n)
    v0 = np.empty(n)
    start = (q0, v0, fext0)
    # the implicit corrector's unknown, the end forces, apart from f1 (the forces evaluated
    # at its iterate); the explicit corrector predicts into f1 itself
    x = np.empty(n) if implicit else f1
    qb = np.empty(n)
    vb = np.empty(n)
    y, uz, move, coupled = newton_buffers(x, gap.shape[0], friction)
    ones = np.ones(n)
    Dq = np.ascontiguousarray(coef[:, 6])
    Dv = np.ascontiguousarray(coef[:, 7])
    for k in range(n):
        f0[k] = fstart[k]
    status, step = OK, 0
    for step in range(1, n_steps + 1):
        _predicted(q, v, f0, fprev, q0, v0, x)
        t += dt
        external_forces(t, patterns, sig, svals, fext)
        passed = (0.0, 0.0, 0.0)
        converged = True
        if not implicit:
            for it in range(corrections + 1):
                _propagate(coef, q0, v0, f0, f1, q, v)
                passed = contact_pass(contact, q, fr, v, rem, ff, gap, press, slip, blocks,
                                      fbuf, ffbuf)
                for k in range(n):
                    f1[k] = fext[k] + rem[k]
            if propagate:
                _propagate(coef, q0, v0, f0, f1, q, v)
        else:
            _propagate(coef, q0, v0, f0, x, q, v)
            for k in range(n):
                qb[k] = q[k] - Dq[k] * x[k]
                vb[k] = v[k] - Dv[k] * x[k]
            converged, rprev, alpha, newton = move_start(friction)
            for it in range(max_iter):
                passed = contact_pass(contact, q, fr, v, rem, ff, gap, press, slip, blocks,
                                      fbuf, ffbuf)
                rf = 0.0
                rq = 0.0
                rv = 0.0
                motion = 0.0
                size_q = 0.0
                change = 0.0
                size_v = 0.0
                for k in range(n):
                    f1[k] = fext[k] + rem[k]
                    r = x[k] - f1[k]
                    y[k] = r
                    rf += r * r
                    rq += (Dq[k] * r) ** 2
                    rv += (Dv[k] * r) ** 2
                    motion += (q[k] - q0[k]) ** 2
                    size_q += q[k] * q[k]
                    change += (v[k] - v0[k]) ** 2
                    size_v += v[k] * v[k]
                tol2 = IMPLICIT_TOL * IMPLICIT_TOL
                if rq <= tol2 * max(motion, 1e-20 * size_q, 1e-300) and (
                        not friction or rv <= tol2 * max(change, 1e-20 * size_v, 1e-300)):
                    converged = True
                    break
                solve, newton, rprev, alpha = friction_move(move, y, rf, rprev, newton, alpha,
                                                            friction)
                if solve:
                    newton_coupled(y, Dq, Dv, ones, contact, fr, gap, press, slip, GQ, GV,
                                   coupled, uz, move)
                for k in range(n):
                    q[k] = qb[k] + Dq[k] * x[k]
                    v[k] = vb[k] + Dv[k] * x[k]
            # v from the forces found; q stays the state they were evaluated at (within the
            # tolerance of the propagated one), so a chunk restarting from it finds the same
            # forces
            _propagate(coef, q0, v0, f0, f1, qb, v)
        modal_step_end(q, v, start, fext, damp, omega2, passed, dt, fr, ff0, ff, dq, acc, energy)
        _carried(fprev, f0, f1)
        status = close_step(step, every, t, state, S, gap, press, slip, energy, converged, out)
        if status != OK:
            break
    _finish(state, f0, fstart, omega2, damp)
    return status, step
