"""The compile lock: exclusive across processes, reentrant within one, taken only to compile."""
import subprocess
import sys
import time

from transient import jit

CHILD = ("import time; from transient.jit import compile_lock; t = time.perf_counter(); "
         "lock = compile_lock(); lock.__enter__(); print(time.perf_counter() - t)")


def test_lock_is_exclusive_across_processes_and_reentrant(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    with jit.compile_lock():
        with jit.compile_lock():              # a kernel compiling the kernels it calls
            child = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE,
                                     text=True, env={**__import__("os").environ})
            time.sleep(1.0)
    waited = float(child.communicate(timeout=60)[0])
    assert waited > 0.5
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
