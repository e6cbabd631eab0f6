"""The friction pass of the reduced contact: regularized Coulomb tractions along and across the
sliding, from the pressures of the normal pass (stepping.remainder_dense) and the velocity.

At point i the sliding velocity of surface 2 relative to surface 1 is s = (V_i - Ct_i v,
-Cc_i v) (along, across the imposed sliding); the traction on surface 1 is w p mu(|s|)
sgn_reg(|s|) s / |s|, with sgn_reg tanh(|s| / v_eps) or (2 / pi) atan(|s| / v_eps), so the
force on the coordinates is Ct_i^T tau_t + Cc_i^T tau_c. Its power on the structure splits
into what the sliding puts in, tau_t V, and what the slip dissipates, tau . s >= 0.

Per point: code (TANH, ATAN; FRICTIONLESS: no friction), v_eps, and a table of mu against |s| (one
entry: constant) in the packed tables (speeds, values, counts).
"""
import numpy as np

from ..jit import njit_fast
from .codes import FRICTIONLESS, TANH
SMALL = 1e-6     # |s| / v_eps below which sgn_reg(|s|) / |s| is its series (no 0 / 0)


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
def friction_dense(Ct, Cc, w, press, V, code, v_eps, table, tab_v, tab_mu, tab_n, v, f):
    """f += Ct^T tau_t + Cc^T tau_c at velocity v (n,), pressures press (m,) of the normal
    pass. Returns (input power tau_t . V, dissipated power tau . s) [W]."""
    m, n = Ct.shape
    p_in = 0.0
    p_diss = 0.0
    for i in range(m):
        if code[i] == FRICTIONLESS or press[i] == 0.0:
            continue
        rt = Ct[i]
        rc = Cc[i]
        st = V[i]
        sc = 0.0
        for j in range(n):
            st -= rt[j] * v[j]
            sc -= rc[j] * v[j]
        s = np.sqrt(st * st + sc * sc)
        mu = friction_coefficient(table[i], s, tab_v, tab_mu, tab_n)
        c = w[i] * press[i] * mu * sign_over_speed(code[i], s, v_eps[i])
        tt = c * st
        tc = c * sc
        for j in range(n):
            f[j] += tt * rt[j] + tc * rc[j]
        p_in += tt * V[i]
        p_diss += tt * st + tc * sc
    return p_in, p_diss
