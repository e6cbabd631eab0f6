"""The memory estimate at load says what each process needs (case/sizes.py): in this process
the model and its largest part whole, or on a Dask cluster the client's model and synthesis
against limits.memory and each part's (or piece's) reduction against a worker's share; and
solver.reduction.method = "auto" chooses the path by it (case/auto.py). Every case here is
counted at load, never meshed, so that models far past the machine's memory are checked in
milliseconds."""
import pytest

from transient.case import sizes
from transient.case.compare import flatten
from transient.case.loading import load
from transient.case.sizes import (MODEL_BYTES_PER_ENTRY, Cluster, entries, generated_cells,
                                  part_bytes, setup_bytes, synthesis_bytes)
from transient.cli import main
from transient.errors import CaseError

from small_cases import PAD_DISC

PAD = "cases/pad_disc.toml"
COMPONENTS = ['solver.reduction.method="components"']
# pad_disc's disc twice as fine along each of its divisions: a 0.5M-dof disc, in pieces
BIG = ["parts.disc.mesh.divisions=[24,288,4]", "parts.disc.pieces=4"]
GB = 1e9


def _cells(overrides):
    """The cells of pad_disc's parts with the overrides, counted at load (unbounded)."""
    parts = load(PAD, overrides + COMPONENTS + ["limits.memory=1e6"]).parts
    return {n: [generated_cells(p.mesh)] for n, p in parts.items()}


def _needs(overrides, cluster=Cluster(remote=True)):
    """(this process's need without workers, its need on the cluster, a worker's) [B] of
    pad_disc with the overrides on the components path."""
    cells, case = _cells(overrides), load(PAD, overrides + COMPONENTS + ["limits.memory=1e6"])
    alone = sizes.memory_need(case, cells)
    on = sizes.memory_need(load(PAD, overrides + COMPONENTS + ["limits.memory=1e6"], cluster),
                           cells)
    return alone.here, on.here, on.worker


def _refusal(capsys, args, where=PAD):
    """The one line a command refused with (exit code 2), naming where (the case file)."""
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {where}: ")
    return err[0]


@pytest.fixture
def machine(monkeypatch):
    """A machine of 1 TB: the workers' share is limits.memory's, whatever this one has."""
    monkeypatch.setattr(sizes, "physical_memory", lambda: 1e12)


def test_on_workers_the_client_is_bounded_and_each_piece_by_its_share(machine, capsys):
    """The big disc in 4 pieces: a limit below this process's need with the part whole is
    refused in this process, by the disc's divisions, and admitted on a scheduler's workers,
    where the client (the model, the parts' bases, the disc's cut) fits it and each piece
    is checked against its worker's budget once reached. On an embedded cluster the workers
    share what the client leaves of limits.memory: a piece that does not fit its share is
    refused by parts.disc.pieces, in one line, exit code 2, before any mesh; one that does is
    admitted."""
    here, client, piece = _needs(BIG)
    assert client < here and piece < here
    limit = 0.5 * (client + here)
    overrides = BIG + COMPONENTS + [f"limits.memory={limit / GB}"]
    with pytest.raises(CaseError, match="limits.memory") as refused:
        load(PAD, overrides)
    assert refused.value.key == "parts.disc.mesh.divisions"
    assert "--workers" in refused.value.message
    assert load(PAD, overrides, Cluster(remote=True)).cluster.remote
    assert limit - client < 2 * piece
    line = _refusal(capsys, ["cea", PAD, "--workers", "2"]
                    + [a for o in overrides for a in ("--set", o)])
    assert ": parts.disc.pieces: " in line and "a worker's share of limits.memory" in line
    roomy = BIG + COMPONENTS + [f"limits.memory={(client + 2.01 * piece) / GB}"]
    assert load(PAD, roomy, Cluster(workers=2)).cluster.workers == 2


