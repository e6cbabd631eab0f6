"""What every stepping kernel does around its physics, in one place: the buffers a step fills,
the energies of a step and their balance, and a step's close (finite? converged? stored?).

Energies (stored per output row): kinetic, strain (structure only: 1/2 q^T K q), contact
(sum w Phi(g)), external work, dissipated; their balance kinetic + strain + contact - work +
dissipated is constant.
"""
import numpy as np
from numba import types
from numba.extending import overload

from ..jit import njit, njit_fast
from .codes import (CONTACT, DISSIPATED, KINETIC, NO_CONVERGENCE, NOT_FINITE, OK, STRAIN,
                    WORK)
from .friction import friction_energy, friction_points
from .layout import DISSIPATED_ACC, FRICTION_ROW, Q_ROW, TIME_ROW, V_ROW, WORK_ACC
from .signals import external_forces


@njit_fast
def step_buffers(state, contact, fr, signals):
    """The arrays a step fills besides the state, for n dofs and m contact points: the contact
    force (n,), the loads at the step's end and at its start (n,: at the state's time), the
    signals' values, the gaps and the pressures (m,), the energy terms (5,), the friction
    force (n,), the slip velocities (2, points with friction), the step's displacement (n,),
    and the friction force at the step's start, carried in the state (with friction only: a
    frictionless state may have fewer rows). contact, fr and signals: the kernels' groups."""
    n = state.shape[1]
    m = contact[1].shape[0]
    n_friction = friction_points(fr)
    patterns, sig, _ = signals
    fext_old = np.empty(n)
    svals = np.empty(patterns.shape[0])
    external_forces(state[TIME_ROW, 0], patterns, sig, svals, fext_old)
    ff0 = state[FRICTION_ROW] if n_friction > 0 else np.empty(n)
    return (np.empty(n), np.empty(n), fext_old, svals, np.empty(m), np.empty(m), np.empty(5),
            np.empty(n), np.empty((2, n_friction)), np.empty(n), ff0)


EXPONENT = np.int64(0x7FF0000000000000)


@njit
def _finite(x):
    """All entries finite, read from the bits (exponent all ones: NaN or Inf). Fastmath lets the
    compiler assume floats are never NaN or Inf and fold np.isfinite to true, even inlined from
    a function compiled without it; integer operations it leaves alone."""
    bits = x.view(np.int64)
    for k in range(bits.shape[0]):
        if bits[k] & EXPONENT == EXPONENT:
            return False
    return True


@njit_fast
def energies(energy, kin, strain, phi, acc, work, dissipated, fr, ff0, ff, dq, p_in, dt):
    """Adds a step's external work and dissipation to acc, fills the energy terms, then, where
    fr has friction, adds the friction's share (friction.friction_energy: ff0 becomes ff; dq
    the step's displacement, p_in the sliding's input power at its end)."""
    acc[WORK_ACC] += work
    acc[DISSIPATED_ACC] += dissipated
    energy[KINETIC] = kin
    energy[STRAIN] = strain
    energy[CONTACT] = phi
    energy[WORK] = acc[WORK_ACC]
    energy[DISSIPATED] = acc[DISSIPATED_ACC]
    if friction_points(fr) > 0:
        friction_energy(acc, energy, ff0, ff, dq, p_in, dt)


@njit_fast
def modal_step_end(q, v, start, fext, damp, omega2, passed, dt, fr, ff0, ff, dq, acc, energy):
    """The energies after a step of a modal system (M = I, diagonal damping and K_lin) from
    start = (q0, v0, fext0) to (q, v, fext): external work and dissipation by the trapezoidal
    rule, kinetic and strain (K_lin's, less the contact's linear part) at the end, the
    friction's share; passed = (phi, lin, p_in) as contact_pass returns them. dq becomes
    q - q0, fext0 fext and ff0 ff."""
    q0, v0, fext0 = start
    phi, lin, p_in = passed
    work = 0.0
    power = 0.0
    kin = 0.0
    strain = -lin
    for k in range(q.shape[0]):
        work += 0.5 * (fext0[k] + fext[k]) * (q[k] - q0[k])
        power += damp[k] * (v0[k] * v0[k] + v[k] * v[k])
        kin += 0.5 * v[k] * v[k]
        strain += 0.5 * omega2[k] * q[k] * q[k]
    for k in range(q.shape[0]):
        dq[k] = q[k] - q0[k]
        fext0[k] = fext[k]
    energies(energy, kin, strain, phi, acc, work, 0.5 * dt * power, fr, ff0, ff, dq, p_in, dt)


@njit
def _status(q, v, energy, converged):
    if not (_finite(q) and _finite(v) and _finite(energy)):
        return NOT_FINITE
    if not converged:
        return NO_CONVERGENCE
    return OK


def _sense(row, q, S, out_s):
    """out_s[row] = the sensors S q: S dense (r, n) in the reduced kernels, a CSR triplet
    (indptr, indices, data) in the full model's."""


@overload(_sense, jit_options={"fastmath": True, "error_model": "numpy"})
def _sense_typed(row, q, S, out_s):
    if isinstance(S, types.Array):
        def dense(row, q, S, out_s):
            for k in range(S.shape[0]):
                s = 0.0
                for j in range(q.shape[0]):
                    s += S[k, j] * q[j]
                out_s[row, k] = s
        return dense

    def sparse(row, q, S, out_s):
        Sp, Si, Sd = S
        for k in range(Sp.shape[0] - 1):
            s = 0.0
            for j in range(Sp[k], Sp[k + 1]):
                s += Sd[j] * q[Si[j]]
            out_s[row, k] = s
    return sparse


@njit_fast
def close_step(step, every, t, state, S, gap, press, slip, energy, converged, out):
    """Step `step` of a chunk closed at time t, the state's time set: its status (NOT_FINITE
    before NO_CONVERGENCE, else OK); the step stored when OK at a multiple of every, in row
    step // every - 1 (a chunk stops at its first failed step): the time, the energies, the
    sensors S q (S dense or CSR), and the contact points' gaps, pressures and (with friction)
    slip velocities when stored (out_v (r, 2, m), or none)."""
    state[TIME_ROW, 0] = t
    q, v = state[Q_ROW], state[V_ROW]
    status = _status(q, v, energy, converged)
    if status != OK or step % every != 0:
        return status
    row = step // every - 1
    out_t, out_s, out_g, out_p, out_v, out_e = out
    out_t[row] = t
    out_e[row] = energy
    _sense(row, q, S, out_s)
    if out_g.shape[1] > 0:
        out_g[row] = gap
        out_p[row] = press
    if out_v.shape[2] > 0:
        out_v[row] = slip
    return status
