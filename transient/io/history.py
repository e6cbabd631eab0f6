"""The HDF5 time history of a run, written chunk by chunk while the run goes.

File layout: one float64 dataset per series, row i holding output row i (`/time`,
`/sensors/<name>`, `/contact/<pair>/gap`, `/energy/<term>`, ...), resizable along axis 0;
`/checkpoint/<name>`, the kernel state at the end of the last appended chunk; root attributes:
the run's meta data (`status`, `rows`, the case text under `CASE_TEXT`, version, timings...).

Readers and crashes. The writer opens the file for each call (append, checkpoint, finish) and
closes it before returning, so between chunks the file on disk is complete and any HDF5 reader
(h5py, h5dump, `transient info`) can open it without SWMR. The writer opens it without HDF5's
file lock: a reader that keeps the file open never stops the run; the price is that a reader
opening it during the few milliseconds of a write may fail and should retry. A killed run
leaves the file readable with every appended chunk and status 'running' (or with its last
chunk cut short, which its first reader repairs: io.reading). (SWMR was not used: it
needs SWMR-aware readers, forbids new attributes while writing, and a crashed SWMR file must be
repaired with h5clear before it opens normally.) In the writing process, close any reader
before the next append: HDF5 will not reopen for writing a file it holds open read-only.

The root attribute `rows` counts the complete rows and is written last in `append`: rows past
it (an append interrupted half way) are cut off by `finish` and `open_for_resume`. Readers
go through `io.reading`, which checks every array first.
"""
import zlib
from pathlib import Path

import h5py
import numpy as np

from ..errors import DamagedHistory, RunAborted, interrupted
from .attributes import short, write_attrs
from .checksums import FILTER, create
from .systems import GROUP as SYSTEM, write_system

CHUNK_BYTES = 2 ** 16      # 64 kB chunks: with the checksum (io.checksums) an append reads,
#                            checks and writes again whole each chunk it adds to, and 1 MB
#                            ones (a long run's series each one chunk) made every append pay
#                            for them; a row read decodes its chunk whole, too
CHECKPOINT = "checkpoint"       # a soft link to the last checkpoint written whole
CHECKPOINTS = "checkpoints"     # its two slots, written in turn
TAILS = "tails"            # a slot's attribute: [first row of its last chunk, CRC] of each
#                            series, in the order of their sorted names
GEOMETRY = "geometry"      # fixed arrays written once (contact points, weights, normals)


def open_history(path, mode):
    return h5py.File(path, mode, locking=False)


