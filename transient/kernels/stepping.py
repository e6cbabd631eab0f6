"""Time stepping kernels: each call integrates a chunk of steps and returns; no Python per step.

The system, in reduced coordinates (M = I) or on the free dofs of the full model:
    M a + c v + K_lin q = F(t) + C^T [w (p(g) + k_t* (g - g0))],   g = C q + g0,
where K_lin = K + C^T diag(w k_t*) C is the stiffness linearized at the preload (k_t*: contact
tangent there), so the contact rows only carry the nonlinear remainder, which vanishes to first
order around the preload. F(t) = sum_j patterns_j s_j(t).

The energies stored per output row, and a step's close, are bookkeeping.py's.

Contact points carry their own law: code (m,) and params (m, 4) (see laws.py), so pairs with
different laws share one set of rows.

Status codes returned: OK, NOT_FINITE (NaN/Inf in the state), NO_CONVERGENCE (implicit).
The exponential kernels are in exponential.py, the implicit Newmark ones in newmark.py.
"""
import numpy as np

from ..jit import njit_fast
from .bookkeeping import close_step, energies, step_buffers
from .codes import OK
from .layout import A_ROW, DAMPING_ACC, Q_ROW, TIME_ROW, V_ROW
from .contact import block_buffers, contact_pass
from .friction import friction_pass_sparse
from .laws import pressure_potential
from .signals import external_forces
from .sparse import csr_matvec


@njit_fast
def _track_min(gap, gmin):
    for i in range(gap.shape[0]):
        if gap[i] < gmin[i]:
            gmin[i] = gap[i]


@njit_fast
def explicit_reduced(state, acc, n_steps, every, dt, omega2, damp, contact, fr, signals, blocks,
                     gmin, out):
    """Central differences (velocity Verlet) on the reduced system, diagonal damping taken
    implicitly in the half step. state (STATE_ROWS, n), acc (ACC_SLOTS,): the rows and slots
    kernels.layout names (q, v, a, the time, the forces the exponential kernels carry; the
    external work and dissipated energy so far, a damping power explicit_full carries);
    gmin (m,): smallest gap of each point so far (the critical step is rechecked against it).
    fr: the friction's arrays (contact.contact_pass), taken at the half-step velocity; the
    state's FRICTION_ROW and the SLIDING_ACC accumulator then carry its force and input power
    (friction.friction_energy). Returns (status, steps done)."""
    patterns, sig, S = signals
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    n = q.shape[0]
    f, fext, fext_old, svals, gap, press, energy, ff, slip, dq, ff0 = step_buffers(
        state, contact, fr, signals)
    fbuf, ffbuf = block_buffers(blocks.shape[0] - 1, n)
    status, step = OK, 0
    for step in range(1, n_steps + 1):
        power = 0.0
        for k in range(n):
            vh = v[k] + 0.5 * dt * a[k]
            dq[k] = dt * vh
            power += damp[k] * v[k] * v[k]
            q[k] += dq[k]
            v[k] = vh
        t += dt
        external_forces(t, patterns, sig, svals, fext)
        phi, lin, p_in = contact_pass(contact, q, fr, v, f, ff, gap,
                                      press, slip, blocks, fbuf, ffbuf)
        _track_min(gap, gmin)
        kin = 0.0
        strain = -lin
        work = 0.0
        for k in range(n):
            # trapezoid: exact work of loads constant or linear over the step
            work += 0.5 * (fext_old[k] + fext[k]) * dq[k]
            fk = fext[k] + f[k] - omega2[k] * q[k]
            vn = (v[k] + 0.5 * dt * fk) / (1.0 + 0.5 * dt * damp[k])
            a[k] = fk - damp[k] * vn
            v[k] = vn
            fext_old[k] = fext[k]
            kin += 0.5 * vn * vn
            strain += 0.5 * omega2[k] * q[k] * q[k]
            power += damp[k] * vn * vn
        energies(energy, kin, strain, phi, acc, work, 0.5 * dt * power, fr, ff0, ff, dq, p_in,
                 dt)
        status = close_step(step, every, t, state, S, gap, press, slip, energy, True, out)
        if status != OK:
            break
    return status, step


