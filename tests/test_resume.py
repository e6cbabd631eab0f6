"""A resumed run continues the very system it checkpointed: bit for bit with an uninterrupted
run on every shipped case (reduced ones included), with the checkpoint taken under other BLAS
and Numba thread counts than the resume, after SIGINT or SIGKILL; and a resume with a case
that changes results is refused by name."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.cli import main
from transient.io.reading import summary

CASES = Path(__file__).resolve().parent.parent / "cases"
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "OMP_NUM_THREADS": "1"}
# each case for a few chunks, interrupted after its first. The reduced cases run on coarser
# meshes (the shipped sizes take minutes of setup here; at those sizes the same test passed,
# 8.7 min in all): the cube, the pad and disc with their sampled rule and exponential scheme,
# and the long case's scheme (one contact pass per step) on the fine rule's 2478 points, so
# that the contact pass runs in two row blocks
PAD = ["parts.disc.mesh.divisions=[4,72,1]", 'parts.disc.mesh.element="hex8"',
       "parts.pad.mesh.divisions=[6,16,1,1]", 'parts.pad.mesh.element="hex8"']
SHORT = {"bar_impact": ("6e-5", "1.2e-4", "200", []),
         "two_bars": ("5e-5", "1e-4", "200", []),
         "drilled_cube": ("5e-4", "1e-3", "100", ["parts.lower.mesh.divisions=[6,6,3]",
                                                  "parts.upper.mesh.divisions=[2,2,2]"]),
         "pad_disc": ("1e-3", "2e-3", "400", PAD),
         "pad_disc_long": ("1e-3", "2e-3", "800", PAD + ['contact.pad_disc.rule="fine"']),
         # friction: the state's friction row and the sliding's power carried, the system's
         # FrictionSet stored (the disc turning, growth at mu = 0.4)
         "pad_disc_squeal": ("1e-3", "2e-3", "400", PAD + [
             "contact.pad_disc.friction.mu=0.4", "loads.tap.vector=[0.0,0.0,-0.02]"])}
FILES = {"pad_disc_squeal": "pad_disc"}


def transient(*args, env=None, check=True):
    done = subprocess.run([sys.executable, "-m", "transient", *args], capture_output=True,
                          text=True, env={**os.environ, **(env or {})})
    if check:
        assert done.returncode == 0, done.stderr
    return done


def series(path):
    """Every stored series and the checkpoint, as arrays."""
    out = {}
    with h5py.File(path, "r", locking=False) as f:
        rows = int(f.attrs["rows"])

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and not name.startswith(("geometry/", "system/",
                                                                      "checkpoint")):
                out[name] = obj[:rows]
        f.visititems(visit)
        # the checkpoint the file links to (its two slots are written in turn)
        out.update({f"checkpoint/{k}": v[()] for k, v in f["checkpoint"].items()})
    return out


def assert_same(a, b):
    assert a.keys() == b.keys()
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


@pytest.mark.parametrize("name", sorted(SHORT))
@pytest.mark.slow
def test_resume_is_bit_for_bit_under_other_thread_counts(tmp_path, name):
    t1, t2, chunk, coarse = SHORT[name]
    case = str(CASES / f"{FILES.get(name, name)}.toml")
    sets = ["--set", f"solver.chunk={chunk}", "--quiet"] + [a for o in coarse
                                                           for a in ("--set", o)]
    whole, part = tmp_path / "whole.h5", tmp_path / "part.h5"
    transient("run", case, "-o", str(whole), "--set", f"solver.t_end={t2}", *sets,
              env=ONE_THREAD)
    transient("run", case, "-o", str(part), "--set", f"solver.t_end={t1}", *sets,
              env=ONE_THREAD)
    # resumed with the machine's default threads: the system and blocks come from the file
    transient("run", case, "-o", str(part), "--resume", "--set", f"solver.t_end={t2}", *sets)
    assert summary(part)["status"] == "complete"
    assert_same(series(whole), series(part))


def wait_for_checkpoint(path, process, timeout=300.0):
    """Until the history at path holds a checkpoint (the child writes it after each chunk)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert process.poll() is None, "the run ended before its first checkpoint"
        try:
            with h5py.File(path, "r", locking=False) as f:
                if "checkpoint" in f and f["checkpoint"].attrs["rows"] > 0:
                    return
        except (OSError, KeyError, RuntimeError):
            # being written: read again (HDF5 may also find a half-written link: RuntimeError
            # "addr overflow", seen once in CI)
            pass
        time.sleep(0.05)
    raise AssertionError("no checkpoint written")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL])
