"""The components path of the reduction (solver.reduction.method = "components", reduce/
components.py): each part reduced on its own and coupled through its contact rows. Bars tied
end to end against one bar of their whole length, a floating bar between two clamped ones, and
pad_disc's reduced modes and preload against the assembled path's."""
import numpy as np
import pytest
import scipy.sparse as sp

from transient.case.loading import load
from transient.errors import CaseError
from transient.model import build_model
from transient.solve.modes import normal_modes
from transient.stages import prepare

from small_cases import PAD_DISC

PAD = "cases/pad_disc.toml"
FMAX = 60000.0
LENGTH, DIVISIONS = 0.1, 20


def bars(tmp_path, count, method="components", right=False, whole=1):
    """count steel bars of LENGTH end to end along x, moving along x only (a rod), the first
    clamped at its left end and, with right, the last at its right end; each joint a
    bilateral pair on the fine rule, stiff against the bars' own stiffness. count = 1 and
    bars = n: one bar of n lengths, the reference."""
    length, divisions = whole * LENGTH, whole * DIVISIONS
    names = ["bar"] if count == 1 else [f"bar{i}" for i in range(count)]
    text = ['[materials.steel]\nE = 2.1e11\nnu = 0.0\nrho = 7800.0\n']
    for i, name in enumerate(names):
        text.append(f'[parts.{name}]\nmaterial = "steel"\n[parts.{name}.mesh]\nkind = "box"\n'
                    f"size = [{length}, 0.01, 0.01]\norigin = [{i * LENGTH}, 0.0, 0.0]\n"
                    f'divisions = [{divisions}, 1, 1]\nelement = "hex8"\n'
                    f'[parts.{name}.sets.all]\nkind = "box"\nmin = [-1.0, -1.0, -1.0]\n'
                    "max = [1.0, 1.0, 1.0]\n"
                    f'[constraints.rod_{name}]\nset = "{name}.all"\ndofs = ["y", "z"]\n')
    text.append(f'[constraints.left]\nset = "{names[0]}.xmin"\ndofs = ["x"]\n')
    if right:
        text.append(f'[constraints.right]\nset = "{names[-1]}.xmax"\ndofs = ["x"]\n')
    for a, b in zip(names, names[1:]):
        text.append(f'[contact.{a}_{b}]\nsurface1 = "{a}.xmax"\nsurface2 = "{b}.xmin"\n'
                    'k = 1.0e19\nrule = "fine"\nlaw.kind = "bilateral"\n')
    text.append(f"[solver]\nt_end = 1.0e-4\n[solver.reduction]\nenabled = true\n"
                f'fmax = {FMAX}\nmethod = "{method}"\n')
    path = tmp_path / f"bars{count}_{whole}_{method}_{right}.toml"
    path.write_text("\n".join(text))
    return load(path)


def rod_frequencies(case):
    """The rod's frequencies below FMAX [Hz] from the whole model (normal_modes, dense)."""
    model = build_model(case)
    modes = normal_modes(model.K, model.M, model.fixed, fmax=FMAX)
    return modes.frequencies


@pytest.mark.parametrize("count", [2, 3])
def test_bars_tied_end_to_end_are_one_bar_of_their_length(tmp_path, count):
    """Tied through the components path, the bars vibrate as one rod of their whole length
    (the same elements: only the joint's penalty, 1e19 Pa/m against the elements' E / h of
    4e13, differs). With three, the middle bar is held by its two joints alone: its rigid
    motion is in its basis. The synthesis is exact as the parts' modes reach further: every
    frequency below fmax within 1e-6 with them to 5 fmax; within 0.1% (issue 45's accuracy)
    at the default cutoff, 2 fmax."""
    right = count == 3
    reference = rod_frequencies(bars(tmp_path, 1, right=right, whole=count))
    assert len(reference) >= 5, reference
    for cutoff, rtol in ((5 * FMAX, 1e-6), (0.0, 1e-3)):
        case = load(bars(tmp_path, count, right=right).path,
                    [f"solver.reduction.cutoff={cutoff}"])
        setup = prepare(case, analysis=True)
        reduced = np.sqrt(setup.system.omega2) / (2 * np.pi)
        np.testing.assert_allclose(reduced[:len(reference)], reference, rtol=rtol)
        assert reduced[len(reference)] > FMAX
    parts = setup.meta["basis_timings"]["part_seconds"]
    assert sorted(parts) == [f"bar{i}" for i in range(count)]


