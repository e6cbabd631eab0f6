"""Reduced basis: the contact shapes kept reproduce the contact flexibility to the tolerance."""
import json

import h5py
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


FREE_BLOCK = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
[parts.block]
material = "steel"
[parts.block.mesh]
kind = "box"
size = [0.02, 0.02, 0.04]
divisions = [3, 3, 6]
origin = [0.0, 0.0, 1.0e-6]
[initial.drop]
part = "block"
velocity = [0.0, 0.0, -1.0]
[contact.wall]
surface1 = "block.zmin"
wall_point = [0.0, 0.0, 0.0]
wall_normal = [0.0, 0.0, 1.0]
[sensors.top]
part = "block"
point = [0.01, 0.01, 0.04]
[solver]
scheme = "explicit"
mass = "lumped"
dt = 2.0e-8
t_end = 1.5e-4
[solver.reduction]
fmax = 50000.0
[output]
contact = true
"""


@pytest.mark.slow
def test_a_free_body_keeps_its_contact_statics_and_lands_as_the_full_model(tmp_path):
    """A block with no constraint falls on a wall. The static responses to its contact loads
    are its rigid motion, 1e10 times their elastic part: normalized as they were, the
    independence test took that part for round-off and dropped every one (9 modes integrated,
    contact 1.6% off the full model). Projected off the modes first, 13 stay, and the contact
    lasts as long and pushes as hard as on the full model within 1% (0.7% measured)."""
    from transient.cli import main
    path = tmp_path / "block.toml"
    path.write_text(FREE_BLOCK)
    stats = {}
    for reduced in (False, True):
        out = tmp_path / f"{reduced}.h5"
        assert main(["run", str(path), "-o", str(out), "--quiet", "--set",
                     f"solver.reduction.enabled={str(reduced).lower()}"]) == 0
        with h5py.File(out, "r") as f:
            force = f["contact/wall/pressure"][:] @ f["geometry/contact/wall/weights"][:]
            on = np.flatnonzero(force > 1e-3 * force.max())
            t = f["time"][:]
            stats[reduced] = (t[on[-1]] - t[on[0]], force.max())
            if reduced:
                asked, kept = json.loads(f.attrs["static_shapes"])
                assert f.attrs["reduced_dofs"] == f.attrs["normal_modes"] + kept and kept >= 10
    (duration, peak), (duration_r, peak_r) = stats[False], stats[True]
    assert duration_r == pytest.approx(duration, rel=1e-2)
    assert peak_r == pytest.approx(peak, rel=1e-2)


def test_free_rows_moved_to_their_dofs_in_place_and_grams_by_blocks():
    """The basis is built in the free rows at the top of X and moved to the dofs in place,
    from the last row up, by pieces: against NumPy's scatter, for runs shorter and longer than
    a piece, a fixed first and last dof, and shifts smaller than a piece (overlapping copies).
    The Grams S^T M S and S^T K S by column blocks equal the whole products, with M and K of
    one pattern or not, and K's low-rank update (a TangentStiffness of the rows' space)."""
    from transient.reduce.basis import COLUMN_BLOCK, _grams, _to_dofs
    from transient.kernels.sparse import shares_pattern
    from transient.solve.lowrank import TangentStiffness
    rng = np.random.default_rng(5)
    ndof, k = 200, 7
    fixed = np.zeros(ndof, bool)
    fixed[[0, 3, 4, 50, 51, 52, 120, 199]] = True
    free = np.flatnonzero(~fixed)
    rows = rng.normal(size=(len(free), k))
    for piece in (1, 5, 4096):
        X = np.full((ndof, k), np.nan)
        X[:len(free)] = rows
        _to_dofs(X, free, rows=piece)
        expected = np.zeros((ndof, k))
        expected[free] = rows
        assert np.array_equal(X, expected)
    n, s = 60, COLUMN_BLOCK + 9
    S = rng.normal(size=(n, s + 3))[:, 3:]          # a strided view, as in the basis
    A = sp.random(n, n, density=0.1, random_state=1)
    A = (A + A.T).tocsr()
    B = sp.random(n, n, density=0.2, random_state=2)
    B = (B + B.T).tocsr()
    cols = np.array([2, 7, 30, 59])
    V = np.linalg.qr(rng.normal(size=(4, 2)))[0]
    core = np.array([[2.0, 0.5], [0.5, 1.0]])
    update = np.zeros((n, n))
    update[np.ix_(cols, cols)] = V @ core @ V.T
    same = sp.csr_matrix((rng.normal(size=A.nnz), A.indices, A.indptr), shape=A.shape)
    same = same + same.T           # (the sum sorts the pattern: A's, sorted, is the same)
    assert shares_pattern(same, A) and not shares_pattern(A, B)
    for M, K in ((A, TangentStiffness(B)), (A, TangentStiffness(B, cols, V, core)),
                 (same, TangentStiffness(A, cols, V, core))):
        GM, GK = _grams(M, K, S)
        assert np.allclose(GM, S.T @ (M @ S), rtol=1e-13, atol=1e-13)
        assert np.allclose(GK, S.T @ ((K.K + update * (K.V is not None)) @ S), rtol=1e-13,
                           atol=1e-13)


def test_the_static_directions_asked_count_the_frictions_coupling_loads():
    """With friction the basis also solves for the coupling loads of the modes (FrictionLoads:
    the stiffness loads of every mode, the damping loads of the band's): they are static
    directions asked, so the kept ones never outnumber them."""
    from test_cea import small
    from transient.stages import prepare
    asked = {}
    for mu in (0.0, 0.4):
        meta = prepare(small(f"contact.pad_disc.friction.mu={mu}")).meta
        asked[mu], kept = meta["static_shapes"]
        assert kept <= asked[mu]
    band = sum(f <= 16000.0 for f in meta["modes_hz"])
    assert 0 < band < meta["normal_modes"] == len(meta["modes_hz"])
    assert asked[0.4] == asked[0.0] + meta["normal_modes"] + band
