"""The friction pass of the reduced contact: regularized Coulomb tractions along and across the
sliding, from the pressures of the normal pass (stepping.remainder_dense) and the velocity.

At point i the sliding velocity of surface 2 relative to surface 1 is s = (V_i - Ct_i v,
-Cc_i v) (along, across the imposed sliding); the traction on surface 1 is w p mu(|s|)
sgn_reg(|s|) s / |s|, with sgn_reg tanh(|s| / v_eps) or (2 / pi) atan(|s| / v_eps), so the
force on the coordinates is Ct_i^T tau_t + Cc_i^T tau_c. Its power on the structure splits
into what the sliding puts in, tau_t V, and what the slip dissipates, tau . s >= 0.

Per point: code (TANH, ATAN; FRICTIONLESS: no friction), v_eps, and a table of mu against |s| (one
entry: constant) in the packed tables (speeds, values, counts).

The implicit kernels also need the traction's derivatives (woodbury.coupled_rows): with
c(s) = mu(s) sgn_reg(s) / s, tau = w p c(|s|) s, so d tau / d s = w p (c I + c'(|s|) |s| e e^T)
(e = s / |s|), and d tau / d g = -k_t w c s.
"""
import numpy as np
from numba import types
from numba.extending import overload

from ..jit import njit_fast
from .codes import DISSIPATED, FRICTIONLESS, TANH, WORK
from .layout import DISSIPATED_ACC, SLIDING_ACC, WORK_ACC

SMALL = 1e-6     # |s| / v_eps below which sgn_reg(|s|) / |s| is its series (no 0 / 0)


def friction_points(fr):
    """The points with friction rows: fr's Ct rows, dense in the reduced kernels, a CSR triplet
    (whose indptr has a single entry without friction) in the full model's."""


# inlined: a shape read, where a call would pass fr's arrays at every step
@overload(friction_points, inline="always")
def _friction_points_typed(fr):
    if isinstance(fr.types[0], types.Array):
        return lambda fr: fr[0].shape[0]
    return lambda fr: fr[0][0].shape[0] - 1


@njit_fast
def friction_coefficient(t, s, tab_v, tab_mu, tab_n):
    """mu(s) of table t: linear between its points, constant beyond its ends."""
    k = tab_n[t]
    if k == 1 or s <= tab_v[t, 0]:
        return tab_mu[t, 0]
    if s >= tab_v[t, k - 1]:
        return tab_mu[t, k - 1]
    j = 1
    while tab_v[t, j] < s:
        j += 1
    a = (s - tab_v[t, j - 1]) / (tab_v[t, j] - tab_v[t, j - 1])
    return tab_mu[t, j - 1] + a * (tab_mu[t, j] - tab_mu[t, j - 1])


@njit_fast
def sign_over_speed(code, s, v_eps):
    """sgn_reg(s) / s, with its limit 1 / v_eps (tanh) or 2 / (pi v_eps) (atan) at s = 0."""
    x = s / v_eps
    if code == TANH:
        if x < SMALL:
            return (1.0 - x * x / 3.0) / v_eps
        return np.tanh(x) / s
    if x < SMALL:
        return (2.0 / np.pi) * (1.0 - x * x / 3.0) / v_eps
    return (2.0 / np.pi) * np.arctan(x) / s


@njit_fast
def coefficient_slope(t, s, tab_v, tab_mu, tab_n):
    """(mu(s), dmu/ds) of table t (the slope of the segment s lies on, 0 beyond the ends)."""
    k = tab_n[t]
    if k == 1 or s <= tab_v[t, 0] or s >= tab_v[t, k - 1]:
        return friction_coefficient(t, s, tab_v, tab_mu, tab_n), 0.0
    j = 1
    while tab_v[t, j] < s:
        j += 1
    slope = (tab_mu[t, j] - tab_mu[t, j - 1]) / (tab_v[t, j] - tab_v[t, j - 1])
    return tab_mu[t, j - 1] + slope * (s - tab_v[t, j - 1]), slope


@njit_fast
def sign_slope(code, s, v_eps):
    """(sgn_reg(s), d sgn_reg / ds - sgn_reg(s) / s): the second is what the traction's
    derivative along the slip needs, -2/3 x^2 / v_eps (times 2 / pi for atan) to leading
    order in x = s / v_eps, taken as that series where the difference would cancel."""
    x = s / v_eps
    if code == TANH:
        g = np.tanh(x)
        if x < 1e-4:
            return g, (-2.0 / 3.0) * x * x / v_eps
        return g, ((1.0 - g * g) - g / x) / v_eps
    g = (2.0 / np.pi) * np.arctan(x)
    if x < 1e-4:
        return g, (2.0 / np.pi) * (-2.0 / 3.0) * x * x / v_eps
    return g, ((2.0 / np.pi) / (1.0 + x * x) - g / x) / v_eps


