"""A part reduced in pieces (reduce/pieces.py, reduce/piece.py: parts.NAME.pieces on the
components path): the cut, the pieces' Craig-Bampton reduction and the cut's shapes, against
the part reduced whole and against the whole model."""
import numpy as np
import pytest
import scipy.sparse as sp

from transient.case.loading import load
from transient.contact.contactset import stack
from transient.contact.pair import build_contact
from transient.errors import CaseError
from transient.model import build_model, constant_load
from transient.model.dofs import free_block, restrict, shifted
from transient.reduce.components import part_tasks, part_work
from transient.reduce.pieces import CUT
from transient.solve.modes import shift_sigma
from transient.stages import prepare

from small_cases import PAD_DISC

PAD = "cases/pad_disc.toml"
COMPONENTS = ['solver.reduction.method="components"', "contact.pad_disc.friction.mu=0.4"]


def disc_tasks(pieces, extra=(), matrices=False):
    """(the disc's PartTask reduced whole, the same in pieces) of the small pad_disc, and with
    matrices the disc's K and M on its free dofs as the whole model holds them."""
    case = load(PAD, PAD_DISC + COMPONENTS + list(extra) + [f"parts.disc.pieces={pieces}"])
    model = build_model(case)
    pairs = build_contact(case, model)
    tasks = part_tasks(case, model, pairs, stack(pairs, model.ndof),
                       [model.load_patterns[n] for n in case.loads], constant_load(case, model))
    whole, cut = (dict((t.name, t) for t in part_work(case, [(d, task, p if keep else None)
                                                             for d, task, p in tasks]))
                  for keep in (False, True))
    if not matrices:
        return whole["disc"], cut["disc"]
    dofs = next(d for d, task, _ in tasks if task[0] == "disc")
    return whole["disc"], cut["disc"], free_block(model.K, dofs), free_block(model.M, dofs)


def same(A, B):
    """A and B the same CSR matrix, entry for entry."""
    A, B = sp.csr_matrix(A), sp.csr_matrix(B)
    return (A.shape == B.shape and np.array_equal(A.indptr, B.indptr)
            and np.array_equal(A.indices, B.indices) and np.array_equal(A.data, B.data))


def test_a_parts_cells_give_its_block_of_the_model_and_a_piece_its_rows():
    """The disc's K and M assembled from its own cells (where a worker reduces it) are the
    whole model's block bit for bit, and each piece's cells give its interior's rows, with
    the cut, bit for bit: no other piece's cell touches an interior dof."""
    _, task, K, M = disc_tasks(3, matrices=True)
    Kp, Mp = task.cells.matrices()
    assert same(Kp, K) and same(Mp, M)
    cut = np.flatnonzero(task.piece_of == CUT)
    for i in range(3):
        I = np.flatnonzero(task.piece_of == i)
        (KI, MI), (KG, MG) = task.cells.subset(task.cell_piece == i).on([(I, I), (I, cut)])
        for A, B in ((KI, restrict(K, I, I)), (MI, restrict(M, I, I)),
                     (KG, restrict(K, I, cut)), (MG, restrict(M, I, cut))):
            assert same(A, B), i
    assert same(task.Kc, restrict(K, cut, cut)) and same(task.Mc, restrict(M, cut, cut))


def test_a_pieces_blocks_and_rows_made_a_block_at_a_time_are_those_made_whole(tmp_path,
                                                                               monkeypatch):
    """Piece.blocks forms A^T X A, A^T X W and W^T X W a block of columns at a time, and
    Piece.expanded the part's rows a block of rows at a time: each the product made whole to
    round-off (relative to its own size), the rows written into a file bit for bit those
    held in memory."""
    from transient.reduce import piece as piece_module
    from transient.reduce.pieces import _piece
    _, task = disc_tasks(3)
    cut = np.flatnonzero(task.piece_of == CUT)
    I = np.flatnonzero(task.piece_of == 0)
    piece, G = _piece(task.name, task.cells.subset(task.cell_piece == 0), I, cut, {},
                      task.shift_hz, task.backend)
    rng = np.random.default_rng(0)
    n, a, c = len(I), 300, 200
    A, ext, V = (rng.standard_normal(s) for s in ((n, a), (n, c), (len(G), c)))
    loads = sp.random(n, 5, density=0.01, random_state=1, format="csr")
    monkeypatch.setattr(piece_module, "block_columns", lambda rows: 64)
    blocks = piece.blocks(A, ext, V, loads)
    for (AXA, AXW, WXW), (X, XG) in zip(blocks, ((piece.K, piece.KG), (piece.M, piece.MG))):
        XW = X @ ext + XG @ V
        for got, whole in ((AXA, A.T @ (X @ A)), (AXW, A.T @ XW),
                           (WXW, ext.T @ XW + V.T @ (XG.T @ ext))):
            assert np.abs(got - whole).max() <= 1e-13 * np.abs(whole).max()
    Ta, Tw = rng.standard_normal((a, 40)), rng.standard_normal((c, 40))
    monkeypatch.setattr(piece_module, "ROW_BLOCK", 100)
    rows = np.lib.format.open_memmap(tmp_path / "T.npy", "w+", np.float64, (n + 7, 40))
    piece.expanded((A, ext), Ta, Tw, rows, np.arange(n) + 7)
    held = piece.expanded((A, ext), Ta, Tw)
    assert np.array_equal(rows[7:], held)
    whole = A @ Ta + ext @ Tw
    assert np.abs(held - whole).max() <= 1e-13 * np.abs(whole).max()


