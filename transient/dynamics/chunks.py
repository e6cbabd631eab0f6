"""Chunks of steps, as pyMOR's time stepping yields states: the kernel integrates a chunk, then
Python gets it back to store, check and report before the next.

`chunks` yields one Chunk per kernel call; its rows are a view of a buffer the next chunk
overwrites, so the consumer stores them before asking for the next. `stop_requests` turns the
signals that ask a run to stop into a flag read between chunks.
"""
import signal
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numba
import numpy as np

from ..errors import interrupted
from ..kernels.codes import NOT_FINITE, OK
from .state import Rows


@dataclass(frozen=True)
class Chunk:
    rows: Rows           # the rows stored by this chunk (finite ones only)
    status: int          # kernels.codes OK, NOT_FINITE, NO_CONVERGENCE
    done: int            # steps the kernel made
    step: int            # steps done since t = 0, after this chunk
    seconds: float       # kernel time


def buffer(system, rows, store_contact):
    """Output rows for chunks of `rows` rows."""
    return Rows.of(system, rows, store_contact)


CHUNK_SECONDS = 0.2   # kernel time an automatic chunk aims at: Python's work between chunks
#                       (the history's rows, its checkpoint, the checks) was 7 ms a chunk on
#                       pad_disc_long, 1.3 s of its 160 chunks of 2000 steps (52 ms each).
#                       Longer chunks keep a thread count that a machine's load made the
#                       faster for a while longer than it is (ThreadChoice retries the other
#                       every PROBE-th chunk)
MIN_CHUNK = 2000      # steps of an automatic chunk at least, and of the first on a thread
#                       count (the fixed default before: a slow kernel is cut as it was)
BUFFER_BYTES = 64e6   # the rows of an automatic chunk at most (its output buffer)


