"""Importing transient changes nothing in the process; transient.configure makes its settings,
and the command line makes them before its first stage."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

# what an import could change: the environment, NumPy's page advice, the OpenMP runtime loaded,
# and glibc's allocator (a setup retaining freed blocks)
STATE = """
import json, os, sys
before = dict(os.environ)
import numpy
core = getattr(numpy, "_core", None) or numpy.core
advice = core.multiarray._get_madvise_hugepage()
{code}
maps = open("/proc/self/maps").read()
print(json.dumps({{"environ": dict(os.environ) == before,
                   "advice": core.multiarray._get_madvise_hugepage() == advice,
                   "iomp": "libiomp5" in maps, "gomp": "libgomp" in maps,
                   "numba_cache": os.environ.get("NUMBA_CACHE_DIR")}}))
"""


def _state(code, env=None):
    done = subprocess.run([sys.executable, "-c", STATE.format(code=code)], capture_output=True,
                          text=True, cwd=ROOT, check=True, env=env)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _clean_env():
    """The environment of a user who set none of the variables configure sets."""
    import os
    return {k: v for k, v in os.environ.items()
            if k not in ("OMP_WAIT_POLICY", "NUMPY_MADVISE_HUGEPAGE", "NUMBA_CACHE_DIR")}


def test_the_issues_check_passes():
    code = ("import os; e = dict(os.environ); import transient; "
            "assert dict(os.environ) == e")
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True, env=_clean_env())


@pytest.mark.slow
def test_importing_the_stages_changes_nothing():
    out = _state("import transient, transient.stages, transient.integration, "
                 "transient.campaign.campaign, transient.cli", env=_clean_env())
    assert out == {"environ": True, "advice": True, "iomp": False, "gomp": False,
                   "numba_cache": None}


def test_configure_makes_the_settings_once_and_keeps_the_users():
    code = """
import transient, transient.heap, transient.jit
transient.configure()
transient.configure()
print(json.dumps([os.environ["OMP_WAIT_POLICY"], os.environ["NUMPY_MADVISE_HUGEPAGE"],
                  transient.heap.permitted()]))
"""
    env = _clean_env()
    out = subprocess.run([sys.executable, "-c", "import json, os" + code], capture_output=True,
                         text=True, cwd=ROOT, check=True, env=env).stdout.splitlines()
    assert json.loads(out[-1]) == ["PASSIVE", "0", True]
    env["OMP_WAIT_POLICY"] = "ACTIVE"
    out = subprocess.run([sys.executable, "-c", "import json, os" + code], capture_output=True,
                         text=True, cwd=ROOT, check=True, env=env).stdout.splitlines()
    assert json.loads(out[-1])[0] == "ACTIVE"


def test_kernels_are_cached_in_transients_directory_without_the_environment(tmp_path):
    """A kernel's cache goes to jit.cache_dir() (keyed by the kernels' sources, or the user's
    NUMBA_CACHE_DIR), set on its dispatcher: no variable is needed, and Numba's own setting for
    the process's other functions is left as it was."""
    code = """
import json, numba
from transient import jit
from transient.kernels.sparse import csr_matmat as csr_dot
print(json.dumps([csr_dot._cache._cache_path.startswith(jit.cache_dir()),
                  numba.config.CACHE_DIR, jit.lock_path().startswith(jit.cache_dir())]))
"""
    env = _clean_env()
    env["XDG_CACHE_HOME"] = str(tmp_path)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True, env=env).stdout.splitlines()
    assert json.loads(out[-1]) == [True, "", True]
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    code += "print(jit.cache_dir())\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True, env=env).stdout.splitlines()
    assert out[-1] == str(tmp_path / "mine")


def test_the_command_line_configures_before_its_first_stage(tmp_path):
    """`transient` makes the settings before main runs a command: NumPy's arrays on small
    pages and the OpenMP wait policy, as main sees them."""
    code = """
import os, sys
from transient.cli import commands
seen = {}
real = commands.main
def main(argv):
    import numpy
    core = getattr(numpy, "_core", None) or numpy.core
    seen["advice"] = core.multiarray._get_madvise_hugepage()
    seen["wait"] = os.environ.get("OMP_WAIT_POLICY")
    return 0
commands.main = main
commands.console(["info", "x.h5"])
print(seen)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, check=True, env=_clean_env()).stdout.strip().splitlines()
    assert out[-1] == "{'advice': False, 'wait': 'PASSIVE'}"
