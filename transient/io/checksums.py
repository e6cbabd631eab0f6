"""Checksums on a history's datasets: every array the history writes carries HDF5's fletcher32
filter, a checksum per chunk that HDF5 checks on each read, so that a file changed after it was
written (a flipped byte on a disk, a copy cut short and patched) is refused instead of read as
numbers. The filter needs chunked datasets; a scalar cannot be chunked and stays unchecked.
Histories written before the filter have none, and read as before.
"""
import h5py
import numpy as np

from ..errors import DamagedHistory

FILTER = {"fletcher32": True}
SLAB_BYTES = 2 ** 26       # the most one read of `verify` takes into memory


def create(group, name, data):
    """A dataset of data under group, chunked and checksummed (a scalar as it is)."""
    data = np.asarray(data)
    if data.ndim == 0:
        return group.create_dataset(name, data=data)
    return group.create_dataset(name, data=data, chunks=True, **FILTER)


def failed(exc):
    """Whether exc is HDF5's error on a chunk whose checksum does not match its data."""
    return isinstance(exc, OSError) and "filter returned failure" in str(exc)


def refused(name):
    """The DamagedHistory of dataset `name`, whose checksum failed."""
    return DamagedHistory(name, "its data fail their checksum: the file was changed after it "
                          "was written")


def verify(f, rows, series, skip=()):
    """Read every checksummed dataset of the open history f, slab by slab: the series (names
    in `series`) up to their `rows` complete rows, the other arrays whole, the groups named in
    skip left out. A chunk whose checksum fails is a DamagedHistory naming its dataset."""
    found = []

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.fletcher32 and not name.startswith(skip):
            found.append(name)

    f.visititems(visit)
    for name in found:
        ds = f[name]
        n = min(rows, len(ds)) if name in series else len(ds)
        row_bytes = ds.dtype.itemsize * int(np.prod(ds.shape[1:]))
        # whole chunks along the rows, SLAB_BYTES at most unless one chunk is more
        step = max(1, SLAB_BYTES // max(row_bytes * ds.chunks[0], 1)) * ds.chunks[0]
        try:
            for start in range(0, n, step):
                ds[start:start + step]
        except OSError as exc:
            if failed(exc):
                raise refused(name) from None
            raise