@njit_fast
def slip_tangent(code, v_eps, t, tab_v, tab_mu, tab_n, st, sc):
    """(c, c' |s|) at slip (st, sc): the traction per unit w p is c s, its derivative
    c I + c' |s| e e^T (module docstring)."""
    s = np.sqrt(st * st + sc * sc)
    mu, dmu = coefficient_slope(t, s, tab_v, tab_mu, tab_n)
    g, rest = sign_slope(code, s, v_eps)
    return mu * sign_over_speed(code, s, v_eps), dmu * g + mu * rest


@njit_fast
def stiffness(code, v_eps, t, tab_v, tab_mu, tab_n, wp, st, sc):
    """c = |tau| / |s| of a point sliding at (st, sc) under the pressure's share wp = w p:
    its traction is c (st, sc) (module docstring)."""
    s = np.sqrt(st * st + sc * sc)
    return wp * friction_coefficient(t, s, tab_v, tab_mu, tab_n) * sign_over_speed(code, s,
                                                                                   v_eps)


@njit_fast
def friction_sparse(Ct, Cc, w, press, V, code, v_eps, table, tab_v, tab_mu, tab_n, v, f, slip):
    """f += Ct^T tau_t + Cc^T tau_c at velocity v (n,) on the full model's dofs, Ct, Cc CSR
    triplets (m rows), pressures press (m,) of the normal pass; slip (2, m) gets each point's
    sliding velocity (along, across), open or not (the reduced kernels' is contact.contact_pass,
    fused with the normal pass). Returns (input power tau_t . V, dissipated power tau . s)."""
    Tp, Ti, Td = Ct
    Up, Ui, Ud = Cc
    m = Tp.shape[0] - 1
    p_in = 0.0
    p_diss = 0.0
    for i in range(m):
        if code[i] == FRICTIONLESS:
            slip[0, i] = V[i]
            slip[1, i] = 0.0
            continue
        st = V[i]
        sc = 0.0
        for k in range(Tp[i], Tp[i + 1]):
            st -= Td[k] * v[Ti[k]]
        for k in range(Up[i], Up[i + 1]):
            sc -= Ud[k] * v[Ui[k]]
        slip[0, i] = st
        slip[1, i] = sc
        if press[i] <= 0.0:
            continue
        c = stiffness(code[i], v_eps[i], table[i], tab_v, tab_mu, tab_n, w[i] * press[i], st,
                      sc)
        tt = c * st
        tc = c * sc
        for k in range(Tp[i], Tp[i + 1]):
            f[Ti[k]] += tt * Td[k]
        for k in range(Up[i], Up[i + 1]):
            f[Ui[k]] += tc * Ud[k]
        p_in += tt * V[i]
        p_diss += tt * st + tc * sc
    return p_in, p_diss


@njit_fast
def friction_pass_sparse(fr, w, press, v, ff, f, slip):
    """The friction force ff at velocity v, added into f too, and the points' slip velocities
    (2, m), when the system has friction: fr = (Ct, Cc, V, code, v_eps, table, speeds, values,
    counts) with Ct, Cc CSR triplets (Ct's indptr of one entry without friction). Returns the
    sliding's input power [W]."""
    if fr[0][0].shape[0] <= 1:
        return 0.0
    for j in range(ff.shape[0]):
        ff[j] = 0.0
    p_in, _ = friction_sparse(fr[0], fr[1], w, press, fr[2], fr[3], fr[4], fr[5], fr[6],
                              fr[7], fr[8], v, ff, slip)
    for j in range(ff.shape[0]):
        f[j] += ff[j]
    return p_in


@njit_fast
def friction_energy(acc, energy, ff0, ff, dq, p_in, dt):
    """The friction's share of a step's energies. Its work on the structure is taken as the
    loads' is, 1/2 (ff0 + ff) . dq (ff0 at the step's start, ff at its end), so that the
    balance closes on the scheme's own arithmetic; the sliding's input, tau_t V, by the
    trapezoid of its power (acc[SLIDING_ACC] carries the power at the start) goes to the
    external work, and what of it the structure did not take to the dissipated energy. ff0
    becomes ff."""
    onto = 0.0
    for j in range(ff.shape[0]):
        onto += 0.5 * (ff0[j] + ff[j]) * dq[j]
        ff0[j] = ff[j]
    inflow = 0.5 * dt * (acc[SLIDING_ACC] + p_in)
    acc[WORK_ACC] += inflow
    acc[DISSIPATED_ACC] += inflow - onto
    acc[SLIDING_ACC] = p_in
    energy[WORK] = acc[WORK_ACC]
    energy[DISSIPATED] = acc[DISSIPATED_ACC]
