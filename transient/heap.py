"""The C heap keeps the setup's freed blocks for its next arrays instead of handing them back.

glibc serves a block of 32 MB and more (its threshold's ceiling) by a fresh mapping and unmaps
it when freed, so each such array is faulted in afresh, page by page; so is the top of the heap
trimmed past twice the threshold. The setup makes and drops many (blocks of n x 128 responses,
a Lanczos step's n x 16 arrays, NNLS columns): with blocks up to RETAIN_BLOCK taken from the
heap and RETAIN_TOP of free memory kept at its top, it faults about half the pages in and
its peak stays where it was (docs/performance.md, "The heap"). The heap is the process's, so
only a process that asked (transient.configure: `permit`) retains. Freed blocks in the heap's
middle stay resident until reused, so a setup near the memory bound keeps glibc's defaults
(stages.prepare decides, from the case's estimate), and the retention ends with the setup
(`setup`): what is free is given back and the thresholds are left where glibc's own
adjustment takes them after large blocks are freed, so a notebook or a campaign's worker does
not keep a setup's peak for good. Only where the allocation happens changes, never the
arithmetic.
"""
import ctypes
import ctypes.util
from contextlib import contextmanager

RETAIN_BLOCK = 128_000_000    # bytes: blocks below this from the heap (glibc M_MMAP_THRESHOLD)
RETAIN_TOP = 512_000_000      # bytes of free memory kept at the heap's top (M_TRIM_THRESHOLD)
# glibc's dynamic thresholds after a large block is freed: the mmap threshold rises to the
# block's size, up to 32 MB on 64 bits (DEFAULT_MMAP_THRESHOLD_MAX), the trim one to twice it
SETTLED_BLOCK, SETTLED_TOP = 32 * 1024 * 1024, 64 * 1024 * 1024
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_state = {"retaining": False, "last_setup": False, "permitted": False}


def _libc():
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt, trim = libc.mallopt, libc.malloc_trim
    except (OSError, AttributeError):
        return None
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return mallopt, trim


def permit():
    """Let setups retain freed blocks (transient.configure: the heap is the process's)."""
    _state["permitted"] = True


def permitted():
    return _state["permitted"]


def retain_freed():
    """From here on, this process's heap keeps freed blocks up to RETAIN_BLOCK for reuse (and
    RETAIN_TOP at its top). glibc only: elsewhere it does nothing. Returns whether the heap
    retains them."""
    if _state["retaining"]:
        _state["last_setup"] = True
        return True
    libc = _libc()
    if libc is None:
        return False
    mallopt, _ = libc
    _state["retaining"] = bool(mallopt(_M_MMAP_THRESHOLD, RETAIN_BLOCK)
                               and mallopt(_M_TRIM_THRESHOLD, RETAIN_TOP))
    _state["last_setup"] = _state["retaining"]
    return _state["retaining"]


def settle():
    """End a retention: the free memory given back to the system (malloc_trim), the thresholds
    at glibc's settled values (SETTLED_BLOCK, SETTLED_TOP). Nothing when not retaining."""
    if not _state["retaining"]:
        return
    mallopt, trim = _libc()
    mallopt(_M_MMAP_THRESHOLD, SETTLED_BLOCK)
    mallopt(_M_TRIM_THRESHOLD, SETTLED_TOP)
    trim(0)
    _state["retaining"] = False


@contextmanager
def setup():
    """A setup's section: retain_freed may be called inside, and the retention ends with it."""
    _state["last_setup"] = False
    try:
        yield
    finally:
        settle()


def retaining():
    return _state["retaining"]


def last_setup_retained():
    """Whether the last setup section retained freed blocks."""
    return _state["last_setup"]