def test_one_part_without_contact_or_load_is_its_own_modes(tmp_path):
    """No pair and no load: the part's basis is its modes alone, and the coupling has no
    static direction to add (it once failed on the empty set)."""
    case = bars(tmp_path, 1)
    reference = rod_frequencies(case)
    setup = prepare(case, analysis=True)
    reduced = np.sqrt(setup.system.omega2) / (2 * np.pi)
    np.testing.assert_allclose(reduced[:len(reference)], reference, rtol=1e-9)


@pytest.mark.slow
def test_pad_disc_preload_and_modes_match_the_assembled_path():
    """The small pad and disc (a sampled rule, the pad held by its abutments and the contact):
    the preload solved in the coupled reduced coordinates carries the assembled preload's
    contact force and displacement, and the reduced frequencies below fmax match the
    assembled basis' within 0.1%, without a factorization of the whole model."""
    cases = {m: load(PAD, PAD_DISC + [f'solver.reduction.method="{m}"'])
             for m in ("assembled", "components")}
    setups = {m: prepare(case, analysis=True, unsampled=m == "components")
              for m, case in cases.items()}
    a, c = setups["assembled"], setups["components"]
    assert "factorization" in a.stages and "factorization" not in c.stages
    assert c.meta["preload_residual"] < 1e-9
    force = a.meta["preload_contact_force"]["pad_disc"]
    assert c.meta["preload_contact_force"]["pad_disc"] == pytest.approx(force, rel=1e-3)
    fmax = load(PAD).solver.reduction.fmax
    fa, fc = (np.sqrt(s.system.omega2) / (2 * np.pi) for s in (a, c))
    n = int(np.sum(fa <= fmax))
    assert n >= 20 and int(np.sum(fc <= fmax)) == n
    np.testing.assert_allclose(fc[:n], fa[:n], rtol=1e-3)
    ua, uc = (s.basis[0] @ (s.basis[1] @ s.state.q) for s in (a, c))
    assert np.linalg.norm(uc - ua) <= 1e-3 * np.linalg.norm(ua)
    # the band's modes in the whole model: the assembled basis holds the structure's own
    # (to the Lanczos' tolerance); the parts' modes and interface shapes approximate them.
    # Measured as the displacement their residual makes, K_lin^-1 (K_lin x - omega^2 M x)
    # against x in the mass norm (the whole model's solve, which the components path has
    # not): its force residual in M^-1's norm is the contact pressure's detail, large on a
    # pad riding its contact springs whatever the motion's error
    assert a.meta["band_residual"] < 1e-4
    assert 0.0 <= c.meta["band_residual"] < 1.0
    assert _shape_error(cases["components"], c, fmax) < 2e-3
    assert c.meta["reduction_method"] == "components"
    # each part's interface statics: what the flexibility criterion dropped is below its
    # tolerance, and the contact's directions on the part are not all kept
    tol = load(PAD).solver.reduction.statics_tolerance
    interfaces = c.meta["basis_timings"]["part_interfaces"]
    assert sorted(interfaces) == ["disc", "pad"]
    for i in interfaces.values():
        assert 0 < i["kept"] <= i["fields"] <= i["loads"] and 0.0 <= i["statics_error"] < tol


def _shape_error(case, setup, fmax):
    """The largest over the band's reduced modes x = T a of |K_lin^-1 r|_M / |x|_M, r =
    K_lin x - omega^2 M x on the whole model's free dofs, K_lin with the contact's tangent at
    the preload: on the rule's candidates (the unsampled model, on which the basis is made;
    setup: prepare's of the case with unsampled=True)."""
    import scipy.sparse.linalg as spl
    from transient.reduce.stage import reduction_mass
    red = setup.unsampled or setup
    model, system = red.model, red.system
    band = np.flatnonzero(system.omega2 <= (2 * np.pi * fmax) ** 2)
    x = red.basis[0] @ red.basis[1][:, band]
    contacts = system.contacts
    C = contacts.C
    free = ~model.fixed
    K = (model.K + C.T @ sp.diags(contacts.weights * system.tangent) @ C).tocsc()
    K = K[free][:, free]
    M = reduction_mass(case, model, None)[0].tocsc()[free][:, free]
    xf = x[free]
    y = spl.splu(K).solve(K @ xf - (M @ xf) * system.omega2[band])
    return float(np.max(np.sqrt(np.einsum("ij,ij->j", y, M @ y)
                                / np.einsum("ij,ij->j", xf, M @ xf))))


