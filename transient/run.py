"""`transient run`: specs -> stages -> a frozen system -> `for chunk in chunks(): history`.

Stages (each runs only if the scene needs it, and is timed): model, contact, factorization,
preload, linearization, reduction (and sampling), time step, integration. Between chunks the
loop stores the rows, writes a checkpoint, checks the energy balance and the critical step, and
moves the progress bar.
"""
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from . import __version__
from .case.checks import check_transient
from .case.signals import compile_signals
from .contact.contactset import stack
from .contact.pair import build_contact, contact_stiffness
from .dynamics import schemes
from .dynamics.chunks import buffer, chunks, fastest_blocks
from .dynamics.critical import critical_tangent
from .dynamics.energy import Balance
from .dynamics.state import State
from .dynamics.system import full_system, reduced_system
from .errors import CaseError, RunAborted
from .io.history import CASE_TEXT, History, load_checkpoint, stored_dt
from .io.series import layout, series
from .kernels.codes import ENERGY_TERMS, NO_CONVERGENCE, NOT_FINITE, OK
from .model import build_model
from .reduce.stage import reduce
from .solve.lowrank import ContactSolver
from .solve.preload import PreloadError, solve_preload


@dataclass(frozen=True)
class Setup:
    """What the stages of a case give the time integration."""
    system: object           # dynamics.system ReducedSystem or FullSystem
    state: State             # the initial state (copy it before integrating)
    rows0: object            # the outputs at the initial state: the history's row 0
    stages: dict             # stage -> seconds
    meta: dict               # what the stages report (points, reduced dofs, preload)
    geometry: dict           # fixed arrays of the history (/geometry)


def _timed(stages, name, fn, *args):
    t0 = time.perf_counter()
    out = fn(*args)
    stages[name] = time.perf_counter() - t0
    return out


def prepare(case):
    """Model, contact, preload, linearization and (optionally) reduction of a case."""
    solver, stages = case.solver, {}
    model = _timed(stages, "model", build_model, case)
    pairs = _timed(stages, "contact", build_contact, case, model) if case.contact else []
    contacts = stack(pairs, model.ndof)
    patterns = [model.load_patterns[name] for name in case.loads]
    constant = sum((p for p, load in zip(patterns, case.loads.values())
                    if load.signal["kind"] == "constant"), np.zeros(model.ndof))
    free = model.free
    # without constant loads there is no preload: the run starts from the undeformed state
    # (with initial velocities), in equilibrium or not
    cs = None
    if np.any(constant) or solver.reduction.enabled:
        cs = _timed(stages, "factorization", ContactSolver, model.K[free][:, free],
                    model.M[free][:, free], contacts.C[:, free],
                    -(2 * np.pi * solver.shift_hz) ** 2, solver.linear_solver)
    try:
        preload = _timed(stages, "preload", solve_preload, model.K, model.fixed, constant,
                         contacts, cs, solver.newton.tolerance, solver.newton.max_iter)
    except PreloadError as exc:
        raise CaseError(case.path, "loads", str(exc)) from None
    if preload.iterations == 0:
        del stages["preload"]
    t0 = time.perf_counter()
    kw = [contacts.weights[s] * preload.tangent[s] for s in contacts.slices.values()]
    K_lin = (model.K + contact_stiffness(pairs, model.ndof, kw=kw)).tocsr() if pairs else model.K
    if pairs:
        stages["linearization"] = time.perf_counter() - t0
    v0 = initial_velocity(case, model)
    signals = compile_signals([load.signal for load in case.loads.values()])
    sensors = model.sensors if case.output.sensors else model.sensors[:0]
    names = tuple(model.sensor_names) if case.output.sensors else ()
    if solver.reduction.enabled:
        M = sp.diags(model.lumped_mass).tocsr() if solver.mass == "lumped" else model.M
        red = reduce(case, model, M, K_lin, pairs, contacts, preload, patterns, v0,
                     cs.solver(contacts.weights * preload.tangent),
                     critical_tangent(contacts, preload.tangent), stages)
        pairs, contacts, preload, meta = red.pairs, red.contacts, red.preload, red.meta
        system = reduced_system(red.T, red.omega2, solver.reduction.fmax, solver.damping,
                                contacts, preload.tangent, patterns, signals, sensors, names,
                                case.output.field)
        state = State.zeros(system.n, contacts.n_points)
        state.q[:], state.v[:] = red.q0, red.v0
    else:
        system = _timed(stages, "time_step", full_system, K_lin, model.lumped_mass,
                        None if solver.lumped else model.M, solver.damping, contacts,
                        preload.tangent, free, patterns, signals, sensors, names,
                        case.output.field)
        meta = {"free_dofs": len(free)}
        state = State.zeros(system.n, contacts.n_points)
        state.q[:], state.v[:] = preload.u[free], v0[free]
    state.gmin[:] = preload.gap
    consistent = not system.reduced and solver.scheme == "implicit" and not solver.lumped
    rows0 = schemes.initial_acceleration(system, state, system.M if consistent else None)
    meta.update(_contact_meta(pairs, contacts, preload))
    return Setup(system, state, rows0, stages, meta, _geometry(case, system, pairs))


