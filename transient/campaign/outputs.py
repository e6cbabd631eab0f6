"""What a campaign finds at each path it will write, judged before any work starts.

Every path is absent, or an output of this package (a history: io.lock.is_history; complex
modes and the campaign's tables: files that carry folder.MARK), or the campaign is refused in
one line naming it: nothing else is ever replaced. An output of this package is then the
variant's own when the case it stores (text, path and overrides) is the variant's but for the
keys a resumed run may change (case.compare.RESUMABLE), as `transient run --resume` checks.
With --resume, a variant's complete outputs are read back, a history stopped short of the new
t_end (killed, interrupted, or a shorter run) continues from its checkpoint, bit for bit with
a fresh run, and anything else of its own is made again; an output of another case is refused
by name, as is a history longer than the new t_end (made again, it would be lost).
"""
import fcntl
import json
import re
from dataclasses import dataclass
from pathlib import Path

from ..case.compare import changed
from ..errors import CaseError, DamagedHistory
from .folder import MARK, modes_file
from .variants import WHERE

# a run stopped from outside (killed, Ctrl-C, SIGTERM): what it stored goes on as it would have
CONTINUED = ("running", "aborted: interrupted", "aborted: terminated")
NAME = re.compile(r"v(\d{3,}|-[0-9a-f]{12})")


@dataclass(frozen=True)
class Plan:
    """What to do with each variant: its row read back from complete outputs (done), or
    'fresh' (made anew) or 'continue' (its history resumed; its complex modes, if any, done)."""
    done: dict               # variant name -> its row read back from its complete outputs
    todo: dict               # variant name -> 'fresh' or 'continue'


def outputs(out, name, kind):
    """A variant's files: its history (run), its complex modes (cea), or both, history first."""
    history, modes = Path(out) / f"{name}.h5", Path(out) / f"{name}.json"
    return {"run": [history], "cea": [modes], "both": [history, modes]}[kind]


def plan(out, variants, cases, kind, resume):
    """The Plan of a campaign in the folder out (variants, and each one's loaded Case by
    name); CaseError on the first path it must not write, or, resuming, on the first output
    of another case."""
    for table in ("sweep.csv", "sweep.json"):
        _check_table(Path(out) / table)
    done, todo = {}, {}
    for v in variants:
        states = [_state(path, cases[v.name], resume) for path in outputs(out, v.name, kind)]
        for path, (state, why) in zip(outputs(out, v.name, kind), states):
            if state == "other":
                raise CaseError(path, "--resume", f"variant {v.name} ({v.label()}): {why}: "
                                "not replaced (remove it, or choose another --out)")
        states = [s for s, _ in states]
        row = _restored(outputs(out, v.name, kind)) if all(s == "done" for s in states) \
            else None
        if row is not None:
            done[v.name] = row
        elif states[0] == "continue" and all(s == "done" for s in states[1:]):
            todo[v.name] = "continue"
        else:
            todo[v.name] = "fresh"
    return Plan(done, todo)


def _restored(paths):
    """The row of a variant read back from its complete outputs; None if one cannot be read
    (of this package and the variant's: made again)."""
    from .tasks import cea_summary, summary
    row = {"status": "complete", "resumed": True}
    try:
        for path in paths:
            row.update(cea_summary(modes_file(path)["modes"]) if path.suffix == ".json"
                       else summary(path))
    except (DamagedHistory, OSError, KeyError, ValueError, TypeError, RuntimeError):
        return None
    return row


def _state(path, case, resume):
    """(state, why) of one output path: 'fresh' (absent, or of this package and to be made
    again), 'done', 'continue' or 'other' (why: what differs)."""
    kind = _kind(path)
    if kind is None:
        return "fresh", ""
    if kind != "file":
        raise CaseError(path, "--out", f"is {kind}: expected a {_what(path)} or nothing")
    if path.suffix == ".h5":
        return _history_state(path, case, resume)
    stored = modes_file(path)
    if stored is None:
        raise CaseError(path, "--out", "exists and is not complex modes written by transient "
                        "sweep: not overwritten (choose another --out)")
    if not resume:
        return "fresh", ""
    differs = _differs(path, stored, case)
    if differs:
        return "other", differs
    return ("done" if stored.get("status") == "complete" else "fresh"), ""


