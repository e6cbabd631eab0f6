"""The process-wide settings that speed transient up, made by `configure()` and never by an
import: the command line and a campaign's Dask workers call it, a notebook user may.

Each one changes the whole process (its environment, NumPy, the OpenMP runtime, the C heap),
so it is the caller's choice; none changes a result, only where memory comes from and how
threads wait. The figures behind them are in the manual's performance page
(docs/performance.md).
"""
import os
import sys

# Idle OpenMP threads sleep instead of spinning, which on a loaded machine stalls every
# parallel region; the runtime reads it when it starts.
WAIT_POLICY = ("OMP_WAIT_POLICY", "PASSIVE")
# NumPy's arrays on small pages: a huge page an array first touches is zeroed through the host
# on a VM whose balloon hands freed memory back, far slower than small pages' faults.
HUGE_PAGES = ("NUMPY_MADVISE_HUGEPAGE", "0")

_done = []


def configure():
    """Make the settings that speed transient up, for this process and those it starts.

    Call it once, first: before the first setup (``transient.stages.prepare``) and before
    any parallel kernel runs. Later calls do nothing. A variable the user has set already is
    kept. It makes four settings, each for the reason given (figures: docs/performance.md):

    - ``OMP_WAIT_POLICY=PASSIVE``: idle OpenMP threads sleep instead of spinning, which on a
      loaded machine stalls every parallel region.
    - ``NUMPY_MADVISE_HUGEPAGE=0`` (and NumPy's switch when NumPy is imported already): arrays
      on small pages, since a ballooned VM zeroes each huge page through its host.
    - MKL's OpenMP runtime (libiomp5) loaded before Numba starts its thread pool, so the
      kernels' threads are the ones ``transient.jit.spinning`` can keep awake between steps.
    - The C heap keeps a setup's freed blocks for its next arrays (``transient.heap``) in
      setups far below ``limits.memory``, instead of faulting each one in afresh.

    The Numba cache needs no call: every kernel is cached under ``transient.jit.cache_dir()``
    (``NUMBA_CACHE_DIR`` when set, else a directory keyed by the kernels' sources).
    """
    if _done:
        return
    for name, value in (WAIT_POLICY, HUGE_PAGES):
        os.environ.setdefault(name, value)
    numpy = sys.modules.get("numpy")
    if numpy is not None and os.environ[HUGE_PAGES[0]] == HUGE_PAGES[1]:
        # NumPy read the variable at its import: its switch does the same now
        core = getattr(numpy, "_core", None) or numpy.core
        core.multiarray._set_madvise_hugepage(False)
    from . import heap, jit
    jit.load_iomp()
    heap.permit()
    _done.append(True)
