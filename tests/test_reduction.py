"""Reduced basis: the contact shapes kept reproduce the contact flexibility to the tolerance."""
import numpy as np
import pytest
import scipy.sparse as sp

from transient.solve.linsolve import factorize
from transient.reduce.basis import reduced_basis


def chain(n=300, m=12):
    """A clamped string of springs and masses, with m contact points on its last 40 dofs."""
    k = np.full(n, 1e6)
    K = sp.diags([2 * k, -k[:-1], -k[:-1]], [0, 1, -1]).tolil()
    K[n - 1, n - 1] = k[0]
    M = sp.diags(np.full(n, 1e-3)).tocsr()
    rng = np.random.default_rng(0)
    rows = np.repeat(np.arange(m), 2)
    cols = (n - 40 + rng.integers(0, 40, 2 * m))
    C = sp.csr_matrix((rng.uniform(0.2, 1.0, 2 * m), (rows, cols)), shape=(m, n))
    return K.tocsr(), M, C


@pytest.mark.parametrize("m", [12, 90])       # fewer points than dofs touched, and more
@pytest.mark.parametrize("tol", [0.0, 1e-3, 1e-1])
def test_contact_flexibility_kept_to_the_tolerance(tol, m):
    K, M, C = chain(m=m)
    stiffness = np.geomspace(1e4, 1e7, C.shape[0])       # w k_t of each point
    fixed = np.zeros(K.shape[0], bool)
    solve = factorize(K)
    basis = reduced_basis(K, M, fixed, 50.0, np.zeros((K.shape[0], 0)), solve, 0.0,
                          (C, stiffness), tol)
    d = np.sqrt(stiffness)
    F = np.asarray(C @ solve(np.asarray(C.T.todense())))
    Cr = np.asarray(C @ basis.T)
    F_red = (Cr / basis.omega2) @ Cr.T
    # the flexibility dropped, relative to the law's: at most tol, and positive (a Galerkin
    # basis is stiffer than the structure)
    drop = np.linalg.eigvalsh((F - F_red) * d[:, None] * d[None, :])
    scale = np.linalg.eigvalsh(F * d[:, None] * d[None, :]).max()     # round-off: relative
    assert drop.min() > -1e-9 * scale
    assert drop.max() <= tol + 1e-9 * scale
    mu = basis.contact_flexibility
    if tol == 0.0:
        assert basis.n_contact_shapes == C.shape[0]
    else:
        assert basis.n_contact_shapes == np.sum(mu >= tol)
    if tol == 1e-1:
        assert basis.n_contact_shapes < C.shape[0]


def test_contact_shapes_from_the_woodbury_solver_match_a_direct_factorization():
    """With more points than touched dofs, the shapes come from the ContactSolver's K^-1 E
    (no solves of their own): the same basis as from a factorization of K_lin itself."""
    from transient.solve.lowrank import ContactSolver
    K, M, C = chain(m=90)
    tangent = np.geomspace(1e3, 1e6, C.shape[0])
    K_lin = (K + C.T @ sp.diags(tangent) @ C).tocsr()
    fixed = np.zeros(K.shape[0], bool)
    solve = ContactSolver(K, M, C, 0.0).solver(tangent)
    assert solve.row_space is not None
    bases = [reduced_basis(K_lin, M, fixed, 50.0, np.zeros((K.shape[0], 0)), s, 0.0,
                           (C, tangent), 1e-3) for s in (solve, factorize(K_lin))]
    assert bases[0].n_contact_shapes == bases[1].n_contact_shapes > 0
    assert np.allclose(bases[0].contact_flexibility, bases[1].contact_flexibility, rtol=1e-8)
    assert np.allclose(bases[0].omega2, bases[1].omega2, rtol=1e-8)
