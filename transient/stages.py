"""The stages of a case up to the time integration: specs -> model -> contact -> factorization
-> preload -> linearization -> reduction (and sampling) -> a frozen system and its initial
state. `prepare` runs each stage only if the scene needs it, and times it; `simulate` integrates
a prepared setup in memory (tests and benchmarks); `integration.run` streams it to a history.
"""
import time
from dataclasses import dataclass

import numpy as np

from .case.signals import compile_signals
from . import heap, setuptimes
from .case.checks import rebased
from .case.sizes import check_steps, parts_cells, setup_bytes
from .contact.contactset import first_tangent, stack
from .contact.pair import build_contact, contact_stiffness
from .dynamics import schemes
from .dynamics.chunks import buffer
from .dynamics.critical import CONTACT_OMEGA_DT, REMAINDER_OMEGA_DT, critical_tangent
from .dynamics.state import Rows, State
from .dynamics.system import full_system, reduced_system
from .errors import CaseError
from .kernels.codes import ENERGY_TERMS, NO_CONVERGENCE, NOT_FINITE, OK
from .model import build_model, constant_load
from .model.band import check_band
from .reduce.basis import rebase
from .reduce.components import components_basis, reduce_parts
from .reduce.reference import reference_basis
from .reduce.stage import reduce, reduction_mass
from .shared import Built, factorization
from .timings import Stages
from . import blas
from .solve.linsolve import why
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
    model: object = None     # the Model (parts, dofs) the system was built from
    basis: tuple = None      # a reduced system's (X, AW): its coordinates on the model's dofs
    #                          are X AW q (the product formed only for field output)
    unsampled: object = None  # asked of prepare: a sampled rule's Setup on its candidates,
    #                           before the sampling (what the cea analyses; no rows0)


def prepare(case, check=None, built=None, unsampled=False, analysis=False, parts=None):
    """Model, contact, preload, linearization and (optionally) reduction of a case.

    The setup's dense algebra runs on one OpenBLAS thread: its calls are many and mid-sized
    (eigh of a few thousand, products of n x a few hundred), where two threads contend with
    PARDISO's and Numba's (docs/performance.md). PARDISO (MKL) keeps its threads, which pay
    for its solves.
    The large products of sections that solve nothing run on every core (transient.blas).
    built: the first stages' results when built already (a Built: cea bounds the model's size
    first, a campaign's variants share them). unsampled: also the Setup of a sampled rule's
    candidates (Setup.unsampled), the cea's, from the same stages. analysis: the system is
    linearized, not integrated (the cea's): it gets no critical step and the Setup no rows0
    (the critical step's eigenvalues are dense work an analysis does not use).
    parts: where the components path reduces its parts (reduce.engine.Engine; None: here),
    and its stage(name, seconds, peak GB) said as each stage ends."""
    with blas.one_thread(), heap.setup():
        stages = Stages(check, getattr(parts, "stage", None))
        return _prepare(case, stages, built or Built(None), unsampled, analysis, parts)


def prepare_parts(case, parts):
    """The components path's parts of a case reduced through parts (a reduce.engine.Engine),
    nothing after them: a campaign does this for one variant before the others fan out, so
    that the parts they share are reduced once on the whole cluster and read back from its
    cache (reduce.engine.cached) by every variant."""
    with blas.one_thread():
        model = build_model(case)
        pairs = build_contact(case, model) if case.contact else []
        reduce_parts(case, model, pairs, stack(pairs, model.ndof),
                     [model.load_patterns[n] for n in case.loads], constant_load(case, model),
                     parts)


def _band_keys(case, analysis):
    """The frequency keys the setup (and the cea of an analysis) solves modes to."""
    solver = case.solver
    if solver.reduction.enabled:
        return [("solver.reduction.fmax", solver.reduction.fmax),
                ("solver.reduction.cutoff", solver.reduction.cutoff)]
    if analysis and solver.modes.fmax:
        return [("solver.modes.fmax", solver.modes.fmax)]
    return [("solver.reduction.fmax", solver.reduction.fmax)] if analysis else []


