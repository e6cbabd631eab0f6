"""Where the parts of the components path are reduced: in this process one after the other,
on a Dask cluster one task a part, and through a cache folder that keeps each part's
reduction under its task's key (reduce.parts.PartTask.key)."""
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..cluster import WHERE, submitted
from ..errors import CaseError
from ..files import saved, whole
from .parts import PartBasis
from .pieces import OnCluster, PiecesTask
from .store import Store

# what a part's cache file holds of its PartBasis beside T (in a file of its own, mapped
# when read back)
_FIELDS = ("Kr", "mode_hz", "n_shapes", "n_static", "interface_mu", "interface_loads")


@dataclass(frozen=True)
class Engine:
    """How the components path reduces its parts: on a Dask client (None: in this process),
    through a cache folder (None: none), done(task, PartBasis) as each part is reduced;
    stage(name, seconds, peak GB) as each stage of the setup ends (None: nothing said); and
    where the parts' bases are kept (a reduce.store.Store; None: in memory)."""
    client: object = None
    cache: object = None
    done: object = None
    stage: object = None
    store: object = None

    def budget(self):
        """The smallest worker's memory limit [B] on the cluster (None: in this process, or
        none set), which each part's reduction must fit."""
        if self.client is None:
            return None
        limits = [w.get("memory_limit") or 0
                  for w in self.client.scheduler_info()["workers"].values()]
        return min(limits) if limits and min(limits) > 0 else None

    def run(self, tasks):
        store = self.store or Store()
        # a fresh part's basis goes from the store straight to the cache's file
        to = None if self.cache is None else (lambda task: _basis_path(self.cache, task))
        runner = (serial(store, to) if self.client is None
                  else on_cluster(self.client, store, to))
        if self.cache is not None:
            runner = cached(runner, self.cache)
        return runner(tasks, self.done)


def serial(store, to=None):
    """A runner of each task in this process, in order, its basis kept in store (or moved to
    the file to(task) names); done(task, PartBasis) after each."""
    to = to or (lambda task: None)

    def run(tasks, done=None):
        out = []
        for task in tasks:
            part = task.run(None, store) if isinstance(task, PiecesTask) else task.run()
            out.append(replace(part, T=store.kept(task.name, part.T, to(task))))
            if done is not None:
                done(task, out[-1])
        return out
    return run


def on_cluster(client, store=None, to=None):
    """A runner of the tasks on a Dask client, one task a part (a part in pieces, a task a
    piece and stage: reduce.pieces), their results in order, each basis kept in store (a
    worker writes it there, this process maps it, or moves it to the file to(task) names);
    done(task, PartBasis) as each finishes. A task whose worker dies is run again on another
    (the scheduler's), the same arithmetic on one thread."""
    store = store or Store()
    to = to or (lambda task: None)

    def run(tasks, done=None):
        from dask.distributed import as_completed
        whole = [i for i, task in enumerate(tasks) if not isinstance(task, PiecesTask)]
        futures = [submitted(client, _run, tasks[i], store, key=f"part-{tasks[i].name}-"
                             f"{tasks[i].key()[:16]}", pure=False) for i in whole]
        index = {f.key: i for i, f in zip(whole, futures)}
        out = [None] * len(tasks)
        # a part in pieces: its stages fan out over the workers beside the whole parts'
        for i, task in enumerate(tasks):
            if i not in index.values():
                part = task.run(OnCluster(client), store)
                out[i] = replace(part, T=store.kept(task.name, part.T, to(task)))
                if done is not None:
                    done(task, out[i])
        for future in as_completed(futures):
            i = index[future.key]
            part = future.result()
            out[i] = replace(part, T=store.mapped(part.T, to(tasks[i])))
            if done is not None:
                done(tasks[i], out[i])
        return out
    return run


def _run(task, store):
    """A part's reduction on a worker: its basis handed back as store's file."""
    from ..settings import configure
    configure()
    part = task.run()
    return replace(part, T=store.written(task.name, part.T))


