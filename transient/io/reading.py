"""A history read back: every array a reader may take checked against its checksum before
anything is read (io.checksums), a killed run's history repaired first, and its summary.

A kill cutting an append short. HDF5 rewrites in place the chunk that holds a series' last
rows when rows are added to it, and the system may stop a killed process half way through that
write: the chunk then holds its committed rows as they were (the same bytes before and after)
and fails its checksum. Each checkpoint keeps the CRC of those committed rows, series by
series (slot attribute `tails`, io.history), so that the first reader of a run that died this
way repairs it (`verified`): the committed rows read raw from the chunk, checked against their
CRC, written again whole, the rows after the checkpoint dropped, which a resume computes again.
"""
import fcntl
import zlib
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from ..dynamics.energy import drift as energy_drift
from ..errors import DamagedHistory
from ..kernels.codes import ENERGY_TERMS
from .attributes import CASE_TEXT, read_attrs
from .checksums import failed, refused, verify
from .history import (CHECKPOINT, CHECKPOINTS, TAILS, checkpoint_rows, open_history,
                      series_shapes, stored_rows, truncate_series)


def _raw_rows(ds, start, stop):
    """Rows start:stop of series ds read from the stored bytes of the chunk that begins at
    row start, its checksum left unchecked (the chunk holds its data, then the checksum)."""
    _, raw = ds.id.read_direct_chunk((start,) + (0,) * (ds.ndim - 1))
    shape = ds.chunks
    data = np.frombuffer(raw, ds.dtype, count=int(np.prod(shape))).reshape(shape)
    # a chunk spans a row's whole shape (one where the shape is zero)
    return data[(slice(0, stop - start),) + tuple(slice(0, n) for n in ds.shape[1:])].copy()


def _cut_tails(f):
    """The rows of a killed run's history that a cut-short append left failing their checksum
    and that its checkpoint vouches for: (checkpoint rows, {series: (first row, rows)}), the
    rows read raw and equal to the CRC the checkpoint keeps; None if the history is not such
    a run's (finished, no checkpoint, or one written before the CRCs)."""
    if f.attrs.get("status") != "running" or CHECKPOINT not in f:
        return None
    rows, names = checkpoint_rows(f), sorted(series_shapes(f))
    tails = np.asarray(f[CHECKPOINT].attrs.get(TAILS, ()))
    if rows < 0 or tails.shape != (len(names), 2) or tails.dtype.kind not in "iu":
        return None
    cut = {}
    for name, (start, crc) in zip(names, tails.tolist()):
        ds = f[name]
        if not 0 <= start < rows <= len(ds):
            continue
        try:
            ds[start:rows]
            continue
        except OSError as exc:
            if not failed(exc):
                raise
        data = _raw_rows(ds, start, rows)
        if zlib.crc32(np.ascontiguousarray(data).tobytes()) != crc:
            raise refused(name)
        cut[name] = (start, data)
    return rows, cut


@contextmanager
def verified(path, held=False):
    """(f, rows): the history at path open read-only and its complete rows, every array its
    readers may take checked against its checksum; a killed run's history whose last append
    was cut short is repaired first (module docstring), under the writer's lock (held: the
    caller holds it already), and reads as its checkpoint's rows. A DamagedHistory
    otherwise."""
    with open_history(path, "r") as f:
        rows = stored_rows(f, path)
        try:
            verify_history(f, rows)
        except DamagedHistory:
            found = _cut_tails(f)
            if not found or not found[1]:
                raise
        else:
            yield f, rows
            return
    _repair(path, held)
    with open_history(path, "r") as f:
        rows = stored_rows(f, path)
        verify_history(f, rows)
        yield f, rows


