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
    if state.array.shape != (6, system.n) or len(state.gmin) != system.n_points:
        raise CaseError(path, "--resume", "damaged history: its checkpoint does not fit its "
                        "system")
    keys = changed(stored, case)
    if keys:
        raise CaseError(case.path, keys[0], f"--resume: differs from the case the history "
                        f"was run with ({', '.join(keys)}); a resumed run may change only "
                        f"{', '.join(RESUMABLE)}")
    return Resumed(system, state, step, dt, blocks, balance, meta)