@dataclass(frozen=True)
class ChunkSize:
    """Steps per kernel call: solver.chunk when set; 0 (automatic) about CHUNK_SECONDS of the
    kernel a call, from the speed of the last chunk on the same thread count, and MIN_CHUNK
    steps at least (and before any), so that Python's work between chunks stays a small
    share of a fast kernel's. Either way at most a `checks`-th of the run, whole rows of
    `every` steps, and an automatic chunk's rows at most BUFFER_BYTES. Where the run is cut
    changes when Python looks, never the numbers."""
    cap: int                 # steps of a chunk at most (the output buffer holds its rows)
    every: int
    fixed: bool

    @classmethod
    def of(cls, chunk, every, n_total, row_bytes, checks):
        """chunk: solver.chunk (0: automatic); row_bytes: one output row's."""
        cap = chunk if chunk else int(BUFFER_BYTES // max(row_bytes, 1)) * every
        cap = max(every, min(cap, -(-n_total // checks)) // every * every)
        return cls(cap, every, bool(chunk))

    def steps(self, seconds_per_step=None):
        """The next chunk's steps, from the last one's seconds per step on its thread count
        (None: not run yet)."""
        if self.fixed:
            return self.cap
        want = MIN_CHUNK if not seconds_per_step else max(MIN_CHUNK,
                                                          CHUNK_SECONDS / seconds_per_step)
        return max(self.every, min(self.cap, int(want) // self.every * self.every))


def chunks(stepper, state, n_total, size, every, out, step=0, threads=None):
    """Advance state to n_total steps, the steps of each kernel call from size (a ChunkSize),
    one row stored every `every` steps into out (a buffer of size.cap // every rows); stops
    after a chunk whose status is not OK. threads: a ThreadChoice that sets each call's Numba
    threads (else the stepper's). A chunk that went non-finite keeps only the rows before the
    first with anything not finite, and the state's time is that of its last row kept."""
    per_step = {}            # thread count -> seconds per step of its last chunk
    while step < n_total:
        count = threads.next() if threads is not None else stepper.threads
        chunk = size.steps(per_step.get(count))
        n = min(threads.steps_of(count, chunk, every) if threads is not None else chunk,
                n_total - step)
        call = replace(stepper, threads=count) if count != stepper.threads else stepper
        t0 = time.perf_counter()
        try:
            status, done = call(state, n, every, out)
        except SystemError as exc:
            # Ctrl-C landing in the kernel's dispatcher: the loop's interrupt all the same
            if interrupted(exc):
                raise KeyboardInterrupt from None
            raise
        seconds = time.perf_counter() - t0
        if threads is not None:
            threads.record(count, seconds, done)
        if done:
            per_step[count] = seconds / done
        # a kernel stopping on a non-finite state or a Newton failure has not stored that step
        rows = (done - (status != OK)) // every
        finite = all(np.all(np.isfinite(x[:rows])) for x in out.arrays) and \
            np.all(np.isfinite(state.array))
        if not finite or status == NOT_FINITE:
            rows = out.finite_rows(rows)
            state.time = out.time[rows - 1] if rows else state.time - done * stepper.dt
            yield Chunk(out.head(rows), NOT_FINITE, done, step + rows * every, seconds)
            return
        step += done
        yield Chunk(out.head(rows), status, done, step, seconds)
        if status != OK:
            return


def threaded_blocks(m):
    """Row blocks of the contact pass, one per Numba thread (a single one below 128 points)."""
    nb = max(1, min(numba.get_num_threads(), m // 64 or 1))
    return np.linspace(0, m, nb + 1).astype(np.int64)


PROBE = 8     # chunks between two retries of the thread count not in use
PROBE_SHARE = 8   # a retry runs this fraction of a chunk: pad_disc_squeal's second spent 13%
#                   of its steps on one thread at 1.75x the step of two (10 s of 120) with
#                   retries of whole chunks


class ThreadChoice:
    """The Numba thread count of each chunk of a reduced run: one, or all (one row block
    each), whichever ran its last chunk faster per step, the other retried every PROBE-th
    chunk. On a shared machine the winner changes from one second to the next: a core taken
    away stalls every step's parallel contact pass (pad_disc_long's stepper on two threads ran
    28-32 or 51-71 us per step in alternate 200-step trials, on one 33-49). Both counts run
    the same blocks, so the choice changes the speed only, never the numbers. The chunks'
    timings choose: no trial steps are spent before the run. A count tried or retried while
    the other is the faster runs a short chunk (PROBE_SHARE), where the results do not depend
    on the chunks either; all threads get a second chunk before the choice, their first
    paying for the team's start."""

    def __init__(self, stepper):
        many = numba.get_num_threads()
        reduced = stepper.blocks is not None and len(stepper.blocks) > 2
        self.counts = (many, 1) if reduced and many > 1 else (stepper.threads,)
        self.seconds = {c: [] for c in self.counts}       # per step, chunk by chunk
        self.steps = dict.fromkeys(self.counts, 0)
        self.calls = 0

    def next(self):
        """The thread count of the next chunk."""
        self.calls += 1
        untried = [c for c in self.counts if not self.seconds[c]]
        if untried:
            return untried[0]
        many = self.counts[0]
        if len(self.counts) > 1 and len(self.seconds[many]) == 1:
            # its first chunk paid for the team's start: judged on a second one (a short one)
            return many
        best = self._fastest()
        if self.calls % PROBE == 0:
            return next((c for c in self.counts if c != best), best)
        return best

    def steps_of(self, count, chunk, every):
        """The steps of a chunk on `count` threads: a whole chunk on the count in use, a
        PROBE_SHARE of it (whole rows of `every` steps) on the other."""
        fastest = self._fastest()
        if fastest is None or count == fastest or len(self.counts) == 1:
            return chunk
        return max(every, chunk // PROBE_SHARE // every * every)

    def _fastest(self):
        """The count whose last chunk ran fastest per step, of those tried (None yet): the
        last only, since on a shared machine the past says little (the first chunk on two
        threads pays for the team's start)."""
        tried = [c for c in self.counts if self.seconds[c]]
        return min(tried, key=lambda c: self.seconds[c][-1]) if tried else None

    def record(self, threads, seconds, steps):
        if steps:
            self.seconds[threads].append(seconds / steps)
            self.steps[threads] += steps

    def summary(self):
        """{threads: [steps run, median us per step]} for the history's timings."""
        return {str(c): [self.steps[c], round(1e6 * float(np.median(self.seconds[c])), 2)
                         if self.seconds[c] else None] for c in self.counts}


class StopRequests(list):
    """The reasons a run was asked to stop (SIGINT, SIGTERM), in order. Over the setup
    (`at_once`) a Ctrl-C raises KeyboardInterrupt where it lands, as Python's own handler
    does, and is also kept here: an interrupt landing in a callback that swallows it (Numba's
    cache notification, a weakref finalizer) is then raised by `check` between stages. Over
    the time loop the request is only kept, and the loop stops after the chunk in hand."""
    at_once = False

    def check(self):
        """Raise KeyboardInterrupt if a stop was requested (between stages of the setup)."""
        if self:
            raise KeyboardInterrupt(self[0])

    def to_loop(self):
        """End of the setup: raise a stop requested in it; from here on a stop is a request
        the loop reads between chunks (the history's first row comes next)."""
        self.check()
        self.at_once = False


@contextmanager
def stop_requests(at_once=False):
    """Turn SIGINT and SIGTERM into a StopRequests the run reads between its stages and its
    chunks: the loop stops after the chunk in hand, with its checkpoint written. A
    KeyboardInterrupt raised wherever the interpreter happens to be can be swallowed (in a
    weakref or h5py callback) and the run would go on. A second Ctrl-C interrupts at once.
    Off the main thread (a worker of a campaign) signals are not ours to take."""
    stop = StopRequests()
    stop.at_once = at_once
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def request(signum, frame):
        again = bool(stop)
        stop.append("interrupted" if signum == signal.SIGINT else
                    f"terminated ({signal.Signals(signum).name})")
        if signum == signal.SIGINT and (again or stop.at_once):
            raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, request) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
