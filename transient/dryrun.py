"""What a command would do, said before it does it (`--dry-run` on run, modes and cea): the
case loaded and checked, the model built (its dofs by part), each contact pair's fine rule
built and its initial gaps checked, and the bounds the work is held to (the memory estimate
against limits.memory, the steps of a run). Nothing is factorized and nothing written: the
checks a command makes before its costly stages, and their figures."""
from . import progress, setuptimes
from .case.sizes import cells_by_part, dofs_by_part, entries, memory_need, worker_budget
from .contact.gaps import check_gaps, initial_gaps
from .contact.pair import pair_interface
from .dynamics.plan import Plan
from .model import build_model
from .model.placement import check_motions


def measure(case, command):
    """A dict of what `command` ("run", "modes" or "cea") would take on the case: parts
    (dofs, free dofs, cells, the pieces the components path reduces it in), pairs (fine
    points, initial gaps), memory (each process's estimate and bound: _memory), for a run
    its steps (exact where the step is known before the setup, else a bound or None) and
    its setup's seconds (the modes' for `modes`) as estimated from those timed on this
    machine, else from its calibration, made now (said as it starts) when there is none
    (setuptimes.estimate: low, high, source, from how many setups; None with the
    setup-time log off)."""
    model = build_model(case)
    free = ~model.fixed
    cells = cells_by_part(model.parts)
    parts = {name: {"dofs": int(len(model.part_dofs(name))),
                     "free_dofs": int(free[model.part_dofs(name)].sum()),
                     "cells": int(sum(n for n, _ in cells[name])),
                     "pieces": case.parts[name].pieces} for name in model.parts}
    check_motions(case, model.parts)
    pairs = {}
    for name in case.contact:
        interface = pair_interface(case, model, name)
        gaps = initial_gaps(interface)
        check_gaps(case, model, name, interface, gaps)
        pairs[name] = {"fine_points": int(interface.fine.n_points), "gap0": gaps.meta()}
    out = {"command": command, "case": str(case.path), "dofs": int(model.ndof),
           "free_dofs": int(free.sum()), "parts": parts, "pairs": pairs,
           "memory": _memory(case, cells, dofs_by_part(model.parts))}
    if command == "run":
        out["steps"] = _steps(case)
    # from the setups this machine has timed, else from its calibration (setuptimes)
    kind = "modes" if command == "modes" else setuptimes.kind(case, command == "cea")
    out["setup_seconds"] = setuptimes.estimate(kind, entries(sum(cells.values(), [])),
                                               announce=progress.started)
    return out


def _memory(case, cells, dofs):
    """The memory estimate of each process (case.sizes.memory_need) against its bound."""
    need = memory_need(case, cells, dofs)
    budget = worker_budget(case, need)
    reduction = case.solver.reduction
    return {"estimate_gb": need.here / 1e9, "limit_gb": case.limits.memory_bytes / 1e9,
            "largest_part": need.part, "client": need.worker is not None,
            "worker_gb": None if need.worker is None else need.worker / 1e9,
            "worker_part": need.worker_part,
            "worker_pieces": case.parts[need.worker_part].pieces if need.worker_part else 1,
            "budget_gb": None if budget is None else budget / 1e9,
            "terms_gb": {what: b / 1e9 for what, b in need.terms},
            "disk_gb": need.disk / 1e9,
            "method": reduction.method if reduction.enabled else None,
            "auto": case.reduction_auto or None}


def _steps(case):
    """{"steps", "exact"} of a run: its plan's at the case's dt (the whole steps and a last
    one shortened, dynamics.plan); at least its plan's at 20 steps a period of
    solver.reduction.fmax for the schemes whose automatic step is that or less (exponential,
    implicit); None where the setup's critical step sets it (central differences)."""
    solver = case.solver
    dt = solver.dt if solver.dt > 0 else (1.0 / (20.0 * solver.reduction.fmax)
                                          if solver.scheme in ("exponential", "implicit")
                                          else None)
    if dt is None:
        return {"steps": None, "exact": False}
    plan = Plan.of(solver.t_end, dt, 1)
    return {"steps": plan.steps + int(plan.partial), "exact": solver.dt > 0}
