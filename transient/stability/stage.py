"""The cea stage: the case's setup up to its system (preload at steady sliding, reduction),
linearized there, and its complex modes: QZ on the reduced model, shift-invert Arnoldi on the
full one (solver.reduction.enabled = false: the reference for small cases).

A sampled rule is analysed on the points it samples from (its pair's regularized fine rule): the
sampling serves the time integration's contact passes, while the linearized matrices of every
fine point cost one product with the basis.
"""
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .. import blas
from .linearize import linearized
from .residual import mode_residuals
from .modes import complex_modes
from .reference import MAX_TOP_DAMPING, Unresolved, full_complex_modes, top_damping
from .rigid import rigid_motions
from .shapes import describe, part_modes, still_parts

FULL_DOFS = 60_000    # free dofs above which the full model's complex LU per shift is refused


@dataclass(frozen=True)
class Analysis:
    """The complex modes of a case at steady sliding, and what describes them."""
    modes: object            # ComplexModes up to fmax
    fmax: float              # [Hz]
    ndof: int                # free dofs of the model
    reduced: int             # dofs of the reduced model (0: the full model)
    stages: dict             # stage -> seconds
    meta: dict               # the setup's (dynamics prepare's meta)
    shapes: list             # the modes described (stability.shapes.describe): the unstable
    #                          ones, or all (cea.shapes)
    model: object = None     # the Model, and
    basis: tuple = None      # (X, A): the modes' coordinates z are X (A z) on the model's dofs
    matrices: tuple = None   # asked for: the linearized (M, D, K) the modes solve
    files: tuple = ()        # the files written (io.complex_modes), output.vtu asking

    def displacement(self, j):
        """(ndof,) complex displacement of mode j (0-based)."""
        X, A = self.basis
        return X @ (A @ self.modes.vectors[:, j])

    def summary(self):
        """What `transient cea --json` prints, but for the total time; on the components
        path with each part's stages [s] (where a part's reduction went: a part in pieces'
        pieces, cut, extension)."""
        out = {"modes": self.modes.table(), "ndof": self.ndof, "reduced": self.reduced,
               "fmax_hz": self.fmax, "growth_rate_threshold": self.modes.threshold,
               "shapes": self.shapes, "files": [str(p) for p in self.files],
               "stages": self.stages}
        parts = ((self.meta or {}).get("basis_timings") or {}).get("part_stages")
        if parts is not None:
            out["part_stages"] = parts
        return out


def analysed_case(case):
    """The case the analysis prepares: sampled rules on their candidates."""
    contact = {name: replace(c, rule="fine") if c.rule == "sampled" else c
               for name, c in case.contact.items()}
    return replace(case, contact=contact)


def fmax_of(case):
    solver = case.solver
    return solver.reduction.fmax if solver.reduction.enabled else (
        solver.modes.fmax or solver.reduction.fmax)


def analyse(case, check=None, built=None, matrices=False, parts=None):
    """Complex modes of a case at its steady sliding state (Analysis); built: its first
    stages' results when built already (shared.Built: a campaign's variants share them);
    matrices: keep the linearized (M, D, K) in the Analysis; parts: where the components
    path reduces its parts (reduce.engine.Engine; None: here)."""
    from ..model import build_model
    from ..shared import Built
    from ..stages import prepare
    stages = {}
    if built is not None and not case.solver.reduction.enabled:
        _bounded(case, int((~built.model.fixed).sum()))
    elif not case.solver.reduction.enabled:
        # the model first (seconds), its size bounded before the setup's stages
        t0 = time.perf_counter()
        built = Built(build_model(case))
        stages["model"] = time.perf_counter() - t0
        _bounded(case, int((~built.model.fixed).sum()))
    setup = prepare(analysed_case(case), check, built, analysis=True, parts=parts)
    stages.update(setup.stages)
    return analysis_of(case, setup, stages, matrices)


