"""Where the parts of the components path are reduced: in this process one after the other,
on a Dask cluster one task a part, and through a cache folder that keeps each part's
reduction under its task's key (reduce.parts.PartTask.key)."""
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..cluster import WHERE, submitted
from ..errors import CaseError
from .parts import PartBasis
from .pieces import OnCluster, PiecesTask

# what a part's cache file holds of its PartBasis
_FIELDS = ("T", "Kr", "mode_hz", "n_shapes", "n_static", "interface_mu", "interface_loads")


@dataclass(frozen=True)
class Engine:
    """How the components path reduces its parts: on a Dask client (None: in this process),
    through a cache folder (None: none), done(task, PartBasis) as each part is reduced; and
    stage(name, seconds, peak GB) as each stage of the setup ends (None: nothing said)."""
    client: object = None
    cache: object = None
    done: object = None
    stage: object = None

    def budget(self):
        """The smallest worker's memory limit [B] on the cluster (None: in this process, or
        none set), which each part's reduction must fit."""
        if self.client is None:
            return None
        limits = [w.get("memory_limit") or 0
                  for w in self.client.scheduler_info()["workers"].values()]
        return min(limits) if limits and min(limits) > 0 else None

    def run(self, tasks):
        runner = serial if self.client is None else on_cluster(self.client)
        if self.cache is not None:
            runner = cached(runner, self.cache)
        return runner(tasks, self.done)


def serial(tasks, done=None):
    """Each task in this process, in order; done(task, PartBasis) after each."""
    out = []
    for task in tasks:
        out.append(task.run())
        if done is not None:
            done(task, out[-1])
    return out


def on_cluster(client):
    """A runner of the tasks on a Dask client, one task a part (a part in pieces, a task a
    piece and stage: reduce.pieces), their results in order; done(task, PartBasis) as each
    finishes. A task whose worker dies is run again on another
    (the scheduler's), the same arithmetic on one thread."""
    def run(tasks, done=None):
        from dask.distributed import as_completed
        whole = [i for i, task in enumerate(tasks) if not isinstance(task, PiecesTask)]
        futures = [submitted(client, _run, tasks[i], key=f"part-{tasks[i].name}-"
                             f"{tasks[i].key()[:16]}", pure=False) for i in whole]
        index = {f.key: i for i, f in zip(whole, futures)}
        out = [None] * len(tasks)
        # a part in pieces: its stages fan out over the workers beside the whole parts'
        for i, task in enumerate(tasks):
            if i not in index.values():
                out[i] = task.run(OnCluster(client))
                if done is not None:
                    done(task, out[i])
        for future in as_completed(futures):
            i = index[future.key]
            out[i] = future.result()
            if done is not None:
                done(tasks[i], out[i])
        return out
    return run


def _run(task):
    from ..settings import configure
    configure()
    return task.run()


def cached(runner, folder):
    """runner through the folder: a task whose key is there is read back, the others run and
    are written (whole, under a temporary name then renamed: a killed run leaves no part
    file half written). Nothing else in the folder is read, changed or deleted."""
    folder = Path(folder)

    def run(tasks, done=None):
        out, todo = [None] * len(tasks), []
        for i, task in enumerate(tasks):
            path = folder / f"part-{task.key()}.npz"
            if path.is_file():
                with np.load(path) as data:
                    out[i] = PartBasis(task.name, data["T"], data["Kr"], data["mode_hz"],
                                       int(data["n_shapes"]), int(data["n_static"]),
                                       {"cache": 0.0}, data["interface_mu"],
                                       int(data["interface_loads"]))
                if done is not None:
                    done(task, out[i])
            else:
                todo.append(i)
        for i, p in zip(todo, runner([tasks[i] for i in todo], done)):
            out[i] = p
            folder.mkdir(parents=True, exist_ok=True)
            path = folder / f"part-{tasks[i].key()}.npz"
            part = folder / f".{path.name}.{os.getpid()}.{time.monotonic_ns()}.npz"
            np.savez(part, **{name: getattr(p, name) for name in _FIELDS})
            os.replace(part, path)
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
    """The Engine of the components path for one call of the API (None: the parts in this
    process, uncached, nothing said), its Dask client closed at the end; on_part(name,
    seconds, cached) as each part is done, on_stage(name, seconds, peak GB) as each stage of
    the setup ends. Asked of an assembled case, the options are refused or unused (used)."""
    done = None if on_part is None else (
        lambda task, part: on_part(task.name, sum(part.seconds.values()),
                                   "cache" in part.seconds))
    if not used(case, workers, scheduler, cache):
        yield None if done is None and on_stage is None else Engine(done=done, stage=on_stage)
        return
    from ..cluster import check_cluster, client_for
    if cache is not None:
        cache = Path(cache)
        if cache.exists() and not cache.is_dir():
            raise CaseError("command line", "--cache", f"{cache} is not a folder")
    client = cluster = None
    if workers or scheduler:
        check_cluster(scheduler, workers)
        client, cluster = client_for(scheduler, workers)
    try:
        yield Engine(client, cache, done, on_stage)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
