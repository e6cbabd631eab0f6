"""(1-eps)-compatibility of an interface (paper eq. 5-10).

The gap energy A = [C1, -C2]^T diag(k w J) [C1, -C2] acts on the normal dofs of the interface nodes
of both sides (side 1 first). Its eigenpairs (A symmetric: SVD = eigh) are pairs of interface
shapes (u1_i, u2_i) with the gap energy sigma_i they generate; small sigma_i / max sigma means the
two surfaces represent the shape alike. C(eps) = card{i: sigma_i / max sigma <= eps} / min(N1, N2).
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .. import blas

ROUND_OFF = 1e-13   # normalized singular values below this are zero to round-off


@dataclass(frozen=True)
class Compatibility:
    k: float                 # stiffness density of the gap energy [Pa/m]
    sigma: np.ndarray        # (N1 + N2,) eigenvalues of A, ascending [N/m]
    shapes: np.ndarray       # (N1 + N2, N1 + N2) eigenvectors (columns), side 1 rows first
    n1: int
    n2: int
    timings: dict

    @property
    def normalized(self):
        return np.maximum(self.sigma, 0.0) / self.sigma.max()

    def kept(self, eps):
        """Number of shapes with sigma_i / max sigma <= eps."""
        return int(np.searchsorted(self.normalized, eps, side="right"))

    def curve(self, eps):
        """C(eps) for an array of eps."""
        return np.searchsorted(self.normalized, np.asarray(eps), side="right") / min(self.n1,
                                                                                       self.n2)

    def traces(self, eps):
        """Traces U1 (N1, r), U2 (N2, r) on each surface of the kept shapes."""
        r = self.kept(eps)
        return self.shapes[:self.n1, :r], self.shapes[self.n1:, :r]


def gap_energy(rule, k):
    """A (dense, symmetric) of a rule at stiffness density k [Pa/m]."""
    B = sp.hstack([rule.C1, -rule.C2]).tocsr()
    return (B.T @ sp.diags(k * rule.weights) @ B).toarray()


def compatibility(rule, k):
    """Eigendecomposition of the gap energy of a (fine) rule."""
    t0 = time.perf_counter()
    A = gap_energy(rule, k)
    t1 = time.perf_counter()
    with blas.every_core():      # nothing else runs: 2747^2 (4x pad_disc) 3.6 -> 2.2 s
        sigma, shapes = sla.eigh(A, driver="evd")
    timings = {"gap_energy": t1 - t0, "eigendecomposition": time.perf_counter() - t1}
    return Compatibility(k, sigma, shapes, rule.C1.shape[1], rule.C2.shape[1], timings)


CLEAN = 1e-6        # a jump separates compatibility levels only when it lands above this
MIN_JUMP = 10.0     # a smaller ratio between neighbours is not a jump
FALLBACK_EPS = 1e-3  # the paper's choice for dynamics when the spectrum has no jump


def auto_eps(normalized):
    """eps in the largest jump of the normalized spectrum, and how it was found.

    A jump counts only if it lands above CLEAN (nested meshes: round-off zeros, then
    incompatible shapes). Below it the spectrum's gaps are those of round-off, which grows with
    the interface, and of the few fields both sides represent (nearly) exactly: constants,
    linear fields, on tet10 faces quadratic ones; a 1M-dof tet10 pad and disc (5603 interface
    dofs) has 1.8e-12 -> 2.1e-11, a ratio of 12, which kept 14 shapes of a continuous spectrum.
    eps is the geometric mean of the jump's ends.
    Without a jump of at least MIN_JUMP, returns FALLBACK_EPS.
    Returns (eps, 'jump at i' or 'no jump: fallback').
    """
    s = np.maximum(np.asarray(normalized, float), 1e-300)
    ratio = s[1:] / s[:-1]
    ratio = np.where(s[1:] >= CLEAN, ratio, 0.0)
    i = int(np.argmax(ratio))
    if ratio[i] < MIN_JUMP:
        return FALLBACK_EPS, "no jump: fallback"
    return float(np.sqrt(max(s[i], ROUND_OFF) * s[i + 1])), f"jump after {i + 1} shapes"
