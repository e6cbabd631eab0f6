"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes.

The public API (transient.api): `load`, `prepare`, `run`, `modes`, `cea` (and a dry run of the
last three), `mu_map` and its `branches`, `compat`, `compat_pairs`, `sweep` and its
`sweep_branches`; a run's `history`, its `summary`, `export` and `modal_growth`; the studies
`bench` and `compare_modes`.
Importing the package changes nothing in the process and loads none of the stages' modules;
`configure()` makes the settings that speed it up (the command line calls it first).
"""
from .settings import configure

__all__ = ["configure", "load", "dry_run", "prepare", "run", "modes", "cea", "mu_map", "compat",
           "compat_pairs", "sweep", "history", "summary", "export", "modal_growth", "bench",
           "compare_modes", "branches", "sweep_branches"]
__version__ = "0.1.0"

# the API's functions come from transient.api on first use (PEP 562), so that importing the
# package imports neither the API nor, through it, the case's readers
_API = frozenset(__all__) - {"configure"}


def __getattr__(name):
    if name in _API:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | _API)
