"""The heap's retention of freed blocks (transient.heap): counted in page faults, each check in a
process of its own (the setting is the process's, for good)."""
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

FAULTS = """
import resource
import numpy as np

def faults(n=8_000_000):
    # a 64 MB array made, written and dropped: the page faults it took
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    a = np.empty(n)
    a[:] = 1.0
    del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
"""


def _run(code):
    done = subprocess.run([sys.executable, "-c", FAULTS + textwrap.dedent(code)],
                          capture_output=True, text=True, cwd=ROOT, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_a_retaining_heap_reuses_a_freed_block_without_faulting_it_again():
    out = _run("""
    import json
    import transient.heap as heap
    plain = [faults(), faults()]
    ok = heap.retain_freed()
    kept = [faults(), faults()]
    heap.settle()
    settled = [faults(), faults()]
    print(json.dumps({"plain": plain, "kept": kept, "settled": settled, "ok": ok,
                      "after": heap.retaining()}))
    """)
    assert out["ok"] and not out["after"]
    pages = 64e6 / 4096
    # glibc maps a 64 MB block afresh each time, faulting its pages in every time
    assert min(out["plain"]) > 0.5 * pages
    # retained: the first block's pages are faulted once, the second reuses them
    assert out["kept"][1] < 0.05 * pages
    # settled: the retained pages were given back, and a 64 MB block is mapped afresh again
    assert min(out["settled"]) > 0.5 * pages


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
@pytest.mark.parametrize("share, configured, retains", [
    (0.1, True, True), (0.8, True, False), (0.1, False, False)])
@pytest.mark.slow
def test_the_setup_retains_freed_blocks_only_far_below_the_memory_bound(share, configured,
                                                                          retains):
    """A setup estimated at over half of limits.memory keeps glibc's defaults (its freed blocks
    in the heap's middle would stay resident); a small one retains them, until it ends. The
    heap is the process's: without transient.configure a setup leaves it alone."""
    out = _run(f"""
    import json
    import transient
    if {configured}:
        transient.configure()
    import transient.heap as heap
    from transient.case.loading import load
    from transient.case.sizes import parts_cells, setup_bytes
    from transient.model import build_model
    from transient.stages import prepare
    case = load("cases/two_bars.toml")
    need = setup_bytes(parts_cells(build_model(case).parts))
    case = load("cases/two_bars.toml", [f"limits.memory={{need / {share} / 1e9}}"])
    prepare(case)
    print(json.dumps({{"retained": heap.last_setup_retained(), "after": heap.retaining()}}))
    """)
    assert out["retained"] is retains
    assert out["after"] is False      # the retention ends with the setup
