"""solver.reduction.method = "auto": the reduction's path chosen once, at load, by the memory
estimate of case.sizes. The assembled path (one factorization of the whole model, the
reference) where its setup fits limits.memory; else the components path (each part reduced
on its own), whose need is a part's at a time; and the components path wherever a part is
cut in pieces (parts.NAME.pieces), which only it reads. The method chosen replaces "auto" in
the case's specs, so that every stage, a campaign's keys and a history's attributes see the
path taken; why it was taken is the Case's reduction_auto, which a history keeps and the
commands say.
"""
from dataclasses import replace

from .sizes import generated_cells, mesh_cells, setup_bytes


def choose_method(case):
    """The case with solver.reduction.method chosen where it says "auto" (the case itself
    otherwise). A part's mesh file is read for its cells (no mesh is built): the setup's
    estimate is of every part."""
    reduction = case.solver.reduction
    if reduction.method != "auto":
        return case
    if not reduction.enabled:
        # the full model: no basis, no path to choose
        return _chosen(case, "assembled", "")
    cut = [name for name, part in case.parts.items() if part.pieces > 1]
    if cut:
        method = "components"
        why = (f"parts.{cut[0]}.pieces = {case.parts[cut[0]].pieces} cuts a part in pieces, "
               "which the components path alone reads")
    else:
        need, have = setup_bytes(all_cells(case)), case.limits.memory_bytes
        method = "assembled" if need <= have else "components"
        why = (f"the assembled setup would take about {need / 1e9:.3g} GB, "
               f"{'within' if need <= have else 'more than'} limits.memory "
               f"({have / 1e9:.3g} GB)")
    return _chosen(case, method, f'solver.reduction.method = "auto" chose {method}: {why}')


def _chosen(case, method, why):
    solver = case.solver
    return replace(case, solver=replace(solver, reduction=replace(solver.reduction,
                                                                 method=method)),
                   reduction_auto=why)


def all_cells(case):
    """(count, nodes per cell) of every cell block of the case's parts: a generator's from
    its divisions, a file's read."""
    from ..mesh.partfile import read_part_file
    cells = []
    for name, part in case.parts.items():
        counted = generated_cells(part.mesh)
        if counted is not None:
            cells.append(counted)
        else:
            cells += mesh_cells(read_part_file(case, name))
    return cells
