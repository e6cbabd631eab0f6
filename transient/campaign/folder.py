"""A campaign's folder (--out): checked to be one, and held by one campaign at a time.

The lock is flock(2) on DIR/sweep.lock, as io.lock holds a history: released by the kernel
when the process dies (SIGKILL included), so a killed sweep leaves no stale lock. The file
names its holder (pid, host, start time, command) for the message that refuses a second
campaign; it is removed when the campaign ends. Each history is still locked by its writer.
"""
import fcntl
import json
import os
import socket
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from ..errors import CaseError
from .variants import WHERE

LOCK = "sweep.lock"
MARK = "transient sweep"       # what the campaign's own files carry to be known as its own


def check_out(out):
    """The Path of --out, refused (CaseError) when empty or naming something not a folder."""
    if not str(out):
        raise CaseError(WHERE, "--out", "an empty name: expected a folder")
    out = Path(out)
    try:
        kind = None if not out.exists() else "dir" if out.is_dir() else (
            "a file" if out.is_file() else "a device, pipe or socket")
    except (OSError, ValueError) as exc:
        raise CaseError(out, "--out", f"not a usable folder name ({exc})") from None
    if kind not in (None, "dir"):
        raise CaseError(out, "--out", f"is {kind}: expected a folder")
    return out


def _holder(path):
    """The holder a lock file names, as text ('unknown' when it names none)."""
    try:
        h = json.loads(Path(path).read_text())
        return (f"pid {h['pid']} on {h['host']}, started {h['started']}: "
                f"{h['command']}")
    except (OSError, ValueError, KeyError, TypeError):
        return "holder unknown"


def _is_lock(path):
    """Whether the file at path is absent, empty or a lock file a campaign wrote."""
    try:
        if not path.exists() or path.stat().st_size == 0:
            return True
        return json.loads(path.read_text()).get("lock") == MARK
    except (OSError, ValueError, AttributeError):
        return False


@contextmanager
def holding(out, command=None):
    """Make the folder out (a Path checked by check_out) and hold it for a campaign; CaseError
    when it cannot be made or written, or another campaign holds it."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CaseError(out, "--out", f"cannot write: {exc.strerror or exc}") from None
    path = out / LOCK
    handle = _take(out, path)
    try:
        handle.truncate(0)
        handle.write(json.dumps({"lock": MARK, "pid": os.getpid(), "host": socket.gethostname(),
                                 "started": time.strftime("%Y-%m-%d %H:%M:%S %z"),
                                 "command": command or " ".join(sys.argv)}) + "\n")
        handle.flush()
        yield out
    finally:
        # removed while still held: a campaign that opens it meanwhile finds it gone (_take)
        try:
            if os.stat(path).st_ino == os.fstat(handle.fileno()).st_ino:
                path.unlink()
        except OSError:
            pass
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()


def _take(out, path):
    """The lock file at path opened and locked; it must still be the file at path once
    locked (the last holder removes it on leaving)."""
    while True:
        if path.is_symlink() or not _is_lock(path):
            raise CaseError(path, "--out", "exists and is not a sweep's lock file: not "
                            "overwritten (choose another folder)")
        try:
            handle = open(path, "a+")
        except OSError as exc:
            raise CaseError(out, "--out", f"cannot write: {exc.strerror or exc}") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            raise CaseError(out, "--out", f"another campaign holds this folder "
                            f"({_holder(path)})") from None
        try:
            if os.stat(path).st_ino == os.fstat(handle.fileno()).st_ino:
                return handle
        except FileNotFoundError:
            pass
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()


def write_whole(path, text):
    """Write text to the file at path whole: under a temporary name in its folder, then
    renamed over it, so that a writer killed half way leaves the old file or none."""
    path = Path(path)
    temporary = path.parent / f".{path.name}.{os.getpid()}.{time.monotonic_ns()}"
    try:
        # the permissions an ordinary file gets (the umask's), unlike mkstemp's owner-only
        fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        with os.fdopen(fd, "w", newline="") as f:
            f.write(text)
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


def modes_file(path):
    """The JSON object of complex modes a campaign wrote at path, or None if it is not one."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError, RecursionError):
        return None
    if isinstance(data, dict) and data.get("written_by") == MARK and isinstance(
            data.get("modes"), list):
        return data
    return None