def _prepare(case, stages, built, want_unsampled=False, analysis=False, parts=None):
    solver = case.solver
    components = solver.reduction.components
    model = (stages.timed("loads", build_model, case, built.model) if built.model is not None
             else stages.timed("model", build_model, case))
    check_band(case, model, _band_keys(case, analysis))
    if built.model is None:
        setuptimes.announce(setuptimes.kind(case, analysis), model)
    small = setup_bytes(parts_cells(model.parts)) <= case.limits.memory_bytes / 2
    if small and heap.permitted():
        heap.retain_freed()     # freed blocks reused, not faulted in afresh (heap's docstring)
    if built.geometry is not None:
        pairs = build_contact(case, model, geometry=built.geometry)
    else:
        pairs = stages.timed("contact", build_contact, case, model) if case.contact else []
    contacts = stack(pairs, model.ndof)
    if solver.scheme == "implicit" and not solver.reduction.enabled:
        # Newmark on the full model keeps S^-1 C^T dense: refused now, not after the setup
        schemes.check_woodbury(len(model.free), contacts.n_points, case.path,
                               contacts.friction is not None)
    patterns = [model.load_patterns[name] for name in case.loads]
    constant = constant_load(case, model)
    free = model.free
    # without constant loads there is no preload: the run starts from the undeformed state
    # (with initial velocities), in equilibrium or not
    cs, unsampled, basis, tangent = None, None, None, None
    if (np.any(constant) or solver.reduction.enabled) and not components:
        cs = built.solver or stages.timed("factorization", factorization, case, model, contacts)
    if components:
        # each part's own basis, the preload solved on their coupling (reduce.components)
        M = reduction_mass(case, model, None)[0]
        basis, preload = stages.timed("components", components_basis, case, model, M, pairs,
                                      contacts, patterns, constant, parts)
    else:
        try:
            preload = stages.timed("preload", solve_preload, model.K, model.fixed, constant,
                                   contacts, cs, solver.newton.tolerance,
                                   solver.newton.max_iter, first_tangent(pairs, contacts))
        except PreloadError as exc:
            raise CaseError(case.path, "loads", str(exc)) from None
        if preload.iterations == 0:
            del stages["preload"]
    t0 = time.perf_counter()
    if solver.reduction.enabled and not components:
        # the tangent solve, which also applies K_lin on the free dofs (tangent.stiffness)
        tangent = cs.solver(contacts.weights * preload.tangent)
    elif not solver.reduction.enabled:
        kw = [contacts.weights[s] * preload.tangent[s] for s in contacts.slices.values()]
        K_lin = ((model.K + contact_stiffness(pairs, model.ndof, kw=kw)).tocsr() if pairs
                 else model.K)
    if pairs and not components:
        stages["linearization"] = time.perf_counter() - t0
    stages.check()
    v0 = initial_velocity(case, model)
    signals = compile_signals([load.signal for load in case.loads.values()])
    sensors = model.sensors if case.output.sensors else model.sensors[:0]
    names = tuple(model.sensor_names) if case.output.sensors else ()
    if solver.reduction.enabled:
        if components:
            red, elsewhere = reduce(case, model, M, pairs, contacts, preload, patterns, v0,
                                    None, None, stages, basis=basis), False
        else:
            red, elsewhere = _assembled(case, stages, built, model, pairs, contacts, preload,
                                        patterns, v0, cs, tangent)
        pairs, contacts, preload, meta = red.pairs, red.contacts, red.preload, red.meta
        if elsewhere:
            meta["basis_mu"] = {name: c.friction.basis_mu for name, c in case.contact.items()
                                if c.friction.basis_mu}
        # the rows and operators on the reduced coordinates
        system, state = stages.timed("reduced_system", _reduced, case, red, patterns, signals,
                                     sensors, names, not analysis, model.loss)
        if want_unsampled and red.unsampled is not None:
            u, t0 = red.unsampled, time.perf_counter()
            unsampled = Setup(*_reduced(case, u, patterns, signals, sensors, names, False,
                                        model.loss),
                              None, {}, dict(u.meta), {}, model, (u.X, u.AW))
            stages["reduced_system"] += time.perf_counter() - t0
    else:
        system = stages.timed("time_step", full_system, K_lin, model.lumped_mass,
                        None if solver.lumped else model.M, solver.damping, contacts,
                        preload.tangent, free, patterns, signals, sensors, names,
                        case.output.field, not analysis, model.loss)
        meta = {"free_dofs": len(free)}
        state = State.zeros(system.n, contacts.n_points)
        state.q[:], state.v[:] = preload.u[free], v0[free]
    state.gmin[:] = preload.gap
    consistent = not system.reduced and solver.scheme == "implicit" and not solver.lumped
    rows0 = None if analysis else schemes.initial_acceleration(
        system, state, case.output.contact, system.M if consistent else None)
    meta.update(_contact_meta(pairs, contacts, preload))
    meta["peak_rss_gb"] = dict(stages.peaks)
    if cs is not None:
        # K - sigma M: the preload's Newton, shift-invert and the static responses
        meta["factorizations"] = {"stiffness": why(getattr(cs.solve0, "backend", "?"),
                                                   solver.linear_solver)}
        meta["factorization_timings"] = dict(cs.timings)
    stages.check()
    if built.model is None and getattr(parts, "cache", None) is None:
        # a setup from scratch, its parts reduced here or on workers but none read back: what
        # a dry run of a case its size on this machine is estimated from
        setuptimes.record_setup(setuptimes.kind(case, analysis), model, pairs,
                                sum(stages.values()))
    return Setup(system, state, rows0, dict(stages), meta, _geometry(case, system, pairs),
                 model, (red.X, red.AW) if system.reduced else None, unsampled)


