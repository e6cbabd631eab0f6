"""Reduced basis: normal modes of the preloaded structure up to fmax, plus static responses to
the contact point loads and the load patterns, M-orthonormalized and re-diagonalized.

The stiffness used is K_lin = K + C^T diag(w k_t*) C, linearized at the preload: in the reduced
coordinates q = T q_r, T^T M T = I and T^T K_lin T = diag(omega^2).
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .linsolve import factorize
from .modes import normal_modes


@dataclass(frozen=True)
class Basis:
    T: np.ndarray            # (ndof, n), zero on fixed dofs
    omega2: np.ndarray       # (n,) [rad^2/s^2], ascending
    n_modes: int             # normal modes below fmax in the basis
    n_static: int            # static vectors added (before removing dependent directions)
    timings: dict


def reduced_basis(K_lin, M, fixed, fmax, statics, backend="auto", shift_hz=1.0):
    """Basis of the modes of (K_lin, M) up to fmax [Hz] and the responses K_lin^-1 statics.

    statics (ndof, s): load vectors (contact point loads C_i^T, load patterns) and displacement
    vectors to represent exactly (the preload). A small negative shift keeps the static solve
    defined when a part floats (no closed contact, no constraint).
    """
    t0 = time.perf_counter()
    free = np.flatnonzero(~fixed)
    modes = normal_modes(K_lin, M, fixed, count=40, fmax=fmax, shift=-shift_hz,
                         backend=backend)
    t_modes = time.perf_counter() - t0
    Phi = modes.shapes[free]
    X = Phi
    if statics.shape[1]:
        sigma = -(2 * np.pi * shift_hz) ** 2
        Kf = (K_lin[free][:, free] - sigma * M[free][:, free]).tocsr()
        S = factorize(Kf, backend)(np.asfortranarray(statics[free]))
        X = np.hstack([Phi, np.atleast_2d(S.T).T])
    t_static = time.perf_counter() - t0 - t_modes
    Mf = M[free][:, free]
    Kf = K_lin[free][:, free]
    # drop directions that the others already span (M-norm), then diagonalize
    Mr = X.T @ (Mf @ X)
    lam, V = np.linalg.eigh(Mr)
    keep = lam > 1e-12 * lam.max()
    X = X @ (V[:, keep] / np.sqrt(lam[keep]))
    Kr = X.T @ (Kf @ X)
    omega2, W = sla.eigh(0.5 * (Kr + Kr.T))
    T = np.zeros((K_lin.shape[0], len(omega2)))
    T[free] = X @ W
    timings = {"modes": t_modes, "statics": t_static,
               "orthonormalization": time.perf_counter() - t0 - t_modes - t_static}
    return Basis(T, np.maximum(omega2, 0.0), len(modes.frequencies), statics.shape[1], timings)