def test_embedded_workers_share_what_the_client_leaves_while_they_reduce(machine):
    """The client cuts a part in pieces between the workers' tasks, the workers waiting: its
    need counts the cut and the waiting workers, and the workers' budget leaves both out. A
    limit that fits the client's whole need, and the workers' peaks beside the model alone,
    not beside the cut, is admitted; a little less is refused."""
    case = load(PAD, BIG + COMPONENTS + ["limits.memory=1e6"], Cluster(workers=2))
    need = sizes.memory_need(case, _cells(BIG))
    terms = dict(need.terms)
    cut, waiting = terms["the cut of disc in 4 pieces"], terms["2 workers waiting"]
    assert cut > 0 and waiting == 2 * sizes.WORKER_IDLE
    assert need.beside == pytest.approx(need.here - cut - waiting)
    limit = 1.001 * max(need.here, need.beside + 2 * need.worker)
    assert need.here + 2 * need.worker > limit
    fits = BIG + COMPONENTS + [f"limits.memory={limit / GB}"]
    assert load(PAD, fits, Cluster(workers=2)).cluster.workers == 2
    with pytest.raises(CaseError):
        load(PAD, BIG + COMPONENTS + [f"limits.memory={0.99 * limit / GB}"],
             Cluster(workers=2))


def test_the_count_of_pieces_that_fits_is_named(machine, capsys):
    """A worker's share that more pieces would fit: the refusal names the count, which loads
    (the client's cut grows with the count, and is counted)."""
    whole = ["parts.disc.mesh.divisions=[24,288,4]"]
    _, client, piece = _needs(whole, Cluster(workers=2))
    overrides = whole + COMPONENTS + [f"limits.memory={(client + 1.5 * piece) / GB}"]
    line = _refusal(capsys, ["run", PAD, "--workers", "2"]
                    + [a for o in overrides for a in ("--set", o)])
    assert ": parts.disc.pieces: " in line and "parts.disc.pieces = " in line
    fits = int(line.split("parts.disc.pieces = ")[1].split(",")[0])
    assert fits > 1
    load(PAD, overrides + [f"parts.disc.pieces={fits}"], Cluster(workers=2))
    with pytest.raises(CaseError, match="share"):
        load(PAD, overrides + [f"parts.disc.pieces={fits - 1}"], Cluster(workers=2))


def test_the_client_past_limits_memory_is_refused_by_the_model(capsys):
    """Below the client's own need the cluster does not help: refused by the meshes' keys,
    what the client holds said."""
    _, client, _ = _needs(BIG)
    overrides = BIG + COMPONENTS + [f"limits.memory={0.9 * client / GB}"]
    line = _refusal(capsys, ["cea", PAD, "--scheduler", "tcp://127.0.0.1:1"]
                    + [a for o in overrides for a in ("--set", o)])
    assert ": parts.disc.mesh.divisions: " in line and "parts.pad.mesh.divisions" in line
    assert "the cluster's client" in line and "limits.memory" in line
    assert "the parts' bases side by side" in line and "the cut of disc in 4 pieces" in line


def test_in_this_process_a_part_in_pieces_counts_whole():
    """In one process a part in pieces takes no less than whole (its pieces' columns and the
    cut's model beside each piece's stage): the estimate counts it whole, while a worker's
    counts the piece, never above the part whole, below it on a large part (a worker's own
    floor beside a small one's)."""
    cells = _cells([])
    alone = sizes.memory_need(load(PAD, COMPONENTS), cells)
    cut = sizes.memory_need(load(PAD, COMPONENTS + ["parts.disc.pieces=4"]), cells)
    assert cut.here == alone.here and cut.part == "disc"
    assert cut.here == (MODEL_BYTES_PER_ENTRY * entries(sum(cells.values(), []))
                        + part_bytes(cells["disc"]))
    on = sizes.memory_need(load(PAD, COMPONENTS + ["parts.disc.pieces=4"],
                                Cluster(workers=2)), cells)
    assert on.worker_part == "disc" and on.worker == part_bytes(cells["disc"], 4)
    assert on.worker <= part_bytes(cells["disc"])
    big = _cells(BIG)["disc"]
    assert part_bytes(big, 4) < part_bytes(big, 2) < part_bytes(big)


def test_the_synthesis_is_each_part_dofs_by_its_columns():
    """The client's bases: each part's dofs (read, or from its entries) times its columns,
    which grow with the basis' cutoff, at most its dofs; a part in pieces adds its cut, which
    grows faster than its count."""
    cells = {"a": [(10, 8)], "b": [(1000, 10)]}
    small = entries(cells["a"]) / sizes.ENTRIES_PER_DOF
    at = sizes.COLUMNS_CUTOFF
    assert synthesis_bytes(cells, at, {"b": 30000}) == pytest.approx(
        8 * small * min(small, sizes.PART_COLUMNS) + 8 * 30000 * sizes.PART_COLUMNS)
    assert synthesis_bytes(cells, 2 * at, {"b": 30000}) == pytest.approx(
        8 * small * min(small, 2 * sizes.PART_COLUMNS) + 8 * 30000 * 2 * sizes.PART_COLUMNS)
    assert sizes.cut_bytes(30000, 1) == 0 < sizes.cut_bytes(30000, 2)
    assert sizes.cut_bytes(30000, 8) > 4 * sizes.cut_bytes(30000, 4)


