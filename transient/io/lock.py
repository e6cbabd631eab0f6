"""One writer per history: a run holds an exclusive lock on its history file from before its
first stage to its last row, so that a second run writing the same file is refused at once
instead of interleaving its rows. The lock is flock(2) on the file itself: advisory, released
by the kernel when the process dies (SIGKILL included), and never taken by readers, which open
the file without locks while it is written.

Taking it also checks the output before any expensive stage: a path that cannot be written, a
directory, or a file that is not a history of this package (a case file, a device) is a
one-line error, and nothing is overwritten."""
import fcntl
from contextlib import contextmanager
from pathlib import Path

import h5py

from ..errors import CaseError
from .attributes import CASE_TEXT


def is_history(path):
    """The file at path is an HDF5 history written by this package."""
    try:
        if not h5py.is_hdf5(path):
            return False
        with h5py.File(path, "r", locking=False) as f:
            return "rows" in f.attrs and CASE_TEXT in f.attrs
    except OSError:
        return False


def _kind(path, key):
    """'dir', 'file', 'other' or None (absent) of an output path; CaseError for a path the
    system cannot even look up (too long, a NUL in it)."""
    try:
        if not path.exists():
            return None
        return "dir" if path.is_dir() else "file" if path.is_file() else "other"
    except (OSError, ValueError) as exc:
        raise CaseError(path, key, f"not a usable file name ({exc})") from None


def check_writable(path, key):
    """Refuse (CaseError) an output file that cannot be written, before the work that makes
    it: a missing or read-only directory, a directory, device or pipe in its place."""
    path = Path(path)
    kind = _kind(path, key)
    if kind == "dir":
        raise CaseError(path, key, "is a directory: expected a file")
    if kind == "other":
        raise CaseError(path, key, "is a device, pipe or socket: expected a file")
    existed = kind is not None
    try:
        open(path, "ab").close()
    except (OSError, ValueError) as exc:        # ValueError: a NUL in the name
        raise CaseError(path, key, f"cannot write: {getattr(exc, 'strerror', None) or exc}") \
            from None
    if not existed:
        path.unlink()


@contextmanager
def writing(path, key, resume=False):
    """Hold the history file at path for a run (key: what names it, '-o' or 'output.file').

    Raises CaseError when it cannot be written, is not a history (or, to resume, does not
    exist), or another run holds it. A file this created is removed if the block fails before
    anything was written to it.
    """
    path = Path(path)
    kind = _kind(path, key)
    if kind == "dir":
        raise CaseError(path, key, "is a directory: expected a history file (.h5)")
    if kind == "other":
        raise CaseError(path, key, "is not a history but a device, pipe or socket: not "
                        "written")
    existed = path.exists() and path.stat().st_size > 0
    if resume and not existed:
        raise CaseError(path, key, "--resume: no history file to resume")
    if existed and not is_history(path):
        raise CaseError(path, key, "exists and is not a history written by transient: not "
                        "overwritten (choose another output file)")
    absent = not path.exists()
    handle, locked, done = None, False, False
    try:
        try:
            handle = open(path, "ab")
        except (OSError, ValueError) as exc:        # ValueError: a NUL in the name
            raise CaseError(path, key, "cannot write: "
                            f"{getattr(exc, 'strerror', None) or exc}") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise CaseError(path, key, "another run is writing this history") from None
        locked = True
        yield path
        done = True
    finally:
        # an interrupt may land anywhere in here: the file this made goes with it, but never
        # one that another run holds (still empty in its setup), nor one that was there
        # before and could not be opened (a name under /proc)
        if (locked or (handle is None and absent)) and not done and not existed \
                and path.exists() and path.stat().st_size == 0:
            path.unlink()
        if locked:
            fcntl.flock(handle, fcntl.LOCK_UN)
        if handle is not None:
            handle.close()
