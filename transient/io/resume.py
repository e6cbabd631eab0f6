"""What a resumed run continues from, read back from its history: the system it integrated,
the state, step, time step, row blocks and energy balance of its last checkpoint. The case
given to resume must be the one stored, but for the keys a resume may change
(case.compare.RESUMABLE); anything else is refused by name."""
from dataclasses import dataclass

import numpy as np

from ..case.compare import RESUMABLE, changed
from ..dynamics.state import State
from ..kernels.layout import ACC_SLOTS, STATE_ROWS
from ..errors import CaseError, DamagedHistory
from ..kernels.codes import BILATERAL, TABLE
from .attributes import read_attrs
from .history import CHECKPOINT
from .reading import check_appendable, load_checkpoint, verified
from .series import layout
from .stored import run_case
from .systems import GROUP, read_system


@dataclass(frozen=True)
class Resumed:
    system: object           # the ReducedSystem or FullSystem the run integrated
    state: State             # at the last checkpoint
    step: int                # steps of dt done there
    dt: float                # the step there (the run's first, or subdivided)
    blocks: np.ndarray       # row blocks of the reduced contact pass (the summation order)
    balance: np.ndarray      # (3,) the energy balance there: E(0), peak, drift
    meta: dict               # the history's root attributes
    every: int = 0           # steps of dt between rows (0: the case's, an older history)
    taken: int = 0           # steps made from t = 0 (a subdivided step's count differs)


def resumed(path, case):
    """The run stored at path, to continue with case (which must be the one it ran); the
    caller holds the history's lock (io.lock.writing), under which a killed run's cut-short
    append is repaired (io.reading.verified)."""
    try:
        with verified(path, held=True) as (f, _):
            meta = read_attrs(f.attrs)
            if GROUP not in f or CHECKPOINT not in f:
                raise CaseError(path, "--resume", "the history keeps no system or checkpoint "
                                "to resume from (written by an older version, or stopped "
                                "before its first chunk): run it again")
            system = read_system(f)
            saved = load_checkpoint(path)
            _fits(system, saved)
            if "dt" not in meta:
                raise DamagedHistory("attribute dt", "missing")
            stored = run_case(path, meta)
            # the series the run appends to, as the stored case's output names them
            check_appendable(f, layout(system, stored.output))
    except DamagedHistory as exc:
        raise CaseError(path, exc.key, f"damaged history, cannot resume: {exc.message}") \
            from None
    except (KeyError, ValueError, TypeError, IndexError, OSError, RuntimeError) as exc:
        # RuntimeError: h5py's on a corrupted file
        raise CaseError(path, "--resume", f"not a history to resume ({exc})") from None
    keys = changed(stored, case)
    if keys:
        raise CaseError(case.path, keys[0], f"--resume: differs from the case the history "
                        f"was run with ({', '.join(keys)}); a resumed run may change only "
                        f"{', '.join(RESUMABLE)}")
    state = State(_padded(saved["state"], (STATE_ROWS, system.n)),
                  _padded(saved["acc"], (ACC_SLOTS,)), saved["gmin"])
    step = int(saved["step"][0])
    # a history before the step's subdivision keeps its step in the attributes only
    dt = float(saved["dt"][0]) if "dt" in saved else float(meta["dt"])
    return Resumed(system, state, step, dt, saved["blocks"], saved["balance"], meta,
                   int(saved["every"][0]) if "every" in saved else 0,
                   int(saved["taken"][0]) if "taken" in saved else step)


