"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes.

Importing the package changes nothing in the process; `configure()` makes the settings that
speed it up (the command line calls it first).
"""
from .settings import configure

__all__ = ["configure"]
__version__ = "0.1.0"
