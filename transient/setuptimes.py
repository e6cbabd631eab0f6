"""The setups this machine has timed, and the time a new one is estimated to take from them.

A setup's time depends on the machine as much as on the model (its cores, its memory's speed,
what else runs), so no figure measured elsewhere is a fair estimate. Each setup that ends
(stages.prepare, from scratch; `transient modes` whole) appends a line to a log in the user's
cache: the host, the kind (assembled, components or full, for a run or a cea; modes), the
model's element-matrix entries and contact fine points, and its seconds. `--dry-run` estimates
from the lines of the same host and path: the setups' time grows as a power of the entries,
fitted over two sizes or more, and from a single size scaled between the powers measured on
the pad and disc family (EXPONENTS: 1.33 on the components path, 1.65 on the assembled one,
docs/performance.md).

Before any setup of a path ran on this host, from this machine's calibration of the path: the
package's own setup of a small pad and disc (transient.calibration), timed in a child process
so that nothing of the caller's changes (its heap's settings, its threads, its peak memory,
its arithmetic), once a package version and at most every MAX_AGE; its line in the same log
says so (`calibration`, not `path`: no setup's estimate reads it). Its seconds are scaled to
the model's entries at the GROWTH exponents.

TRANSIENT_SETUP_LOG names the log (`off`: none is read or written, and no calibration made).
"""
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from . import progress

EXPONENTS = (1.3, 1.7)     # the range of the measured growth of a setup with its entries
# the range of the power of the entries' ratio that takes the calibration's seconds to a real
# setup's on the pad and disc family (docs/performance.md, "Setup time before any setup ran")
GROWTH = (0.7, 1.1)
KEPT = 200                 # the newest lines read
MAX_AGE = 30 * 86400.0     # a calibration older [s] is made again: the machine may have changed
TIMEOUT = 180.0            # a calibration that takes longer [s] is no estimate of this machine
# a model this large (element-matrix entries; the 4x pad_disc has a little more) takes minutes
# to set up on every machine measured: worth a calibration before its setup, a small share of it
LONG = 50e6


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
    """One setup timed, appended as one line. A log that cannot be written is skipped: it never
    fails a setup."""
    if seconds > 0:
        _append({"host": platform.node(), "path": path_kind, "entries": int(entries),
                 "fine_points": int(fine_points), "seconds": float(seconds)})


def _append(record):
    """A line appended to the log, in one write: lines of processes that end at once do not
    interleave."""
    path = log_path()
    if path is None:
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, (json.dumps(record) + "\n").encode())
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


def announce(path_kind, model):
    """On a terminal (progress.shown), a line as a setup from scratch starts: its time as
    estimated here. It calibrates the machine first only before a model of LONG entries or
    more: a shorter setup is said from what is known already, or not at all."""
    if not progress.showing():
        return
    from .case.sizes import entries, parts_cells
    size = entries(parts_cells(model.parts))
    found = estimate(path_kind, size, size >= LONG, progress.started)
    if found is not None:
        source = (f"from {found['setups']} setup(s) of its kind timed here"
                  if found["source"] == "setups" else "from this machine's calibration")
        progress.started(f"setup: about {_minutes(found['low'])} to "
                         f"{_minutes(found['high'])} ({source})")


def _minutes(seconds):
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def _records():
    """The log's newest lines of this host, as dicts (those cut short or not JSON left out)."""
    path = log_path()
    if path is None or not path.is_file():
        return []
    try:
        lines = path.read_bytes().decode(errors="replace").splitlines()[-KEPT:]
    except OSError:
        return []
    out, host = [], platform.node()
    for line in lines:
        try:
            r = json.loads(line)
        except ValueError:
            continue
        if isinstance(r, dict) and r.get("host") == host:
            out.append(r)
    return out


def _timed(records, path_kind):
    """(entries, seconds) of the setups of a path."""
    out = []
    for r in records:
        try:
            if r["path"] == path_kind and r["entries"] > 0 and r["seconds"] > 0:
                out.append((float(r["entries"]), float(r["seconds"])))
        except (KeyError, TypeError):
            continue          # a calibration, or a line of another version: no setup's
    return out


