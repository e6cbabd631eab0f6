"""Block shift-invert Lanczos against a dense eigensolver: every eigenvalue below the bound,
none missed where they are multiple (a square membrane's doublets), M-orthonormal vectors."""
import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from transient.solve.lanczos import NotConverged, block_lanczos


def membrane(nx=20, seed=0):
    """A square membrane's stiffness (its eigenvalues are double off the diagonal) and a mass
    that is lumped on a random diagonal or the identity."""
    L1 = sp.diags([-np.ones(nx - 1), 2 * np.ones(nx), -np.ones(nx - 1)], [-1, 0, 1])
    K = (sp.kron(L1, sp.eye(nx)) + sp.kron(sp.eye(nx), L1)).tocsc()
    if seed is None:
        return K, sp.identity(nx * nx, format="csr")
    return K, sp.diags(np.random.default_rng(seed).uniform(0.5, 2.0, nx * nx)).tocsr()


def solver(K, M, sigma):
    lu = spla.splu((K - sigma * M).tocsc())
    return lambda B: lu.solve(np.asarray(B))


@pytest.mark.parametrize("seed", [None, 0])
@pytest.mark.parametrize("block", [2, 8, 16])
def test_every_eigenvalue_below_the_bound(seed, block):
    K, M = membrane(seed=seed)
    ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    k = 40 + int(np.argmax(np.diff(ref[39:]) > 1e-6 * ref[39]))    # about 40 wanted
    sigma, lam_max = -0.01, 0.5 * (ref[k - 1] + ref[k])
    lam, X, steps = block_lanczos(solver(K, M, sigma), M, sigma, lam_max=lam_max, block=block)
    ref = ref[ref <= lam_max]
    assert np.sum(lam <= lam_max) == len(ref) and len(lam) > len(ref)
    assert np.abs(lam[:len(ref)] - ref).max() <= 1e-11 * ref.max()
    assert np.abs(X.T @ (M @ X) - np.eye(len(lam))).max() <= 1e-12
    assert np.abs(K @ X - (M @ X) * lam).max() <= 1e-10 * lam.max()


def test_the_first_count_pairs():
    K, M = membrane(seed=1)
    lam, X, _ = block_lanczos(solver(K, M, -0.01), M, -0.01, count=25, block=8)
    ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)[:25]
    assert np.abs(lam[:25] - ref).max() <= 1e-11 * ref.max()


def test_a_basis_too_small_is_said():
    K, M = membrane(seed=2)
    with pytest.raises(NotConverged, match="eigenpairs in a basis of"):
        block_lanczos(solver(K, M, -0.01), M, -0.01, lam_max=2.0, block=4, max_dim=40)


def test_a_space_that_closes_returns_every_pair_exactly():
    K, M = membrane(nx=6, seed=3)
    lam, X, _ = block_lanczos(solver(K, M, -0.01), M, -0.01, lam_max=1e9, block=5)
    ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    assert len(lam) == 36 and np.abs(lam - ref).max() <= 1e-12 * ref.max()


def floating(nx=12, spring=1e-9):
    """A clamped membrane and a free one joined by a weak spring at a corner: the free one's
    rigid mode is nearly zero, so near a small shift its theta is 1e6 times the elastic ones
    (drilled_cube's upper cube on a soft contact)."""
    L1 = sp.diags([-np.ones(nx - 1), 2 * np.ones(nx), -np.ones(nx - 1)], [-1, 0, 1])
    N1 = L1.tolil()
    N1[0, 0] = N1[-1, -1] = 1.0
    N1 = N1.tocsr()
    K = sp.block_diag([sp.kron(L1, sp.eye(nx)) + sp.kron(sp.eye(nx), L1),
                       sp.kron(N1, sp.eye(nx)) + sp.kron(sp.eye(nx), N1)]).tolil()
    i, j = 0, nx * nx
    K[i, i] += spring
    K[j, j] += spring
    K[i, j] -= spring
    K[j, i] -= spring
    return K.tocsc(), sp.diags(np.random.default_rng(4).uniform(0.5, 2.0, 2 * nx * nx)).tocsr()


def test_a_floating_part_far_above_the_elastic_modes():
    K, M = floating()
    sigma = -1e-8
    ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    assert (1 / (ref[0] - sigma)) / (1 / (ref[1] - sigma)) > 1e6
    lam, X, _ = block_lanczos(solver(K, M, sigma), M, sigma, count=20, block=8)
    # one Gram for the whole block left these 0.5 off orthogonal and 23% off in eigenvalue
    assert np.abs(X.T @ (M @ X) - np.eye(len(lam))).max() <= 1e-12
    assert np.abs(lam[1:20] - ref[1:20]).max() <= 1e-9 * ref[19]
    assert abs(lam[0] - ref[0]) <= 1e-9 * ref[1]


def test_a_basis_that_stops_converging_is_said():
    K, M = membrane(seed=5)
    lu = spla.splu((K + 0.01 * M).tocsc())
    rng = np.random.default_rng(0)

    def noisy(B):        # solves with 1e-6 relative noise: the residuals never reach 1e-12
        X = lu.solve(np.asarray(B))
        return X * (1 + 1e-6 * rng.standard_normal(X.shape))
    with pytest.raises(NotConverged, match="stalled"):
        block_lanczos(noisy, M, -0.01, count=30, block=4)


def test_a_looser_tolerance_keeps_the_eigenvalues():
    """tol 1e-9 (the setup's, reduce.basis.MODES_TOL) stops earlier with the same eigenvalues:
    they converge as the square of the residual, so only the vectors carry the looser bound."""
    K, M = membrane(nx=30, seed=1)
    ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    lam_max = 0.5 * (ref[39] + ref[40]) if ref[40] - ref[39] > 1e-6 * ref[39] else ref[39] * 1.0001
    ref = ref[ref <= lam_max]
    tight = block_lanczos(solver(K, M, -0.01), M, -0.01, lam_max=lam_max, block=8)
    lam, X, steps = block_lanczos(solver(K, M, -0.01), M, -0.01, lam_max=lam_max, block=8,
                                  tol=1e-9)
    assert steps < tight[2]
    assert np.abs(lam[:len(ref)] - ref).max() <= 1e-12 * ref.max()
    assert np.abs(X.T @ (M @ X) - np.eye(len(lam))).max() <= 1e-12
    assert np.abs(K @ X - (M @ X) * lam).max() <= 1e-7 * lam.max()
