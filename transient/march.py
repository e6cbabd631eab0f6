"""The time loop of `transient run`: chunks of steps on the rows' grid, each stored and checked,
then the run's end (dynamics.plan), and the step subdivided where the run fails, as
code_aster's DECOUPE does.

A run fails when its state goes non-finite, Newton does not converge, or the energy balance
drifts past solver.drift_tolerance at a row. It then goes back to the last row before the
failure (its checkpoint, replayed to that row: the same numbers), halves the step, doubles
`every` (the rows keep a uniform time axis), rebuilds the stepper (the exponential scheme's
propagators depend on the step) and goes on at the new step to the end: a step that failed
where the friction grows would fail again there. Down to the case's floor, dt /
2^subdivision; below it the run aborts, keeping its history, with the steps it tried.

The checkpoint is the last state the run vouches for: written after a chunk once its rows are
judged (from the first CHECKS-th of the run on: before, the energy held is small and the
step's error a large share of it), so every failure goes back to a row at or after it. Where
a failure is found, and the row it goes back to, depend on the rows alone, never on where the
run was cut into chunks: a subdivided run is the same run after run, and resumed.
"""
import time
from dataclasses import dataclass

import numpy as np

from .dynamics.chunks import ChunkSize, ThreadChoice, buffer, chunks
from .dynamics.plan import Plan, retime
from .errors import RunAborted
from .io.series import series
from .kernels.codes import NOT_FINITE, OK
from .progress import bar as progress_bar
from .stages import stepper

CHECKS = 20           # chunks a run is cut into at least (checks between them)
JUDGED_ROWS = 2 ** 16  # the row a run's balance is judged from at latest (else the first
#                        CHECKS-th of its rows): its energies are kept until then, to find
#                        where a failure began


@dataclass(frozen=True)
class Outcome:
    status: str
    steps: int            # steps made from t = 0 (the replays of a subdivision not counted)
    t_stored: float       # the time of the last row stored [s]
    dt: float             # the step it ended with [s]
    drift: float          # the energy balance's drift
    timings: dict         # what `timings` made of the kernel's seconds and threads
    subdivisions: list    # {"t", "dt", "why"} of each halving


@dataclass(frozen=True)
class _Base:
    """The checkpoint: the state, steps, balance and rows stored there."""
    state: object
    step: int
    taken: int
    balance: object
    rows: int


@dataclass(frozen=True)
class _Failure:
    kind: str             # "drift", "not finite" or "newton"
    why: str              # what failed and when, for the note and the abort
    kept: int             # rows since the checkpoint before the failure
    rows: object          # the failing chunk's rows (a view of the output buffer)
    done: int             # the steps it made
    grid: bool            # a chunk of whole rows (not the run's end)