def test_a_basis_at_another_friction_is_refused_with_components():
    """The part bases do not depend on the friction: contact.<pair>.friction.basis_mu, which
    shares a basis across a friction sweep, has nothing to share there, and is refused at
    load, before the model is built."""
    with pytest.raises(CaseError, match="basis_mu") as refused:
        load(PAD, PAD_DISC + ['solver.reduction.method="components"',
                              "contact.pad_disc.friction.mu=0.4",
                              "contact.pad_disc.friction.basis_mu=0.3"])
    assert refused.value.key == "contact.pad_disc.friction.basis_mu"


def _reduced(case, engine):
    setup = prepare(case, analysis=True, parts=engine)
    return setup.basis[0] @ setup.basis[1], setup.system.omega2


@pytest.mark.slow
def test_a_cached_part_is_read_back_and_only_a_changed_part_is_reduced_again(tmp_path):
    """Through a cache folder each part's reduction is kept under the key of what it is made
    from: the same case again reads both parts back, bit for bit; a stiffer pad reduces the
    pad again and reads the disc (counted by the engine's done)."""
    from transient.reduce.engine import Engine
    made = []
    engine = Engine(cache=tmp_path / "parts", done=lambda task, part: made.append(
        (task.name, "cache" in part.seconds)))
    overrides = PAD_DISC + ['solver.reduction.method="components"']
    T0, w0 = _reduced(load(PAD, overrides), engine)
    assert sorted(made) == [("disc", False), ("pad", False)]
    made.clear()
    T1, w1 = _reduced(load(PAD, overrides), engine)
    assert sorted(made) == [("disc", True), ("pad", True)]
    assert np.array_equal(T0, T1) and np.array_equal(w0, w1)
    made.clear()
    _reduced(load(PAD, overrides + ["materials.lining.E=4.0e9"]), engine)
    assert sorted(made) == [("disc", True), ("pad", False)]
    assert len(list((tmp_path / "parts").glob("part-*.npz"))) == 3
    assert not list((tmp_path / "parts").glob(".*"))


def test_a_part_larger_than_a_worker_is_refused_naming_its_key(monkeypatch):
    """The cluster's smallest worker bounds each part's reduction (estimated from its cells):
    a part above it is refused before any is reduced, by the key that sizes it (a piece's
    floor taken as a whole part's, its share of the part whole and no dense term: a worker's
    own floor would leave no count of pieces of this small disc below the disc whole, and a
    smaller share no piece of it above the pad whole)."""
    from transient.case import sizes
    from transient.reduce.components import check_parts
    monkeypatch.setattr(sizes, "PIECE_FLOOR", sizes.PART_BYTES_FLOOR)
    monkeypatch.setattr(sizes, "PIECE_SHARE", 1.0)
    monkeypatch.setattr(sizes, "PIECE_DENSE", 0.0)
    case = load(PAD, PAD_DISC + ['solver.reduction.method="components"'])
    model = build_model(case)
    check_parts(case, model, None)
    check_parts(case, model, 1e12)
    with pytest.raises(CaseError, match="worker's memory") as refused:
        check_parts(case, model, 1e6)
    assert refused.value.key in ("parts.disc.pieces", "parts.pad.pieces")
    # a worker that a piece of the disc would fit: the count that does is named
    from transient.case.sizes import cells_by_part, part_bytes
    cells = cells_by_part(model.parts)["disc"]
    budget = 0.5 * (part_bytes(cells, 2) + part_bytes(cells, 3))
    assert part_bytes(cells_by_part(model.parts)["pad"]) <= budget
    with pytest.raises(CaseError, match="parts.disc.pieces = 3") as refused:
        check_parts(case, model, budget)
    assert refused.value.key == "parts.disc.pieces"
    check_parts(load(PAD, PAD_DISC + ['solver.reduction.method="components"',
                                      "parts.disc.pieces=3"]), model, budget)