# a calibration that failed within MAX_AGE: not tried again before (each try may take TIMEOUT)
FAILED = {"failed": True}


def calibrated(records, path_kind, version, now=None):
    """{"entries", "seconds"} of this host's newest calibration of a path at this version made
    within MAX_AGE, FAILED where that one failed, or None."""
    now = time.time() if now is None else now
    host = platform.node()
    for r in reversed(records):
        try:
            if (r["calibration"], r["version"], r["host"]) != (path_kind, version, host) \
                    or not 0 <= now - r["time"] <= MAX_AGE:
                continue
            if r.get("failed"):
                return FAILED
            if r["entries"] > 0 and r["seconds"] > 0:
                return {"entries": float(r["entries"]), "seconds": float(r["seconds"])}
        except (KeyError, TypeError):
            continue
    return None


def measure(path_kind):
    """{"entries", "seconds"} of this machine's calibration of a path (transient.calibration),
    in a child process with the log off (its setups are no setups of the log); None if it
    failed or took over TIMEOUT: an estimate is never worth failing a command."""
    argv = [sys.executable, "-m", "transient.calibration", path_kind]
    env = dict(os.environ, TRANSIENT_SETUP_LOG="off")
    try:
        done = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=TIMEOUT,
                              cwd=Path(__file__).resolve().parent.parent)
        r = json.loads(done.stdout.splitlines()[-1])
        found = {"entries": float(r["entries"]), "seconds": float(r["seconds"])}
    except (subprocess.SubprocessError, OSError, ValueError, KeyError, IndexError, TypeError):
        return None
    return found if found["entries"] > 0 and found["seconds"] > 0 else None


def estimate(path_kind, entries, calibrate=True, announce=None):
    """{"low", "high" [s], "setups": how many it is from, "source": "setups" or
    "calibration"} for a setup of `entries` on this host and path; None when the log is off,
    or before any setup of the path ran here without a calibration (`calibrate` false, or
    it failed).

    From this host's setups of the path: fitted t = c entries^p over two sizes or more (p
    held within EXPONENTS), the range the fit's largest residual; from one size, its setups'
    times scaled at both EXPONENTS. Before any: this machine's calibration of the path, its
    seconds scaled at both GROWTH exponents, made now and kept in the log when there is
    none of this version (calibrate true; announce(text) called first, as it takes
    seconds)."""
    if log_path() is None:
        return None
    records = _records()
    timed = _timed(records, path_kind)
    if timed:
        return {**_from_setups(timed, entries), "setups": len(timed), "source": "setups"}
    from . import __version__
    found = calibrated(records, path_kind, __version__)
    if found is None and calibrate:
        if announce is not None:
            announce(f"calibrating this machine's {path_kind} setup (once a version, "
                     "seconds): no setup of its kind timed here yet")
        found = measure(path_kind)
        line = {"host": platform.node(), "calibration": path_kind, "version": __version__,
                "time": time.time()}
        _append({**line, "entries": int(found["entries"]), "seconds": found["seconds"]}
                if found is not None else {**line, "failed": True})
    if found is None or found is FAILED:
        return None
    # a model below the calibration's size takes at most its seconds: much of a small
    # setup's time (the Lanczos' dense steps, Python) does not shrink with its entries
    ratio = entries / found["entries"]
    scaled = [found["seconds"] * ratio ** p
              for p in (GROWTH if ratio >= 1 else (0.0, max(GROWTH)))]
    return {"low": min(scaled), "high": max(scaled), "setups": 0, "source": "calibration"}


def _from_setups(timed, entries):
    """{"low", "high"} of a setup of `entries` from (entries, seconds) of setups timed."""
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
        return {"low": math.exp(mid - spread), "high": math.exp(mid + spread)}
    scaled = [b + q * (target - a) for a, b in zip(x, y) for q in EXPONENTS]
    return {"low": math.exp(min(scaled)), "high": math.exp(max(scaled))}