def _contact_meta(pairs, contacts, preload):
    return {
        "preload_iterations": preload.iterations, "preload_residual": preload.residual,
        "preload_contact_force": {name: float((contacts.weights * preload.pressure)[s].sum())
                                  for name, s in contacts.slices.items()},
        "n_points": contacts.n_points,
        "pairs": {p.name: {"rule": p.spec.rule, "points": p.rule.n_points,
                           "regularized": p.spec.regularized, "eps": p.eps,
                           "kept": p.compat.kept(p.eps) if p.compat else None,
                           "candidates": p.candidates or None,
                           "law": p.spec.law.kind} for p in pairs}}


def _geometry(case, system, pairs):
    geometry = {}
    if case.output.field and system.reduced:
        # u = T q: kept so that an export needs no rebuild of the basis (a rebuild repeats
        # the setup, and its rank decisions may differ with the BLAS threads)
        geometry["field/basis"] = system.T
    if case.output.contact:
        for p in pairs:
            geometry.update({f"contact/{p.name}/points": p.rule.points,
                             f"contact/{p.name}/normals": p.rule.normals,
                             f"contact/{p.name}/weights": p.rule.weights})
    return geometry


def initial_velocity(case, model):
    v = np.zeros(model.ndof)
    for spec in case.initial.values():
        v[model.part_dofs(spec.part).reshape(-1, 3)] = spec.velocity
    v[model.fixed] = 0.0
    return v


def choose_dt(case, setup, stored=None):
    """The time step: the case's, checked against the critical step, or an automatic one; a
    resumed run keeps the one stored in its history."""
    solver = case.solver
    dt = solver.dt if stored is None else stored
    if solver.scheme in ("exponential", "implicit"):
        # unconditionally stable: the step is set by accuracy, 20 steps per period at fmax
        return dt or 1.0 / (20.0 * solver.reduction.fmax)
    critical = setup.system.critical.dt
    if dt == 0.0:
        dt = 0.9 * critical
        if not np.isfinite(dt):
            raise CaseError(case.path, "solver.dt", "no stiffness bounds the step: give dt")
    elif dt > critical and not solver.force_dt:
        raise CaseError(case.path, "solver.dt", f"{dt:.3e} s is above the critical step of "
                        f"central differences {critical:.3e} s (set solver.force_dt = true to "
                        "run anyway)")
    return dt


def _stepper(case, setup, dt, blocks=None):
    try:
        return schemes.stepper(setup.system, case.solver, dt, blocks)
    except CaseError as exc:
        raise CaseError(case.path, exc.key, exc.message) from None


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
    stepper = _stepper(case, setup, dt)
    if system.reduced:
        blocks = saved["blocks"] if resume else fastest_blocks(
            stepper, state, system.sensors.shape[0], system.n_points)
        stepper = _stepper(case, setup, dt, np.asarray(blocks, np.int64))
    stages.update(stepper.stages)
    meta = {CASE_TEXT: case.text, "case_path": str(Path(case.path).resolve()),
            "overrides": list(case.overrides), "version": __version__, "dt": dt,
            "dt_critical": system.critical.dt, "scheme": solver.scheme,
            "reduced": system.reduced, "steps_planned": n_total, "every": every,
            "stages": stages, **setup.meta, **stepper.meta}
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
            for c in chunks(stepper, state, n_total, chunk, every, out, step):
                t_kernel += c.seconds
                step = c.step
                if len(c.rows.time):
                    history.append(series(system, output, c.rows))
                    balance.update(c.rows.energy)
                if c.status == NOT_FINITE:
                    raise RunAborted(f"state not finite after t = {state.time:.6g} s (the "
                                     "last finite row kept)")
                history.checkpoint({**state.arrays(), "step": np.array([step]),
                                    "blocks": stepper.blocks if system.reduced
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


def simulate(case, setup, dt, n_steps, every=1):
    """Integrate a prepared setup in memory with the case's scheme on one row block (no
    history file, no checks between chunks): for tests and benchmarks that compare schemes.

    Returns (series, status, kernel seconds): series maps "time", "sensors/<name>",
    "energy/<term>" and, if the case stores contact, "contact/gap" and "contact/pressure" (all
    points) to arrays with one row per `every` steps, the initial state first.
    """
    state = setup.state.copy()
    out = buffer(setup.system, n_steps // every, case.output.contact)
    t0 = time.perf_counter()
    status, done = _stepper(case, setup, dt)(state, n_steps, every, out)
    seconds = time.perf_counter() - t0
    rows = [np.concatenate([first[:1], x[:done // every]])
            for first, x in zip(setup.rows0.arrays, out.arrays)]
    result = {"time": rows[0]}
    result.update({f"sensors/{name}": rows[1][:, k]
                   for k, name in enumerate(setup.system.sensor_names)})
    result.update({f"energy/{term}": rows[4][:, k] for k, term in enumerate(ENERGY_TERMS)})
    if case.output.contact:
        result["contact/gap"], result["contact/pressure"] = rows[2], rows[3]
    return result, {OK: "complete", NOT_FINITE: "not finite",
                    NO_CONVERGENCE: "no convergence"}[status], seconds


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
