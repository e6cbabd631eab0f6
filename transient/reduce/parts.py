"""Where the parts of the components path are reduced: in this process one after the other,
on a Dask cluster one task a part, and through a cache folder that keeps each part's
reduction under the key of everything it is made from.

A part's task (PartTask) holds its own matrices and interface loads; its key hashes them with
the settings and the source of the code that reduces it, so that a campaign that changes the
pad's lining reduces the pad again and reads the disc, the caliper and the bracket back, and
a reduction made by other code is never read as this one's.
"""
import hashlib
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# the modules whose arithmetic makes a part's reduction: their source is in its key
_SOURCES = ("reduce/components.py", "reduce/basis.py", "solve/modes.py", "solve/lanczos.py",
            "solve/linsolve.py", "model/dofs.py")
_FIELDS = ("T", "Kr", "mode_hz", "n_shapes", "n_static")


@dataclass(frozen=True)
class PartTask:
    """One part's reduction to make: part_basis' arguments."""
    name: str
    K: object                # (n, n) sparse, the part's free dofs
    M: object
    interface: tuple         # (E, Cc, stiffness) or None
    loads: np.ndarray        # (n, s)
    fmax: float              # the cutoff its modes reach [Hz]
    shift_hz: float
    tol: float
    backend: str

    def run(self):
        from ..solve import blas
        from .components import part_basis
        with blas.one_thread():
            return part_basis(self.name, self.K, self.M, self.interface, self.loads,
                              self.fmax, self.shift_hz, self.tol, self.backend)

    def key(self):
        """The hex digest of what the reduction is made from (not the part's name: two equal
        parts share it)."""
        h = hashlib.sha256()
        for text in _source_texts():
            h.update(text)
        h.update(repr((self.fmax, self.shift_hz, self.tol, self.backend)).encode())
        arrays = [self.K.data, self.K.indices, self.K.indptr, self.M.data, self.M.indices,
                  self.M.indptr, self.loads]
        if self.interface is not None:
            arrays += list(self.interface)
        for a in arrays:
            a = np.ascontiguousarray(a)
            h.update(repr((a.dtype.str, a.shape)).encode())
            h.update(a.data)
        return h.hexdigest()

    def bytes(self):
        """An estimate of the peak memory of its reduction [B]: the factor of K (about 40 times
        K's entries for tet10 in 3D), the modes and responses (n x their columns), twice."""
        n = self.K.shape[0]
        k = 0 if self.interface is None else self.interface[0].shape[1]
        return int(40 * 12 * self.K.nnz + 8 * n * (3 * (k + self.loads.shape[1]) + 400))


@dataclass(frozen=True)
class Engine:
    """How the components path reduces its parts: on a Dask client (None: in this process),
    through a cache folder (None: none), done(task, PartBasis) as each part is reduced."""
    client: object = None
    cache: object = None
    done: object = None

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


_TEXTS = []


def _source_texts():
    if not _TEXTS:
        root = Path(__file__).resolve().parent.parent
        _TEXTS.extend((root / name).read_bytes() for name in _SOURCES)
    return _TEXTS


def serial(tasks, done=None):
    """Each task in this process, in order; done(task, PartBasis) after each."""
    out = []
    for task in tasks:
        out.append(task.run())
        if done is not None:
            done(task, out[-1])
    return out


def on_cluster(client):
    """A runner of the tasks on a Dask client, one task a part, their results in order;
    done(task, PartBasis) as each finishes. A task whose worker dies is run again on another
    (the scheduler's), the same arithmetic on one thread."""
    def run(tasks, done=None):
        from dask.distributed import as_completed
        futures = [client.submit(_run, task, key=f"part-{task.name}-{task.key()[:16]}",
                                 pure=False) for task in tasks]
        index = {f.key: i for i, f in enumerate(futures)}
        out = [None] * len(tasks)
        for future in as_completed(futures):
            i = index[future.key]
            out[i] = future.result()
            if done is not None:
                done(tasks[i], out[i])
        return out
    return run


def _run(task):
    import transient
    transient.configure()
    return task.run()


def cached(runner, folder):
    """runner through the folder: a task whose key is there is read back, the others run and
    are written (whole, under a temporary name then renamed: a killed run leaves no part
    file half written). Nothing else in the folder is read, changed or deleted."""
    folder = Path(folder)

    def run(tasks, done=None):
        from .components import PartBasis
        out, todo = [None] * len(tasks), []
        for i, task in enumerate(tasks):
            path = folder / f"part-{task.key()}.npz"
            if path.is_file():
                with np.load(path) as data:
                    out[i] = PartBasis(task.name, data["T"], data["Kr"], data["mode_hz"],
                                       int(data["n_shapes"]), int(data["n_static"]),
                                       {"cache": 0.0})
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
