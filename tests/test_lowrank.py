"""ContactSolver: Woodbury updates of one factorization against direct solves, with fewer
contact rows than touched dofs and with more (a fine rule)."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from transient.solve.lowrank import ContactSolver


def spd(n, seed):
    """A sparse SPD stiffness of n dofs and an identity mass."""
    A = sp.random(n, n, density=0.05, random_state=seed)
    return (A + A.T + n * sp.eye(n)).tocsr(), sp.eye(n).tocsr()


@pytest.mark.parametrize("m", [5, 60])
def test_updates_solve_the_updated_system(m):
    rng = np.random.default_rng(m)
    n = 80
    K, M = spd(n, 1)
    cols = rng.choice(n, 12, replace=False)               # the dofs contact touches
    rows = np.repeat(np.arange(m), 3)
    C = sp.csr_matrix((rng.standard_normal(3 * m), (rows, rng.choice(cols, 3 * m))),
                      shape=(m, n))
    cs = ContactSolver(K, M, C, -4.0)
    assert cs.by_columns == (m > 12)
    b = rng.standard_normal((n, 2))
    for d in (rng.uniform(0, 1e3, m), np.zeros(m)):
        x = cs.solver(d)(b)
        A = (K + 4.0 * M + C.T @ sp.diags(d) @ C).tocsc()
        assert np.allclose(x, spla.spsolve(A, b), rtol=1e-9, atol=1e-12)
        assert np.allclose(cs.solver(d)(b[:, 0]), x[:, 0])


def test_the_solver_forms_a0_when_asked_and_bounds_its_blocks_by_bytes():
    """A0 = K - sigma M is not held beside its factors (a sparse matrix more through the
    setup: 0.40 GB of 4x pad_disc's peak), and travels to another process as K and M; the blocks of
    right-hand sides shrink where n x 128 floats would pass BLOCK_BYTES."""
    import pickle
    from transient.solve.lowrank import BLOCK_BYTES, block_columns
    rng = np.random.default_rng(11)
    n, m = 80, 60
    K, M = spd(n, 3)
    cols = rng.choice(n, 12, replace=False)
    C = sp.csr_matrix((rng.standard_normal(m), (np.arange(m), rng.choice(cols, m))),
                      shape=(m, n))
    cs = ContactSolver(K, M, C, -4.0)
    assert "A0" not in vars(cs)
    assert set(cs.timings) == {"factors", "row_space", "responses"}
    assert min(cs.timings.values()) >= 0
    assert abs(cs.A0 - (K + 4.0 * M)).max() == 0
    d, b = rng.uniform(0, 1e3, m), rng.standard_normal(n)
    copy = pickle.loads(pickle.dumps(cs))
    assert np.array_equal(copy.solver(d)(b), cs.solver(d)(b))
    assert block_columns(66_554) == 128 and block_columns(231_000) == 128
    assert block_columns(971_042) == 32 and block_columns(10**8) == 8
    assert block_columns(2 * 10**6, most=16) == 16
    assert 8 * 971_042 * block_columns(971_042) <= BLOCK_BYTES


def test_rows_of_low_rank_run_on_their_row_space():
    """Regularized rows: dense on the touched dofs but of rank rho < k < m."""
    rng = np.random.default_rng(7)
    n, m, k, rho = 80, 60, 20, 6
    K, M = spd(n, 2)
    cols = np.sort(rng.choice(n, k, replace=False))
    dense = np.zeros((m, n))
    dense[:, cols] = rng.standard_normal((m, rho)) @ rng.standard_normal((rho, k))
    C = sp.csr_matrix(dense)
    cs = ContactSolver(K, M, C, -4.0)
    assert cs.by_columns and cs.Rm.shape == (m, rho) and cs.Z.shape == (n, rho)
    b = rng.standard_normal((n, 2))
    d = rng.uniform(0, 1e2, m)
    x = cs.solver(d)(b)
    direct = (K + 4.0 * M + C.T @ sp.diags(d) @ C).tocsc()
    assert np.allclose(x, spla.spsolve(direct, b), rtol=1e-9, atol=1e-12)
    known = cs.solver(d).row_space
    cols_, V, Rm, R = known.cols, known.V, known.Rm, known.R
    assert np.allclose(Rm @ V.T, dense[:, cols_])
    B = np.zeros((n, rho))
    B[cols_] = V
    assert np.allclose(known.responses(R()), spla.spsolve(direct, B), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("m", [5, 60])
def test_without_room_for_z_the_solves_are_the_same(m, monkeypatch):
    """Z = A0^-1 B (n x rank) not held (a mesh where it would not fit): each use solves for it,
    and the solves, row space and responses are those with Z held."""
    import transient.solve.lowrank as lowrank
    rng = np.random.default_rng(3 + m)
    n, k = 80, 20
    K, M = spd(n, 4)
    cols = np.sort(rng.choice(n, k, replace=False))
    dense = np.zeros((m, n))
    dense[:, cols] = rng.standard_normal((m, 6)) @ rng.standard_normal((6, k))
    if m < k:
        dense[:, cols] = rng.standard_normal((m, k))
    C = sp.csr_matrix(dense)
    held = ContactSolver(K, M, C, -4.0)
    monkeypatch.setattr(lowrank, "MAX_BYTES", 8.0 * n * held.G.shape[0] - 1)
    solved = ContactSolver(K, M, C, -4.0)
    assert held.Z is not None and solved.Z is None and solved.lowrank
    assert np.array_equal(held.G, solved.G)
    d = rng.uniform(0, 1e2, m)
    b = rng.standard_normal((n, 3))
    assert np.allclose(solved.solver(d)(b), held.solver(d)(b), rtol=1e-12, atol=1e-15)
    assert np.allclose(solved.solver(d)(b[:, 0]), held.solver(d)(b[:, 0]), rtol=1e-12,
                       atol=1e-15)
    if m > k:
        Y = rng.standard_normal((held.G.shape[0], 5))
        # in blocks of 2 right-hand sides: the last one short
        monkeypatch.setattr(lowrank, "BLOCK", 2)
        assert np.allclose(solved.responses(Y), held.responses(Y), rtol=1e-12, atol=1e-15)
        assert np.allclose(solved.responses(Y[:, 0]), held.responses(Y[:, 0]), rtol=1e-12,
                           atol=1e-15)


@pytest.mark.parametrize("path", ["rows", "row-space", "negative-d", "dense", "no-contact"])
def test_the_tangent_stiffness_is_k_plus_the_update(path, monkeypatch):
    """TangentSolve.stiffness applies K + C^T diag(d) C (the setup's K_lin on the free dofs)
    without forming it, whichever form the solver holds the rows in, and tocsr forms it."""
    import transient.solve.lowrank as lowrank
    rng = np.random.default_rng(11)
    n, k = 80, 20
    K, M = spd(n, 5)
    cols = np.sort(rng.choice(n, k, replace=False))
    m = 5 if path == "rows" else 0 if path == "no-contact" else 60
    dense = np.zeros((m, n))
    dense[:, cols] = rng.standard_normal((m, 6)) @ rng.standard_normal((6, k))
    if path == "dense":
        monkeypatch.setattr(lowrank, "MAX_BYTES", 1.0)     # A0 + C^T D C factorized
    C = sp.csr_matrix(dense)
    cs = ContactSolver(K, M, C, -4.0)
    assert cs.by_columns == (path in ("row-space", "negative-d"))
    assert cs.lowrank == (path not in ("dense", "no-contact"))
    d = rng.uniform(0, 1e2, m)
    if path == "negative-d":
        d[:3] *= -1.0            # a softening tangent: no D^1/2
    stiffness = cs.solver(d).stiffness
    K_lin = (K + C.T @ sp.diags(d) @ C).toarray()
    X = rng.standard_normal((n, 4))
    scale = np.abs(K_lin).max()
    assert np.allclose(stiffness @ X, K_lin @ X, rtol=1e-12, atol=1e-12 * scale * n)
    assert np.allclose(stiffness @ X[:, 1], K_lin @ X[:, 1], rtol=1e-12,
                       atol=1e-12 * scale * n)
    assert np.allclose(stiffness.toarray(), K_lin, rtol=1e-12, atol=1e-12 * scale)
    assert stiffness.shape == (n, n)


def test_factored_rows_give_the_same_row_space_and_solves():
    """Rows given as L B^T (regularized rules) with dependent columns of L, as the two sides'
    compatible shapes give: the row space from the r x r algebra is the dense rows' one, cut
    at the same rank, and the solves match the direct ones."""
    rng = np.random.default_rng(11)
    n, m, k, r = 90, 70, 24, 10
    K, M = spd(n, 3)
    cols = np.sort(rng.choice(n, k, replace=False))
    L = rng.standard_normal((m, r))
    L[:, -3:] = L[:, :3] @ rng.standard_normal((3, 3))      # rank r - 3
    B = np.zeros((n, r))
    B[cols] = rng.standard_normal((k, r))
    C = sp.csr_matrix(L @ B.T)
    dense = ContactSolver(K, M, C, -4.0)
    factored = ContactSolver(K, M, C, -4.0, factors=(L, sp.csr_matrix(B)))
    assert dense.Rm.shape == factored.Rm.shape == (m, r - 3)
    V1, V2 = dense.V, factored.V
    assert np.allclose(V1 @ (V1.T @ V2), V2, atol=1e-10)
    assert np.allclose(factored.Rm @ V2.T, C[:, factored.cols].toarray(), atol=1e-10)
    b = rng.standard_normal((n, 2))
    d = rng.uniform(0, 1e2, m)
    direct = (K + 4.0 * M + C.T @ sp.diags(d) @ C).tocsc()
    assert np.allclose(factored.solver(d)(b), spla.spsolve(direct, b), rtol=1e-9, atol=1e-12)


@pytest.mark.slow
def test_regularized_pairs_carry_their_rows_factored():
    """A regularized pair holds its rows as factors only (its rule's C1, C2 are None): the
    rows, their subsets, C T, the contact force and the interface stiffness they give are those
    of the explicit projected rows C1 P1 T1 - C2 P2 T2 (pad_disc, coarse)."""
    from pathlib import Path

    from transient.case.loading import load
    from transient.contact.contactset import stack
    from transient.contact.pair import build_contact, contact_stiffness
    from transient.contact.regularize import regularized_rule
    from transient.model import build_model
    case = load(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml",
                ["parts.disc.mesh.divisions=[4,48,1]", "parts.pad.mesh.divisions=[3,8,1,1]"])
    model = build_model(case)
    pairs = build_contact(case, model)
    (pair,) = pairs
    assert pair.rule.C1 is None and pair.rule.C2 is None
    # the explicit rows, from the fine rule and the projectors P_n = Q_n Y_n
    (Q1, Y1), (Q2, Y2) = pair.projections
    explicit = sp.csr_matrix(pair.interface.observation(
        regularized_rule(pair.interface.fine, Q1 @ Y1, Q2 @ Y2), model.ndof))
    contacts = stack(pairs, model.ndof)
    assert contacts.rows is None
    L, B = contacts.factors
    assert L is pair.factors[0]        # one pair's: not copied (0.81 GB at 1M dofs)
    # the model's K and M share one pattern (0.31 GB at 1M dofs)
    assert np.shares_memory(model.K.indices, model.M.indices)
    assert np.shares_memory(model.K.indptr, model.M.indptr)
    assert L.shape[1] < contacts.n_points
    scale = np.abs(explicit.toarray()).max()
    assert np.abs((contacts.C - explicit).toarray()).max() <= 1e-13 * scale
    keep = np.arange(0, contacts.n_points, 3)
    sub = contacts.subset(keep, contacts.weights[keep])
    assert sub.rows is not None and np.abs((sub.C - explicit[keep]).toarray()).max() <= \
        1e-13 * scale
    rng = np.random.default_rng(1)
    T = rng.standard_normal((model.ndof, 4))
    assert np.allclose(contacts.observe(T), explicit @ T, rtol=1e-12, atol=1e-12 * scale)
    u = 1e-7 * rng.standard_normal(model.ndof)
    f, g, p, kt = contacts.force(u)
    g_ref = explicit @ u + contacts.gap0
    p_ref = contacts.laws(g_ref)[0]
    assert np.allclose(g, g_ref, rtol=1e-12, atol=1e-12 * np.abs(g_ref).max())
    f_ref = explicit.T @ (contacts.weights * p_ref)
    assert np.allclose(f, f_ref, rtol=1e-10, atol=1e-11 * np.abs(f_ref).max())
    kw = rng.uniform(0.5, 2.0, contacts.n_points) * contacts.weights * pair.k
    K = contact_stiffness(pairs, model.ndof, kw=[kw]).toarray()
    K_ref = (explicit.T @ sp.diags(kw) @ explicit).toarray()
    assert np.abs(K - K_ref).max() <= 1e-11 * np.abs(K_ref).max()


def test_several_pairs_factors_held_by_pair_multiply_as_the_block_diagonal():
    """contact.blocks.PairFactors (each pair's L on its own points and shapes, a pair with no
    point kept, one with none at all) against the block-diagonal dense L it stands for: L Y and
    L^T y on blocks and vectors, a subset of the points (sorted indices, a slice), and the
    contact set's products through it (observe, the normal load, the rows) against the
    explicit rows of the same factors."""
    from transient.contact.blocks import PairFactors, pair_factors
    from transient.contact.regularize import factored_rows
    rng = np.random.default_rng(2)
    blocks = [rng.normal(size=(7, 3)), rng.normal(size=(5, 4)), np.zeros((0, 2)),
              rng.normal(size=(6, 2))]
    L = PairFactors(blocks)
    dense = L.toarray()
    assert dense.shape == L.shape == (18, 11)
    assert np.array_equal(dense[7:12, 3:7], blocks[1]) and not dense[:7, 3:].any()
    Y, y = rng.normal(size=(11, 4)), rng.normal(size=(18, 3))
    for got, want in ((L @ Y, dense @ Y), (L @ Y[:, 0], dense @ Y[:, 0]),
                      (L.T @ y, dense.T @ y), (L.T @ y[:, 0], dense.T @ y[:, 0])):
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13 * np.abs(want).max())
    keep = np.array([0, 3, 6, 12, 13, 17])           # none of the second pair's points
    assert np.array_equal(L[keep].toarray(), dense[keep])
    assert L[keep].shape == (6, 11) and L[keep].blocks[1].shape == (0, 4)
    assert np.array_equal(L[7:12].toarray(), dense[7:12])
    assert [(r, c) for r, c, _ in pair_factors(L)][1] == (slice(7, 12), slice(3, 7))
    B = sp.random(30, 11, density=0.3, random_state=3, format="csr")
    explicit = factored_rows(dense, B)
    assert np.abs((factored_rows(L, B) - explicit).toarray()).max() <= \
        1e-13 * np.abs(explicit.toarray()).max()
    # the brake corner's eleven pairs, with friction on the pads: its contact set against
    # the same set with L dense
    from dataclasses import replace
    from pathlib import Path

    from transient.case.loading import load
    from transient.contact.contactset import stack
    from transient.contact.pair import build_contact
    from transient.model import build_model
    case = load(Path(__file__).resolve().parent.parent / "cases" / "brake_corner.toml",
                ["contact.pad_in_disc.friction.mu=0.4", "contact.pad_out_disc.friction.mu=0.4"])
    model = build_model(case)
    contacts = stack(build_contact(case, model), model.ndof)
    L, B = contacts.factors
    assert isinstance(L, PairFactors) and len(L.blocks) == 11
    twin = replace(contacts, factors=(L.toarray(), B))
    T = rng.normal(size=(model.ndof, 3))
    z = rng.normal(size=(contacts.n_points, 2))

    def close(got, want):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    close(contacts.observe(T), twin.observe(T))
    for got, want in zip(contacts.observe_tangential(T), twin.observe_tangential(T)):
        close(got, want)
    for load_of in ("normal_load", "tangential_load", "across_load"):
        close(getattr(contacts, load_of)(z), getattr(twin, load_of)(z))
    keep = np.arange(0, contacts.n_points, 5)
    close(contacts.subset(keep, contacts.weights[keep]).observe(T),
          twin.subset(keep, twin.weights[keep]).observe(T))


def test_pardiso_analysis_says_what_the_factorization_takes(capsys):
    """The symbolic analysis reports the factors a factorization then holds: nonzeros at least
    those of the upper triangle (no fewer than the matrix), memory and flops positive; and
    benchmarks/bench_factor.py reports it with the model's memory for a shipped case."""
    import json
    from pathlib import Path

    from transient.solve.linsolve import available, pardiso_analysis
    if "pardiso" not in available():
        pytest.skip("PARDISO not installed")
    n = 400
    A = sp.diags([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    A = sp.kron(sp.eye(20), A) + sp.kron(sp.diags([-np.ones(19), -np.ones(19)], [-1, 1]),
                                           sp.eye(n)) + 2.0 * sp.eye(20 * n)
    r = pardiso_analysis(A.tocsr())
    assert sp.triu(A).nnz <= r["factor_nnz"] <= (20 * n) ** 2 / 2
    assert 0 < r["factor_gb"] <= r["peak_gb"] and r["gflop"] >= 0
    import bench_factor      # benchmarks/: setup.cfg's pythonpath
    root = Path(__file__).resolve().parent.parent
    bench_factor.main([str(root / "cases" / "two_bars.toml"), "--factor", "--json"])
    row = json.loads(capsys.readouterr().out)
    assert row["free_dofs"] > 0 and row["factor_nnz"] >= row["free_dofs"]
    assert row["peak_rss_gb"] >= row["model_peak_rss_gb"] > 0


@pytest.mark.slow
def test_a_setup_frees_the_factors_it_owns_after_its_last_solve(monkeypatch):
    """The setup that factorized K - sigma M frees the factors once the basis has made its
    last solve (at 1M dofs they were 10.3 GB of the 24 GB the Grams after them ran out of);
    a released PARDISO refuses to solve. A campaign's shared solver is not released, solves
    for the next variant, and both setups reduce to the same system."""
    from pathlib import Path

    from transient.case.loading import load
    from transient.solve.linsolve import available
    from transient.shared import build_shared
    from transient.stages import prepare
    case = load(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml",
                ["parts.disc.mesh.divisions=[3,36,1]", "parts.pad.mesh.divisions=[3,6,1,1]"])
    released, release = [], ContactSolver.release
    monkeypatch.setattr(ContactSolver, "release",
                        lambda self: (released.append(self), release(self))[1])
    owned = prepare(case)
    assert len(released) == 1
    if "pardiso" in available():
        with pytest.raises(RuntimeError, match="released"):
            released[0].solve0(np.ones(released[0].n))
    built = build_shared(case, "factorization")
    shared = prepare(case, built=built)
    assert len(released) == 1
    assert np.isfinite(built.solver.solve0(np.ones(built.solver.n))).all()
    assert np.array_equal(owned.basis[0], shared.basis[0])
    assert np.array_equal(owned.basis[1], shared.basis[1])


@pytest.mark.parametrize("shift", [0.0, 0.3 + 1e-3j])
def test_pardiso_schur_complement_is_the_condensation_by_dense_solves(shift):
    """schur_complement: A_GG - A_GI A_II^-1 A_IG of a real symmetric and of a complex
    symmetric (not Hermitian) A on its last dofs, against NumPy's dense solve, each to
    round-off of its own size; A_GG's diagonal stored as explicit zeros where it is empty."""
    from transient.solve.linsolve import available, schur_complement
    if "pardiso" not in available():
        pytest.skip("PARDISO not installed")
    rng = np.random.default_rng(3)
    n, g = 300, 40
    B = sp.random(n, n, density=0.02, random_state=4)
    D = (B + B.T + sp.diags(rng.uniform(4, 5, n))).toarray() - shift * np.eye(n)
    D[n - g:, n - g:] = 0.0
    C = sp.coo_matrix(D)
    diagonal = np.arange(n - g, n)
    A = sp.csr_matrix((np.r_[C.data, np.zeros(g)], (np.r_[C.row, diagonal],
                                                    np.r_[C.col, diagonal])), shape=(n, n))
    A.sort_indices()
    assert A[n - g:, n - g:].nnz == g
    I, G = slice(0, n - g), slice(n - g, n)
    want = D[G, G] - D[G, I] @ np.linalg.solve(D[I, I], D[I, G])
    got = schur_complement(A, g)
    assert got.dtype == want.dtype
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
