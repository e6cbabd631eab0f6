"""The components path of the reduction (solver.reduction.method = "components"): each part
reduced on its own, the assembly coupled through its contact rows in reduced coordinates.

Component mode synthesis with free interfaces and residual attachment shapes (MacNeal, Rubin):
each part's basis holds its normal modes to the cutoff (its rigid modes too when it floats)
and its static responses to the contact point loads on its interface (normal, and tangential
where a pair has friction: the tractions the parts exchange), to the load patterns and to the
constant load. The coupled structure's static response to any contact force is a sum of the
parts' responses to their share of it, so the preload lies in the span exactly where the
interface responses are all kept (statics_tolerance = 0) and to the tolerance's flexibility
otherwise. The preload is solved by Newton in the reduced coordinates, and the basis is
diagonalized on the contact-linearized stiffness there: no factorization of the whole model.
"""
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..case.sizes import cells_by_part, check_workers, dofs_by_part, peak_rss_gb
from ..contact.blocks import points_gram
from ..contact.contactset import first_tangent
from ..dynamics.critical import critical_tangent
from ..errors import CaseError
from ..model.dofs import free_block, restricted
from ..model.partcells import PartCells
from .. import blas
from ..solve.preload import Preload
from .basis import Basis, flexible_shapes
from .fields import part_rigid_motions, support_stiffness
from .engine import Engine
from .parts import PartError, PartInterface, PartTask
from .pieces import CUT, PiecesTask, piece_of_dofs
from .coupling import ALONG, PairRows
from .sampling import ReducedPreloadError, reduced_preload
from .synthesis import Synthesis

# how far beyond the basis' cutoff each part's modes and interface fields reach: the coupled
# modes to the cutoff are only as exact as the parts' bases reach past it (component modes
# beyond the band the assembly keeps), while the coupling's condensation stays at the cutoff,
# so the reduced model grows little (docs/performance.md: the band modes' shape errors)
PART_REACH = 1.5


def part_tasks(case, model, pairs, contacts, patterns, constant):
    """(dofs, (name, cells, interface, loads), pieces) of each part: the arguments of
    part_basis on the part's free dofs, which sit at dofs, its K and M to be assembled from
    its cells (model.partcells.PartCells) where it is reduced. pieces (None: the part whole)
    for a part parts.NAME.pieces cuts: (piece_of, cell_piece, Kc, Mc), the piece of each free
    dof and of each cell (reduce.pieces) and K and M on the cut, which the pieces share. The
    interface (a PartInterface) holds the contact's loads E on the part: with factored rows (a
    regularized rule, C = L B^T) the columns of B on the part, the traces of the
    (1-eps)-compatible shapes (with friction the tangential rows' too), which the part reduces
    to the fields of its loaded interface (reduce.fields); else a unit load on each dof the rows
    touch, kept whole. The rows reach the task as their gram in E's coordinates (k x k), not
    point by point."""
    free = ~model.fixed
    f = contacts.friction
    scale = contacts.weights * law_tangent(pairs, contacts)
    kinds = 1 if f is None else 3
    if contacts.factors is not None:
        B = contacts.factors[1]
        E_all = sp.hstack([sp.csr_matrix(b) for b in [B] + ([f.along, f.across] if f else [])])
        E_all = E_all.tocsr()
        r = B.shape[1]
        grams = _pair_grams(pairs, contacts, scale)
        # each column's compatible shape, -1 on a tied pair's (kept whole)
        tied = np.concatenate([np.full(pair.factors[1].shape[1],
                                       pair.spec.law.kind == "bilateral") for pair in pairs])
        shape_of = np.tile(np.where(tied, -1, np.arange(r)), kinds)
        support = support_stiffness(pairs, model.ndof)
    else:
        E_all, rows = None, sp.vstack([contacts.C] + (list(contacts.tangential()) if f
                                                      else [])).tocsc()
        scale = np.tile(scale, kinds)
    loads = np.stack([constant] + list(patterns), axis=1)
    quadrature = case.solver.quadrature
    degrees = (quadrature.stiffness or None, quadrature.mass or None)
    lumped = case.solver.mass == "lumped"
    out = []
    for name in model.parts:
        dofs = model.part_dofs(name)
        dofs = dofs[free[dofs]]
        cells = PartCells.of(model, name, dofs, degrees, lumped)
        if E_all is None:
            # the dofs the rows touch, each loaded alone
            Rp = rows[:, dofs].tocsc()
            cols = np.flatnonzero(np.diff(Rp.indptr))
            E = sp.csr_matrix((np.ones(len(cols)), (cols, np.arange(len(cols)))),
                              shape=(len(dofs), len(cols)))
            Cc, shape, block = Rp[:, cols], np.full(len(cols), -1), np.zeros(len(cols), int)
            gram = (Cc.T @ sp.diags(np.maximum(scale, 0.0)) @ Cc).toarray()
        else:
            Ep = E_all[dofs].tocsc()
            cols = np.flatnonzero(np.diff(Ep.indptr))
            E, shape, block = Ep[:, cols], shape_of[cols], cols // r
            gram = _gram_on(grams, cols % r, block)
        interface = None
        if len(cols):
            fields = (shape >= 0).any()
            interface = PartInterface(sp.csc_matrix(E), gram, shape, block,
                                      free_block(support, dofs) if fields else None,
                                      part_rigid_motions(model.points, dofs) if fields
                                      else None)
        count = case.parts[name].pieces
        out.append((dofs, (name, cells, interface, loads[dofs]),
                    None if count <= 1 else _pieces(model, name, dofs, count, interface,
                                                    lumped)))
    return out


