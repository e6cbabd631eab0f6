"""The contact pass of the reduced kernels: the normal force's nonlinear remainder and the
friction, point by point in one pass over the rows (C, and with friction Ct, Cc of the same
point read together).

Rows are split in blocks, each adding into its own row of a buffer, then summed in block
order: the arithmetic is set by the blocks alone, whether the blocks run on one thread or
several (Numba's thread count at the call), so that choice may be taken from a timing. A
single block runs serially, off the thread pool, and nothing outside the block loop is an
array expression (Numba would make it a parallel loop that wakes the pool on every pass).
With one block the sums are those of the normal pass followed by the friction pass, the two
passes the kernels made before they were fused: the same numbers.
"""
import numba
import numpy as np

from ..jit import njit_fast, njit_parallel
from .codes import FRICTIONLESS
from .friction import stiffness
from .laws import pressure_potential


@njit_fast
def _contact_rows(C, g0, w, kt0, code, params, q, fr, v, fb, ffb, gap, press, slip, start,
                  stop):
    """Rows start..stop of the fused pass: the normal remainder added into fb, the friction
    tractions at velocity v into ffb (friction's module docstring). Returns
    (contact potential, 1/2 sum w k_t* (g - g0)^2, the sliding's input power) of those rows."""
    n = C.shape[1]
    Ct, Cc, V, fcode, v_eps, table, tab_v, tab_mu, tab_n = fr
    friction = Ct.shape[0] > 0
    phi = 0.0
    lin = 0.0
    p_in = 0.0
    for i in range(start, stop):
        row = C[i]
        s = 0.0
        for j in range(n):
            s += row[j] * q[j]
        g = g0[i] + s
        p, _, potential_i = pressure_potential(code[i], params[i], g)
        r = w[i] * (p + kt0[i] * s)
        for j in range(n):
            fb[j] += r * row[j]
        gap[i] = g
        press[i] = p
        phi += w[i] * potential_i
        lin += 0.5 * w[i] * kt0[i] * s * s
        if not friction:
            continue
        if fcode[i] == FRICTIONLESS:
            slip[0, i] = V[i]
            slip[1, i] = 0.0
            continue
        rt = Ct[i]
        rc = Cc[i]
        st = V[i]
        sc = 0.0
        for j in range(n):
            st -= rt[j] * v[j]
            sc -= rc[j] * v[j]
        slip[0, i] = st
        slip[1, i] = sc
        if p <= 0.0:             # open, or a bilateral tie in tension: no friction
            continue
        c = stiffness(fcode[i], v_eps[i], table[i], tab_v, tab_mu, tab_n, w[i] * p, st, sc)
        tt = c * st
        tc = c * sc
        for j in range(n):
            ffb[j] += tt * rt[j] + tc * rc[j]
        p_in += tt * V[i]
    return phi, lin, p_in


@njit_fast
def _sum_blocks(buf, out):
    """out = the rows of buf summed in block order."""
    for j in range(out.shape[0]):
        acc = 0.0
        for b in range(buf.shape[0]):
            acc += buf[b, j]
        out[j] = acc


@njit_parallel
def contact_pass(C, g0, w, kt0, code, params, q, fr, v, f, ff, gap, press, slip, blocks, fbuf,
                 ffbuf):
    """f = C^T [w (p(g) + k_t* (g - g0))] + ff, ff the friction force at velocity v (fr:
    Ct, Cc, V, code, v_eps, table, speeds, values, counts; with no rows: none, ff untouched),
    in one pass over the points in row blocks (module docstring). Fills gap, press (m,) and
    with friction slip (2, m). Returns (contact potential, 1/2 sum w k_t* (g - g0)^2, the
    sliding's input power [W])."""
    n = C.shape[1]
    nb = blocks.shape[0] - 1
    friction = fr[0].shape[0] > 0
    if nb == 1:
        for j in range(n):
            f[j] = 0.0
        if friction:
            for j in range(n):
                ff[j] = 0.0
        phi, lin, p_in = _contact_rows(C, g0, w, kt0, code, params, q, fr, v, f, ff, gap,
                                       press, slip, 0, C.shape[0])
    else:
        parts = np.empty((nb, 3))
        for b in numba.prange(nb):
            fb = fbuf[b]
            ffb = ffbuf[b]
            for j in range(n):
                fb[j] = 0.0
                ffb[j] = 0.0
            parts[b, 0], parts[b, 1], parts[b, 2] = _contact_rows(
                C, g0, w, kt0, code, params, q, fr, v, fb, ffb, gap, press, slip, blocks[b],
                blocks[b + 1])
        phi = 0.0
        lin = 0.0
        p_in = 0.0
        for b in range(nb):
            phi += parts[b, 0]
            lin += parts[b, 1]
            p_in += parts[b, 2]
        _sum_blocks(fbuf, f)
        if friction:
            _sum_blocks(ffbuf, ff)
    if friction:
        for j in range(n):
            f[j] += ff[j]
    return phi, lin, p_in
