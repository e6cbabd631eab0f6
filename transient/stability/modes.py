"""Complex modes of M a + D v + K q = 0 (dense, QZ): the frequency-domain answer to squeal.

With friction, K is not symmetric (the friction stiffness mu C_t^T diag(w k_t) C_n) and two
modes can coalesce into a pair of complex eigenvalues lambda = real +- i omega, one growing
(real > 0: flutter). The first-order form [[I, 0], [0, M]] z' = [[0, I], [-K, -D]] z, z = (q,
v), is solved by QZ (scipy.linalg.eig on the pencil): a few hundred reduced dofs at most.
"""
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

# a mode is unstable when it grows faster than this fraction of |lambda| (a damping ratio below
# -1e-6: e-folding in 1e6 / (2 pi) periods, 30 s at 5 kHz), and faster than the case's
# cea.threshold.growth_rate. Slower growth is neither resolved by the arithmetic (eigenvalues
# of the non-normal friction system carry round-off of eps ||A||: pad_disc at mu = 0.4 left a
# neutral disc mode at 2.8e-9 |lambda|) nor meaningful for squeal
UNSTABLE_RTOL = 1e-6


@dataclass(frozen=True)
class ComplexModes:
    eigenvalues: np.ndarray   # (n,) lambda [1/s], imaginary part >= 0, by frequency
    vectors: np.ndarray       # (ndof, n) the displacement part of each mode, unit max entry
    threshold: float = 0.0    # [1/s] the growth rate an unstable mode exceeds

    @property
    def frequency_hz(self):
        return self.eigenvalues.imag / (2 * np.pi)

    @property
    def real(self):
        """Growth rate [1/s]: > 0 grows."""
        return self.eigenvalues.real

    @property
    def damping_ratio(self):
        """-real / |lambda|: negative for a growing mode."""
        return -self.eigenvalues.real / np.maximum(np.abs(self.eigenvalues), 1e-300)

    @property
    def unstable(self):
        real = self.eigenvalues.real
        return (real > UNSTABLE_RTOL * np.abs(self.eigenvalues)) & (real > self.threshold)

    def below(self, fmax):
        """The modes up to fmax [Hz]."""
        keep = self.frequency_hz <= fmax
        return ComplexModes(self.eigenvalues[keep], self.vectors[:, keep], self.threshold)

    def table(self):
        """One dict per mode (the JSON of `transient cea`)."""
        return [{"frequency_hz": float(f), "real": float(r), "damping_ratio": float(z),
                 "unstable": bool(u)}
                for f, r, z, u in zip(self.frequency_hz, self.real, self.damping_ratio,
                                      self.unstable)]


def complex_modes(M, D, K):
    """Complex modes of the dense (n, n) matrices M (symmetric positive definite), D and K.

    Returns one eigenvalue of each conjugate pair (imaginary part >= 0; real eigenvalues, of
    overdamped or divergent motion, once each), sorted by frequency then real part. K may be
    complex (a loss factor's i H): its eigenvalues then pair as lambda and -conj(lambda), the
    one of positive frequency decaying and its mirror growing, which is not a motion (a
    structural damping holds at positive frequencies only): the positive ones are kept.
    """
    dtype = complex if any(np.iscomplexobj(X) for X in (M, D, K)) else float
    M, D, K = (np.asarray(X, dtype=dtype) for X in (M, D, K))
    n = M.shape[0]
    eye, zero = np.eye(n), np.zeros((n, n))
    if np.array_equal(M, eye):
        # a reduced model's M = I: the standard problem, Hessenberg QR (half QZ's time), by
        # NumPy's LAPACK call, which lets other threads run (SciPy's holds the GIL: the cea
        # makes the pad's own modes meanwhile) and took 0.39 s against SciPy's 0.46 (754^2)
        lam, Z = np.linalg.eig(np.block([[zero, eye], [-K, -D]]))
        lam, Z = lam.astype(complex), Z.astype(complex)    # (real when every root is real)
    else:
        lam, Z = sla.eig(np.block([[zero, eye], [-K, -D]]), np.block([[eye, zero], [zero, M]]))
    scale = np.max(np.abs(lam)) if lam.size else 1.0
    # a conjugate pair's members agree to round-off: keep the one above the real axis, and a
    # real eigenvalue (|imag| at round-off) once
    real_axis = np.abs(lam.imag) <= 1e-12 * scale
    keep = (lam.imag > 0) & ~real_axis | real_axis
    lam = np.where(real_axis, lam.real + 0j, lam)[keep]
    Z = Z[:n, keep]
    order = np.lexsort((lam.real, lam.imag))
    lam, Z = lam[order], Z[:, order]
    big = np.argmax(np.abs(Z), axis=0)
    Z = Z / Z[big, np.arange(Z.shape[1])]
    return ComplexModes(lam, Z)
