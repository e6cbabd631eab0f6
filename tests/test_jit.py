"""The compile lock: exclusive across processes, reentrant within one, taken only to compile."""
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from transient import jit

ROOT = Path(__file__).resolve().parent.parent
BAR = ROOT / "cases" / "bar_impact.toml"

# the child says where it is at each step, so the test waits on what it says, not on time
CHILD = """
import fcntl
from transient import jit
print("ready", flush=True)
with open(jit.lock_path(), "a") as f:
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        print("free", flush=True)
    except BlockingIOError:
        print("busy", flush=True)
with jit.compile_lock():
    print("acquired", flush=True)
"""


def test_lock_is_exclusive_across_processes_and_reentrant(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    with jit.compile_lock():
        with jit.compile_lock():              # a kernel compiling the kernels it calls
            child = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE,
                                     text=True, env=dict(os.environ))
            assert child.stdout.readline().strip() == "ready"
            assert child.stdout.readline().strip() == "busy"
    # released by the outer block only: the child, blocked until now, takes it
    assert child.stdout.readline().strip() == "acquired"
    assert child.wait(timeout=60) == 0
    assert (tmp_path / ".compile.lock").exists()


def test_kernels_compile_under_the_lock_once_per_signature(tmp_path, monkeypatch):
    taken = []
    real = jit.compile_lock

    def counting():
        taken.append(1)
        return real()
    monkeypatch.setattr(jit, "compile_lock", counting)

    @jit.njit
    def twice(x):
        return 2 * x
    assert twice(2) == 4 and twice(3) == 6
    assert len(taken) == 1
    assert twice(1.5) == 3.0
    assert len(taken) == 2


SPIN_CHILD = """
import numpy as np, scipy.sparse as sp
from transient import jit
from transient.solve.linsolve import factorize
# PARDISO first, as in a run's factorization stage: MKL loads libiomp5, which then serves
# Numba's threads too (with Numba's pool started first, MKL takes libgomp instead)
factorize(sp.eye(4).tocsr(), "pardiso")(np.ones(4))
lib = jit._iomp()
lib.kmp_set_blocktime(7)
with jit.spinning():
    inside = lib.kmp_get_blocktime()
after = lib.kmp_get_blocktime()
try:
    with jit.spinning():
        raise KeyboardInterrupt
except KeyboardInterrupt:
    pass
print(inside, after, lib.kmp_get_blocktime())
"""