class History:
    """Writer of one history file; make one with `create` or `open_for_resume`.

    Use it as a context manager: leaving the block normally marks the run complete (unless
    `finish` was called), an exception (KeyboardInterrupt included) marks it 'aborted: <reason>';
    either way the file is closed with every appended chunk.
    """

    def __init__(self, path, layout):
        self.path = Path(path)
        self.layout = layout
        self.closed = False

    @classmethod
    def create(cls, path, meta, layout, overwrite=False, expected_rows=None, geometry=None,
               system=None):
        """Create a history file with empty series and status 'running'.

        Parameters
        ----------
        path : str or Path
        meta : dict
            Root attributes: strings and numbers as such, dicts, lists and None as JSON text.
        layout : dict
            Series name -> shape of one row, e.g. {"time": (), "contact/pad_disc/gap": (m,)}.
        overwrite : bool
            Replace an existing file (otherwise ValueError).
        expected_rows : int, optional
            Rows the run will store: caps the chunk length so short runs make small files.
        geometry : dict, optional
            Name -> array stored once under /geometry (not a series), e.g. the positions of
            the contact points, which maps of the contact series need.
        system : ReducedSystem or FullSystem, optional
            The system the run integrates, kept under /system so that a resume continues it
            (io.systems).
        """
        path = Path(path)
        if path.exists() and not overwrite:
            raise ValueError(f"{path}: file exists (pass overwrite=True to replace it)")
        shapes = {name: tuple(int(n) for n in shape) for name, shape in layout.items()}
        for reserved in (CHECKPOINT, CHECKPOINTS, GEOMETRY, SYSTEM):
            if reserved in shapes or any(n.startswith(reserved + "/") for n in shapes):
                raise ValueError(f"series name '{reserved}' is reserved")
        with open_history(path, "w") as f:
            for name, shape in shapes.items():
                rows = _chunk_rows(shape, expected_rows)
                # zero-length row axes cannot be chunked as fixed dimensions
                f.create_dataset(name, shape=(0,) + shape,
                                 maxshape=(None,) + tuple(n or None for n in shape),
                                 chunks=(rows,) + tuple(max(n, 1) for n in shape), dtype="f8",
                                 **FILTER)
            for name, value in (geometry or {}).items():
                create(f, f"{GEOMETRY}/{name}", value)
            if system is not None:
                write_system(f, system)
            write_attrs(f.attrs, meta)
            f.attrs["status"] = "running"
            f.attrs["rows"] = 0
        return cls(path, shapes)

    @classmethod
    def open_for_resume(cls, path, meta=None):
        """Reopen a history (running, aborted or complete) to append after its stored rows.

        Rows past the checkpoint, if there is one, are dropped: the run resumes from the
        checkpoint's state and recomputes them. Sets status back to 'running'. meta: root
        attributes to store anew (what the resumed run changed: its case, t_end...).
        """
        path = Path(path)
        with open_history(path, "r+") as f:
            rows = stored_rows(f, path)
            if CHECKPOINT in f and 0 <= checkpoint_rows(f) < rows:
                rows = checkpoint_rows(f)
            layout = series_shapes(f)
            # running on disk before the cut rewrites a chunk in place: a kill inside it
            # leaves a history its first reader repairs (io.reading)
            f.attrs["status"] = "running"
            f.flush()
            truncate_series(f, layout, rows)
            write_attrs(f.attrs, meta or {})
        return cls(path, layout)

    def rows(self):
        """Number of complete rows stored."""
        with open_history(self.path, "r") as f:
            return stored_rows(f, self.path)

    def append(self, rows):
        """Append n rows to every series: rows maps each series name to an array (n, *shape)."""
        self._check_open()
        arrays = self._check_rows(rows)
        n = len(next(iter(arrays.values()), ()))
        with open_history(self.path, "r+") as f:
            start = int(f.attrs["rows"])
            for name, value in arrays.items():
                ds = f[name]
                ds.resize(start + n, axis=0)
                ds[start:] = value
            f.attrs["rows"] = start + n

    def checkpoint(self, state):
        """Store the kernel state (name -> array) at the end of the last appended chunk.

        Two slots are written in turn and /checkpoint links to the last one written whole: the
        new slot is filled and flushed before the link moves, so a process killed at any point
        leaves the previous checkpoint whole (a kill between the arrays and the rows attribute
        of a single group left new arrays under old rows: a resume that skipped rows). Arrays
        are rewritten in place when their shape and type are unchanged, so the file does not
        grow with each checkpoint (HDF5 does not reuse the space of deleted datasets).
        """
        self._check_open()
        arrays = {name: np.asarray(value) for name, value in state.items()}
        for name in arrays:
            if "/" in name:
                raise ValueError(f"checkpoint name '{name}': no '/' allowed")
        with open_history(self.path, "r+") as f:
            link = f.get(CHECKPOINT, getlink=True)
            last = link.path if isinstance(link, h5py.SoftLink) else ""
            slot = f"/{CHECKPOINTS}/{'1' if last.endswith('/0') else '0'}"
            group = f.require_group(slot)
            # marks the slot as partly written until every array is in
            group.attrs["rows"] = -1
            for name in set(group) - set(arrays):
                del group[name]
            for name, value in arrays.items():
                old = group.get(name)
                if old is not None and old.shape == value.shape and old.dtype == value.dtype:
                    old[...] = value
                else:
                    if old is not None:
                        del group[name]
                    create(group, name, value)
            rows = int(f.attrs["rows"])
            # numbers of one shape: rewritten in place, the file does not grow
            group.attrs.modify(TAILS, np.array([tail(f[name], rows)
                                                for name in sorted(self.layout)], np.int64))
            group.attrs["rows"] = rows
            f.flush()
            if link is not None:
                del f[CHECKPOINT]
            f[CHECKPOINT] = h5py.SoftLink(slot)

    def truncate(self, rows):
        """Drop the rows past the first `rows` (a subdivided step goes back to a row before
        them); the checkpoint's rows stay."""
        self._check_open()
        with open_history(self.path, "r+") as f:
            truncate_series(f, self.layout, rows)

    def annotate(self, meta):
        """Store root attributes (name -> value, as `create`'s meta) while the run goes: what
        it learns on the way (a subdivided step, its end row)."""
        self._check_open()
        with open_history(self.path, "r+") as f:
            write_attrs(f.attrs, meta)

    def finish(self, status, timings=None):
        """Set the final status ('complete' or 'aborted: <reason>'), store timings, close.

        Parameters
        ----------
        status : str
        timings : dict, optional
            Name -> seconds, e.g. {"setup": 1.2, "kernel": 30.5, "total": 32.0}; None keeps
            the timings stored so far.
        """
        self._check_open()
        if status != "complete" and not status.startswith("aborted: "):
            raise ValueError(f"status: expected 'complete' or 'aborted: <reason>', got "
                             f"{status!r}")
        with open_history(self.path, "r+") as f:
            truncate_series(f, self.layout, int(f.attrs["rows"]))
            if timings is not None:
                write_attrs(f.attrs, {"timings": timings})
            f.attrs["status"] = status
        self.closed = True

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if not self.closed:
            self.finish("complete" if exc is None else f"aborted: {_reason(exc)}")
        return False

    def _check_open(self):
        if self.closed:
            raise ValueError(f"{self.path}: history already finished")

    def _check_rows(self, rows):
        if set(rows) != set(self.layout):
            missing = sorted(set(self.layout) - set(rows))
            extra = sorted(set(rows) - set(self.layout))
            raise ValueError(f"append: rows must hold every series (missing {missing}, "
                             f"unknown {extra})")
        arrays = {name: np.asarray(value, dtype=float) for name, value in rows.items()}
        for name, a in arrays.items():
            if a.ndim == 0 or a.shape[1:] != self.layout[name]:
                raise ValueError(f"append: '{name}' has shape {a.shape}, expected (n,) + "
                                 f"{self.layout[name]}")
        counts = sorted({len(a) for a in arrays.values()})
        if len(counts) > 1:
            raise ValueError(f"append: series have different numbers of rows {counts}")
        return arrays


