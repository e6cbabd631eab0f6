"""The setup's OpenBLAS thread counts: one thread by default, every core inside every_core, and
the same products either way to round-off."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from transient import blas


def openblas_threads():
    return [i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas"]


@pytest.mark.every_core
def test_every_core_raises_the_threads_and_gives_them_back():
    cores = len(os.sched_getaffinity(0))
    with blas.one_thread():
        assert set(openblas_threads()) == {1}
        with blas.every_core():
            # OpenBLAS caps the count at the pool it started with (OMP_NUM_THREADS)
            assert all(1 <= t <= cores for t in openblas_threads())
            inside = openblas_threads()
        assert set(openblas_threads()) == {1}
    if cores > 1 and os.environ.get("OMP_NUM_THREADS", "") in ("", str(cores)):
        assert max(inside) > 1


@pytest.mark.every_core
def test_products_on_every_core_equal_one_thread_to_round_off():
    rng = np.random.default_rng(0)
    A, B = rng.standard_normal((3000, 300)), rng.standard_normal((300, 200))
    with blas.one_thread():
        one, gram1 = A @ B, A.T @ A
        with blas.every_core():
            every, gram = A @ B, A.T @ A
            again = A @ B
    np.testing.assert_allclose(every, one, rtol=0, atol=1e-12 * np.abs(one).max())
    np.testing.assert_allclose(gram, gram1, rtol=0, atol=1e-12 * np.abs(gram1).max())
    assert np.array_equal(gram, gram.T)          # syrk: symmetric to the last bit
    assert np.array_equal(again, every)          # the same split, the same sums


def test_every_core_keeps_to_a_one_thread_worker(monkeypatch):
    """A campaign's workers run with OPENBLAS_NUM_THREADS=1: every_core stays at one thread
    there, and takes every core where nothing caps it."""
    from threadpoolctl import threadpool_info
    from transient import blas
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    assert blas.budget() == 1
    with blas.every_core():
        assert {i["num_threads"] for i in threadpool_info()
                if i["internal_api"] == "openblas"} == {1}
    monkeypatch.delenv("OPENBLAS_NUM_THREADS")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert blas.budget() == len(os.sched_getaffinity(0))


@pytest.mark.every_core
def test_this_thread_alone_sets_numba_and_mkl_for_its_thread_only():
    """Inside, the calling thread has one Numba and one MKL thread, another thread keeps its
    own; after, the caller's come back."""
    import threading

    import numba

    from transient.blas import mkl_runtime
    try:
        mkl = mkl_runtime()
    except OSError:
        pytest.skip("no MKL")
    outside = (numba.get_num_threads(), mkl.MKL_Get_Max_Threads())
    seen, inside, other = {}, threading.Event(), threading.Event()

    def elsewhere():
        inside.wait()
        seen["other"] = (numba.get_num_threads(), mkl.MKL_Get_Max_Threads())
        other.set()

    t = threading.Thread(target=elsewhere)
    t.start()
    with blas.this_thread_alone():
        seen["inside"] = (numba.get_num_threads(), mkl.MKL_Get_Max_Threads())
        inside.set()
        other.wait()
    t.join()
    assert seen["inside"] == (1, 1)
    assert seen["other"] == outside and (numba.get_num_threads(),
                                         mkl.MKL_Get_Max_Threads()) == outside


@pytest.mark.slow
def test_every_core_tests_in_a_process_of_their_own():
    """The suite's workers run at their share of the cores (tests/conftest.py), where a test of
    several threads would pass on one without testing them: those tests (every_core) run here
    in one process without the suite's counts, and must all run and pass."""
    shared = os.environ.get("TRANSIENT_THREADS_SHARE", "").split()
    if not shared:
        pytest.skip("this process has every core: the every_core tests ran in it")
    drop = set(shared) | {"TRANSIENT_THREADS_SHARE", "PYTEST_XDIST_WORKER",
                          "PYTEST_XDIST_WORKER_COUNT", "PYTEST_XDIST_TESTRUNUID"}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p",
                          "no:cacheprovider", "-m", "every_core", "-rs", "tests"],
                         cwd=Path(__file__).parents[1], env=env, capture_output=True, text=True)
    last = out.stdout.strip().splitlines()[-1]
    assert out.returncode == 0 and "passed" in last and "skipped" not in last, out.stdout[-3000:]
