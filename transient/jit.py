"""Numba flags in one place: every kernel is cached on disk and compiled without the GIL.

Two processes compiling the same kernels at once can leave mismatched cache files that later
crash on load (numba#10128: a stability study or a CI run starting several `transient run`
together). Compilation, and the cache lookup that precedes it, therefore hold a file lock in
the cache directory; calls of an already compiled kernel never touch it. The lock is
reentrant within a process, since compiling a kernel compiles the kernels it calls. Every
checkout with the same kernels shares it, and a compile on a busy machine can hold it for
minutes: its holder writes who it is into the file, and a process waiting for it says so and
can be stopped (SIGINT, SIGTERM).

`spinning` keeps Numba's OpenMP threads awake between the parallel regions of a kernel call.

Every kernel is cached in `cache_dir()`, set on its dispatcher when it is decorated, so the
cache needs no environment variable and the process's other Numba functions keep theirs.
"""
import ctypes
import fcntl
import hashlib
import os
import signal
import socket
import sys
import threading
import time
from contextlib import contextmanager

from pathlib import Path

import numba
from numba.core import caching

_guard = threading.RLock()
_held = {"depth": 0, "file": None}


def cache_dir():
    """NUMBA_CACHE_DIR when set, else a directory keyed by the source of every module jitted
    code comes from: Numba checks only a function's own file, so a kernel that inlines a law or
    a signal from another module would otherwise keep a stale copy after that module changes."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return os.environ["NUMBA_CACHE_DIR"]
    here = Path(__file__).parent
    digest = hashlib.sha1()
    for path in [here / "jit.py"] + sorted((here / "kernels").glob("*.py")):
        digest.update(path.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return str(base / "transient" / "numba" / digest.hexdigest()[:16])


def lock_path():
    return os.path.join(cache_dir(), ".compile.lock")


POLL_S = 0.1        # between tries of a lock held elsewhere
NOTICE_S = 1.5      # of waiting before the wait is said on stderr (TRANSIENT_LOCK_NOTICE_S)


@contextmanager
def compile_lock():
    """Exclusive across processes (flock), reentrant within one."""
    with _guard:
        if _held["depth"] == 0:
            path = lock_path()
            os.makedirs(os.path.dirname(path), exist_ok=True)
            f = open(path, "a+", encoding="utf-8", errors="replace")
            try:
                _acquire(f, path)
            except BaseException:
                f.close()
                raise
            _held["file"] = f
        _held["depth"] += 1
        try:
            yield
        finally:
            _held["depth"] -= 1
            if _held["depth"] == 0:
                f = _held.pop("file")
                _held["file"] = None
                f.truncate(0)
                fcntl.flock(f, fcntl.LOCK_UN)
                f.close()


def _acquire(f, path):
    """flock f, polled: a wait past NOTICE_S is one line on stderr naming the holder, and
    SIGINT or SIGTERM end it (a blocking flock never returned to the signal's flag). Then the
    holder's pid, host and command go into the file for the next one waiting."""
    if not _took(f):
        with _stoppable():
            waited, told, notice = time.monotonic(), False, _notice_s()
            while not _took(f):
                if not told and time.monotonic() - waited >= notice:
                    f.seek(0)
                    holder = _one_line(f.read()) or "a process that does not say"
                    print(f"waiting for the Numba compile lock {path}, held by {holder} "
                          "(compiling the same kernels; SIGINT or SIGTERM stops)",
                          file=sys.stderr, flush=True)
                    told = True
                time.sleep(POLL_S)
    f.truncate(0)
    f.write(f"pid {os.getpid()} on {socket.gethostname()}: "
            f"{_one_line(' '.join(sys.argv))[:200]}")
    f.flush()


def _notice_s():
    """NOTICE_S, or the environment's TRANSIENT_LOCK_NOTICE_S (the test suite's 'inf': its two
    workers compile the same kernels, and its tests hold a command's stderr to one line)."""
    try:
        return float(os.environ.get("TRANSIENT_LOCK_NOTICE_S", NOTICE_S))
    except ValueError:
        return NOTICE_S


def _took(f):
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False


def _one_line(text):
    return " ".join(str(text).split())


@contextmanager
def _stoppable():
    """SIGINT and SIGTERM raise KeyboardInterrupt('interrupted' or 'terminated (SIGTERM)',
    the reasons the command line maps to 130 and 143) over the block, after the handler in
    place (a run's, which records the stop) has run. Off the main thread: nothing to take."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum, frame):
        handler = previous[signum]
        if handler == signal.SIG_IGN:
            return
        if callable(handler):
            handler(signum, frame)
        raise KeyboardInterrupt("interrupted" if signum == signal.SIGINT else
                                f"terminated ({signal.Signals(signum).name})")
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


class _Locator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Numba's user-provided cache locator, at cache_dir() rather than numba.config's."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = os.path.join(cache_dir(), self.get_suitable_cache_subpath(py_file))

    def get_cache_path(self):
        return self._cache_path


class _CacheImpl(caching.CompileResultCacheImpl):
    _locator_classes = [_Locator]


class _Cache(caching.FunctionCache):
    _impl_class = _CacheImpl


def _locked(**flags):
    """numba.njit(**flags) cached in cache_dir(), with the dispatcher's compile path (taken
    only for argument types it has not compiled yet) under compile_lock."""
    def decorate(fn):
        dispatcher = numba.njit(**flags)(fn)
        dispatcher._cache = _Cache(dispatcher.py_func)
        compile_for_args = dispatcher._compile_for_args

        def locked(*args, **kws):
            with compile_lock():
                return compile_for_args(*args, **kws)
        dispatcher._compile_for_args = locked
        return dispatcher
    return decorate


njit = _locked(nogil=True, error_model="numpy")
njit_fast = _locked(nogil=True, error_model="numpy", fastmath=True)
njit_parallel = _locked(nogil=True, error_model="numpy", fastmath=True,
                        parallel=True)
# parallel without fastmath: no fused multiply-adds, so the sums are SciPy's to the last bit
njit_parallel_ieee = _locked(nogil=True, error_model="numpy", parallel=True)


SPIN_MS = 200     # Intel's documented default blocktime


@contextmanager
def spinning(ms=SPIN_MS):
    """Numba's OpenMP threads wait `ms` spinning after each parallel region, over the block.

    The reduced kernel's contact pass is one parallel region per step, tens of microseconds
    apart. MKL's OpenMP runtime (libiomp5, loaded by PARDISO: it exports the GOMP entry points
    and so serves Numba's omp layer too) falls to a blocktime of 0 in the setup, so the threads
    slept between passes and two threads stepped slower than one (docs/performance.md,
    "Threads of the kernel"). The setting is restored after the block:
    between chunks the history's writes do not compete with spinning threads. Under libgomp
    (no MKL: `load_iomp`) this does nothing."""
    lib = _iomp()
    if lib is None:
        yield
        return
    before = lib.kmp_get_blocktime()
    lib.kmp_set_blocktime(ms)
    try:
        yield
    finally:
        lib.kmp_set_blocktime(before)


_runtime = {}


def _iomp():
    """libiomp5 if this process has loaded it (kept once found), else None."""
    if "iomp" not in _runtime:
        try:
            with open("/proc/self/maps") as f:
                paths = {line.split()[-1] for line in f if "libiomp5" in line}
        except OSError:
            paths = set()
        if not paths:
            return None
        lib = ctypes.CDLL(sorted(paths)[0])
        _runtime["iomp"] = lib if hasattr(lib, "kmp_set_blocktime") else None
    return _runtime["iomp"]


def load_iomp():
    """MKL's OpenMP runtime (libiomp5, the MKL wheels' lib directory) loaded into the process's
    global scope before Numba starts its thread pool, when MKL is installed. Numba's omp layer
    takes the GOMP entry points of the runtime loaded first: PARDISO's first threaded call
    loads libiomp5, but a parallel kernel that runs before it (a setup stage before the
    factorization: model.dofs.restricted) binds Numba and then MKL to libgomp, whose threads
    `spinning` cannot keep awake (docs/performance.md). transient.configure calls it."""
    from ctypes.util import find_library
    for path in (Path(sys.prefix, "lib", "libiomp5.so"), find_library("iomp5")):
        if path and (not isinstance(path, Path) or path.exists()):
            try:
                ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
                return
            except OSError:
                continue