def _assembled(case, stages, built, model, pairs, contacts, preload, patterns, v0, cs,
               tangent):
    """(ReducedModel, whether its basis was made at another friction) of the assembled path:
    the basis of the whole model on its factorization cs and the tangent solve."""
    M, Mf = reduction_mass(case, model, cs)
    # the factors freed after the basis' last solve, unless a campaign's variants share them
    release = cs.release if cs is not built.solver else None
    basis, sample, shared, elsewhere = None, None, built.basis, rebased(case)
    if shared is None and elsewhere:
        shared = stages.timed("reference", reference_basis, case, model, M, pairs, cs,
                              patterns, Mf)
    if shared is not None:
        # a basis made at another friction (or this case's own, shared by a campaign)
        basis = (stages.timed("reduction", rebase, shared.basis, shared.K0r,
                              tangent.stiffness, M, model.fixed, preload.u)
                 if elsewhere else shared.basis)
        sample = shared.sample
        if release is not None:
            release()           # the last solve was the preload's
        release = None
    return reduce(case, model, M, pairs, contacts, preload, patterns, v0, tangent,
                  critical_tangent(contacts, preload.tangent), stages, cs.C, Mf, release,
                  basis, sample), elsewhere


def _reduced(case, red, patterns, signals, sensors, names, critical=True, loss=None):
    """(system, initial state) of a ReducedModel; critical: with its critical step; loss:
    the model's H (its viscous share at solver.damping.loss_frequency, else at the band's
    top, reduction.fmax)."""
    solver = case.solver
    damping = solver.damping
    system = reduced_system(red.X, red.AW, red.omega2, solver.reduction.modes_fmax, damping,
                            red.contacts, red.preload.tangent, patterns, signals, sensors,
                            names, case.output.field, red.preload.pressure, critical, loss,
                            damping.loss_frequency or solver.reduction.fmax)
    state = State.zeros(system.n, red.contacts.n_points)
    state.q[:], state.v[:] = red.q0, red.v0
    state.gmin[:] = red.preload.gap
    return system, state


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
                           "law": p.spec.law.kind,
                           "gap0": p.gaps.meta() if p.gaps else None} for p in pairs}}


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
    return choose_step(case, setup, stored)[0]


