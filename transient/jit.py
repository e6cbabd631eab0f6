"""Numba flags in one place: every kernel is cached on disk and compiled without the GIL.

Two processes compiling the same kernels at once can leave mismatched cache files that later
crash on load (numba#10128: a stability study or a CI run starting several `transient run`
together). Compilation, and the cache lookup that precedes it, therefore hold a file lock in
the cache directory; calls of an already compiled kernel never touch it. The lock is
reentrant within a process, since compiling a kernel compiles the kernels it calls.
"""
import fcntl
import os
import tempfile
import threading
from contextlib import contextmanager

import numba

_guard = threading.RLock()
_held = {"depth": 0, "file": None}


def lock_path():
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(tempfile.gettempdir(), "numba")
    return os.path.join(base, ".compile.lock")


@contextmanager
def compile_lock():
    """Exclusive across processes (flock), reentrant within one."""
    with _guard:
        if _held["depth"] == 0:
            path = lock_path()
            os.makedirs(os.path.dirname(path), exist_ok=True)
            f = open(path, "a")
            fcntl.flock(f, fcntl.LOCK_EX)
            _held["file"] = f
        _held["depth"] += 1
        try:
            yield
        finally:
            _held["depth"] -= 1
            if _held["depth"] == 0:
                f = _held.pop("file")
                _held["file"] = None
                fcntl.flock(f, fcntl.LOCK_UN)
                f.close()


def _locked(**flags):
    """numba.njit(**flags), with the dispatcher's compile path (taken only for argument types
    it has not compiled yet) under compile_lock."""
    def decorate(fn):
        dispatcher = numba.njit(**flags)(fn)
        compile_for_args = dispatcher._compile_for_args

        def locked(*args, **kws):
            with compile_lock():
                return compile_for_args(*args, **kws)
        dispatcher._compile_for_args = locked
        return dispatcher
    return decorate


njit = _locked(cache=True, nogil=True, error_model="numpy")
njit_fast = _locked(cache=True, nogil=True, error_model="numpy", fastmath=True)
njit_parallel = _locked(cache=True, nogil=True, error_model="numpy", fastmath=True,
                        parallel=True)
# parallel without fastmath: no fused multiply-adds, so the sums are SciPy's to the last bit
njit_parallel_ieee = _locked(cache=True, nogil=True, error_model="numpy", parallel=True)
