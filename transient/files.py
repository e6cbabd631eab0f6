"""A file written whole: the package's outputs replace an old file only once complete."""
import os
import time


def whole(path, write):
    """write(temporary) under a temporary name in path's folder, then renamed to path: a
    writer stopped half way leaves the old file or none (two writers, their own names)."""
    temporary = path.parent / f".{path.name}.{os.getpid()}.{time.monotonic_ns()}.part"
    try:
        write(temporary)
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


def saved(path, save, *args, **kwargs):
    """save(file, *args, **kwargs) into path through an open file: NumPy's savers add their
    suffix to a path that lacks it (a temporary name of whole's)."""
    with open(path, "wb") as f:
        save(f, *args, **kwargs)
