"""The contact pass of the reduced kernels: the normal force's nonlinear remainder and the
friction, in one pass over the rows (C, and with friction Ct, Cc of the same points read
together).

Rows are split in blocks, each adding into its own row of a buffer, then summed in block
order: the arithmetic is set by the blocks alone, whether the blocks run on one thread or
several (Numba's thread count at the call), so that choice may be taken from a timing. A
single block runs serially, off the thread pool, and nothing outside the block loop is an
array expression (Numba would make it a parallel loop that wakes the pool on every pass).
Within a block the points go four at a time: their dots share each load of the state and
their updates one load and store of the force, which a row at a time bound the pass by its
stores (pad_disc_long, 421 x 345 rows: 45 -> 32 us a pass on one thread, 46 -> 25 us a step
on two; pad_disc_squeal's step on two threads 189-205 -> 160-168 us, where three row sets no
longer fit one core's cache). The sums differ from a row at a time's in round-off only.
"""
import numba
import numpy as np

from ..jit import njit_fast, njit_parallel
from .codes import FRICTIONLESS
from .friction import stiffness
from .laws import pressure_potential


@njit_fast
def _point(i, s, g0, w, kt0, code, params, gap, press):
    """Point i at s = C_i q: its gap and pressure stored; returns (its remainder's force
    density w (p + k_t* s), its potential w Phi, its 1/2 w k_t* s^2)."""
    g = g0[i] + s
    p, _, potential_i = pressure_potential(code[i], params[i], g)
    gap[i] = g
    press[i] = p
    return w[i] * (p + kt0[i] * s), w[i] * potential_i, 0.5 * w[i] * kt0[i] * s * s


@njit_fast
def _dots4(r0, r1, r2, r3, x):
    """The dots of four rows with x, in one loop: each load of x serves the four."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    for j in range(x.shape[0]):
        y = x[j]
        s0 += r0[j] * y
        s1 += r1[j] * y
        s2 += r2[j] * y
        s3 += r3[j] * y
    return s0, s1, s2, s3


@njit_fast
def _normal_rows(C, g0, w, kt0, code, params, q, fb, gap, press, start, stop):
    """Rows start..stop without friction, four at a time: their four dots share each load of
    q, and their updates one load and store of fb (a row at a time, the update's store of
    every entry bound the pass: pad_disc_long's 421 x 345 rows took 45 us, 2.5 times their
    product with q alone). Returns (contact potential, 1/2 sum w k_t* (g - g0)^2)."""
    n = C.shape[1]
    phi = 0.0
    lin = 0.0
    i = start
    while i + 4 <= stop:
        r0 = C[i]
        r1 = C[i + 1]
        r2 = C[i + 2]
        r3 = C[i + 3]
        s0, s1, s2, s3 = _dots4(r0, r1, r2, r3, q)
        a0, e0, l0 = _point(i, s0, g0, w, kt0, code, params, gap, press)
        a1, e1, l1 = _point(i + 1, s1, g0, w, kt0, code, params, gap, press)
        a2, e2, l2 = _point(i + 2, s2, g0, w, kt0, code, params, gap, press)
        a3, e3, l3 = _point(i + 3, s3, g0, w, kt0, code, params, gap, press)
        for j in range(n):
            fb[j] += (a0 * r0[j] + a1 * r1[j]) + (a2 * r2[j] + a3 * r3[j])
        phi += (e0 + e1) + (e2 + e3)
        lin += (l0 + l1) + (l2 + l3)
        i += 4
    while i < stop:
        row = C[i]
        s = 0.0
        for j in range(n):
            s += row[j] * q[j]
        a, e, l_ = _point(i, s, g0, w, kt0, code, params, gap, press)
        for j in range(n):
            fb[j] += a * row[j]
        phi += e
        lin += l_
        i += 1
    return phi, lin


@njit_fast
def _traction(i, p, st, sc, fr, w, slip):
    """Point i's friction at pressure p, sliding at (st, sc): its slip stored; returns its
    traction (along, across) and its share of the sliding's input power."""
    Ct, Cc, V, fcode, v_eps, table, tab_v, tab_mu, tab_n = fr
    if fcode[i] == FRICTIONLESS:
        slip[0, i] = V[i]
        slip[1, i] = 0.0
        return 0.0, 0.0, 0.0
    slip[0, i] = st
    slip[1, i] = sc
    if p <= 0.0:             # open, or a bilateral tie in tension: no friction
        return 0.0, 0.0, 0.0
    c = stiffness(fcode[i], v_eps[i], table[i], tab_v, tab_mu, tab_n, w[i] * p, st, sc)
    return c * st, c * sc, c * st * V[i]