def _pieces(model, name, dofs, count, interface, lumped):
    """(piece_of, cell_piece, Kc, Mc) of the part name cut in count pieces (part_tasks'). K
    and M couple no two cells' nodes but through a cell, which the cut's nodes already part;
    the interface's springs may, and put the dofs they join across pieces in the cut."""
    part = model.parts[name]
    coupling = None
    if interface is not None and interface.support is not None:
        coupling = interface.support
    piece_of, cell_piece = piece_of_dofs(
        model.points, [c + part.offset for c in part.mesh.cells.values()], dofs, count,
        coupling)
    cut = dofs[piece_of == CUT]
    M = sp.diags(model.lumped_mass).tocsr() if lumped else model.M
    Kc, Mc = restricted((model.K, M), cut, cut)
    return piece_of, cell_piece, Kc, Mc


def _pair_grams(pairs, contacts, scale):
    """(offsets (pairs + 1,), [L_s^T diag(scale_s) L_s]) of each pair's factor L_s: the rows'
    gram on the compatible shapes, block diagonal by pair, and the same along and across the
    sliding (C = L B^T, Ct = L Bt^T, Cc = L Bc^T share L). Each pair's points see only its own
    shapes, so no points x every shape product is formed."""
    offsets = np.concatenate([[0], np.cumsum([pair.factors[0].shape[1] for pair in pairs])])
    grams = []
    for pair, s in zip(pairs, contacts.slices.values()):
        grams.append(points_gram(np.asarray(pair.factors[0]), np.maximum(scale[s], 0.0)))
    return offsets, grams


def _gram_on(grams, shape, block):
    """The rows' gram (k, k) on a part's loads: the compatible shapes shape (k,) of the row
    kinds block (k,) (normal, along, across); loads of other kinds or pairs do not meet."""
    offsets, blocks = grams
    pair = np.searchsorted(offsets, shape, side="right") - 1
    gram = np.zeros((len(shape), len(shape)))
    for kind, p in np.unique(np.stack([block, pair]), axis=1).T:
        idx = np.flatnonzero((block == kind) & (pair == p))
        j = shape[idx] - offsets[p]
        gram[np.ix_(idx, idx)] = blocks[p][np.ix_(j, j)]
    return gram