def test_a_pieces_condensation_from_its_schur_complement_is_the_one_by_solves(monkeypatch):
    """Piece.condensed with PARDISO's Schur complement of K - z M at the complex shift (S
    and Mh from one factorization, C a solve a mode) and with Psi by solves (two for each cut
    dof): the same condensation, each array to round-off of its own size, the piece's columns
    the same."""
    from transient.reduce import piece as piece_module
    from transient.reduce.pieces import PIECE_REACH, _piece, _share
    from transient.solve.linsolve import available
    if "pardiso" not in available():
        pytest.skip("PARDISO not installed")
    _, task = disc_tasks(3)
    cut = np.flatnonzero(task.piece_of == CUT)
    I = np.flatnonzero(task.piece_of == 1)
    piece, G = _piece(task.name, task.cells.subset(task.cell_piece == 1), I, cut,
                      _share(task.interface, I, False), task.shift_hz, task.backend)
    loads = sp.csr_matrix(task.loads)[I]
    by_schur = piece.condensed(loads, PIECE_REACH * task.fmax)
    monkeypatch.setattr(piece_module, "schur_by_pardiso", lambda backend: False)
    by_solves = piece.condensed(loads, PIECE_REACH * task.fmax)
    assert np.array_equal(by_schur[0], by_solves[0])
    S, Mh, _, _, C = by_solves[1]
    assert min(np.abs(S).max(), np.abs(Mh).max(), np.abs(C).max()) > 0
    for got, want in zip(by_schur[1], by_solves[1]):
        assert got.shape == want.shape
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()


@pytest.mark.parametrize("pieces", [2, 3])
def test_the_cut_leaves_no_piece_meeting_another(pieces):
    """Each piece's interior meets the cut alone (K, M and the interface's springs), the
    pieces are of about one size, and the cut is a small share of the part."""
    _, task, K, M = disc_tasks(pieces, matrices=True)
    of = task.piece_of
    assert set(np.unique(of)) == set(range(pieces)) | {CUT}
    coupling = sp.coo_matrix(abs(K) + abs(M) + abs(task.interface.support))
    a, b = of[coupling.row], of[coupling.col]
    assert not np.any((a >= 0) & (b >= 0) & (a != b))
    sizes = np.bincount(of[of >= 0])
    assert sizes.min() >= 0.8 * sizes.max()
    assert np.sum(of == CUT) < 0.2 * len(of)


@pytest.mark.parametrize("pieces", [2, 3])
def test_a_part_in_pieces_has_the_whole_parts_modes(pieces):
    """The disc in pieces: its modes in the band (the part's reach over PART_REACH) within
    1e-5 of the disc reduced whole (with the cut's characteristic constraint modes for its
    shapes, the condensation's alone, they miss by 2e-4 to 2e-3), as many to its reach; its basis
    M-orthonormal, Kr its stiffness."""
    whole, task, K, M = disc_tasks(pieces, matrices=True)
    a, b = whole.run(), task.run()
    band = a.mode_hz <= task.fmax / 1.5
    assert band.sum() >= 20 and len(b.mode_hz) == len(a.mode_hz)
    np.testing.assert_allclose(b.mode_hz[band], a.mode_hz[band], rtol=1e-5)
    np.testing.assert_allclose(b.T.T @ (M @ b.T), np.eye(b.T.shape[1]), atol=1e-9)
    np.testing.assert_allclose(b.Kr, b.T.T @ (K @ b.T), rtol=1e-9,
                               atol=1e-9 * np.abs(b.Kr).max())


