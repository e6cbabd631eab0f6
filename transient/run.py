"""`transient run`: specs -> stages -> a frozen system -> `for chunk in chunks(): history`.

Stages (each runs only if the scene needs it, and is timed): model, contact, factorization,
preload, linearization, reduction (and sampling), time step, integration. Between chunks the
loop stores the rows, writes a checkpoint, checks the energy balance and the critical step, and
moves the progress bar.
"""
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import __version__
from .case.checks import check_transient
from .dynamics.chunks import ChunkSize, ThreadChoice, buffer, chunks, stop_requests, threaded_blocks
from .dynamics.energy import Balance
from .errors import RunAborted
from .io.history import CASE_TEXT, History
from .io.lock import writing
from .io.resume import resumed
from .io.series import layout, series
from .kernels.codes import NO_CONVERGENCE, NOT_FINITE
from .stages import choose_dt, prepare, stepper


CHECKS = 20       # energy balance and critical step checks per run, at least


@dataclass(frozen=True)
class RunResult:
    path: str
    status: str
    steps: int
    t_end: float
    dt: float
    dt_critical: float
    stages: dict
    timings: dict
    energy_drift: float
    meta: dict = None         # what prepare reports: contact points of each pair, reduced dofs


@dataclass
class _Start:
    """Where the run loop starts: a new run after its setup, or a resumed one."""
    system: object
    state: object
    step: int
    dt: float
    scheme: object
    history: History
    balance: Balance
    stages: dict
    meta: dict


def run(case, path, resume=False, progress=None, key="output.file", built=None,
        on_setup=None):
    """Integrate a case to solver.t_end, streaming to the HDF5 file at path (named by key in
    errors: '-o' or output.file). The output is checked and held (io.lock) before the first
    stage; a resumed run continues the system stored in the history. Returns a RunResult; a
    run that stops early (NaN, energy drift, Ctrl-C) keeps every chunk in the file, marked
    `aborted: <reason>`. built: the first stages' results when built already (a campaign's
    variants share them: shared.Built). on_setup(setup): called with a new run's setup (with
    Setup.unsampled) before the integration: a campaign's variant analyses its modes there.
    """
    check_transient(case)
    t_start = time.perf_counter()
    # the stop requests are held from here: over the setup a Ctrl-C ends the run at once, or
    # at the next stage if it landed where it was swallowed, and leaves no file
    with stop_requests(at_once=True) as stop, writing(path, key, resume):
        start = _resume(case, path, stop) if resume else _new(case, path, stop, built, on_setup)
        return _loop(case, path, start, progress, t_start, stop)


def _new(case, path, stop, built=None, on_setup=None):
    setup = prepare(case, stop.check, built, unsampled=on_setup is not None)
    if on_setup is not None:
        on_setup(setup)
    system, output = setup.system, case.output
    dt = choose_dt(case, setup)
    n_total = int(round(case.solver.t_end / dt))
    scheme = stepper(case, system, dt)
    if system.reduced:
        scheme = replace(scheme, blocks=threaded_blocks(system.n_points))
    stages = {**setup.stages, **scheme.stages}
    meta = {CASE_TEXT: case.text, "case_path": str(Path(case.path).resolve()),
            "overrides": list(case.overrides), "version": __version__, "dt": dt,
            "dt_critical": system.critical.dt, "scheme": case.solver.scheme,
            "reduced": system.reduced, "steps_planned": n_total, "every": output.every,
            "stages": stages, **setup.meta, **scheme.meta}
    stop.to_loop()
    history = History.create(path, meta, layout(system, output), overwrite=True,
                             expected_rows=n_total // output.every + 1,
                             geometry=setup.geometry, system=system)
    history.append(series(system, output, setup.rows0))
    return _Start(system, setup.state.copy(), 0, dt, scheme, history,
                  Balance(setup.rows0.energy[0]), stages, {**setup.meta, **scheme.meta})