def test_the_memory_bound_takes_the_model_and_its_largest_part():
    """limits.memory against the components path's need, the model whole and one part's
    reduction at a time: a bound between that and the assembled setup's refuses the assembled
    case at load, by the meshes' keys, and lets the components one in. pad_disc with a pad as
    large as its disc (counted at load, never meshed): a part's fixed floor outweighs the
    saving on a model of a few megabytes, and one part holding most of it saves little."""
    from transient.case.sizes import MODEL_BYTES_PER_ENTRY, entries, generated_cells, \
        part_bytes, setup_bytes
    halves = ["parts.pad.mesh.divisions=[15,36,3,2]"]
    cells = {n: [generated_cells(p.mesh)] for n, p in load(PAD, halves).parts.items()}
    assert 0.4 < entries(cells["pad"]) / entries(cells["disc"]) < 1.0
    assembled = setup_bytes(sum(cells.values(), []))
    parts = (MODEL_BYTES_PER_ENTRY * entries(sum(cells.values(), []))
             + max(part_bytes(c) for c in cells.values()))
    assert parts < 0.8 * assembled
    bound = [f"limits.memory={0.5 * (parts + assembled) / 1e9}"]
    with pytest.raises(CaseError, match="limits.memory") as refused:
        load(PAD, halves + bound + ['solver.reduction.method="assembled"'])
    assert refused.value.key.endswith(".mesh.divisions")
    load(PAD, halves + bound + ['solver.reduction.method="components"',
                                "solver.reduction.enabled=true"])


class _CrashOnce:
    """A part's task whose first attempt kills its worker process (a node lost mid-task):
    the marker file says it ran once."""

    def __init__(self, task, marker):
        self.task, self.marker, self.name = task, str(marker), task.name

    def key(self):
        return self.task.key()

    def run(self):
        import os
        if not os.path.exists(self.marker):
            open(self.marker, "w").close()
            os._exit(1)
        return self.task.run()


@pytest.mark.slow
def test_parts_on_a_cluster_equal_parts_here_and_a_killed_worker_is_made_up(tmp_path):
    """One task a part on a LocalCluster of two one-thread workers: the same basis as in this
    process (to round-off: other BLAS threads), each part reported as it finishes. The
    scheduler runs a dead worker's part again on another: the basis then equals the one of
    the cluster that lost none, bit for bit (one-thread workers, the same arithmetic)."""
    pytest.importorskip("dask.distributed")
    import sys
    import cloudpickle
    from transient.reduce.engine import Engine, on_cluster
    from transient.reduce.components import components_basis
    from transient.cluster import client_for
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    case = load(PAD, PAD_DISC + ['solver.reduction.method="components"'])
    model = build_model(case)
    from transient.contact.pair import build_contact
    from transient.contact.contactset import stack
    from transient.model import constant_load

    class Crashing:
        def __init__(self, client, crash):
            self.client, self.crash, self.done, self.cache = client, crash, None, None
            self.stage = None

        def budget(self):
            return None

        def run(self, tasks):
            if self.crash:
                tasks = [_CrashOnce(t, tmp_path / f"ran-{t.name}") if t.name == "disc" else t
                         for t in tasks]
            return on_cluster(self.client)(tasks)

    here = _reduced(case, None)
    client, cluster = client_for(None, 2)
    try:
        made = []
        there = _reduced(case, Engine(client, done=lambda task, part: made.append(task.name)))
        assert sorted(made) == ["disc", "pad"]
        np.testing.assert_allclose(there[1], here[1], rtol=1e-9)
        np.testing.assert_allclose(np.abs(there[0]), np.abs(here[0]),
                                   atol=1e-9 * np.abs(here[0]).max())
        bases = []
        for crash in (False, True):
            pairs = build_contact(case, model)
            basis, _ = components_basis(case, model, model.M, pairs,
                                        stack(pairs, model.ndof), [], constant_load(case, model),
                                        Crashing(client, crash))
            bases.append(basis)
    finally:
        client.close()
        cluster.close()
    assert (tmp_path / "ran-disc").exists()
    assert np.array_equal(bases[0].X.toarray(), bases[1].X.toarray())
    assert np.array_equal(bases[0].omega2, bases[1].omega2)


