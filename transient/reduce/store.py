"""Where the components path keeps its parts' bases T_p: in files mapped into memory, not in
the orchestrating process' own memory.

The synthesis holds every part's basis side by side (reduce.synthesis), the largest of the
path's arrays (a part's dofs times its columns), and reads each only a part at a time: the
coupling's rows read its interface rows, the preload and the fields a product per part. On a
file mapped read-only its pages are the system's cache, read when a product needs them and
let go under pressure, as a superelement's basis is read back from disk for data recovery.
The numbers are those of the same arrays in memory: a mapped array is an ndarray to NumPy
and BLAS.

A Store without a folder keeps the bases in memory (a cluster whose workers do not share
this machine's disk). Otherwise its folder is made under the system's temporary directory
(TMPDIR), each file unlinked as soon as it is mapped (the mapping keeps it while the basis
lives), and the folder removed at close(): nothing is left of it after the run.
"""
import errno
import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import saved, whole


@dataclass(frozen=True)
class Store:
    """Files for the parts' bases in folder (None: the bases kept in memory, as returned)."""
    folder: Path = None

    @classmethod
    def made(cls):
        """A store in a new folder under the system's temporary directory."""
        return cls(Path(tempfile.mkdtemp(prefix="transient-parts-")))

    def _path(self, name):
        return self.folder / f"{name}.{os.getpid()}.{time.monotonic_ns()}.npy"

    def empty(self, name, shape, order="C"):
        """A writable (n, w) array for columns filled in place (a part in pieces, its rows a
        piece at a time; a piece's extension): mapped from a new file, or in memory."""
        if self.folder is None:
            return np.empty(shape, order=order)
        return np.lib.format.open_memmap(self._path(name), mode="w+", dtype=np.float64,
                                         shape=shape, fortran_order=order == "F")

    def written(self, name, T):
        """The path of a file holding T (on a worker, for the process that maps it), or T
        itself when the store keeps bases in memory."""
        if self.folder is None or isinstance(T, (str, Path)):
            return T
        if isinstance(T, np.memmap) and not isinstance(T.base, np.memmap):
            T.flush()
            return T.filename
        path = self._path(name)
        np.save(path, T)
        if isinstance(T, np.memmap):
            # the columns of a larger file of this store (a piece's A2 of its X): copied
            # out, that file's name goes (its mapping stays while it is referenced)
            larger = Path(T.base.filename)
            if larger.parent == self.folder and larger.exists():
                larger.unlink()
        return str(path)

    def mapped(self, T, to=None):
        """T read-only, mapped from the file written() gave (then unlinked: the mapping
        keeps it), or as it is; with to (a path outside the store: a cache's), mapped from
        there, T's file moved to it (moved)."""
        if isinstance(T, np.memmap) and not isinstance(T.base, np.memmap):
            T = self.written("", T)
        if to is not None:
            return np.load(moved(T, Path(to)), mmap_mode="r")
        if not isinstance(T, (str, Path)):
            return T
        out = np.load(T, mmap_mode="r")
        os.unlink(T)
        return out

    def kept(self, name, T, to=None):
        """T written to this store's file and mapped back (from to, with to: mapped's): its
        memory given back now."""
        return self.mapped(self.written(name, T), to)

    def close(self):
        """Removes the store's folder (its files are unlinked as they are mapped: what is
        left is a killed stage's)."""
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)


def moved(T, to):
    """to, holding T: T's file renamed to it where both share a file system, else copied
    there through a temporary name and unlinked; an array in memory written there. The
    basis is written once, not once to the store and again to its destination."""
    if not isinstance(T, (str, Path)):
        whole(to, lambda temporary: saved(temporary, np.save, T))
        return to
    try:
        os.replace(T, to)
    except OSError as exc:      # another file system: a copy, whole or not at all
        if exc.errno != errno.EXDEV:
            raise
        whole(to, lambda temporary: shutil.copyfile(T, temporary))
        os.unlink(T)
    return to
