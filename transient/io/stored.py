"""A history file read back for pictures and exports; bad input raises one-line CaseErrors.

The layout is the one `history` writes: `/time`, the series `/<group>/<name>` with one row per
output row, `/geometry/...` written once, and the meta data as root attributes.
"""
from dataclasses import dataclass
from pathlib import Path

import h5py

from ..errors import CaseError
from .history import CASE_TEXT, GEOMETRY, summary


@dataclass(frozen=True)
class Stored:
    """What a history holds (the arrays stay in the file until read)."""
    path: Path
    rows: int            # complete rows
    series: dict         # name -> shape of one row
    meta: dict           # root attributes decoded (`history.summary`), status included

    def scalars(self):
        """Names of the series with one number per row (sensors, energy terms)."""
        return [name for name, shape in self.series.items() if not shape and name != "time"]

    def open(self):
        """The HDF5 file, read only, as a context manager: for reading rows one at a time.

        Opened without HDF5's file lock, as the writer does, so reading never stops a run.
        """
        return h5py.File(self.path, "r", locking=False)

    def read(self, name):
        """Every complete row of one series, as an array."""
        with self.open() as f:
            return f[name][: self.rows]

    def time(self):
        """The time of every row [s]."""
        return self.read("time")

    def geometry(self, name):
        """A fixed array under /geometry (e.g. 'contact/wall/points'), None if absent."""
        with self.open() as f:
            key = f"{GEOMETRY}/{name}"
            return f[key][()] if key in f else None

    def case_text(self):
        """The case file as it was run."""
        with self.open() as f:
            return f.attrs[CASE_TEXT]

    def pairs(self):
        """Contact pair name -> its description (rule, points, regularized, eps, law)."""
        return self.meta.get("pairs") or {}

    def error(self, key, message):
        return CaseError(self.path, key, message)


def read_summary(path):
    """`history.summary` of the file at path; a missing or foreign file is a CaseError."""
    path = Path(path)
    if not path.exists():
        raise CaseError(path, "", "file not found")
    try:
        return summary(path)
    except (OSError, KeyError, ValueError, TypeError, RuntimeError) as exc:
        raise CaseError(path, "", f"not a transient history, or a damaged one ({exc})") from None


def open_history(path):
    """The history at path, checked to be one with a /time series."""
    path = Path(path)
    d = read_summary(path)
    if "time" not in d["series"]:
        raise CaseError(path, "", "not a transient history: no /time series")
    meta = dict(d["meta"], status=d["status"])
    return Stored(path, d["steps"], {k: tuple(v) for k, v in d["series"].items()}, meta)