def _repair(path, held):
    """Write the cut tails of a killed run's history at path again whole (`_cut_tails`)."""
    try:
        with open(path, "ab") as handle:
            if not held:
                try:
                    fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    raise DamagedHistory("history", "being written by its run: read it "
                                         "again") from None
            with open_history(path, "r+") as f:
                # read again under the lock: a resume may have repaired it meanwhile
                rows, cut = _cut_tails(f) or (stored_rows(f, path), {})
                for name, (start, data) in cut.items():
                    # down to the chunk's first row: HDF5 drops the chunk unread
                    f[name].resize(start, axis=0)
                    f[name].resize(rows, axis=0)
                    f[name][start:rows] = data
                if cut:
                    truncate_series(f, series_shapes(f), rows)
    except PermissionError:
        raise DamagedHistory("history", "its run was killed in a write that left its last "
                             "rows failing their checksum: make the file writable and read "
                             "it again to repair it") from None


def verify_history(f, rows):
    """Read every checksummed array of the open history f that its readers may take (the
    series' `rows` complete rows, the checkpoint linked, the system and geometry): a
    DamagedHistory names the first whose data fail their checksum (io.checksums)."""
    link = f.get(CHECKPOINT, getlink=True)
    linked = link.path.strip("/") if isinstance(link, h5py.SoftLink) else ""
    # the other slot may be one a kill cut short while it was written: never read
    slots = f.get(CHECKPOINTS)
    skip = tuple(f"{CHECKPOINTS}/{slot}/" for slot in
                 (slots if isinstance(slots, h5py.Group) else ())
                 if f"{CHECKPOINTS}/{slot}" != linked)
    verify(f, rows, series_shapes(f), skip)


def check_appendable(f, layout):
    """Raise DamagedHistory unless the series of the open file f are those of layout (name ->
    shape of one row), each resizable along its rows as `create` makes them: what
    `open_for_resume` and `append` rely on."""
    stored = series_shapes(f)
    for name in sorted(set(stored) | set(layout)):
        if name not in layout:
            raise DamagedHistory(name, "not a series the run writes")
        if name not in stored:
            raise DamagedHistory(name, "missing, the run writes it")
        if stored[name] != tuple(layout[name]):
            raise DamagedHistory(name, f"rows of shape {stored[name]}, expected "
                                 f"{tuple(layout[name])}")
        if f[name].chunks is None or f[name].maxshape[0] is not None:
            raise DamagedHistory(name, "a dataset that cannot grow (not written by "
                                 "transient)")


def load_checkpoint(path):
    """The state stored by the last `History.checkpoint` (name -> array, bit for bit)."""
    with open_history(path, "r") as f:
        if CHECKPOINT not in f:
            raise ValueError(f"{path}: no checkpoint")
        if checkpoint_rows(f) < 0:
            raise ValueError(f"{path}: the checkpoint was interrupted while being written")
        group = f[CHECKPOINT]
        for name in group:
            if not isinstance(group[name], h5py.Dataset):
                raise DamagedHistory(f"{CHECKPOINT}/{name}", "a group, expected an array")
        return {name: group[name][()] for name in group}


def summary(path):
    """What `transient info` shows of a history file, as JSON-ready data.

    Returns
    -------
    dict
        path, status, steps (rows stored), t_end [s] (None without rows or /time), timings
        (dict), energy_drift (`energy_drift` of the /energy/<term> series, None without them),
        series (name -> shape of one row), meta (the other root attributes, the case text
        left out), file_size [bytes].
    """
    path = Path(path)
    with verified(path) as (f, rows):
        series = {name: list(shape) for name, shape in series_shapes(f).items()}
        meta = read_attrs(f.attrs)
        t_end = float(f["time"][rows - 1]) if rows and "time" in series else None
        drift = energy_drift({name: f[f"energy/{name}"][:rows] for name in ENERGY_TERMS
                              if f"energy/{name}" in series})
    meta.pop(CASE_TEXT, None)
    meta.pop("rows")
    if "status" not in meta:
        raise DamagedHistory("attribute status", "missing")
    return {"path": str(path), "status": meta.pop("status"), "steps": rows, "t_end": t_end,
            "timings": meta.pop("timings", {}), "energy_drift": drift, "series": series,
            "meta": meta, "file_size": path.stat().st_size}
