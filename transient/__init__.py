"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes."""
import os

# Idle OpenMP threads sleep instead of spinning: on a busy machine spinning threads stall every
# parallel region (measured here: 20x slower kernels at a load of 4 on 2 cores).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

__version__ = "0.1.0"