def law_tangent(pairs, contacts):
    """(P,) the contact law's tangent each point's interface shapes are measured against: the
    pair's k on exponential laws (the preload, where the law's own tangent is, comes after
    the reduction), the law's tangent at the initial gap on the others."""
    return np.maximum(first_tangent(pairs, contacts), contacts.laws(contacts.gap0.copy())[1])


def components_basis(case, model, M, pairs, contacts, patterns, constant, engine=None):
    """(Basis, Preload) of the components path: each part's PartBasis (engine: a
    reduce.engine.Engine, where and through which cache; None: in this process), the preload
    by Newton in the coupled reduced coordinates, the basis diagonalized on K_lin there."""
    reduction = case.solver.reduction
    engine = engine or Engine()
    t0 = time.perf_counter()
    say = _stages(engine, t0)
    dofs, parts = reduce_parts(case, model, pairs, contacts, patterns, constant, engine, say)
    t_parts = time.perf_counter() - t0
    X = Synthesis(model.ndof, dofs, [p.T for p in parts])
    Kr = sla.block_diag(*[p.Kr for p in parts])
    w = contacts.weights
    with blas.every_core():         # dense algebra in reduced coordinates, no solve beside it
        rows = PairRows(contacts, X)
        say("coupling rows")
        preload = _preload(case, contacts, pairs, X, Kr, rows, constant)
        say("coupling preload")
        K_lin = rows.stiffness(Kr, w * preload.tangent, sliding=False)
        # divide and conquer: MRRR (evr, the default) stalls on the clustered spectra of
        # the parts' modes beside their statics' and contact springs' far larger ones
        omega2, A = sla.eigh(0.5 * (K_lin + K_lin.T), driver="evd")
        loads = X.T @ np.stack([constant] + list(patterns), axis=1)
        A, omega2, n_modes, n_shapes = condensed(
            K_lin, omega2, A, reduction.modes_fmax,
            rows.gram(w * critical_tangent(contacts, preload.tangent)), loads,
            X.T @ (M @ preload.u), reduction.statics_tolerance)
        say("coupling modes")
    timings = {"parts": t_parts, "coupling": time.perf_counter() - t0 - t_parts,
               "part_seconds": {p.name: sum(p.seconds.values()) for p in parts},
               "part_stages": {p.name: p.seconds for p in parts},
               "synthesis_dofs": int(X.shape[1]),
               "part_interfaces": {p.name: {"loads": p.interface_loads,
                                            "fields": len(p.interface_mu), "kept": p.n_shapes,
                                            "statics_error": p.statics_error(
                                                reduction.statics_tolerance)}
                                   for p in parts}}
    basis = Basis(X, A, np.maximum(omega2, 0.0), n_modes, loads.shape[1] + 1, timings,
                  n_shapes, None, len(omega2) - n_modes, None,
                  np.sqrt(np.maximum(omega2[:n_modes], 0.0)) / (2 * np.pi))
    return basis, preload


def reduce_parts(case, model, pairs, contacts, patterns, constant, engine, say=None):
    """(dofs, PartBasis) of each part, reduced through engine (a reduce.engine.Engine): the
    components path's first stage, and all a campaign does before its variants fan out
    (reduce.engine.cached then holds the parts they share)."""
    say = say or _stages(engine, time.perf_counter())
    check_parts(case, model, engine.budget())
    tasks = part_tasks(case, model, pairs, contacts, patterns, constant)
    say("part tasks")
    work = part_work(case, tasks)
    try:
        parts = engine.run(work)
    except PartError as exc:
        raise CaseError(case.path, f"parts.{exc.part}", f"its stiffness cannot be factorized "
                        f"on its own ({exc}): is it held by constraints, or free to "
                        "move?") from None
    say("parts")
    return [d for d, _, _ in tasks], parts


