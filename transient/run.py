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
from .dynamics.chunks import buffer, chunks, fastest_blocks
from .dynamics.energy import Balance
from .errors import CaseError, RunAborted
from .io.history import CASE_TEXT, History, load_checkpoint, stored_dt
from .io.series import layout, series
from .kernels.codes import NO_CONVERGENCE, NOT_FINITE
from .stages import choose_dt, prepare, stepper


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


def run(case, path, resume=False, progress=None):
    """Integrate a case to solver.t_end, streaming to the HDF5 file at path.

    Returns a RunResult; a run that stops early (NaN, energy drift, Ctrl-C) keeps every chunk
    in the file, marked `aborted: <reason>`, and its status says so.
    """
    check_transient(case)
    solver, output = case.solver, case.output
    t_start = time.perf_counter()
    setup = prepare(case)
    system, stages = setup.system, dict(setup.stages)
    try:
        saved = load_checkpoint(path) if resume else None
        dt = choose_dt(case, setup, stored_dt(path) if resume else None)
    except (ValueError, KeyError, OSError) as exc:
        raise CaseError(path, "", f"--resume: {exc}") from None
    every = output.every
    chunk = max(every, solver.chunk // every * every)
    n_total = int(round(solver.t_end / dt))
    state = setup.state.copy()
    scheme = stepper(case, setup, dt)
    if system.reduced:
        blocks = saved["blocks"] if resume else fastest_blocks(
            scheme, state, system.sensors.shape[0], system.n_points)
        scheme = replace(scheme, blocks=np.asarray(blocks, np.int64))
    stages.update(scheme.stages)
    meta = {CASE_TEXT: case.text, "case_path": str(Path(case.path).resolve()),
            "overrides": list(case.overrides), "version": __version__, "dt": dt,
            "dt_critical": system.critical.dt, "scheme": solver.scheme,
            "reduced": system.reduced, "steps_planned": n_total, "every": every,
            "stages": stages, **setup.meta, **scheme.meta}
    step = 0
    if resume:
        history = History.open_for_resume(path)
        state.restore(saved)
        step = int(saved["step"][0])
    else:
        history = History.create(path, meta, layout(system, output), overwrite=True,
                                 expected_rows=n_total // every + 1, geometry=setup.geometry)
        history.append(series(system, output, setup.rows0))
    balance = Balance(setup.rows0.energy[0])
    status, t_kernel = "complete", 0.0
    bar = _progress_bar(progress, n_total, step)
    out = buffer(system, chunk // every, output.contact)
    with history:
        try:
            for c in chunks(scheme, state, n_total, chunk, every, out, step):
                t_kernel += c.seconds
                step = c.step
                if len(c.rows.time):
                    history.append(series(system, output, c.rows))
                    balance.update(c.rows.energy)
                if c.status == NOT_FINITE:
                    raise RunAborted(f"state not finite after t = {state.time:.6g} s (the "
                                     "last finite row kept)")
                history.checkpoint({**state.arrays(), "step": np.array([step]),
                                    "blocks": scheme.blocks if system.reduced
                                    else np.zeros(0)})
                bar.update(c.done)
                _check(case, system, state, dt, balance, c.status)
        except RunAborted as exc:
            status = f"aborted: {exc}"
        except KeyboardInterrupt:
            status = "aborted: interrupted"
        finally:
            bar.close()
        timings = _timings(stages, t_kernel, t_start)
        history.finish(status, timings)
    return RunResult(str(path), status, step, state.time, dt, system.critical.dt, stages,
                     timings, balance.drift, setup.meta)


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
        raise RunAborted(f"energy balance drifted by {balance.drift:.2e} of the peak "
                         f"mechanical energy (tolerance {solver.drift_tolerance:g}) at "
                         f"t = {state.time:.6g} s")


def _timings(stages, t_kernel, t_start):
    return {"setup": sum(stages.values()), "kernel": t_kernel,
            "total": time.perf_counter() - t_start}


class _NoBar:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress_bar(progress, total, initial):
    if not progress:
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=total, initial=initial, unit="step", file=sys.stderr, leave=False,
                smoothing=0.1)
