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
    return Rows.empty(rows, system.sensors.shape[0], system.n_points if store_contact else 0)


def chunks(stepper, state, n_total, chunk, every, out, step=0):
    """Advance state to n_total steps, chunk steps per kernel call, one row stored every
    `every` steps into out (a buffer of chunk // every rows); stops after a chunk whose status
    is not OK. A chunk that went non-finite keeps only the rows before the first with
    anything not finite, and the state's time is that of its last row kept."""
    while step < n_total:
        n = min(chunk, n_total - step)
        t0 = time.perf_counter()
        try:
            status, done = stepper(state, n, every, out)
        except SystemError as exc:
            # Ctrl-C landing in the kernel's dispatcher: the loop's interrupt all the same
            if interrupted(exc):
                raise KeyboardInterrupt from None
            raise
        seconds = time.perf_counter() - t0
        # a kernel stopping on a non-finite state has not stored that step
        rows = (done - (status == NOT_FINITE)) // every
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


def fastest_threads(stepper, state, n_sensors, m, steps=20):
    """The Numba thread count that runs the stepper's blocks fastest here and now: one, or
    all (threads stall when the machine's cores are busy). Both run the same blocks, so the
    choice changes the speed only, never the numbers."""
    if len(stepper.blocks) <= 2:
        return 1
    times = {}
    for threads in (1, numba.get_num_threads()):
        trial = replace(stepper, threads=threads)
        best = np.inf
        for _ in range(2):       # the first call may compile
            out = Rows.empty(steps, n_sensors, m)
            t0 = time.perf_counter()
            trial(state.copy(), steps, 1, out)
            best = min(best, time.perf_counter() - t0)
        times[threads] = best
    return min(times, key=times.get)


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
