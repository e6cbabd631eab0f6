"""The setups this machine has timed, and the time a new one is estimated to take from them.

A setup's time depends on the machine as much as on the model (its cores, its memory's speed,
what else runs), so no figure measured elsewhere is a fair estimate. Each setup that ends
(stages.prepare, from scratch; `transient modes` whole) appends a line to a log in the user's
cache: the host, the kind (assembled, components or full, for a run or a cea; modes), the
model's element-matrix entries and contact fine points, and its seconds. `--dry-run` estimates from the lines of the same host and path: the setups'
time grows as a power of the entries, fitted over two sizes or more, and from a single size
scaled between the powers measured on the pad and disc family (EXPONENTS: 1.33 on the
components path, 1.65 on the assembled one, docs/performance.md). None before any setup
of that path ran on this host.

TRANSIENT_SETUP_LOG names the log (`off`: none is read or written).
"""
import json
import math
import os
import platform
from pathlib import Path

EXPONENTS = (1.3, 1.7)     # the range of the measured growth of a setup with its entries
KEPT = 200                 # the newest lines read


def log_path():
    """The log's path, or None when TRANSIENT_SETUP_LOG is `off`."""
    named = os.environ.get("TRANSIENT_SETUP_LOG")
    if named == "off":
        return None
    if named:
        return Path(named)
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "transient" / "setups.jsonl"


def kind(case, analysis):
    """The kind of setup a case makes, as the log keys it: the reduction's method (or the
    full model's) and whether it is an analysis' (cea) or a run's."""
    reduction = case.solver.reduction
    method = reduction.method if reduction.enabled else "full"
    return f"{method}/{'cea' if analysis else 'run'}"


def record(path_kind, entries, fine_points, seconds):
    """One setup timed, appended as one line (one write: lines of processes that end at once
    do not interleave). A log that cannot be written is skipped: it never fails a setup."""
    path = log_path()
    if path is None or not seconds > 0:
        return
    line = json.dumps({"host": platform.node(), "path": path_kind, "entries": int(entries),
                       "fine_points": int(fine_points), "seconds": float(seconds)}) + "\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, line.encode())
        finally:
            os.close(fd)
    except OSError:
        pass


def record_setup(path_kind, model, pairs, seconds):
    """record of a setup of model (its element-matrix entries) with its contact pairs (their
    fine rules' points)."""
    from .case.sizes import entries, parts_cells
    record(path_kind, entries(parts_cells(model.parts)),
           sum(p.interface.fine.n_points for p in pairs), seconds)


def _timed(path_kind):
    """(entries, seconds) of the log's newest setups of this host on this path."""
    path = log_path()
    if path is None or not path.is_file():
        return []
    host, out = platform.node(), []
    try:
        lines = path.read_text().splitlines()[-KEPT:]
    except OSError:
        return []
    for line in lines:
        try:
            r = json.loads(line)
            if r["host"] == host and r["path"] == path_kind and r["entries"] > 0 \
                    and r["seconds"] > 0:
                out.append((float(r["entries"]), float(r["seconds"])))
        except (ValueError, KeyError, TypeError):
            continue          # a line of another version, or cut short: not this estimate's
    return out


def estimate(path_kind, entries):
    """{"low", "high" [s], "setups": how many it is from} for a setup of `entries` on this
    host and path, or None before any ran here. Fitted t = c entries^p over two sizes or
    more (p held within EXPONENTS), the range the fit's largest residual; from one size,
    its setups' times scaled at both EXPONENTS."""
    timed = _timed(path_kind)
    if not timed:
        return None
    x = [math.log(e) for e, _ in timed]
    y = [math.log(s) for _, s in timed]
    target = math.log(entries)
    if max(x) - min(x) > math.log(1.5):
        mx, my = sum(x) / len(x), sum(y) / len(y)
        p = sum((a - mx) * (b - my) for a, b in zip(x, y)) / sum((a - mx) ** 2 for a in x)
        p = min(max(p, EXPONENTS[0]), EXPONENTS[1])
        c = my - p * mx
        spread = max(abs(b - c - p * a) for a, b in zip(x, y))
        mid = c + p * target
        low, high = math.exp(mid - spread), math.exp(mid + spread)
    else:
        scaled = [b + q * (target - a) for a, b in zip(x, y) for q in EXPONENTS]
        low, high = math.exp(min(scaled)), math.exp(max(scaled))
    return {"low": low, "high": high, "setups": len(timed)}