def _history_state(path, case, resume):
    from ..io.lock import is_history
    if not is_history(path):
        raise CaseError(path, "--out", "exists and is not a history written by transient: not "
                        "overwritten (choose another --out)")
    _check_unlocked(path)
    if not resume:
        return "fresh", ""
    try:
        meta, step = _stored_run(path)
    except (DamagedHistory, OSError, KeyError, ValueError, TypeError, RuntimeError):
        # a history of this package that cannot be continued: made again
        return "fresh", ""
    differs = _differs(path, meta, case)
    if differs:
        return "other", differs
    status = meta.get("status")
    steps = int(round(case.solver.t_end / meta["dt"]))
    if status == "complete" and step is not None and step > steps:
        return "other", (f"holds a longer run ({step} steps of {meta['dt']:.4g} s, "
                         f"solver.t_end {case.solver.t_end:g} s makes {steps})")
    if status == "complete" and step == steps:
        return "done", ""
    if step is not None and step <= steps and (status == "complete"
                                               or status.startswith(CONTINUED)):
        return "continue", ""
    return "fresh", ""


def _stored_run(path):
    """(root attributes, steps of its checkpoint or None) of a history."""
    import h5py
    from ..io.attributes import read_attrs
    from ..io.history import CHECKPOINT, SYSTEM
    from ..io.reading import load_checkpoint
    with h5py.File(path, "r", locking=False) as f:
        meta = read_attrs(f.attrs)
        # a resume continues the system the history stores, from its checkpoint
        has_checkpoint = CHECKPOINT in f and SYSTEM in f
    if not isinstance(meta.get("dt"), float) or not isinstance(meta.get("status"), str):
        raise ValueError("no time step or status")
    step = int(load_checkpoint(path)["step"][0]) if has_checkpoint else None
    return meta, step


def _differs(path, stored, case):
    """What differs between the case an output stores and the variant's ('' if nothing)."""
    from ..io.stored import run_case
    try:
        keys = changed(run_case(path, stored), case)
    except CaseError as exc:
        return f"its stored case does not load ({exc.message})"
    except (TypeError, ValueError, AttributeError, RecursionError) as exc:
        # complex modes whose stored case, path or overrides are not text (edited by hand)
        return f"its stored case does not load ({type(exc).__name__}: {exc})"
    if keys:
        return (f"made with another case ({', '.join(keys[:5])}"
                + (", ..." if len(keys) > 5 else "")
                + (" differ)" if len(keys) > 1 else " differs)"))
    return ""


def _check_unlocked(path):
    """Refuse a history another run is writing (it holds the history's flock: io.lock)."""
    with open(path, "rb") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise CaseError(path, "--out", "another run is writing this history") from None
        fcntl.flock(f, fcntl.LOCK_UN)


def _kind(path):
    """None (absent or empty: what an interrupted writer leaves), 'file', or what else it
    is."""
    try:
        if path.is_symlink() and not path.exists():
            return "a broken link"
        if not path.exists():
            return None
        if path.is_dir():
            return "a directory"
        if not path.is_file():
            return "a device, pipe or socket"
        return "file" if path.stat().st_size else None
    except (OSError, ValueError) as exc:
        raise CaseError(path, "--out", f"not a usable file name ({exc})") from None


def _what(path):
    return {".h5": "history", ".json": "JSON file"}.get(path.suffix, "table")


def _check_table(path):
    """Refuse a sweep.csv or sweep.json that is not a campaign's table."""
    kind = _kind(path)
    if kind is None:
        return
    if kind != "file":
        raise CaseError(path, "--out", f"is {kind}: expected a sweep's table or nothing")
    if not (is_sweep_json(path) if path.suffix == ".json" else is_sweep_csv(path)):
        raise CaseError(path, "--out", "exists and is not a table written by transient "
                        "sweep: not overwritten (choose another --out)")


def is_sweep_json(path):
    """sweep.json as a campaign writes it (an earlier version's without the mark too)."""
    from .tasks import KINDS
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError, RecursionError):
        return False
    return (isinstance(data, dict) and data.get("kind") in KINDS
            and isinstance(data.get("rows"), list) and isinstance(data.get("parameters"), list)
            and data.get("written_by", MARK) == MARK)


def is_sweep_csv(path):
    """sweep.csv as a campaign writes it: its first columns, and a variant's name on each
    row."""
    import csv
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except (OSError, ValueError, csv.Error):
        return False
    return (bool(rows) and rows[0][:3] == ["variant", "status", "seconds"]
            and all(row and NAME.fullmatch(row[0]) for row in rows[1:]))
