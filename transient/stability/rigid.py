"""Rigid modes of floating parts, taken out of the full model's shift-invert Arnoldi.

A part free to move (no constraint, no contact closed at the preload) has K r = 0 for its
rigid motions r. In the first-order pencil each is a Jordan block at lambda = 0 (the motion and
its velocity): two free bars make one defective eigenvalue of multiplicity 24, on which ARPACK
does not converge. Where a part's rigid motions span an invariant subspace of the pencil on
both sides (K n = K^T n = 0, and D maps them into M times them: no friction or closed contact
touches them), the spectral projector that removes them is known in closed form, and their own
eigenvalues are those of the small problem restricted to them.
"""
from dataclasses import dataclass

import numpy as np

from ..model.dofs import rigid_motions as dof_rigid_motions

# a rigid motion's strain energy is round-off (1e-16 of the largest eigenvalue of the pair
# (K, M) on two_bars): below this fraction it is zero, which leaves elastic modes down to a
# millionth of the mesh's highest frequency untouched
RIGID_RTOL = 1e-12
# residuals of the invariance (K n, K^T n, D n - M n C) above this fraction of their scale
# leave a part's rigid motions to the Arnoldi
INVARIANT_RTOL = 1e-10


@dataclass(frozen=True)
class Floating:
    """The rigid modes deflated: N (n, r) M-orthonormal on the free dofs, C = N^T D N."""
    N: np.ndarray
    MN: np.ndarray
    C: np.ndarray
    damping_scale: float     # max |D_ii| / M_ii [1/s]

    @property
    def rank(self):
        return self.N.shape[1]

    def project(self, z):
        """z (2n,) without its part along the rigid modes and their velocities: the spectral
        projector I - Q W^H, Q = diag(N, N), W = diag(M N, M N) (W^H Q = I)."""
        if not self.rank:
            return z
        n = self.N.shape[0]
        z1, z2 = z[:n], z[n:]
        return np.concatenate([z1 - self.N @ (self.MN.T @ z1), z2 - self.N @ (self.MN.T @ z2)])

    def modes(self):
        """(eigenvalues, displacement vectors) of the rigid modes: r at lambda = 0 (K is zero
        on them), and the nonzero eigenvalues of -C (a mass-proportional damping's -alpha),
        one of each conjugate pair."""
        lam = np.zeros(self.rank, complex)
        vectors = self.N.astype(complex)
        if self.rank and np.abs(self.C).max() > 0:
            mu, V = np.linalg.eig(-self.C)
            keep = (np.abs(mu) > 1e-10 * self.damping_scale) & (mu.imag >= 0)
            lam = np.concatenate([lam, mu[keep]])
            vectors = np.hstack([vectors, self.N @ V[:, keep]])
        return lam, vectors


def rigid_motions(model, free):
    """Per part, its six rigid motions (three translations, three rotations about its centroid)
    on the free dofs: a list of (len(free), 6) arrays."""
    where = np.full(model.ndof, -1)
    where[free] = np.arange(len(free))
    out = []
    for name in model.parts:
        dofs = model.part_dofs(name)
        centre = model.points[dofs[::3] // 3].mean(axis=0)
        dofs = dofs[where[dofs] >= 0]
        R = np.zeros((len(free), 6))
        R[where[dofs]] = dof_rigid_motions(model.points, dofs, centre)
        out.append(R)
    return out


def floating(M, D, K, motions):
    """The Floating of sparse M, D, K (n, n) on the free dofs: of the parts' rigid motions
    (rigid_motions), those K holds at zero energy, kept where they are invariant."""
    n = K.shape[0]
    diag_m = M.diagonal()
    kscale = float(np.max(K.diagonal() / diag_m))
    dscale = float(np.max(np.abs(D.diagonal()) / diag_m)) if D.nnz else 0.0
    kept = []
    # all parts' motions together first: parts tied by a closed contact move rigidly as one
    # (a floating assembly); one by one where friction couples some of them to the rest
    for group in ([np.hstack(motions)] if motions else []), motions:
        for R in group:
            N = _zero_energy(M, K, R, kscale)
            if N.shape[1] and _invariant(M, D, K, N, kscale, dscale):
                kept.append(N)
        if kept:
            break
    N = np.hstack(kept) if kept else np.zeros((n, 0))
    MN = M @ N
    return Floating(N, MN, N.T @ (D @ N), dscale)


def _zero_energy(M, K, R, kscale):
    """The M-orthonormal combinations of R's columns whose energy is round-off."""
    G = R.T @ (M @ R)
    g, V = np.linalg.eigh(G)
    if g[-1] <= 0:
        return R[:, :0]
    real = g > 1e-12 * g[-1]
    B = R @ (V[:, real] / np.sqrt(g[real]))
    S = B.T @ (K @ B)
    s, U = np.linalg.eigh(0.5 * (S + S.T))
    return B @ U[:, s <= RIGID_RTOL * kscale]


def _invariant(M, D, K, N, kscale, dscale):
    """Whether span{(N, 0), (0, N)} is invariant on both sides of the first-order pencil."""
    MN = M @ N
    size = np.linalg.norm(MN)
    C = N.T @ (D @ N)
    residuals = (np.linalg.norm(K @ N) / kscale, np.linalg.norm(K.T @ N) / kscale,
                 np.linalg.norm(D @ N - MN @ C) / max(dscale, 1e-300),
                 np.linalg.norm(D.T @ N - MN @ C.T) / max(dscale, 1e-300))
    return max(residuals) <= INVARIANT_RTOL * size