def _fits(system, saved):
    """Raise DamagedHistory unless the stored system and checkpoint fit together: the kernels
    index with these sizes and trust them (a damaged file must not reach them)."""
    import scipy.sparse as sp
    n, m = system.n, system.n_points
    c = system.contacts
    # blocks: any length on a full system, which does not use them
    checkpoint = {"state": (STATE_ROWS, n), "acc": (ACC_SLOTS,), "gmin": (m,), "step": (1,),
                  "balance": (3,), "blocks": (len(np.atleast_1d(saved.get("blocks", ()))),)}
    # an earlier version's state and accumulators, without the friction's rows
    legacy = {"state": (6, n), "acc": (3,)} if system.contacts.friction is None else {}
    # the step, rows and steps made: kept since the step may be subdivided
    optional = {"dt": (1,), "every": (1,), "taken": (1,)}
    for name, want in {**checkpoint, **optional}.items():
        value = saved.get(name)
        if value is None and name in optional:
            continue
        if value is None:
            raise DamagedHistory(f"{CHECKPOINT}/{name}", "missing")
        kinds = {"step": "iu", "blocks": "fiu", "every": "iu", "taken": "iu"}.get(name, "f")
        if value.shape not in (want, legacy.get(name)) or value.dtype.kind not in kinds:
            raise DamagedHistory(f"{CHECKPOINT}/{name}", f"a {value.dtype} array of shape "
                                 f"{value.shape}, expected {want} "
                                 + ("integers" if kinds == "iu" else "numbers"))
        low = 0 if name == "taken" else np.nextafter(0, 1)
        if name in optional and not low <= value[0] < np.inf:
            raise DamagedHistory(f"{CHECKPOINT}/{name}", f"{value[0]}, expected "
                                 + ("a step > 0" if name == "dt" else "a count"))
    # None: any length (the sensors' rows)
    arrays = {"contacts/gap0": (c.gap0, (m,)), "contacts/weights": (c.weights, (m,)),
              "contacts/code": (c.code, (m,)), "contacts/params": (c.params, (m, 4)),
              "contacts/C": (c.C, (m, None)), "tangent": (system.tangent, (m,)),
              "patterns": (system.patterns, (None, n)), "sensors": (system.sensors, (None, n)),
              "critical/kt_checked": (system.critical.kt_checked, (m,)),
              "critical/rows": (system.critical.rows, (m,)), "C": (system.C, (m, n))}
    if system.reduced:
        arrays.update({"omega2": (system.omega2, (n,)), "damp": (system.damp, (n,))})
    else:
        arrays.update({"K": (system.K, (n, n)), "M": (system.M, (n, n)),
                       "mass": (system.mass, (n,)), "free": (system.free, (n,))})
    for name, (A, want) in arrays.items():
        shape = tuple(np.shape(A))
        if len(shape) != len(want) or any(w not in (None, s) for s, w in zip(shape, want)):
            raise DamagedHistory(f"{GROUP}/{name}", f"shape {shape}, expected "
                                 + str(want).replace("None", "any"))
        # the kernels are compiled for float64 values and int64 codes and indices
        integers = name in ("contacts/code", "free")
        dtype = getattr(A, "dtype", np.dtype(object))
        if dtype.kind not in ("iu" if integers else "f"):
            raise DamagedHistory(f"{GROUP}/{name}", f"{dtype} data, expected "
                                 + ("integers" if integers else "floating point numbers"))
    for name in ("C", "sensors") + (() if system.reduced else ("K", "M")):
        A = getattr(system, name)
        if sp.issparse(A):
            try:
                A.check_format(full_check=True)
            except (ValueError, TypeError, IndexError) as exc:
                raise DamagedHistory(f"{GROUP}/{name}", f"not a sparse matrix ({exc})") \
                    from None
    codes, params, table_t, table_v, table_n = system.signals
    for k, (A, kinds) in enumerate(zip(system.signals, ("iu", "f", "f", "f", "iu"))):
        dtype = getattr(A, "dtype", np.dtype(object))
        if dtype.kind not in kinds:
            raise DamagedHistory(f"{GROUP}/signals/{k}", f"{dtype} data, expected "
                                 + ("integers" if kinds == "iu" else "floating point numbers"))
    J = system.patterns.shape[0]
    if (len(codes) != J or params.shape != (J, 8) or table_t.shape != table_v.shape
            or len(table_t) != J or len(table_n) != J or np.any(table_n > table_t.shape[1])
            or np.any(table_n < 0) or np.any((codes < 0) | (codes > TABLE))):
        raise DamagedHistory(f"{GROUP}/signals", "the signals do not fit the load patterns")
    if np.any((c.code < 0) | (c.code > BILATERAL)):
        raise DamagedHistory(f"{GROUP}/contacts/code", "contact laws that are not known")
    blocks = saved["blocks"]
    if system.reduced and (len(blocks) < 2 or blocks[0] != 0 or blocks[-1] != m
                           or np.any(np.diff(blocks) < 0) or np.any(blocks % 1 != 0)):
        raise DamagedHistory(f"{CHECKPOINT}/blocks", "row blocks that do not cover the "
                             "contact points")


def _padded(a, shape):
    """a with zeros after its rows up to shape (an earlier version's checkpoint)."""
    if a.shape == shape:
        return a
    out = np.zeros(shape)
    out[tuple(slice(0, k) for k in a.shape)] = a
    return out
