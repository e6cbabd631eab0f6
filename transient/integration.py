"""Time integration (`transient run`): specs -> stages -> a frozen system -> the time loop
(march) -> history.

Stages (each runs only if the scene needs it, and is timed): model, contact, factorization,
preload, linearization, reduction (and sampling), time step, integration. A resumed run
skips them: it continues the system and state its history keeps.
"""
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import __version__
from .case.checks import check_transient
from .dynamics.chunks import stop_requests, threaded_blocks
from .dynamics.energy import Balance
from .dynamics.plan import Plan
from .io.attributes import CASE_TEXT
from .io.history import History
from .io.lock import writing
from .io.resume import resumed
from .io.series import layout, series
from .march import march
from .stages import choose_step, prepare, stepper


@dataclass(frozen=True)
class RunResult:
    """What a run did: its history's path and status, its steps and timings."""
    path: str
    status: str
    steps: int                # steps made from t = 0
    t_end: float              # the time of the last row stored
    dt: float                 # the step it ended with (subdivided or not)
    dt_critical: float
    stages: dict
    timings: dict
    energy_drift: float
    meta: dict = None         # what prepare reports: contact points of each pair, reduced dofs,
    #                           what set the step (dt_reason)
    subdivisions: list = ()   # {"t", "dt", "why"} of each halving of the step

    @property
    def dt_reason(self):
        """What set the run's first step (stages.choose_step), '' for a history from before
        the reason was stored."""
        return (self.meta or {}).get("dt_reason", "")

    def summary(self):
        """What `transient run --json` prints."""
        return {"file": self.path, "status": self.status, "steps": self.steps,
                "t_end": self.t_end, "dt": self.dt, "dt_reason": self.dt_reason,
                "dt_critical": self.dt_critical,
                "stages": self.stages, "timings": self.timings,
                "energy_drift": self.energy_drift, "subdivisions": list(self.subdivisions)}


@dataclass
class _Start:
    """Where the run loop starts: a new run after its setup, or a resumed one."""
    system: object
    state: object
    step: int                 # in steps of dt, from t = 0
    dt: float
    every: int                # steps of dt between rows
    scheme: object
    history: History
    balance: Balance
    stages: dict
    meta: dict
    dt_first: float           # the run's first step: the subdivisions' floor is set from it
    taken: int = 0            # steps made from t = 0
    subdivisions: tuple = ()


def run(case, path, resume=False, progress=None, key="output.file", built=None,
        on_setup=None, note=None, parts=None):
    """Integrate a case to solver.t_end, streaming to the HDF5 file at path (named by key in
    errors: '-o' or output.file). The output is checked and held (io.lock) before the first
    stage; a resumed run continues the system stored in the history. Returns a RunResult; a
    run that stops early (NaN, energy drift past every subdivision of its step, Ctrl-C) keeps
    every chunk in the file, marked `aborted: <reason>`. built: the first stages' results
    when built already (a campaign's variants share them: shared.Built). on_setup(setup):
    called with a new run's setup (with Setup.unsampled) before the integration: a campaign's
    variant analyses its modes there. note(line): how a subdivided step is told (stderr).
    parts: where the components path reduces its parts (reduce.engine.Engine; None: here).
    """
    check_transient(case)
    t_start = time.perf_counter()
    # the stop requests are held from here: over the setup a Ctrl-C ends the run at once, or
    # at the next stage if it landed where it was swallowed, and leaves no file
    with stop_requests(at_once=True) as stop, writing(path, key, resume):
        start = (_resume(case, path, stop) if resume
                 else _new(case, path, stop, built, on_setup, parts))

        def timings(kernel, threads):
            return {"setup": sum(start.stages.values()), "kernel": kernel,
                    "total": time.perf_counter() - t_start, "kernel_threads": threads}
        out = march(case, start, progress, stop, timings, note)
    return RunResult(str(path), out.status, out.steps, out.t_stored, out.dt,
                     start.system.critical.dt, start.stages, out.timings, out.drift,
                     start.meta, out.subdivisions)


def _case_meta(case):
    """The case a history is run with, as its attributes keep it (io.stored.run_case)."""
    return {CASE_TEXT: case.text, "case_path": str(Path(case.path).resolve()),
            "overrides": list(case.overrides)}


def _new(case, path, stop, built=None, on_setup=None, parts=None):
    setup = prepare(case, stop.check, built, unsampled=on_setup is not None, parts=parts)
    if on_setup is not None:
        on_setup(setup)
    system, output = setup.system, case.output
    dt, reason = choose_step(case, setup)
    scheme = stepper(case, system, dt)
    if system.reduced:
        scheme = replace(scheme, blocks=threaded_blocks(system.n_points))
    stages = {**setup.stages, **scheme.stages}
    plan = Plan.of(case.solver.t_end, dt, output.every)
    meta = {**_case_meta(case), "version": __version__, "dt": dt, "dt_reason": reason,
            "dt_critical": system.critical.dt, "scheme": case.solver.scheme,
            "reduced": system.reduced, "every": output.every, "stages": stages,
            **setup.meta, **scheme.meta}
    stop.to_loop()
    history = History.create(path, meta, layout(system, output), overwrite=True,
                             expected_rows=plan.steps // output.every + 2,
                             geometry=setup.geometry, system=system)
    history.append(series(system, output, setup.rows0))
    return _Start(system, setup.state.copy(), 0, dt, output.every, scheme, history,
                  Balance(setup.rows0.energy[0]), stages,
                  {**setup.meta, **scheme.meta, "dt_reason": reason}, dt)


def _resume(case, path, stop):
    t0 = time.perf_counter()
    r = resumed(path, case)
    scheme = stepper(case, r.system, r.dt, np.asarray(r.blocks, np.int64) if r.system.reduced
                     else None)
    stop.to_loop()
    # the case it now runs to: a later resume, and a campaign's, check against these; the
    # end row of a run that ended off its rows' grid is dropped (it is past the checkpoint)
    history = History.open_for_resume(path, {**_case_meta(case), "end_row": False})
    stages = {"resume": time.perf_counter() - t0, **scheme.stages}
    return _Start(r.system, r.state, r.step, r.dt, r.every or case.output.every, scheme,
                  history, Balance.restore(r.balance), stages, r.meta,
                  float(r.meta["dt"]), r.taken, tuple(r.meta.get("subdivisions") or ()))