class Loop:
    """One run's loop from its start (run._Start) to solver.t_end; `march` runs it."""

    def __init__(self, case, start, progress, note):
        self.case, self.system, self.history = case, start.system, start.history
        self.state, self.balance, self.scheme = start.state, start.balance, start.scheme
        self.step, self.taken, self.rows = start.step, start.taken, start.history.rows()
        self.plan = Plan.of(case.solver.t_end, start.dt, start.every)
        self.floor = start.dt_first / 2 ** case.solver.subdivision
        first = Plan.of(case.solver.t_end, start.dt_first, case.output.every)
        self.judged = min(-(-first.steps // (first.every * CHECKS)), JUDGED_ROWS)
        self.subdivisions = list(start.subdivisions)
        self.kernel, self.t_stored = 0.0, start.state.time
        self.threads = ThreadChoice(start.scheme)
        self.bar = progress_bar(progress, self._total(), self.step)
        self.note = note or self.bar.write
        self._buffers()

    def _total(self):
        return self.plan.steps + self.plan.partial

    def _buffers(self):
        output = self.case.output
        row_bytes = sum(x.nbytes for x in buffer(self.system, 1, output.contact).arrays)
        self.size = ChunkSize.of(self.case.solver.chunk, self.plan.every, self.plan.steps,
                                 row_bytes, CHECKS)
        self.out = buffer(self.system, self.size.cap // self.plan.every, output.contact)

    def run(self, stop):
        self.history.annotate({"steps_planned": self._total()})
        self._checkpoint()
        while True:
            failure = self._grid(stop) or self._end()
            if failure is None:
                return
            self._subdivide(failure)

    def _grid(self, stop):
        """Chunks to the plan's last row on its grid: None there, or the first _Failure."""
        for c in chunks(self.scheme, self.state, self.plan.grid, self.size, self.plan.every,
                        self.out, self.step, self.threads):
            self.kernel += c.seconds
            failure = self._judge(c.rows, c.status, c.done)
            if failure is not None:
                return failure
            self._store(c.rows)
            self.step, self.taken = c.step, self.taken + c.done
            if self.step // self.plan.every >= self.judged:
                self._checkpoint()
            self.bar.update(c.done)
            if stop:
                raise RunAborted(stop[0])
            self._check_critical()
        return None

    def _end(self):
        """The steps past the grid, the last one shortened to t_end, stored as the end row
        and not checkpointed: None, or the _Failure."""
        plan = self.plan
        if not plan.end_row or self.step != plan.grid:
            return None
        whole, t0, status = plan.steps - self.step, time.perf_counter(), OK
        if whole:
            # one row at the last whole step, or none before a shortened one
            status, _ = self.scheme(self.state, whole, whole + plan.partial, self.out)
        if status == OK and plan.partial:
            last = plan.t_end - self.state.time
            retime(self.state, self.case.solver.scheme, last / plan.dt)
            status, _ = stepper(self.case, self.system, last, self.scheme.blocks)(
                self.state, 1, 1, self.out)
        self.kernel += time.perf_counter() - t0
        rows, done = self.out.head(1), whole + plan.partial
        if status == OK and rows.finite_rows(1) == 0:
            status = NOT_FINITE
        failure = self._judge(rows if status == OK else self.out.head(0), status, done, False)
        if failure is not None:
            return failure
        self._store(rows)
        self.step, self.taken = plan.steps + plan.partial, self.taken + done
        self.history.annotate({"end_row": True})
        self.bar.update(done)
        return None

    def _judge(self, rows, status, done, grid=True):
        """The _Failure of a chunk (its finite rows, status, steps made), None when it holds:
        a row judged whose energy balance drifts (then the first row that drifts since the
        checkpoint, judged or not, is where it began), a non-finite state or a Newton
        failure (then the row before)."""
        tolerance = self.case.solver.drift_tolerance
        first = self.step // self.plan.every + 1          # the run's row index of rows[0]
        over = self.balance.first_over(rows.energy, tolerance, self.judged - first)
        if over is None and status == OK:
            return None
        since = np.concatenate(self.pending + [rows.energy])
        began = self.base.balance.first_over(since, tolerance)
        if over is not None:
            row, drift = over
            return _Failure("drift", f"energy balance drifted by {drift:.2e} of the largest "
                            f"energy held or exchanged (tolerance {tolerance:g}) at t = "
                            f"{rows.time[row]:.6g} s", began[0], rows, done, grid)
        t = float(rows.time[-1]) if len(rows.time) else self.state.time
        kept = min(len(since), began[0] if began else len(since))
        if status == NOT_FINITE:
            return _Failure("not finite", f"state not finite after t = {t:.6g} s", kept,
                            rows, done, grid)
        return _Failure("newton", f"Newton iterations did not converge in "
                        f"{self.case.solver.newton.max_iter} after t = {t:.6g} s", kept, rows,
                        done, grid)

    def _subdivide(self, failure):
        """Back to the last row before the failure, at half the step; below the floor, the
        abort."""
        plan, base = self.plan, self.base
        if plan.dt / 2 < self.floor * (1 - 1e-9):
            self._abort(failure)
        # the rows to that one: those stored since the checkpoint, and the chunk's before it
        since = np.concatenate(self.pending + [failure.rows.energy])[:failure.kept]
        stored = self.rows - base.rows
        if failure.kept < stored:
            self.history.truncate(base.rows + failure.kept)
        elif failure.kept > stored:
            self.history.append(series(self.system, self.case.output,
                                       failure.rows.head(failure.kept - stored)))
        self.rows = base.rows + failure.kept
        self.balance = base.balance.copy()
        self.balance.update(since)
        # the state there: the checkpoint's, replayed (the same numbers)
        self.state, n = base.state.copy(), failure.kept * plan.every
        t0 = time.perf_counter()
        for start in range(0, n, self.size.cap):
            self.scheme(self.state, min(self.size.cap, n - start), plan.every, self.out)
        self.kernel += time.perf_counter() - t0
        self.t_stored = self.state.time
        self.step, self.taken = 2 * (base.step + n), base.taken + n
        self.plan = plan.halved()
        self.scheme = stepper(self.case, self.system, self.plan.dt, self.scheme.blocks)
        retime(self.state, self.case.solver.scheme, 0.5)
        self.subdivisions.append({"t": self.state.time, "dt": self.plan.dt,
                                  "why": failure.why})
        self._checkpoint()
        self.history.annotate({"subdivisions": self.subdivisions, "dt_end": self.plan.dt,
                               "steps_planned": self._total()})
        self._buffers()
        self.bar.restart(self._total(), self.step)
        self.note(f"step subdivided at t = {self.state.time:.6g} s: {plan.dt:.4g} -> "
                  f"{self.plan.dt:.4g} s ({failure.why})")

    def _abort(self, failure):
        """Keep the rows before a non-finite state or a Newton failure, or every row of a
        drifting chunk (checkpointed: a resume with a larger tolerance goes on), and stop."""
        critical, solver, dt = self.system.critical, self.case.solver, self.plan.dt
        self._store(failure.rows)
        if failure.kind == "drift":
            self.taken += failure.done
            if failure.grid:
                self.step += failure.done
                self._checkpoint()
        if failure.kind == "not finite":
            hint = " (the last finite row kept)" + critical.stick_hint(dt, solver.scheme,
                                                                        solver.corrector)
        elif failure.kind == "newton":
            hint = " (smaller dt, or a larger solver.newton.max_iter)"
        else:
            hint = critical.drift_hint(dt) if solver.scheme == "explicit" else ""
        tried = ""
        if solver.subdivision:
            steps = [self.floor * 2 ** k for k in range(solver.subdivision, -1, -1)]
            tried = (f"; no step down to the floor dt / {2 ** solver.subdivision} held "
                     f"(steps tried: {', '.join(f'{s:.4g}' for s in steps)} s; "
                     "solver.subdivision)")
        raise RunAborted(failure.why + hint + tried)

    def _store(self, rows):
        if len(rows.time):
            self.history.append(series(self.system, self.case.output, rows))
            self.balance.update(rows.energy)
            self.pending.append(rows.energy.copy())
            self.rows += len(rows.time)
            self.t_stored = float(rows.time[-1])

    def _checkpoint(self):
        self.history.checkpoint({
            **self.state.arrays(), "step": np.array([self.step]),
            "blocks": self.scheme.blocks if self.system.reduced else np.zeros(0),
            "balance": self.balance.arrays(), "dt": np.array([self.plan.dt]),
            "every": np.array([self.plan.every]), "taken": np.array([self.taken])})
        self.base = _Base(self.state.copy(), self.step, self.taken, self.balance.copy(),
                          self.rows)
        self.pending = []

    def _check_critical(self):
        """Stop (RunAborted) an explicit run whose step is above the critical one at the
        deepest penetration reached."""
        solver, dt, gmin = self.case.solver, self.plan.dt, self.state.gmin
        if solver.scheme == "explicit" and not solver.force_dt:
            dt_max = self.system.critical.at(gmin)
            if dt > dt_max:
                raise RunAborted(f"dt {dt:.3e} s is above the critical step {dt_max:.3e} s "
                                 f"at the deepest penetration reached ({gmin.min():.3e} m) "
                                 f"at t = {self.state.time:.6g} s")


def march(case, start, progress, stop, timings, note=None):
    """Run the loop of a run's start to solver.t_end (or its stop) and finish its history
    with the run's status and timings(kernel seconds, threads). note(line): how a
    subdivision is told (stderr by default). Returns an Outcome."""
    loop = Loop(case, start, progress, note)
    status = "complete"
    with start.history as history:
        try:
            loop.run(stop)
        except RunAborted as exc:
            status = f"aborted: {exc}"
        except KeyboardInterrupt:
            status = "aborted: interrupted"
        finally:
            loop.bar.close()
        history.annotate({"dt_end": loop.plan.dt})
        spent = timings(loop.kernel, loop.threads.summary())
        history.finish(status, spent)
    return Outcome(status, loop.taken, loop.t_stored, loop.plan.dt, loop.balance.drift,
                   spent, loop.subdivisions)