def _basis_path(folder, task):
    """The file of a task's basis in a cache folder (made if need be)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return _files(folder, task)[1]


def _files(folder, task):
    """(its reduced matrices' file, its basis' file) of a task in a cache folder."""
    stem = folder / f"part-{task.key()}"
    return stem.with_suffix(".npz"), stem.with_suffix(".T.npy")


def cached(runner, folder):
    """runner through the folder: a task whose key is there is read back (its basis mapped
    from its file), the others run and are written (each file under a temporary name then
    renamed, the basis first: a killed run leaves no part half written; a basis the runner
    moved there already is not written again). Nothing else in the folder is read, changed
    or deleted."""
    folder = Path(folder)

    def run(tasks, done=None):
        out, todo = [None] * len(tasks), []
        for i, task in enumerate(tasks):
            path, basis = _files(folder, task)
            if path.is_file() and basis.is_file():
                with np.load(path) as data:
                    out[i] = PartBasis(task.name, np.load(basis, mmap_mode="r"), data["Kr"],
                                       data["mode_hz"], int(data["n_shapes"]),
                                       int(data["n_static"]), {"cache": 0.0},
                                       data["interface_mu"], int(data["interface_loads"]))
                if done is not None:
                    done(task, out[i])
            else:
                todo.append(i)
        for i, p in zip(todo, runner([tasks[i] for i in todo], done)):
            folder.mkdir(parents=True, exist_ok=True)
            path, basis = _files(folder, tasks[i])
            if not (isinstance(p.T, np.memmap)
                    and Path(p.T.filename).resolve() == basis.resolve()):
                whole(basis, lambda t: saved(t, np.save, p.T))
                p = replace(p, T=np.load(basis, mmap_mode="r"))
            whole(path, lambda t: saved(t, np.savez, **{name: getattr(p, name)
                                                        for name in _FIELDS}))
            out[i] = p
        return out
    return run


def used(case, workers=0, scheduler=None, cache=None):
    """Whether the components path's options (--workers, --scheduler, --cache) are used:
    not where none is given, nor where "auto" chose the assembled path (Case.reduction_auto:
    a case of any size may be given them); refused on a case that names a path whose basis
    is made in this process, whole (the assembled path, the full model)."""
    if not (workers or scheduler or cache):
        return False
    if case.solver.reduction.components:
        return True
    if case.reduction_auto:
        return False
    option = "--workers" if workers else "--scheduler" if scheduler else "--cache"
    raise CaseError(WHERE, option, "reduces the parts of the components path: set "
                    'solver.reduction.enabled = true and solver.reduction.method = '
                    '"components"')


@contextmanager
def engine_for(case, workers=0, scheduler=None, cache=None, on_part=None, on_stage=None):
    """The Engine of the components path for one call of the API (without options: the
    parts in this process, uncached), its Dask client closed and its store removed at the
    end; on_part(name, seconds, cached) as each part is done, on_stage(name, seconds, peak
    GB) as each stage of the setup ends. Asked of an assembled case, the options are
    refused or unused (used)."""
    done = None if on_part is None else (
        lambda task, part: on_part(task.name, sum(part.seconds.values()),
                                   "cache" in part.seconds))
    # the parts' bases in files of this machine where it and the workers share a disk (not
    # an existing cluster's: its workers' files are theirs)
    store = Store.made() if case.solver.reduction.components and not scheduler else Store()
    client = cluster = None
    try:
        if not used(case, workers, scheduler, cache):
            yield Engine(done=done, stage=on_stage, store=store)
            return
        from ..cluster import check_cluster, client_for
        if cache is not None:
            cache = Path(cache)
            if cache.exists() and not cache.is_dir():
                raise CaseError("command line", "--cache", f"{cache} is not a folder")
        if workers or scheduler:
            check_cluster(scheduler, workers)
            client, cluster = client_for(scheduler, workers)
        yield Engine(client, cache, done, on_stage, store)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        store.close()