@pytest.mark.slow
def test_the_commands_reduce_the_parts_through_a_cache_and_refuse_it_when_assembled(
        tmp_path, capsys):
    """`transient cea --cache DIR`: a line a part as it is reduced, then as it is read back;
    the model line says the parts were reduced on their own. The options of the parts asked
    of an assembled case: one line naming the option, exit 2."""
    from transient.cli import main
    args = ["cea", PAD, "--cache", str(tmp_path / "parts"), "--set",
            'solver.reduction.method="components"', "--set", "contact.pad_disc.friction.mu=0.4"]
    args += [a for o in PAD_DISC for a in ("--set", o)]
    assert main(args) == 0
    first = capsys.readouterr()
    assert sorted(line.split(":")[0] for line in first.err.splitlines()
                  if "reduced in" in line) == ["part disc", "part pad"]
    assert "each part reduced on its own" in first.out
    assert main(args) == 0
    second = capsys.readouterr()
    assert sorted(line for line in second.err.splitlines() if line) == [
        "part disc: read back from the cache", "part pad: read back from the cache"]
    # the same modes, to the last digit printed (the stages' seconds aside)
    assert second.out.splitlines()[:-1] == first.out.splitlines()[:-1]
    assert main(["cea", PAD, "--workers", "2", "--set",
                 'solver.reduction.method="assembled"']) == 2
    refused = capsys.readouterr().err.strip().splitlines()
    assert len(refused) == 1 and "--workers" in refused[0]


@pytest.mark.slow
def test_a_lining_campaign_reduces_the_disc_once(tmp_path):
    """`transient sweep --kind cea --cache DIR` with the components path on two workers: the
    first variant's parts are reduced on the cluster before the variants fan out, so the disc
    is reduced once and every variant reads it back, each reducing its own pad at most (3
    parts kept for 2 moduli), and a variant's modes equal `transient cea`'s of the same case
    through the same cache."""
    pytest.importorskip("dask.distributed")
    import json
    from transient import api
    overrides = PAD_DISC + ['solver.reduction.method="components"',
                         "contact.pad_disc.friction.mu=0.4"]
    campaign = api.sweep(PAD, ["materials.lining.E=[4.0e9,5.0e9]"], tmp_path / "sweep",
                         kind="cea", overrides=overrides, workers=2, cache=tmp_path / "parts")
    assert [r["status"] for r in campaign.rows] == ["complete", "complete"]
    assert len(list((tmp_path / "parts").glob("part-*.npz"))) == 3
    assert [r["parts_reduced"] for r in campaign.rows] == [[], ["pad"]]
    alone = api.cea(load(PAD, overrides + ["materials.lining.E=4.0e9"]), cache=tmp_path / "parts")
    swept = json.loads((tmp_path / "sweep" / campaign.rows[0]["output"]).read_text())
    assert [m["frequency_hz"] for m in swept["modes"]] == alone.modes.frequency_hz.tolist()


def test_a_part_with_no_static_direction_keeps_its_modes():
    """A part with no load on it and no interface direction kept (a coarse statics tolerance)
    has its modes alone as basis, not an error."""
    from transient.reduce.parts import with_statics
    rng = np.random.default_rng(0)
    Phi = np.linalg.qr(rng.standard_normal((12, 3)))[0]
    X = np.asfortranarray(np.hstack([Phi, np.zeros((12, 2))]))
    T = with_statics(X, 3, sp.identity(12, format="csr"))
    assert np.array_equal(T, Phi)


