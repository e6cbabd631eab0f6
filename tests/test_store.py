"""The components path's parts' bases kept in files mapped into memory (reduce/store.py): the
same numbers as in memory, nothing left on disk."""
import numpy as np
import pytest

from transient.case.loading import load
from transient.reduce.engine import Engine
from transient.reduce.parts import PartTask
from transient.reduce.store import Store
from transient.stages import prepare

from small_cases import PAD_DISC

PAD = "cases/pad_disc.toml"
COMPONENTS = ['solver.reduction.method="components"']


def _mapped(T):
    """Whether T's memory is a file's mapping."""
    while T is not None:
        if isinstance(T, np.memmap):
            return True
        T = T.base if isinstance(T, np.ndarray) else None
    return False


def _setup(overrides, store):
    setup = prepare(load(PAD, PAD_DISC + COMPONENTS + overrides), analysis=True,
                    parts=Engine(store=store))
    X, AW = setup.basis
    return [T for _, T in X.parts], X @ AW, setup.system.omega2


@pytest.mark.parametrize("pieces", [1, 2])
def test_bases_in_files_give_the_numbers_of_bases_in_memory(tmp_path, pieces):
    """Each part's basis (the disc whole, and in 2 pieces filled a piece's rows at a time)
    mapped from a file: the parts' bases, the reduced basis on the model's dofs and the
    reduced frequencies bit for bit those held in memory; the files are unlinked once
    mapped and the folder removed at close."""
    extra = [f"parts.disc.pieces={pieces}"] if pieces > 1 else []
    store = Store(tmp_path / "store")
    store.folder.mkdir()
    mapped = _setup(extra, store)
    assert list(store.folder.iterdir()) == []
    store.close()
    assert not store.folder.exists()
    held = _setup(extra, Store())
    assert all(_mapped(T) for T in mapped[0]) and not any(_mapped(T) for T in held[0])
    for a, b in zip(mapped[0], held[0]):
        assert np.array_equal(a, b)
    assert np.array_equal(mapped[1], held[1])
    assert np.array_equal(mapped[2], held[2])


def test_the_api_leaves_no_file_of_its_store(tmp_path, monkeypatch):
    """transient.prepare on the components path makes its store under the temporary
    directory and leaves nothing there, its basis still readable afterwards (the mapping
    keeps the unlinked files)."""
    import tempfile
    from transient import api
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    setup = api.prepare(api.load(PAD, PAD_DISC + COMPONENTS))
    X, AW = setup.basis
    assert all(_mapped(T) for _, T in X.parts)
    assert list(tmp_path.iterdir()) == []
    assert np.isfinite((X @ AW).sum())


@pytest.mark.parametrize("folder", [True, False])
def test_a_fresh_part_is_written_once_into_the_cache(tmp_path, monkeypatch, folder):
    """Through --cache a part reduced fresh goes from the store to the cache's file (renamed,
    or written there by a store in memory): its basis saved once, not to the store and again
    to the cache; the store left empty, the cache read back as the same numbers."""
    saves, digests = [], []
    save = np.save
    monkeypatch.setattr(np, "save", lambda file, a, *args, **kwargs: (
        saves.append(np.shape(a)), save(file, a, *args, **kwargs))[1])
    # a task's key, asked by the cache's lookup, its file names and its writing, hashed once
    digest = PartTask._digest
    monkeypatch.setattr(PartTask, "_digest", lambda task: (digests.append(task.name),
                                                           digest(task))[1])
    store = Store(tmp_path / "store") if folder else Store()
    if folder:
        store.folder.mkdir()
    case = load(PAD, PAD_DISC + COMPONENTS)
    fresh = prepare(case, analysis=True, parts=Engine(cache=tmp_path / "cache", store=store))
    shapes = [T.shape for _, T in fresh.basis[0].parts]
    assert sorted(saves) == sorted(shapes)
    assert sorted(digests) == ["disc", "pad"]
    assert folder is False or list(store.folder.iterdir()) == []
    bases = sorted((tmp_path / "cache").glob("part-*.T.npy"))
    assert len(bases) == 2 and sorted(np.load(b).shape for b in bases) == sorted(shapes)
    again = prepare(case, analysis=True, parts=Engine(cache=tmp_path / "cache", store=store))
    assert len(saves) == 2
    for (_, a), (_, b) in zip(fresh.basis[0].parts, again.basis[0].parts):
        assert np.array_equal(a, b)


def test_a_store_without_a_folder_keeps_arrays_as_they_are():
    """Store() (a cluster whose workers do not share this disk): bases stay in memory."""
    T = np.arange(6.0).reshape(3, 2)
    store = Store()
    assert store.kept("p", T) is T
    assert isinstance(store.empty("p", (2, 2)), np.ndarray)
    store.close()


@pytest.mark.slow
def test_a_workers_basis_is_mapped_by_the_client_from_the_file_it_wrote(tmp_path):
    """On a LocalCluster of two workers the pad's task writes its basis to the store and this
    process maps it, the disc's 2 pieces keep their columns in files between stages: the
    numbers those of the same cluster holding everything in memory, bit for bit (one-thread
    workers), no file left."""
    pytest.importorskip("dask.distributed")
    from transient.cluster import client_for
    client, cluster = client_for(None, 2)
    try:
        store = Store(tmp_path / "store")
        store.folder.mkdir()
        runs = []
        for where in (store, Store()):
            setup = prepare(load(PAD, PAD_DISC + COMPONENTS + ["parts.disc.pieces=2"]),
                            analysis=True, parts=Engine(client, store=where))
            X, AW = setup.basis
            runs.append(([T for _, T in X.parts], X @ AW, setup.system.omega2))
        assert list(store.folder.iterdir()) == []
    finally:
        client.close()
        cluster.close()
    (mapped, X1, w1), (held, X2, w2) = runs
    assert all(_mapped(T) for T in mapped) and not any(_mapped(T) for T in held)
    assert all(np.array_equal(a, b) for a, b in zip(mapped, held))
    assert np.array_equal(X1, X2) and np.array_equal(w1, w2)