def test_the_assembled_estimate_is_unchanged_by_workers():
    cells = _cells([])
    for cluster in (Cluster(), Cluster(workers=2), Cluster(remote=True)):
        need = sizes.memory_need(load(PAD, [], cluster), cells)
        assert need.here == setup_bytes(sum(cells.values(), [])) and need.worker is None


def test_auto_chooses_assembled_where_it_fits_and_components_where_it_does_not():
    """auto: the assembled path where its setup's estimate fits limits.memory, the case's
    specs then those of the assembled case itself; else the components path, where the
    model and its largest part fit; the choice and why kept beside the specs. pad_disc with
    a pad as large as half its disc: one part holding most of a model saves little."""
    auto = ['solver.reduction.method="auto"', "parts.pad.mesh.divisions=[15,36,3,2]"]
    case = load(PAD, auto)
    assert case.solver.reduction.method == "assembled"
    assembled = load(PAD, auto[1:] + ['solver.reduction.method="assembled"'])
    assert flatten(case) == flatten(assembled)
    assert case.reduction_auto.startswith('solver.reduction.method = "auto" chose assembled')
    cells = _cells(auto[1:])
    whole = setup_bytes(sum(cells.values(), []))
    components, _, _ = _needs(auto[1:])
    assert components < whole
    between = [f"limits.memory={0.5 * (components + whole) / GB}"]
    case = load(PAD, auto + between)
    assert case.solver.reduction.method == "components"
    assert "more than limits.memory" in case.reduction_auto
    with pytest.raises(CaseError, match="limits.memory") as refused:
        load(PAD, auto + [f"limits.memory={0.9 * components / GB}"])
    assert refused.value.key == "parts.disc.mesh.divisions"
    assert 'solver.reduction.method = "auto" chose components' in refused.value.message


def test_auto_takes_components_where_a_part_is_in_pieces():
    """Pieces are read by the components path alone: a case that cuts a part asks for it,
    small as it is (assembled would leave the key unread)."""
    case = load(PAD, PAD_DISC + ['solver.reduction.method="auto"', "parts.disc.pieces=2"])
    assert case.solver.reduction.method == "components"
    assert "parts.disc.pieces = 2" in case.reduction_auto
    with pytest.raises(CaseError, match="components") as refused:
        load(PAD, PAD_DISC + ['solver.reduction.method="auto"', "parts.disc.pieces=2",
                              "solver.reduction.enabled=false"])
    assert refused.value.key == "parts.disc.pieces"


def test_auto_where_components_would_be_refused(capsys):
    """A basis at another friction (basis_mu) is the assembled path's alone: admitted where
    auto chooses it, refused by the key where auto must take the components path, in one
    line before any mesh."""
    rebased = ['solver.reduction.method="auto"', "contact.pad_disc.friction.mu=0.4",
               "contact.pad_disc.friction.basis_mu=0.3"]
    assert load(PAD, rebased).solver.reduction.method == "assembled"
    line = _refusal(capsys, ["cea", PAD] + [a for o in rebased + ["parts.disc.pieces=2"]
                                            for a in ("--set", o)])
    assert ": contact.pad_disc.friction.basis_mu: " in line and "auto" in line
    with pytest.raises(CaseError, match="basis_mu"):
        load(PAD, COMPONENTS + rebased[1:])


def test_auto_on_mesh_files_counts_their_cells(tmp_path):
    """A mesh file's cells are read at load when auto needs them: a file that is not there
    is refused by its key before anything else is built."""
    corner = load("cases/brake_corner.toml", ['solver.reduction.method="auto"'])
    assert corner.solver.reduction.method == "assembled"
    text = open("cases/brake_corner.toml").read().replace('"brake_corner/disc.msh"',
                                                          '"nowhere/disc.msh"')
    path = tmp_path / "corner.toml"
    path.write_text(text)
    with pytest.raises(CaseError) as refused:
        load(path, ['solver.reduction.method="auto"'])
    assert refused.value.key == "parts.disc.mesh.path"
    # the full model has no path to choose: its files are not read at load
    assert load(path, ['solver.reduction.method="auto"', "solver.reduction.enabled=false"])


