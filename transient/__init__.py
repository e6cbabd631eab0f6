"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes.

The public API (transient.api): `load`, `prepare`, `run`, `modes`, `cea`, `compat`, `sweep`.
Importing the package changes nothing in the process and loads none of the stages' modules;
`configure()` makes the settings that speed it up (the command line calls it first).
"""
import importlib
import sys
import types

from .settings import configure

__all__ = ["configure", "load", "prepare", "run", "modes", "cea", "compat", "sweep"]
__version__ = "0.1.0"

# the public functions named as submodules are (transient/run.py, cea/, sweep/)
_SHARED = ("run", "cea", "sweep")


class _Entry:
    # transient.run, .cea and .sweep: called, the API's function; any attribute is the
    # submodule's, so that `import transient.cea.stage` and its users keep working

    def __init__(self, name):
        object.__setattr__(self, "_name", name)

    def _function(self):
        return getattr(importlib.import_module(f"{__name__}.api"), self._name)

    def _module(self):
        return importlib.import_module(f"{__name__}.{self._name}")

    def __call__(self, *args, **kwargs):
        return self._function()(*args, **kwargs)

    @property
    def __doc__(self):
        return self._function().__doc__

    @property
    def __wrapped__(self):
        return self._function()

    def __getattr__(self, attr):
        return getattr(self._module(), attr)

    def __setattr__(self, attr, value):
        setattr(self._module(), attr, value)

    def __delattr__(self, attr):
        delattr(self._module(), attr)

    def __repr__(self):
        return f"<transient.{self._name}: the function transient.api.{self._name}>"


class _Package(types.ModuleType):
    def __setattr__(self, name, value):
        # the import system sets a submodule on its package once imported: the entry stays
        if name in _SHARED and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


def __getattr__(name):
    if name in ("load", "prepare", "modes", "compat"):
        return getattr(importlib.import_module(f"{__name__}.api"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


run, cea, sweep = (_Entry(name) for name in _SHARED)
sys.modules[__name__].__class__ = _Package