@pytest.mark.parametrize("pieces", [2, 3])
def test_a_part_in_pieces_spans_its_static_responses(pieces):
    """The tap moved onto the disc, and a band low enough that the traces of its modes do
    not span the cut: the disc's static responses to its loads lie in its basis to
    round-off, through the cut's relaxations (without them, 7e-3 of the response is
    outside)."""
    _, task, K0, M = disc_tasks(pieces, ["solver.reduction.fmax=2000.0",
                                         'loads.tap.part="disc"',
                                         "loads.tap.point=[0.0,-0.12,0.0]"], matrices=True)
    b = task.run()
    K = shifted(K0, M, shift_sigma(-task.shift_hz))
    u = sp.linalg.spsolve(sp.csc_matrix(K), task.loads)
    u = u.reshape(len(u), -1)
    left = u - b.T @ (b.T.T @ (M @ u))
    norms = [np.sqrt(x @ (M @ x)) for x in u.T]
    assert max(norms) > 0
    for j, m in enumerate(norms):
        assert np.sqrt(left[:, j] @ (M @ left[:, j])) <= 1e-10 * m


def test_pieces_are_refused_off_the_components_path():
    with pytest.raises(CaseError, match="components") as refused:
        load(PAD, PAD_DISC + ["parts.disc.pieces=2", 'solver.reduction.method="assembled"'])
    assert refused.value.key == "parts.disc.pieces"


@pytest.mark.slow
def test_pad_disc_with_its_disc_in_pieces_matches_the_disc_whole():
    """The coupled, contact-linearized modes below fmax of the small pad_disc at mu 0.4 with
    its disc in 2 and 3 pieces: within 1e-5 of the disc reduced whole."""
    fmax = load(PAD).solver.reduction.fmax

    def frequencies(pieces):
        case = load(PAD, PAD_DISC + COMPONENTS + [f"parts.disc.pieces={pieces}"])
        setup = prepare(case, analysis=True, unsampled=True)
        f = np.sqrt(setup.system.omega2) / (2 * np.pi)
        return f[f <= fmax]
    whole = frequencies(1)
    assert len(whole) >= 20
    for pieces in (2, 3):
        np.testing.assert_allclose(frequencies(pieces), whole, rtol=1e-5)


@pytest.mark.slow
def test_pieces_on_a_cluster_equal_pieces_here():
    """The pieces' stages on a LocalCluster of two one-thread workers: the part's basis, its
    Kr and modes equal those made in this process bit for bit."""
    pytest.importorskip("dask.distributed")
    from transient.cluster import client_for
    from transient.reduce.pieces import OnCluster
    _, task = disc_tasks(3)
    here = task.run()
    client, cluster = client_for(None, 2)
    try:
        there = task.run(OnCluster(client))
    finally:
        client.close()
        cluster.close()
    for name in ("T", "Kr", "mode_hz"):
        assert np.array_equal(getattr(here, name), getattr(there, name)), name


@pytest.mark.slow
def test_the_pieces_benchmark_measures_the_part_against_it_whole(tmp_path):
    """benchmarks/bench_pieces.py on the small pad_disc: a row for the disc whole and one in
    2 pieces, its band's error against the whole's, the table written."""
    import json
    import bench_pieces
    out = tmp_path / "rows.json"
    args = [PAD, "--part", "disc", "--pieces", "2", "--json", str(out),
            "--markdown", str(tmp_path / "table.md")]
    for s in PAD_DISC:
        args += ["--set", s]
    assert bench_pieces.main(args) == 0
    data = json.loads(out.read_text())
    rows = data["rows"] if isinstance(data, dict) else data
    assert [r["pieces"] for r in rows] == [1, 2]
    assert rows[0]["error"] == 0.0 and 0.0 < rows[1]["error"] < 1e-5
    assert rows[1]["cut"] > 0 and rows[1]["band_modes"] >= 20
    assert "| disc | 2 |" in (tmp_path / "table.md").read_text()


@pytest.mark.slow
def test_a_task_carrying_its_cells_is_submitted_without_dasks_warning():
    """A part's or piece's task carries its inputs on purpose (a lost worker's task reruns
    from them): cluster.submitted sends one above Dask's large-graph threshold without the
    warning a user would read as a fault, where a plain submit warns."""
    import warnings
    pytest.importorskip("dask.distributed")
    from transient.cluster import client_for, submitted
    client, cluster = client_for(None, 1)
    big = np.ones(2_000_000)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            assert submitted(client, np.sum, big, pure=False).result() == big.size
        assert not [w for w in caught if "large graph" in str(w.message)]
        with pytest.warns(UserWarning, match="large graph"):
            client.submit(np.sum, big, pure=False).result()
    finally:
        client.close()
        cluster.close()