@njit_fast
def _friction_fours(contact, q, fr, v, fb, ffb, gap, press, slip, start, stop):
    """_contact_rows with friction on the rows start.. four at a time (as _normal_rows), up to
    the last four before stop: each four's normal part by _normal_rows, then the dots and
    updates of their rows along and across in loops of their own. pad_disc_squeal's three row
    sets (3.6 MB) come from the shared cache on one thread, where this is no faster than a row
    at a time; on two, each core's half fits its own, and a step is 15% faster. Returns
    (contact potential, 1/2 sum w k_t* (g - g0)^2, the sliding's input power, the first row
    left)."""
    C, g0, w, kt0, code, params = contact
    n = C.shape[1]
    Ct, Cc, V = fr[0], fr[1], fr[2]
    phi = 0.0
    lin = 0.0
    p_in = 0.0
    i = start
    while i + 4 <= stop:
        e, l_ = _normal_rows(C, g0, w, kt0, code, params, q, fb, gap, press, i, i + 4)
        phi += e
        lin += l_
        t0, t1, t2, t3 = Ct[i], Ct[i + 1], Ct[i + 2], Ct[i + 3]
        c0, c1, c2, c3 = Cc[i], Cc[i + 1], Cc[i + 2], Cc[i + 3]
        u0, u1, u2, u3 = _dots4(t0, t1, t2, t3, v)
        x0, x1, x2, x3 = _dots4(c0, c1, c2, c3, v)
        b0, d0, i0 = _traction(i, press[i], V[i] - u0, -x0, fr, w, slip)
        b1, d1, i1 = _traction(i + 1, press[i + 1], V[i + 1] - u1, -x1, fr, w, slip)
        b2, d2, i2 = _traction(i + 2, press[i + 2], V[i + 2] - u2, -x2, fr, w, slip)
        b3, d3, i3 = _traction(i + 3, press[i + 3], V[i + 3] - u3, -x3, fr, w, slip)
        for j in range(n):
            ffb[j] += (b0 * t0[j] + b1 * t1[j]) + (b2 * t2[j] + b3 * t3[j])
        for j in range(n):
            ffb[j] += (d0 * c0[j] + d1 * c1[j]) + (d2 * c2[j] + d3 * c3[j])
        p_in += (i0 + i1) + (i2 + i3)
        i += 4
    return phi, lin, p_in, i


@njit_fast
def _contact_rows(contact, q, fr, v, fb, ffb, gap, press, slip, start, stop):
    """Rows start..stop of the fused pass: the normal remainder added into fb, the friction
    tractions at velocity v into ffb (friction's module docstring). Returns
    (contact potential, 1/2 sum w k_t* (g - g0)^2, the sliding's input power) of those rows."""
    C, g0, w, kt0, code, params = contact
    n = C.shape[1]
    Ct, Cc, V, fcode, v_eps, table, tab_v, tab_mu, tab_n = fr
    friction = Ct.shape[0] > 0
    if not friction:
        phi, lin = _normal_rows(C, g0, w, kt0, code, params, q, fb, gap, press, start, stop)
        return phi, lin, 0.0
    phi, lin, p_in, start = _friction_fours(contact, q, fr, v, fb, ffb,
                                            gap, press, slip, start, stop)
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


PAD = 8      # doubles (a 64-byte cache line) between the rows of the blocks' force buffers


@njit_fast
def block_buffers(nblocks, n):
    """The row blocks' force buffers of contact_pass (normal, friction): a row of n per block,
    PAD apart. Rows side by side shared the cache line at each boundary, which two threads then
    wrote in turn at every four points (false sharing; docs/performance.md). Only where the
    sums are stored changes, not the sums."""
    return np.empty((nblocks, n + PAD)), np.empty((nblocks, n + PAD))


@njit_fast
def _sum_blocks(buf, out):
    """out = the rows of buf summed in block order."""
    for j in range(out.shape[0]):
        acc = 0.0
        for b in range(buf.shape[0]):
            acc += buf[b, j]
        out[j] = acc


@njit_parallel
def contact_pass(contact, q, fr, v, f, ff, gap, press, slip, blocks, fbuf, ffbuf):
    """f = C^T [w (p(g) + k_t* (g - g0))] + ff, ff the friction force at velocity v (fr:
    Ct, Cc, V, code, v_eps, table, speeds, values, counts; with no rows: none, ff untouched),
    in one pass over the points in row blocks (module docstring). Fills gap, press (m,) and
    with friction slip (2, m). Returns (contact potential, 1/2 sum w k_t* (g - g0)^2, the
    sliding's input power [W])."""
    C, g0, w, kt0, code, params = contact
    n = C.shape[1]
    nb = blocks.shape[0] - 1
    friction = fr[0].shape[0] > 0
    if nb == 1:
        for j in range(n):
            f[j] = 0.0
        if friction:
            for j in range(n):
                ff[j] = 0.0
        phi, lin, p_in = _contact_rows(contact, q, fr, v, f, ff, gap, press, slip, 0, C.shape[0])
    else:
        parts = np.empty((nb, 3))
        for b in numba.prange(nb):
            fb = fbuf[b]
            ffb = ffbuf[b]
            for j in range(n):
                fb[j] = 0.0
                ffb[j] = 0.0
            parts[b, 0], parts[b, 1], parts[b, 2] = _contact_rows(
                contact, q, fr, v, fb, ffb, gap, press, slip, blocks[b],
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