@pytest.mark.parametrize("regularized", [True, False])
def test_the_coupling_rows_a_pair_at_a_time_are_the_whole_rows(regularized):
    """reduce.coupling.PairRows holds each pair's rows on its own parts' columns only, and the
    part tasks the rows' gram a pair's shapes at a time: both against the whole rows, points x
    every part's columns, formed densely (factored rows, and the fine rule's plain ones)."""
    from transient.contact.contactset import stack
    from transient.contact.pair import build_contact
    from transient.reduce.basis import contact_gram
    from transient.reduce.components import law_tangent, part_tasks
    from transient.reduce.synthesis import Synthesis
    from transient.reduce.coupling import PairRows
    case = load(PAD, PAD_DISC + ['solver.reduction.method="components"',
                              "contact.pad_disc.friction.mu=0.4",
                              f"contact.pad_disc.regularized={str(regularized).lower()}"])
    model = build_model(case)
    pairs = build_contact(case, model)
    contacts = stack(pairs, model.ndof)
    assert (contacts.factors is not None) == regularized
    rng = np.random.default_rng(1)
    dofs = [model.part_dofs(name) for name in model.parts]
    X = Synthesis(model.ndof, dofs, [rng.normal(size=(len(d), 7)) for d in dofs])
    rows = PairRows(contacts, X)
    whole = [contacts.observe(X)] + list(contacts.observe_tangential(X))
    q, y, wd = rng.normal(size=X.shape[1]), rng.normal(size=contacts.n_points), \
        rng.uniform(1.0, 2.0, contacts.n_points)
    for kind, R in enumerate(whole):
        np.testing.assert_allclose(rows.observe(q, kind), R @ q, rtol=1e-12,
                                   atol=1e-12 * np.abs(R @ q).max())
        np.testing.assert_allclose(rows.load(y, kind), R.T @ y, rtol=1e-12,
                                   atol=1e-12 * np.abs(R.T @ y).max())
    Kr = np.diag(rng.uniform(1.0, 2.0, X.shape[1]))
    Cr, Ct, _ = whole
    m = contacts.friction.m
    for sliding, left in ((False, Cr), (True, Cr + m[:, None] * Ct)):
        expected = Kr + (left.T * wd) @ Cr
        np.testing.assert_allclose(rows.stiffness(Kr, wd, sliding), expected, rtol=1e-11,
                                   atol=1e-12 * np.abs(expected).max())
    expected = contact_gram(np.vstack(whole), np.tile(wd, 3))
    np.testing.assert_allclose(rows.gram(wd), expected, rtol=1e-11,
                               atol=1e-12 * np.abs(expected).max())
    # the part tasks' gram of the rows on each part's loads E: C = Cc E^T
    constant = np.zeros(model.ndof)
    scale = np.tile(contacts.weights * law_tangent(pairs, contacts), 3)
    stacked = sp.vstack([contacts.C] + list(contacts.tangential())).tocsr()
    for (part_dofs, (name, _, interface, _), _) in part_tasks(case, model, pairs, contacts, [],
                                                           constant):
        # with C = Cc E^T the part's rows, E G E^T = C^T diag(scale) C on the part
        Cp = stacked[:, part_dofs]
        touched = np.flatnonzero(np.diff(Cp.tocsc().indptr))
        E = interface.E.toarray()[touched]
        expected = (Cp.T @ sp.diags(scale) @ Cp).toarray()[np.ix_(touched, touched)]
        np.testing.assert_allclose(E @ interface.G @ E.T, expected, rtol=1e-9,
                                   atol=1e-10 * np.abs(expected).max(), err_msg=name)


def test_the_synthesis_held_by_part_multiplies_as_its_dense_matrix():
    """reduce.synthesis.Synthesis (the parts' bases side by side, a dof in none) against the
    dense X it stands for: X Y and X^T Y on real and complex blocks and vectors, R X for sparse
    R dense on the interface (BLAS) and scattered (csr_dot) and for a dense R, a pair's
    restricted product, the congruence X^T H X, and a pickled copy (a Dask task's)."""
    import pickle
    from transient.reduce.synthesis import Synthesis
    rng = np.random.default_rng(3)
    ndof, dofs = 40, [np.arange(0, 15), np.arange(16, 28), np.arange(28, 40)]
    X = Synthesis(ndof, dofs, [rng.normal(size=(len(d), w)) for d, w in zip(dofs, (4, 3, 5))])
    Xd = X.toarray()
    assert Xd.shape == X.shape == (40, 12) and not Xd[15].any()
    Y = rng.normal(size=(12, 3)) + 1j * rng.normal(size=(12, 3))
    Z = rng.normal(size=(40, 3))
    for got, want in ((X @ Y, Xd @ Y), (X @ Y[:, 0].real, Xd @ Y[:, 0].real),
                      (X.T @ Z, Xd.T @ Z), (X.T @ Z[:, 0], Xd.T @ Z[:, 0])):
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13 * np.abs(want).max())
    dense_rows = sp.csr_matrix(rng.normal(size=(5, 40)) * (rng.random((5, 40)) < 0.8))
    scattered = sp.random(60, 40, density=0.02, random_state=4, format="csr")
    for R in (dense_rows, scattered, dense_rows.T.tocsr().T, dense_rows.toarray()):
        np.testing.assert_allclose(R @ X, R @ Xd, rtol=1e-13, atol=1e-13 * np.abs(R @ Xd).max())
    R = sp.csr_matrix(scattered.toarray() * (np.arange(40) < 15))       # the first part's
    cols, RX = X.restricted(R)
    assert cols.tolist() == [0, 1, 2, 3]
    np.testing.assert_allclose(RX, (R @ Xd)[:, cols], rtol=1e-13)
    H = sp.random(40, 40, density=0.1, random_state=5, format="csr")
    np.testing.assert_allclose(X.congruence(H), Xd.T @ (H @ Xd), rtol=1e-12,
                               atol=1e-13 * np.abs(Xd.T @ (H @ Xd)).max())
    assert np.array_equal(pickle.loads(pickle.dumps(X)).toarray(), Xd)
