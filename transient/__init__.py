"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes."""
import hashlib
import os
import sys
from pathlib import Path

# Idle OpenMP threads sleep instead of spinning: on a busy machine spinning threads stall every
# parallel region (measured here: 20x slower kernels at a load of 4 on 2 cores).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

# NumPy's arrays on small pages unless the user says otherwise (NumPy asks the kernel for 2 MB
# transparent huge pages on arrays of 4 MB and more). On a VM whose balloon hands freed memory
# back to the host (this machine's: virtio-balloon free page reporting), each huge page an
# array faults in is zeroed through the host at 0.1-0.2 GB/s: 35% of the setup's CPU samples
# sat in the kernel's clear_page, and `transient cea` on pad_disc took 32 s (17 s of system
# time) against 17.7 s (3.4 s) on small pages, `transient modes` 22 s against 9.4 s. On bare
# metal small pages cost a page fault per 4 KB, some 0.1-0.3 s per GB an array first touches.
# NumPy reads the variable at its import; when it came first, its switch does the same.
_HUGE = "NUMPY_MADVISE_HUGEPAGE"
if _HUGE not in os.environ:
    os.environ[_HUGE] = "0"          # also for the processes this one starts (Dask workers)
    if "numpy" in sys.modules:
        _core = getattr(sys.modules["numpy"], "_core", None) or sys.modules["numpy"].core
        _core.multiarray._set_madvise_hugepage(False)


def _numba_cache_dir():
    """A Numba cache keyed by the source of every module jitted code comes from: Numba checks
    only a function's own file, so a kernel that inlines a law or a signal from another module
    would otherwise keep a stale copy after that module changes."""
    here = Path(__file__).parent
    digest = hashlib.sha1()
    for path in [here / "jit.py"] + sorted((here / "kernels").glob("*.py")):
        digest.update(path.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    return str(base / "transient" / "numba" / digest.hexdigest()[:16])


os.environ.setdefault("NUMBA_CACHE_DIR", _numba_cache_dir())

__version__ = "0.1.0"