def test_auto_is_the_default_and_every_shipped_case_takes_the_assembled_path():
    """The default chooses the assembled path on every shipped case (their histories are
    those of the assembled path, bit for bit), and says why."""
    from pathlib import Path
    for path in sorted(Path("cases").glob("*.toml")):
        case = load(path)
        if case.solver.reduction.enabled:
            assert case.solver.reduction.method == "assembled", path
            assert "chose assembled" in case.reduction_auto, path


@pytest.mark.slow
def test_a_setup_keeps_why_auto_chose():
    """The reduced setup's attributes (a history's, the cea's model line) say what auto chose
    and why."""
    from transient.stages import prepare
    setup = prepare(load(PAD, PAD_DISC), analysis=True)
    assert setup.meta["reduction_method"] == "assembled"
    assert setup.meta["reduction_auto"].startswith('solver.reduction.method = "auto" chose')


def test_a_history_keeps_the_method_auto_chose(tmp_path):
    """The case a history keeps is rebuilt with the method auto chose for its run, not
    chosen again: its mesh files need not be there any more."""
    from transient.io.attributes import CASE_TEXT
    from transient.io.stored import run_case
    meta = {CASE_TEXT: open("cases/brake_corner.toml").read(),
            "case_path": str(tmp_path / "gone" / "corner.toml"), "overrides": [],
            "reduction_method": "components",
            "reduction_auto": 'solver.reduction.method = "auto" chose components: ...'}
    case = run_case(tmp_path / "run.h5", meta)
    assert case.solver.reduction.method == "components" and not case.reduction_auto
    with pytest.raises(CaseError, match="does not load"):
        run_case(tmp_path / "run.h5", {k: v for k, v in meta.items()
                                       if k != "reduction_auto"})


def test_the_parts_options_unused_where_auto_takes_the_assembled_path(capsys):
    """--workers given to a case whose "auto" takes the assembled path: said unused on
    standard error, and the dry run goes on; refused, in one line, where the case names the
    assembled path itself."""
    args = ["cea", PAD, "--dry-run", "--workers", "2"] + [a for o in PAD_DISC
                                                         for a in ("--set", o)]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert err.startswith("--workers: not used: solver.reduction.method = \"auto\" chose "
                          "assembled")
    assert 'solver.reduction.method = "auto" chose assembled' in out
    line = _refusal(capsys, args + ["--set", 'solver.reduction.method="assembled"'],
                    "command line")
    assert line.startswith("error: command line: --workers: ")


def test_the_parts_bases_are_counted_on_disk_here_and_in_memory_from_a_scheduler(
        machine, monkeypatch, capsys):
    """The parts' bases go to files of the temporary directory on this machine (in this
    process and on its embedded cluster: reduce.store), so the client's memory leaves them
    out and the disk counts them; a scheduler's workers hand them back whole, in memory. A
    disk too small is refused in one line naming TMPDIR, before any mesh."""
    cells = _cells(BIG)
    bases = synthesis_bytes(cells, load(PAD, BIG + COMPONENTS).solver.reduction.modes_fmax)
    for cluster in (Cluster(), Cluster(workers=2)):
        need = sizes.memory_need(load(PAD, BIG + COMPONENTS + ["limits.memory=1e6"], cluster),
                                 cells)
        assert need.disk == bases
        assert all("bases" not in what for what, _ in need.terms)
    remote = sizes.memory_need(load(PAD, BIG + COMPONENTS + ["limits.memory=1e6"],
                                    Cluster(remote=True)), cells)
    assert remote.disk == 0 and ("the parts' bases side by side", bases) in remote.terms
    monkeypatch.setattr(sizes.shutil, "disk_usage",
                        lambda path: type("Usage", (), {"free": 0.5 * bases})())
    line = _refusal(capsys, ["cea", PAD] + [a for o in BIG + COMPONENTS + ["limits.memory=1e6"]
                                          for a in ("--set", o)])
    assert "TMPDIR" in line and "the parts' bases" in line
    load(PAD, BIG + COMPONENTS + ["limits.memory=1e6"], Cluster(remote=True))