@pytest.mark.slow
def test_a_run_stopped_by_a_signal_resumes_to_the_uninterrupted_run(tmp_path, sig):
    # the run is long enough never to end by itself; the uninterrupted reference and the
    # resume go to a time set after the stop, whenever the signal landed
    case = str(CASES / "bar_impact.toml")
    sets = ["--set", "solver.chunk=100", "--set", "output.every=10", "--quiet"]
    whole, part = tmp_path / "whole.h5", tmp_path / "part.h5"
    child = subprocess.Popen([sys.executable, "-m", "transient", "run", case, "-o", str(part),
                              "--set", "solver.t_end=1.0", "--set", "limits.steps=100000000",
                              *sets], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for_checkpoint(part, child)
    child.send_signal(sig)
    out, err = child.communicate(timeout=120)
    stopped = summary(part)
    if sig == signal.SIGINT:
        assert child.returncode == 130 and stopped["status"] == "aborted: interrupted"
        # what it says it did is what the file holds
        line = next(x for x in out.splitlines() if "aborted" in x)
        assert f"to t = {stopped['t_end']:.6g} s" in line
    elif sig == signal.SIGTERM:
        # a batch scheduler's notice: the same orderly stop, checkpoint written
        assert child.returncode == 143 and stopped["status"] == "aborted: terminated (SIGTERM)"
    else:
        assert child.returncode == -signal.SIGKILL and stopped["status"] == "running"
    t_end = f"solver.t_end={stopped['t_end'] + 1e-3!r}"
    transient("run", case, "-o", str(whole), "--set", t_end, *sets)
    transient("run", case, "-o", str(part), "--resume", "--set", t_end, *sets)
    assert_same(series(whole), series(part))


@pytest.mark.parametrize("change, key", [
    ("materials.steel.E=1.0e11", "materials.steel.E"),
    ("solver.dt=1e-7", "solver.dt"),
    ("parts.bar.mesh.divisions=[50,1,1]", "parts.bar.mesh.divisions"),
    ("contact.wall.law.lambda=1e6", "contact.wall.law.lambda"),
])
@pytest.mark.slow
def test_resume_with_a_case_that_changes_results_is_refused_by_name(tmp_path, capsys, change,
                                                                     key):
    path = tmp_path / "bar.h5"
    case = str(CASES / "bar_impact.toml")
    assert main(["run", case, "-o", str(path), "--quiet", "--set", "solver.t_end=6e-5"]) == 0
    before = path.read_bytes()
    capsys.readouterr()
    assert main(["run", case, "-o", str(path), "--resume", "--quiet", "--set", change]) == 2
    err = capsys.readouterr().err
    assert f": {key}: --resume: differs" in err and len(err.strip().splitlines()) == 1
    assert path.read_bytes() == before          # the history is left as it was
    # a longer t_end is what resume is for
    assert main(["run", case, "-o", str(path), "--resume", "--quiet", "--set",
                 "solver.t_end=1.2e-4"]) == 0


def test_thread_choice_follows_the_last_chunks_and_retries_the_other():
    """One or all threads, whichever ran its last chunk faster per step; the other one is
    retried every PROBE-th chunk, on a short one; a run without row blocks keeps the
    stepper's setting."""
    import numba
    import numpy as np

    from transient.dynamics.chunks import PROBE, PROBE_SHARE, ThreadChoice
    from transient.dynamics.schemes import Stepper
    many = numba.get_num_threads()
    full = ThreadChoice(Stepper("explicit", 1e-6, None))
    assert full.counts == (0,) and full.next() == 0
    if many == 1:
        return
    stepper = Stepper("explicit", 1e-6, None, blocks=np.array([0, 200, 400], np.int64))
    choice = ThreadChoice(stepper)
    first = choice.next()
    assert first == many                          # each tried once, all threads first
    choice.record(first, 3.0, 1000)               # slow: 3 ms per step (the team's start)
    assert choice.next() == 1
    choice.record(1, 1.0, 1000)
    seen = []
    for _ in range(2 * PROBE):
        seen.append(choice.next())
        choice.record(seen[-1], 1.0 if seen[-1] == 1 else 0.5, 1000)
    # all threads get a second chunk, faster now: the run follows them, and retries one
    # thread every PROBE-th chunk (the third call was the second chunk on all threads)
    assert seen[0] == many and all(c == many for c in seen[1:PROBE - 3])
    assert seen[PROBE - 3] == 1 and all(c == many for c in seen[PROBE - 2:2 * PROBE - 3])
    assert seen[2 * PROBE - 3] == 1               # the next probe
    summary = choice.summary()
    assert set(summary) == {str(many), "1"} and sum(s for s, _ in summary.values()) == \
        1000 * (2 + 2 * PROBE)
    # a retry of the slower count is a short chunk, of whole rows; the faster runs whole ones
    assert choice.steps_of(many, 2000, 4) == 2000
    assert choice.steps_of(1, 2000, 4) == 2000 // PROBE_SHARE // 4 * 4
    assert choice.steps_of(1, 2000, 3) % 3 == 0 and choice.steps_of(1, 5, 4) == 4
    assert full.steps_of(0, 2000, 4) == 2000


@pytest.mark.parametrize("name", ["two_bars", "pad_disc_squeal"])
@pytest.mark.slow
def test_automatic_chunks_give_the_fixed_chunks_history(tmp_path, name):
    """solver.chunk = 0 cuts the run by the kernel's speed (dynamics.chunks.ChunkSize): the
    history, its last checkpoint included, is the one of a fixed chunk bit for bit."""
    _, t2, _, coarse = SHORT[name]
    case = str(CASES / f"{FILES.get(name, name)}.toml")
    sets = [a for o in coarse + [f"solver.t_end={t2}"] for a in ("--set", o)] + ["--quiet"]
    fixed, auto = tmp_path / "fixed.h5", tmp_path / "auto.h5"
    # 24 steps a chunk: cut elsewhere than the automatic chunks (a 20th of the run here)
    transient("run", case, "-o", str(fixed), "--set", "solver.chunk=24", *sets)
    transient("run", case, "-o", str(auto), "--set", "solver.chunk=0", *sets)
    assert_same(series(fixed), series(auto))


def test_chunk_size_is_a_share_of_a_second_of_the_kernel_within_its_bounds():
    """A set solver.chunk as before; an automatic one MIN_CHUNK steps first and at least, else
    about CHUNK_SECONDS of the kernel at the last speed, within a checks-th of the run and
    the rows' BUFFER_BYTES, in whole rows."""
    from transient.dynamics.chunks import BUFFER_BYTES, CHUNK_SECONDS, MIN_CHUNK, ChunkSize
    fixed = ChunkSize.of(500, 8, 10**6, 100, 20)
    assert (fixed.cap, fixed.steps(), fixed.steps(1e-9)) == (496, 496, 496)
    assert ChunkSize.of(10**6, 8, 1000, 100, 20).cap == 48       # a 20th of the run
    auto = ChunkSize.of(0, 8, 10**7, 100, 20)
    assert auto.cap == 500_000 and auto.steps() == MIN_CHUNK == auto.steps(10.0)
    assert auto.steps(1e-6) == int(CHUNK_SECONDS / 1e-6) // 8 * 8 > MIN_CHUNK
    assert auto.steps(1e-9) == auto.cap
    assert ChunkSize.of(0, 8, 8000, 100, 20).steps() == 400       # a 20th, below MIN_CHUNK
    rows = ChunkSize.of(0, 3, 10**9, 10**5, 20)      # wide rows: the buffer bounds the chunk
    assert rows.cap == int(BUFFER_BYTES // 10**5) * 3 and rows.cap % 3 == 0
