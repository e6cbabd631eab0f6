"""A history file read back for pictures and exports; bad input raises one-line CaseErrors.

The layout is the one `history` writes: `/time`, the series `/<group>/<name>` with one row per
output row, `/geometry/...` written once, and the meta data as root attributes.
"""
from dataclasses import dataclass, replace
from pathlib import Path

import h5py
import numpy as np

from ..errors import CaseError, DamagedHistory
from .attributes import CASE_TEXT, read_attrs
from .history import GEOMETRY
from .reading import summary


@dataclass(frozen=True)
class Stored:
    """What a history holds (`transient.history`): the arrays stay in the file until read.

    ``path``; ``rows``, the complete rows (a history still written, or stopped early, reads as
    those); ``series``, name -> shape of one row (``"sensors/tip": ()``,
    ``"contact/NAME/gap": (m,)``); ``meta``, the run's attributes, its ``status`` included.
    """
    path: Path
    rows: int            # complete rows
    series: dict         # name -> shape of one row
    meta: dict           # root attributes decoded (`reading.summary`), status included

    def uniform(self):
        """This history without its end row when that row is off the rows' grid (a run whose
        t_end is not on it stores its end as a row of its own: attribute end_row): the rows
        that spectra take, at one sample step."""
        if self.meta.get("end_row") and self.rows > 1:
            return replace(self, rows=self.rows - 1)
        return self

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
        key = f"{GEOMETRY}/{name}"
        with self.open() as f:
            if key not in f:
                return None
            if not isinstance(f[key], h5py.Dataset) or f[key].dtype.kind not in "fiu":
                raise self.error(key, "damaged history: expected an array of numbers")
            return f[key][()]

    def contact_geometry(self, pair):
        """Positions (m, 3) [m], normals (m, 3) and weights (m,) [m^2] of the contact points
        of a stored pair, checked against its gap and pressure series (m values per row)."""
        widths = {self.series.get(f"contact/{pair}/{s}") for s in ("gap", "pressure")}
        if len(widths) != 1 or None in widths or len(next(iter(widths))) != 1:
            raise self.error(f"contact/{pair}", "damaged history: expected a gap and a "
                             "pressure series of one value per contact point")
        (m,), out = widths.pop(), {}
        for key, shape in (("points", (m, 3)), ("normals", (m, 3)), ("weights", (m,))):
            name = f"{GEOMETRY}/contact/{pair}/{key}"
            value = self.geometry(f"contact/{pair}/{key}")
            if value is None:
                raise self.error(name, "no contact point positions: run with output.contact "
                                 "= true (this version stores them)" if key == "points" else
                                 "missing: the history is damaged")
            if value.shape != shape:
                raise self.error(name, f"damaged history: shape {value.shape}, expected "
                                 f"{shape}")
            if not np.all(np.isfinite(value)):
                raise self.error(name, "damaged history: values that are not finite")
            out[key] = value
        return out

    def friction_law(self, pair):
        """The friction law of a stored pair's points (io.systems.read_friction_law), None
        without friction."""
        from .systems import read_friction_law
        with self.open() as f:
            try:
                return read_friction_law(f, pair)
            except (KeyError, TypeError, ValueError) as exc:
                raise self.error("system/contacts/friction", f"damaged history: {exc}") from None

    def case(self):
        """The case the history was run with, rebuilt from the text, path and overrides it
        keeps."""
        with self.open() as f:
            try:
                text = read_attrs(f.attrs).get(CASE_TEXT)
            except DamagedHistory as exc:
                raise self.error(exc.key, f"damaged history: {exc.message}") from None
        return run_case(self.path, {**self.meta, CASE_TEXT: text})

    def applied_load(self, name):
        """The load `name` of the case the history keeps (its `loads.NAME`), as the run applied
        it: an AppliedLoad whose `values(t)` rebuild its amplitude at the rows' times."""
        loads = self.case().loads
        if name not in loads:
            raise self.error("--input", f"no load '{name}' in the run's case (loads: "
                             f"{', '.join(loads) or 'none'})")
        load = loads[name]
        if load.kind == "pressure":
            size, direction = load.value, None
        else:
            size = float(np.linalg.norm(load.vector))
            direction = np.asarray(load.vector, float) / size if size > 0 else None
        if load.signal["kind"] == "constant" or size == 0:
            raise self.error("--input", f"load '{name}' does not vary in time (signal "
                             f"{load.signal['kind']}, size {size:g}): it is part of the "
                             "preload, no input of a transfer function")
        return AppliedLoad(name, load.kind, LOAD_UNITS[load.kind], size, direction,
                           dict(load.signal))

    def pairs(self):
        """Contact pair name -> its description (rule, points, regularized, eps, law)."""
        return self.meta.get("pairs") or {}

    def error(self, key, message):
        return CaseError(self.path, key, message)


LOAD_UNITS = {"force": "N", "pressure": "Pa", "gravity": "m/s^2"}


@dataclass(frozen=True)
class AppliedLoad:
    """A load of a run's case: its size (|vector| of a force [N] or of gravity [m/s^2], the
    value of a pressure [Pa]) times its time signal (case.signals) is the amplitude the run
    applied; the force's (or gravity's) direction, None for a pressure (normal to its faces)."""
    name: str
    kind: str                # force, pressure, gravity
    unit: str
    size: float
    direction: np.ndarray    # (3,) unit vector, or None
    signal: dict             # kind and that kind's keys

    def values(self, t):
        """The amplitude at times t [s], in `unit`: the signal evaluated as the kernels
        evaluate it at each step (case.signals.evaluate, their reference)."""
        from ..case.signals import evaluate
        return self.size * evaluate(self.signal, t)


def run_case(path, meta):
    """The case a history at path was run with, from its root attributes meta (the case text
    included); one it does not keep is a CaseError naming the attribute."""
    from ..case.loading import parse
    for key in (CASE_TEXT, "case_path"):
        if meta.get(key) is None:
            raise CaseError(path, f"attribute {key}", "missing: the history keeps no case to "
                            "rebuild the run from (damaged, or not written by transient)")
    overrides = list(meta.get("overrides") or [])
    if meta.get("reduction_auto") and meta.get("reduction_method") in ("assembled",
                                                                       "components"):
        # the method "auto" chose for the run, not chosen again: its meshes need not be
        # there any more, nor the memory it was chosen by
        overrides.append(f'solver.reduction.method="{meta["reduction_method"]}"')
    try:
        return parse(meta[CASE_TEXT], meta["case_path"], overrides)
    except CaseError as exc:
        # named by the history that keeps it: the stored case path need not be a file
        raise CaseError(path, f"attribute {CASE_TEXT}", f"the stored case does not load "
                        f"({exc})") from None


def read_summary(path):
    """`reading.summary` of the file at path; a missing or foreign file is a CaseError."""
    path = Path(path)
    if not path.exists():
        raise CaseError(path, "", "file not found")
    try:
        return summary(path)
    except DamagedHistory as exc:
        raise CaseError(path, exc.key, f"damaged history: {exc.message}") from None
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
