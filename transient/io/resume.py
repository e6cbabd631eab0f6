"""What a resumed run continues from, read back from its history: the system it integrated,
the state, step, time step, row blocks and energy balance of its last checkpoint. The case
given to resume must be the one stored, but for the keys a resume may change
(case.compare.RESUMABLE); anything else is refused by name."""
from dataclasses import dataclass

import h5py
import numpy as np

from ..case.compare import RESUMABLE, changed
from ..case.loading import parse
from ..dynamics.state import State
from ..errors import CaseError
from .history import CASE_TEXT, CHECKPOINT, _read_attrs, _rows, load_checkpoint
from .systems import GROUP, read_system


@dataclass(frozen=True)
class Resumed:
    system: object           # the ReducedSystem or FullSystem the run integrated
    state: State             # at the last checkpoint
    step: int                # steps done there
    dt: float
    blocks: np.ndarray       # row blocks of the reduced contact pass (the summation order)
    balance: np.ndarray      # (3,) the energy balance there: E(0), peak, drift
    meta: dict               # the history's root attributes


def resumed(path, case):
    """The run stored at path, to continue with case (which must be the one it ran)."""
    try:
        with h5py.File(path, "r", locking=False) as f:
            _rows(f, path)
            meta = _read_attrs(f.attrs)
            if GROUP not in f or CHECKPOINT not in f:
                raise CaseError(path, "--resume", "the history keeps no system or checkpoint "
                                "to resume from (written by an older version, or stopped "
                                "before its first chunk): run it again")
            system = read_system(f)
        saved = load_checkpoint(path)
        stored = parse(meta[CASE_TEXT], meta["case_path"], meta.get("overrides") or [])
        dt = float(meta["dt"])
        state = State(saved["state"], saved["acc"], saved["gmin"])
        step, blocks, balance = int(saved["step"][0]), saved["blocks"], saved["balance"]
    except (KeyError, ValueError, TypeError, OSError) as exc:
        raise CaseError(path, "--resume", f"not a history to resume ({exc})") from None
    try:
        _fits(system, state, blocks)
    except (ValueError, TypeError, IndexError) as exc:
        raise CaseError(path, "--resume", f"damaged history: {exc}") from None
    keys = changed(stored, case)
    if keys:
        raise CaseError(case.path, keys[0], f"--resume: differs from the case the history "
                        f"was run with ({', '.join(keys)}); a resumed run may change only "
                        f"{', '.join(RESUMABLE)}")
    return Resumed(system, state, step, dt, blocks, balance, meta)


def _fits(system, state, blocks):
    """Raise ValueError unless the stored system and checkpoint fit together: the kernels
    index with these sizes and trust them (a damaged file must not reach them)."""
    import scipy.sparse as sp
    n, m = system.n, system.n_points
    c = system.contacts
    shapes = {"state": (state.array.shape, (6, n)), "gmin": (state.gmin.shape, (m,)),
              "weights": (c.weights.shape, (m,)), "code": (c.code.shape, (m,)),
              "params": (c.params.shape, (m, 4)), "tangent": (system.tangent.shape, (m,)),
              "C": (system.C.shape, (m, n)), "sensors": (system.sensors.shape[1:], (n,))}
    if system.reduced:
        shapes.update({"omega2": (system.omega2.shape, (n,)), "damp": (system.damp.shape, (n,))})
    else:
        shapes.update({"K": (system.K.shape, (n, n)), "M": (system.M.shape, (n, n)),
                       "mass": (system.mass.shape, (n,))})
    for name, (got, want) in shapes.items():
        if tuple(got) != want:
            raise ValueError(f"stored {name} has shape {tuple(got)}, expected {want}")
    for A in (system.C, system.sensors) + (() if system.reduced else (system.K, system.M)):
        if sp.issparse(A):
            A.check_format(full_check=True)
    codes, params, table_t, table_v, table_n = system.signals
    J = system.patterns.shape[0]
    if (len(codes) != J or params.shape != (J, 8) or table_t.shape != table_v.shape
            or len(table_t) != J or len(table_n) != J or np.any(table_n > table_t.shape[1])
            or np.any(table_n < 0) or np.any((codes < 0) | (codes > 5))):
        raise ValueError("stored signals do not fit the load patterns")
    if np.any((c.code < 0) | (c.code > 2)):
        raise ValueError("stored contact laws are not known")
    blocks = np.asarray(blocks)
    if system.reduced and (len(blocks) < 2 or blocks[0] != 0 or blocks[-1] != m
                           or np.any(np.diff(blocks) < 0)):
        raise ValueError("stored row blocks do not cover the contact points")