def part_work(case, tasks):
    """The PartTask (a PiecesTask for a part cut in pieces) of each of part_tasks'."""
    reduction, solver = case.solver.reduction, case.solver
    settings = (PART_REACH * reduction.modes_fmax, solver.shift_hz,
                reduction.statics_tolerance, solver.linear_solver)
    return [PartTask(*task, *settings) if pieces is None
            else PiecesTask(*task, *settings, *pieces) for _, task, pieces in tasks]


def _stages(engine, t0):
    """say(name): engine.stage(name, seconds since the last, peak GB), or nothing."""
    last = [t0]

    def say(name):
        if engine.stage is not None:
            now = time.perf_counter()
            engine.stage(name, now - last[0], peak_rss_gb())
            last[0] = now
    return say


def condensed(K_lin, omega2, A, cutoff, gram, loads, q, tol):
    """The coupled synthesis condensed again, as the assembled basis is made on the whole
    model (double modal synthesis): in the parts' coordinates (M = I, K_lin = A diag(omega2)
    A^T), the coupled modes to the cutoff, the contact shapes of the flexibility beyond them
    (basis.flexible_shapes on the rows' gram, the law's stiffness at the preload), the responses
    beyond them to the loads, and the preload q itself. The reduced model is then the size of
    the assembled one, not the sum of the parts' bases. Returns (A2 (R, n), omega2 (n,) of
    K_lin on it ascending, the modes kept, the contact shapes kept)."""
    keep = omega2 <= (2 * np.pi * cutoff) ** 2
    Am, Ab = A[:, keep], A[:, ~keep]
    H = (Ab / omega2[~keep]) @ Ab.T
    shapes, _ = flexible_shapes(H, None, None, tol, H.__matmul__, gram=gram)
    S = np.hstack([shapes, H @ loads, (q - Am @ (Am.T @ q))[:, None]])
    for _ in range(2):            # what the modes hold, out (twice, for round-off)
        S -= Am @ (Am.T @ S)
    norms = np.linalg.norm(S, axis=0)
    S = S[:, norms > 1e-12 * max(norms.max(), 1e-300)]
    S /= np.linalg.norm(S, axis=0)
    W = Am
    if S.shape[1]:            # none: no contact, no load and no preload beyond the modes
        lam, V = np.linalg.eigh(S.T @ S)
        big = lam > 1e-12 * max(lam.max(), 1.0)
        W = np.hstack([Am, S @ (V[:, big] / np.sqrt(lam[big]))])
    omega2, V = np.linalg.eigh(W.T @ (K_lin @ W))
    return W @ V, omega2, int(keep.sum()), shapes.shape[1]


def check_parts(case, model, budget):
    """Refuse a part whose reduction's estimated memory (from its cells) exceeds budget [B],
    a worker's, naming the key that sizes it (case.sizes.check_workers); None: no bound here
    (limits.memory's, at the model, holds the largest part)."""
    if budget is not None:
        check_workers(case, cells_by_part(model.parts), lambda name, pieces: budget,
                      dofs=dofs_by_part(model.parts))


def _preload(case, contacts, pairs, X, Kr, rows, constant):
    """The Preload of the coupled reduced model: Newton from the undeformed state, its first
    step at least at each pair's k (first_tangent: an exponential law is far softer at zero
    gap than where the load takes it); rows: the coupling's PairRows."""
    t0 = time.perf_counter()
    g0 = contacts.gap0
    if not np.any(constant):
        p, kt, _ = contacts.laws(g0.copy())
        return Preload(np.zeros(X.shape[0]), g0.copy(), p, kt, 0, 0.0,
                       time.perf_counter() - t0)
    newton = case.solver.newton
    try:
        q, g, p, kt, it, res = reduced_preload(
            Kr, X.T @ constant, rows.operator(), contacts, np.zeros(Kr.shape[0]),
            newton.tolerance, newton.max_iter,
            rows.operator(ALONG) if contacts.friction is not None else None,
            first_tangent(pairs, contacts), rows)
    except ReducedPreloadError as exc:
        raise CaseError(case.path, "loads", str(exc)) from None
    return Preload(X @ q, g, p, kt, it, res, time.perf_counter() - t0)