def _resume(case, path, stop):
    t0 = time.perf_counter()
    r = resumed(path, case)
    scheme = stepper(case, r.system, r.dt, np.asarray(r.blocks, np.int64) if r.system.reduced
                     else None)
    stop.to_loop()
    history = History.open_for_resume(path)
    stages = {"resume": time.perf_counter() - t0, **scheme.stages}
    return _Start(r.system, r.state, r.step, r.dt, scheme, history, Balance.restore(r.balance),
                  stages, r.meta)


def _loop(case, path, start, progress, t_start, stop):
    solver, output, system, state = case.solver, case.output, start.system, start.state
    history, balance, scheme, dt = start.history, start.balance, start.scheme, start.dt
    every = output.every
    n_total = int(round(solver.t_end / dt))
    # the checks between chunks come at least every CHECKS-th of the run, so a run going
    # wrong is stopped within that fraction of its length (where a run is cut changes nothing)
    row_bytes = sum(x.nbytes for x in buffer(system, 1, output.contact).arrays)
    size = ChunkSize.of(solver.chunk, every, n_total, row_bytes, CHECKS)
    step, t_stored = start.step, state.time
    status, t_kernel = "complete", 0.0
    bar = _progress_bar(progress, n_total, step)
    out = buffer(system, size.cap // every, output.contact)
    threads = ThreadChoice(scheme)
    with history:
        try:
            for c in chunks(scheme, state, n_total, size, every, out, step, threads):
                t_kernel += c.seconds
                if len(c.rows.time):
                    history.append(series(system, output, c.rows))
                    balance.update(c.rows.energy)
                    t_stored = float(c.rows.time[-1])
                step = c.step
                if c.status == NOT_FINITE:
                    hint = system.critical.stick_hint(dt, case.solver.scheme,
                                                      case.solver.corrector)
                    raise RunAborted(f"state not finite after t = {state.time:.6g} s (the "
                                     f"last finite row kept){hint}")
                history.checkpoint({**state.arrays(), "step": np.array([step]),
                                    "blocks": scheme.blocks if system.reduced
                                    else np.zeros(0), "balance": balance.arrays()})
                bar.update(c.done)
                if stop:
                    raise RunAborted(stop[0])
                _check(case, system, state, dt, balance, c.status)
        except RunAborted as exc:
            status = f"aborted: {exc}"
        except KeyboardInterrupt:
            status = "aborted: interrupted"
        finally:
            bar.close()
        timings = {**_timings(start.stages, t_kernel, t_start),
                   "kernel_threads": threads.summary()}
        history.finish(status, timings)
    # what the history holds: its last row, and the steps its checkpoint reached
    return RunResult(str(path), status, step, t_stored, dt, system.critical.dt, start.stages,
                     timings, balance.drift, start.meta)


def _check(case, system, state, dt, balance, status):
    """Stop the run (RunAborted) on Newton failure, a step above the critical one at the
    deepest penetration reached, or a drifting energy balance."""
    solver = case.solver
    if status == NO_CONVERGENCE:
        raise RunAborted(f"Newton iterations did not converge in {solver.newton.max_iter} at "
                         f"t = {state.time:.6g} s (smaller dt, or a larger "
                         "solver.newton.max_iter)")
    if solver.scheme == "explicit" and not solver.force_dt:
        dt_max = system.critical.at(state.gmin)
        if dt > dt_max:
            raise RunAborted(f"dt {dt:.3e} s is above the critical step {dt_max:.3e} s at "
                             f"the deepest penetration reached ({state.gmin.min():.3e} m) at "
                             f"t = {state.time:.6g} s")
    if balance.drift > solver.drift_tolerance:
        hint = system.critical.drift_hint(dt) if solver.scheme == "explicit" else ""
        raise RunAborted(f"energy balance drifted by {balance.drift:.2e} of the largest "
                         f"energy held or exchanged (tolerance {solver.drift_tolerance:g}) "
                         f"at t = {state.time:.6g} s{hint}")


def _timings(stages, t_kernel, t_start):
    return {"setup": sum(stages.values()), "kernel": t_kernel,
            "total": time.perf_counter() - t_start}


class _NoBar:
    update = close = staticmethod(lambda *args: None)


def _progress_bar(progress, total, initial):
    if not progress:
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=total, initial=initial, unit="step", file=sys.stderr, leave=False,
                smoothing=0.1)