def choose_step(case, setup, stored=None):
    """(dt, reason): choose_dt's step and what set it, in words a run prints and stores (the
    case's solver.dt, the history's, or the bound the automatic step took)."""
    solver = case.solver
    dt = solver.dt if stored is None else stored
    reason = "solver.dt" if stored is None else "the step stored in the history, resumed"
    if solver.scheme in ("exponential", "implicit"):
        # unconditionally stable: the step is set by accuracy, 20 steps per period at fmax,
        # but for the exponential scheme's explicit correctors of a stiff contact remainder
        critical = setup.system.critical
        dt_max = (np.inf if solver.scheme == "implicit" else
                  critical.remainder_dt(solver.corrector))
        if dt == 0.0:
            accuracy = 1.0 / (20.0 * solver.reduction.fmax)
            dt = min(accuracy, 0.9 * dt_max)
            reason = ("20 steps a period at solver.reduction.fmax" if dt == accuracy else
                      f"0.9 of the {solver.corrector} corrector's bound on the friction's "
                      "damping at steady sliding" if dt_max == critical.friction_dt else
                      f"0.9 of the {solver.corrector} corrector's bound on the contact "
                      "remainder (contact.*.k)")
        elif dt > dt_max and not solver.force_dt and dt > critical.friction_dt:
            raise CaseError(case.path, "solver.dt", f"{dt:.3e} s: the {solver.corrector} "
                            "corrector takes the friction explicitly, and its damping at "
                            f"steady sliding bounds the step at {critical.friction_dt:.3e} s "
                            "(w p mu / V across the sliding, w p dmu/ds along): "
                            "solver.corrector "
                            '= "implicit", a smaller step, or solver.force_dt = true to run '
                            "anyway")
        elif dt > dt_max and not solver.force_dt:
            pair = critical.stiffest_point(dt)[1]
            raise CaseError(case.path, "solver.dt", f"{dt:.3e} s: the {solver.corrector} "
                            "corrector takes the contact beyond the preload's tangent "
                            f"explicitly, and contact.{pair}.k puts it at omega dt = "
                            f"{dt * critical.omega_remainder:.3g}, above "
                            f"{REMAINDER_OMEGA_DT[solver.corrector]:g}: solver.corrector = "
                            f'"implicit", a step up to {dt_max:.3e} s, or solver.force_dt = '
                            "true to run anyway")
        check_steps(case, dt)
        return dt, reason
    critical = setup.system.critical
    if dt == 0.0:
        # stable, and within the range where an impact conserves energy
        bounds = {"0.9 of central differences' critical step": 0.9 * critical.dt,
                  "the contact's penalty at omega_c dt = "
                  f"{CONTACT_OMEGA_DT} (contact.*.k)": critical.contact_dt,
                  "0.9 of central differences' bound on the friction's damping at steady "
                  "sliding": 0.9 * critical.friction_dt}
        reason = min(bounds, key=bounds.get)
        dt = bounds[reason]
        if not np.isfinite(dt):
            raise CaseError(case.path, "solver.dt", "no stiffness bounds the step: give dt")
    elif dt > critical.dt and not solver.force_dt:
        raise CaseError(case.path, "solver.dt", f"{dt:.3e} s is above the critical step of "
                        f"central differences {critical.dt:.3e} s (set solver.force_dt = true "
                        "to run anyway)")
    elif dt > critical.friction_dt and not solver.force_dt:
        raise CaseError(case.path, "solver.dt", f"{dt:.3e} s is above the step at which "
                        "central differences take the friction's damping at steady sliding "
                        f"stably, {critical.friction_dt:.3e} s (w p mu / V across the "
                        "sliding, w p dmu/ds along; solver.force_dt = true to run anyway)")
    elif dt > critical.contact_dt and not solver.force_dt:
        pair = critical.stiffest_point(dt)[1]
        raise CaseError(case.path, "solver.dt", f"{dt:.3e} s runs the contact's penalty "
                        f"(contact.{pair}.k) at omega_c dt = {dt * critical.omega_contact:.2f}, "
                        f"above {CONTACT_OMEGA_DT}, where impacts gain or lose energy at each "
                        f"chatter: a step up to {critical.contact_dt:.3e} s, a lower "
                        f"contact.{pair}.k, or solver.force_dt = true to run anyway")
    check_steps(case, dt)
    return dt, reason


def stepper(case, system, dt, blocks=None):
    """The case's scheme on a system at step dt; its refusals name the case file."""
    try:
        return schemes.stepper(system, case.solver, dt, blocks)
    except CaseError as exc:
        raise CaseError(case.path, exc.key, exc.message) from None


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
    status, done = stepper(case, setup.system, dt)(state, n_steps, every, out)
    seconds = time.perf_counter() - t0
    rows = Rows(*(np.concatenate([first[:1], x[:done // every]])
                  for first, x in zip(setup.rows0.arrays, out.arrays)))
    result = {"time": rows.time}
    result.update({f"sensors/{name}": rows.sensors[:, k]
                   for k, name in enumerate(setup.system.sensor_names)})
    result.update({f"energy/{term}": rows.energy[:, k] for k, term in enumerate(ENERGY_TERMS)})
    if case.output.contact:
        result["contact/gap"], result["contact/pressure"] = rows.gap, rows.pressure
    return result, {OK: "complete", NOT_FINITE: "not finite",
                    NO_CONVERGENCE: "no convergence"}[status], seconds
