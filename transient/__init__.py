"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes."""
import hashlib
import os
from pathlib import Path

# Idle OpenMP threads sleep instead of spinning: on a busy machine spinning threads stall every
# parallel region (measured here: 20x slower kernels at a load of 4 on 2 cores).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


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
