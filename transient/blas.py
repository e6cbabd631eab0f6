"""Thread counts of the setup's dense algebra (OpenBLAS, through threadpoolctl), and the MKL
runtime whose threads (PARDISO's) this_thread_alone sets and solve.linsolve calls: the
process's numerical runtimes, on the ground floor every stage may import.

The setup runs on one OpenBLAS thread (stages.prepare): most of its dense calls are mid-sized
and come between PARDISO's solves, whose MKL threads two OpenBLAS threads contend with. The
large products of a section that solves nothing run on every core (`every_core`), where they
scale (docs/performance.md, "Threads of the setup's dense algebra").

The section, not a timing, decides, so the arithmetic is the same run after run: OpenBLAS splits
a product by blocks of its result, each summed whole by one thread. Two threads sum some entries
in another order than one thread does, a difference of round-off (1e-16 of the entries).
"""
import ctypes
import functools
import os
import sys
from contextlib import contextmanager
from ctypes.util import find_library
from pathlib import Path


@functools.cache
def _openblas():
    from threadpoolctl import ThreadpoolController
    return ThreadpoolController().select(internal_api="openblas")


@contextmanager
def one_thread():
    """OpenBLAS on one thread inside (the setup's default)."""
    with _openblas().limit(limits=1):
        yield


def budget():
    """The threads this process may use: the cores it may run on, capped by
    OPENBLAS_NUM_THREADS or OMP_NUM_THREADS when set (a campaign's one-thread workers: N of
    them share the cores, and every_core taking both on each made the setup's stages 2-5
    times slower, 6 variants of pad_disc slower on two workers than one by one)."""
    cores = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
             else os.cpu_count() or 1)
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        value = os.environ.get(name, "")
        if value.isdigit() and int(value) > 0:
            cores = min(cores, int(value))
    return cores


@contextmanager
def every_core():
    """OpenBLAS on every core this process may use (budget), inside; as before, after."""
    with _openblas().limit(limits=budget()):
        yield


@contextmanager
def this_thread_alone():
    """Numba's and MKL's threads at one for the calling thread only, inside (both set per
    thread; OpenBLAS's count is the process's: hold one_thread around both threads): work
    beside another thread's on a core of its own, with one thread's arithmetic wherever it
    runs (PARDISO's conditional reproducibility is per thread count)."""
    import numba
    try:
        mkl = mkl_runtime()
    except (ImportError, OSError):
        mkl = None
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    local = mkl.MKL_Set_Num_Threads_Local(1) if mkl is not None else None
    try:
        yield
    finally:
        numba.set_num_threads(before)
        if mkl is not None:
            mkl.MKL_Set_Num_Threads_Local(local)


@functools.cache
def mkl_runtime():
    """The MKL runtime (mkl_rt, which the pypardiso wheel brings), loaded once a process.

    Looked for where pypardiso looks, without its cost: importing pypardiso builds a solver
    at import, and each solver it builds globs the environment's whole lib tree for mkl_rt
    when the loader's path lacks it, several times a process. The wheel puts it in the
    environment's lib directory, read here first; pypardiso's own search is the fallback
    (another layout, Windows)."""
    path = os.environ.get("PYPARDISO_MKL_RT") or find_library("mkl_rt")
    if path is None:
        import site
        found = [p for root in (sys.prefix, site.USER_BASE)
                 for p in sorted(Path(root, "lib").glob("libmkl_rt.so*"), key=lambda p:
                                 len(p.name))]
        path = str(found[0]) if found else None
    if path is None:
        from pypardiso import PyPardisoSolver
        return PyPardisoSolver().libmkl
    return ctypes.CDLL(path)