def analysis_of(case, setup, stages=None, matrices=False):
    """The Analysis of a case from its setup (prepare's: of analysed_case(case), or a sampled
    rule's Setup.unsampled, the same arithmetic before the sampling); stages: the setup's
    seconds, which the analysis's own join; matrices: as analyse's."""
    stages = dict(stages or {})
    system = setup.system
    if not system.reduced:
        # (analyse bounds it before its setup; a setup made for a run is bounded here)
        _bounded(case, len(system.free))
    fmax = fmax_of(case)
    t0 = time.perf_counter()
    # The still parts' own modes (the unstable modes' description: a factorization and a
    # Lanczos of the pad alone, 0.35 s on pad_disc) are made beside the dense QZ, which keeps
    # one core busy and leaves the other idle: the QZ on one BLAS thread, the part modes on
    # one thread of everything (_alone), so that the arithmetic is the same whichever ends
    # first. On one core (a campaign's worker) they come after, if needed, the same way.
    model, still = setup.model, still_parts(case, setup.model)
    with blas.one_thread(), ThreadPoolExecutor(1) as pool:
        beside = ({p: pool.submit(_alone, model, p, fmax) for p in still}
                  if blas.budget() > 1 else None)
        M, D, K = linearized(system, setup.state)
        if system.reduced:
            modes = complex_modes(M, D, K).below(fmax)
        else:
            modes = _full_modes(case, model, system, (M, D, K), fmax)
        modes = replace(modes, threshold=case.cea.growth_rate)
        stages["complex_modes"] = time.perf_counter() - t0
        ndof = setup.meta.get("free_dofs", system.n)
        basis = (setup.basis if system.reduced else
                 (_full_basis(model.ndof, system.free), sp.identity(system.n, format="csr")))
        t0 = time.perf_counter()
        which = (np.flatnonzero(modes.unstable) if case.cea.shapes == "unstable" else
                 np.arange(len(modes.eigenvalues)))
        own = ({p: done.result() for p, done in beside.items()} if beside is not None else
               {p: _alone(model, p, fmax) for p in still} if len(which) else None)
        shapes = describe(case, model, basis, modes, which, fmax, own)
        if system.reduced and len(which):
            mass = model.M if case.solver.mass != "lumped" else sp.diags(model.lumped_mass)
            for row, rho in zip(shapes, mode_residuals(model, mass, system, setup.state, basis,
                                                       modes, which)):
                row["residual"] = float(rho)
        stages["shapes"] = time.perf_counter() - t0
    return Analysis(modes, fmax, int(ndof), system.n if system.reduced else 0, stages,
                    setup.meta, shapes, model, basis, (M, D, K) if matrices else None)


def _alone(model, part, fmax):
    """part_modes on one thread of Numba and MKL, whatever thread runs it."""
    with blas.this_thread_alone():
        return part_modes(model, part, fmax)


def _full_modes(case, model, system, MDK, fmax):
    """full_complex_modes with the floating parts' rigid modes deflated, its bounds' failure
    a CaseError."""
    try:
        return full_complex_modes(*MDK, fmax, rigid_motions(model, system.free))
    except Unresolved as exc:
        raise case.error("solver.reduction.enabled", f"the full model's complex modes: {exc}: "
                         "analyse the reduced model (solver.reduction.enabled = true) or "
                         "lower solver.modes.fmax") from None


def _full_basis(ndof, free):
    """The free dofs' injection in the model's dofs (sparse)."""
    return sp.csr_matrix((np.ones(len(free)), (free, np.arange(len(free)))),
                         shape=(ndof, len(free)))


def _bounded(case, dofs):
    """One complex LU per shift: the full model is the reference for small cases, and its
    Arnoldi does not resolve the modes a heavy Rayleigh beta spreads about the shifts."""
    if dofs > FULL_DOFS:
        raise case.error("solver.reduction.enabled", f"the full model's complex modes "
                         f"({dofs} free dofs, above {FULL_DOFS}) take a complex factorization per "
                         "shift: analyse the reduced model (solver.reduction.enabled = true)")
    beta = case.solver.damping.beta
    ratio = top_damping(beta, fmax_of(case))
    if ratio > MAX_TOP_DAMPING:
        raise case.error("solver.damping.beta", f"{beta:g} s damps the band's top at a ratio "
                         f"of {ratio:.3g} (beta pi fmax; its modes overdamped from "
                         f"{1 / (np.pi * beta):.3g} Hz), a cloud of eigenvalues the full "
                         f"model's Arnoldi does not resolve: expected at most {MAX_TOP_DAMPING}, "
                         "or the reduced model (solver.reduction.enabled = true)")
