"""Time signals evaluated inside the kernels, from the arrays `case.signals.compile_signals`
packs (see that module for the kinds and their active windows)."""
import numpy as np

from ..jit import njit, njit_fast
from .codes import (AMPLITUDE, CHIRP, CONSTANT, DURATION, F1, FREQUENCY, IMPULSE, PHASE, RISE,
                    SINE, START, STEP, TABLE)


@njit
def signal_value(j, t, codes, params, table_t, table_v, table_n):
    """Value [-] of signal j at time t [s] (arrays from `compile_signals`)."""
    code = codes[j]
    if code == CONSTANT:
        return 1.0
    if code == TABLE:
        return _table_value(j, t, table_t, table_v, table_n[j])
    tau = t - params[j, START]
    if tau < 0.0:
        return 0.0
    a = params[j, AMPLITUDE]
    d = params[j, DURATION]
    if code == STEP:
        rise = params[j, RISE]
        # tau >= rise first: a zero rise never divides
        return a if tau >= rise else a * tau / rise
    if code == IMPULSE:
        return a * np.sin(np.pi * tau / d) if tau < d else 0.0
    if code == SINE:
        if d > 0.0 and tau >= d:
            return 0.0
        return a * np.sin(2.0 * np.pi * params[j, FREQUENCY] * tau + params[j, PHASE])
    if code == CHIRP:
        if tau >= d:
            return 0.0
        f0 = params[j, FREQUENCY]
        return a * np.sin(2.0 * np.pi * tau * (f0 + 0.5 * (params[j, F1] - f0) * tau / d))
    return 0.0


@njit
def _table_value(j, t, table_t, table_v, n):
    """Linear interpolation in row j of the tables, 0 before the first time, last value after."""
    if t < table_t[j, 0]:
        return 0.0
    if t >= table_t[j, n - 1]:
        return table_v[j, n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if table_t[j, mid] <= t:
            lo = mid
        else:
            hi = mid
    w = (t - table_t[j, lo]) / (table_t[j, hi] - table_t[j, lo])
    return table_v[j, lo] + w * (table_v[j, hi] - table_v[j, lo])


@njit
def signal_values(t, codes, params, table_t, table_v, table_n, out):
    """Fill out (J,) with every signal's value at time t [s]."""
    for j in range(codes.shape[0]):
        out[j] = signal_value(j, t, codes, params, table_t, table_v, table_n)


@njit_fast
def external_forces(t, patterns, sig, svals, fext):
    """fext = patterns^T s(t), the loads at time t [s] on the reduced or the full dofs (sig:
    the packed signals); svals gets the signals' values."""
    signal_values(t, sig[0], sig[1], sig[2], sig[3], sig[4], svals)
    fext[:] = 0.0
    for j in range(patterns.shape[0]):
        s = svals[j]
        if s != 0.0:
            for k in range(fext.shape[0]):
                fext[k] += s * patterns[j, k]
