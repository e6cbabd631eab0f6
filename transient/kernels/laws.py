"""Contact laws p(g): pressure p >= 0 [Pa] as a function of the gap g [m] (g < 0: penetration).

Chosen by an integer code inside kernels (no function objects passed to cached kernels).
params (4,) per law:
  EXPONENTIAL: p0 [Pa], lambda [1/m], g_lin [m]: p = p0 exp(-lambda g) for g >= g_lin, and below
      g_lin the linear continuation with the same value and slope (no overflow at any penetration).
  LINEAR: k [Pa/m]: unilateral penalty p = k max(-g, 0).
  BILATERAL: k [Pa/m]: tied, p = -k g (tension allowed).
tangent k_t = -dp/dg >= 0; potential Phi(g) = integral from g to infinity of p (for the energy;
bilateral: 1/2 k g^2).
"""
import numpy as np

from ..jit import njit
from .codes import EXPONENTIAL, LINEAR


@njit
def pressure_potential(code, params, g):
    """(p, k_t, Phi) at gap g, with a single exponential."""
    if code == EXPONENTIAL:
        p0, lam, g_lin = params[0], params[1], params[2]
        if g >= g_lin:
            p = p0 * np.exp(-lam * g)
            return p, lam * p, p / lam
        p_lin = p0 * np.exp(-lam * g_lin)
        d = g_lin - g
        return (p_lin + lam * p_lin * d, lam * p_lin,
                p_lin / lam + p_lin * d + 0.5 * lam * p_lin * d * d)
    k = params[0]
    if code == LINEAR:
        if g < 0.0:
            return -k * g, k, 0.5 * k * g * g
        return 0.0, 0.0, 0.0
    return -k * g, k, 0.5 * k * g * g


@njit
def pressure(code, params, g):
    """(p, k_t) at gap g."""
    p, kt, _ = pressure_potential(code, params, g)
    return p, kt


@njit
def potential(code, params, g):
    """Phi(g) with p = -dPhi/dg, Phi >= 0 [J/m^2]."""
    return pressure_potential(code, params, g)[2]


@njit
def evaluate(code, params, g, p, kt, phi):
    """Vector version: p, k_t and Phi at gaps g (m,) with per-point code (m,), params (m, 4)."""
    for i in range(g.shape[0]):
        p[i], kt[i], phi[i] = pressure_potential(code[i], params[i], g[i])