@njit_fast
def remainder_sparse(Cp, Ci, Cd, g0, w, kt0, code, params, q, f, gap, press):
    """Sparse version of remainder_dense (rows of a CSR matrix C)."""
    f[:] = 0.0
    phi = 0.0
    lin = 0.0
    for i in range(g0.shape[0]):
        s = 0.0
        for k in range(Cp[i], Cp[i + 1]):
            s += Cd[k] * q[Ci[k]]
        g = g0[i] + s
        p, _, potential_i = pressure_potential(code[i], params[i], g)
        r = w[i] * (p + kt0[i] * s)
        for k in range(Cp[i], Cp[i + 1]):
            f[Ci[k]] += r * Cd[k]
        gap[i] = g
        press[i] = p
        phi += w[i] * potential_i
        lin += 0.5 * w[i] * kt0[i] * s * s
    return phi, lin


@njit_fast
def explicit_full(state, acc, n_steps, every, dt, K, mass, alpha, beta, contact, fr, signals, gmin,
                  out):
    """Central differences on the free dofs of the full model: K = (indptr, indices, data) of
    K_lin (CSR), lumped mass (n,), Rayleigh damping alpha M (implicit in the half step) and
    beta K (on the half-step velocity); C and S dense-free CSR triplets; fr the friction's
    arrays with CSR rows (friction_pass_sparse), taken at the half-step velocity as in
    explicit_reduced. Same state and outputs as explicit_reduced; acc[DAMPING_ACC] carries the
    damping power at the end of the last step."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    n = q.shape[0]
    Kp, Ki, Kd = K
    Cp, Ci, Cd = C
    f, fext, fext_old, svals, gap, press, energy, ff, slip, dq, ff0 = step_buffers(
        state, contact, fr, signals)
    ku = np.empty(n)
    kv = np.empty(n)
    # the damping power at the end of the last step, carried (it takes K at the half-step
    # velocity, which a chunk's start does not have)
    power_old = acc[DAMPING_ACC]
    status, step = OK, 0
    for step in range(1, n_steps + 1):
        for k in range(n):
            vh = v[k] + 0.5 * dt * a[k]
            dq[k] = dt * vh
            q[k] += dq[k]
            v[k] = vh
        t += dt
        external_forces(t, patterns, sig, svals, fext)
        phi, lin = remainder_sparse(Cp, Ci, Cd, g0, w, kt0, code, params, q, f, gap, press)
        p_in = friction_pass_sparse(fr, w, press, v, ff, f, slip)
        _track_min(gap, gmin)
        csr_matvec(Kp, Ki, Kd, q, ku)
        if beta != 0.0:
            csr_matvec(Kp, Ki, Kd, v, kv)
        work = 0.0
        kin = 0.0
        strain = -lin
        power = 0.0
        for k in range(n):
            work += 0.5 * (fext_old[k] + fext[k]) * dq[k]
            fk = fext[k] + f[k] - ku[k]
            if beta != 0.0:
                fk -= beta * kv[k]
            vn = (v[k] + 0.5 * dt * fk / mass[k]) / (1.0 + 0.5 * dt * alpha)
            a[k] = fk / mass[k] - alpha * vn
            v[k] = vn
            fext_old[k] = fext[k]
            kin += 0.5 * mass[k] * vn * vn
            strain += 0.5 * q[k] * ku[k]
            power += alpha * mass[k] * vn * vn
            if beta != 0.0:
                power += beta * vn * kv[k]
        energies(energy, kin, strain, phi, acc, work, 0.5 * dt * (power_old + power), fr, ff0,
                 ff, dq, p_in, dt)
        power_old = power
        acc[DAMPING_ACC] = power
        status = close_step(step, every, t, state, S, gap, press, slip, energy, True, out)
        if status != OK:
            break
    return status, step