def tail(ds, rows):
    """[first row, CRC-32] of the rows below `rows` in the chunk of series ds that holds row
    `rows`: the committed rows the next append rewrites in place."""
    start = rows - rows % ds.chunks[0]
    return [start, zlib.crc32(np.ascontiguousarray(ds[start:rows]).tobytes())]


def _chunk_rows(shape, expected_rows):
    rows = max(1, CHUNK_BYTES // (8 * max(1, int(np.prod(shape)))))
    return min(rows, max(1, expected_rows)) if expected_rows else rows


def stored_rows(f, path):
    """The complete rows, checked against the series: a damaged count or series is an error."""
    if "rows" not in f.attrs:
        raise DamagedHistory("attribute rows", "missing (not a history written by transient?)")
    value = f.attrs["rows"]
    if not isinstance(value, (int, np.integer)) or value < 0:
        raise DamagedHistory("attribute rows", f"{short(value)}, expected a count")
    for name in series_shapes(f):
        ds = f[name]
        # a row axis of numbers is what every reader indexes and plots
        if ds.ndim == 0 or ds.dtype.kind not in "fiu":
            raise DamagedHistory(name, f"a {ds.dtype} dataset of shape {ds.shape}, expected "
                                 "rows of numbers")
        if name == "time" and ds.ndim != 1:
            raise DamagedHistory(name, f"rows of shape {ds.shape[1:]}, expected one time each")
        if ds.shape[0] < value:
            raise DamagedHistory(name, f"{ds.shape[0]} rows, attribute 'rows' says "
                                 f"{int(value)}")
    return int(value)


def series_shapes(f):
    shapes = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and not name.startswith((CHECKPOINT + "/",
                                                                   CHECKPOINTS + "/",
                                                                   GEOMETRY + "/",
                                                                   SYSTEM + "/")):
            shapes[name] = obj.shape[1:]

    f.visititems(visit)
    return shapes


def truncate_series(f, layout, rows):
    for name in layout:
        if f[name].shape[0] != rows:
            f[name].resize(rows, axis=0)
    f.attrs["rows"] = rows


def _reason(exc):
    """One line saying why a run stopped."""
    lines = str(exc).strip().splitlines()
    if interrupted(exc):
        return "interrupted by the user"
    if isinstance(exc, RunAborted) and lines:
        return lines[0]
    return f"{type(exc).__name__}: {lines[0]}" if lines else type(exc).__name__


def checkpoint_rows(f):
    """The rows the checkpoint of the open file f was taken at, -1 while it is written."""
    group = f[CHECKPOINT]
    value = group.attrs.get("rows") if isinstance(group, h5py.Group) else None
    if not isinstance(value, (int, np.integer)) or value < -1:
        raise DamagedHistory(f"{CHECKPOINT} attribute rows", f"{short(value)}, expected a "
                             "count")
    return int(value)