@pytest.mark.slow
def test_spinning_sets_mkls_blocktime_for_the_block_only():
    """Under MKL's OpenMP runtime the kernel's threads spin between the steps' parallel
    regions inside the block, and the runtime's own setting comes back after it (a fresh
    process: which runtime serves depends on what started first)."""
    import pytest
    from transient.solve.linsolve import available
    if "pardiso" not in available():
        pytest.skip("no PARDISO: MKL's OpenMP runtime is not loaded, spinning does nothing")
    out = subprocess.run([sys.executable, "-c", SPIN_CHILD], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == [str(jit.SPIN_MS), "7", "7"]



FIRST_CHILD = """
import ctypes
import numpy as np
import transient
transient.configure()
import scipy.sparse as sp
from transient.kernels.sparse import csr_dot
# a parallel kernel before any MKL call (a setup stage before the factorization)
csr_dot(sp.eye(8).tocsr(), np.ones((8, 2)))
from transient import jit


class Info(ctypes.Structure):
    _fields_ = [("fname", ctypes.c_char_p), ("fbase", ctypes.c_void_p),
                ("sname", ctypes.c_char_p), ("saddr", ctypes.c_void_p)]


# the GOMP entry point the process's global scope gives, as Numba's omp layer binds it
address = ctypes.cast(ctypes.CDLL(None).GOMP_parallel, ctypes.c_void_p)
info = Info()
ctypes.CDLL(None).dladdr(address, ctypes.byref(info))
print(jit._iomp() is not None, b"libiomp5" in info.fname)
"""


@pytest.mark.slow
def test_numbas_threads_are_mkls_whatever_runs_first():
    """With MKL installed and transient configured, Numba's OpenMP pool is served by libiomp5
    even when a parallel kernel starts it before PARDISO's first call: `spinning` then keeps
    the kernel's threads awake (under libgomp it cannot: docs/performance.md)."""
    import pytest
    from transient.solve.linsolve import available
    if "pardiso" not in available():
        pytest.skip("no PARDISO: no MKL OpenMP runtime to prefer")
    out = subprocess.run([sys.executable, "-c", FIRST_CHILD], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["True", "True"]


HUGE_CHILD = """
import os
{imports}
core = getattr(numpy, "_core", None) or numpy.core
print(core.multiarray._get_madvise_hugepage(), os.environ.get("NUMPY_MADVISE_HUGEPAGE"))
"""


@pytest.mark.slow
def test_numpy_arrays_on_small_pages_unless_the_user_says():
    """transient.configure turns NumPy's huge-page advice off (its arrays' huge pages are
    zeroed through the host on a ballooned VM), whether NumPy was imported before it or after,
    and passes the setting to the processes it starts; a NUMPY_MADVISE_HUGEPAGE of the user's
    is kept, and importing transient alone leaves NumPy's advice as it was."""
    def child(imports, value=None):
        env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"}
        if value is not None:
            env["NUMPY_MADVISE_HUGEPAGE"] = value
        out = subprocess.run([sys.executable, "-c", HUGE_CHILD.format(imports=imports)],
                             capture_output=True, text=True, env=env, check=True)
        return out.stdout.split()
    configured = "; transient.configure()"
    assert child("import transient, numpy" + configured) == ["False", "0"]
    assert child("import numpy, transient" + configured) == ["False", "0"]
    assert child("import numpy, transient" + configured, "1") == ["True", "1"]
    assert child("import transient, numpy") == child("import numpy")


def _lines(stream):
    """A queue of the stream's lines, read by a thread (None at its end): the test waits on
    what the child says, with a bound that only a hang reaches."""
    import queue
    import threading
    out = queue.Queue()

    def read():
        for line in stream:
            out.put(line)
        out.put(None)
    threading.Thread(target=read, daemon=True).start()
    return out


@pytest.mark.parametrize("command, sig, code", [
    ("modes", signal.SIGTERM, 143), ("run", signal.SIGTERM, 143), ("run", signal.SIGINT, 130)])
@pytest.mark.slow
def test_a_wait_for_the_lock_says_who_holds_it_and_a_signal_ends_it(tmp_path, monkeypatch,
                                                                     command, sig, code):
    """A command whose kernels are not compiled waits for the lock another process holds:
    after a moment one line on stderr names the lock file and its holder, and SIGTERM or
    SIGINT ends it with the command line's codes (a blocking flock never reached the run's
    check of its stop requests)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("TRANSIENT_LOCK_NOTICE_S", str(jit.NOTICE_S))
    args = [sys.executable, "-m", "transient", command, str(BAR)]
    if command == "run":
        args += ["-o", str(tmp_path / "out.h5"), "--quiet"]
    with jit.compile_lock():
        holder = (tmp_path / "cache" / ".compile.lock").read_text()
        assert holder.startswith(f"pid {os.getpid()} on ")
        child = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                 text=True, env=dict(os.environ), cwd=ROOT)
        try:
            lines = _lines(child.stderr)
            line = lines.get(timeout=600)
            assert line is not None and line.startswith("waiting for the Numba compile lock "
                                                         f"{jit.lock_path()}, held by {holder}")
            child.send_signal(sig)
            assert child.wait(timeout=600) == code
        finally:
            child.kill()
    rest = []
    while (line := lines.get(timeout=60)) is not None:
        rest.append(line)
    assert rest == [("terminated (SIGTERM)" if sig == signal.SIGTERM else "interrupted") + "\n"]
    # released: the file says no holder
    assert (tmp_path / "cache" / ".compile.lock").read_text() == ""
