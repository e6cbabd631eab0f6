"""Contact pairs of a case through the stages interface -> compatibility -> regularize -> rule.

The sampled rule leaves this stage as the (regularized) fine rule: its points are chosen after
the reduction, on the reduced dynamics (sampling.py).

A stage runs only when the pair needs it: the fine rule without regularization does no
eigendecomposition; `need_compatibility` forces it (for `transient compat`).
"""
import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .coarse import select, side_bases
from .compatibility import auto_eps, compatibility
from ..errors import CaseError
from .friction import pair_sliding
from .gaps import check_gaps, initial_gaps
from .interface import InterfaceError, build_interface, build_wall_interface
from ..model.model import resolve_set
from ..model.placement import check_motions
from .regularize import (dual_factors, factor_projectors, factored_rows, primal_basis,
                         regularized_rule, row_factors)
from .rules import centre_rule, gauss_rule
from ..mesh.mesh import unit
from ..mesh.selections import set_faces

DENSE_FILL = 0.1   # fill of the rows above which C^T diag(k w) C is formed dense


@dataclass(frozen=True)
class ContactPair:
    name: str
    spec: object              # ContactSpec of the pair
    interface: object         # Interface (fine rule)
    compat: object            # Compatibility, or None when not computed
    eps: float                # eps used (None without compatibility)
    eps_source: str           # where eps comes from: the case, or the automatic choice
    rule: object              # the Rule whose observation the solvers use
    primal: object            # T_eps for the primal formulation, else None
    coarse: object            # CoarseRule of the greedy rule, else None
    timings: dict             # stage -> seconds, in the order run
    candidates: int = 0       # sampled rule: the fine points it was sampled from
    factors: tuple = None     # (L, B): the rule's observation is L B^T (regularize.row_factors);
    #                           the rule's C1, C2 are then None
    projections: tuple = None  # with factors: (Q1, Y1), (Q2, Y2) of the sides' projectors
    sliding: object = None    # friction.PairFriction with friction, else None
    gaps: object = None       # gaps.InitialGaps of the fine rule

    @property
    def k(self):
        return self.spec.k

    def observation(self, ndof):
        """(P, ndof) gap observation of the pair's rule in model dofs (formed from the factors
        when the pair holds them: only for what needs the explicit rows)."""
        if self.factors is not None:
            return factored_rows(*self.factors)
        return self.interface.observation(self.rule, ndof)


def _surface(case, model, ref, key):
    part, name = resolve_set(case, model.parts, ref, key, surface=True)
    faces = set_faces(part.mesh, name)
    if not faces:
        raise CaseError(case.path, key, f"selection '{ref}' holds no boundary face")
    return part, faces


def _check_wall(case, key, part, faces, spec):
    """A wall point that the surface's round-off can see: not past the whole part (a
    penetration deeper than the part, whose forces overflow), nor so far along the wall that
    the faces projected about it lose their areas."""
    nodes = np.unique(np.concatenate([np.ravel(c) for c in faces.values()]))
    x, n = part.mesh.points[nodes], unit(spec.wall_normal)
    with np.errstate(over="ignore", invalid="ignore"):
        offset = np.asarray(spec.wall_point, float) - x.mean(axis=0)
        depth = float(np.max(-(x - np.asarray(spec.wall_point, float)) @ n))
        along = offset - (offset @ n) * n
        # (scaled: its square overflows past 1e154 m)
        along = float(np.abs(along).max() * np.linalg.norm(along / max(np.abs(along).max(),
                                                                          1e-300)))
    along_n = part.mesh.points @ n
    thick = float(along_n.max() - along_n.min())
    size = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
    if not depth <= thick:
        raise CaseError(case.path, key, f"{list(spec.wall_point)} puts surface "
                        f"'{spec.surface1}' up to {depth:.3g} m behind the wall, through the "
                        f"part ({thick:.3g} m along the normal): expected a wall at or near "
                        "the surface")
    if not along <= 1e6 * size:
        raise CaseError(case.path, key, f"{list(spec.wall_point)} lies {along:.3g} m along the "
                        f"wall from surface '{spec.surface1}' ({size:.3g} m across): expected a "
                        "point of the wall nearer it")


# The spec fields the pair's geometry reads (interface, compatibility, regularization, rule):
# variants equal on them share it (shared.READS); the law and the friction are the variant's
GEOMETRY = ("surface1", "surface2", "wall", "wall_point", "wall_normal", "order", "k", "rule",
            "candidates", "points", "tolerance", "weights", "master", "regularized", "eps",
            "formulation", "project", "norm")


def build_pair(case, model, name, need_compatibility=False):
    """The contact pair `name` of a case: its geometry, with the case's sliding; its initial
    gaps checked against its law and preload before the compatibility's eigensolver."""
    t0 = time.perf_counter()
    interface = pair_interface(case, model, name)
    seconds = time.perf_counter() - t0
    check_gaps(case, model, name, interface, initial_gaps(interface))
    return attach(case, build_geometry(case, model, name, need_compatibility,
                                       (interface, seconds)))


def attach(case, pair):
    """The pair as a case has it from a geometry built for it or for another case equal on
    GEOMETRY: the case's own spec (law, friction) and, with friction, its sliding."""
    spec = case.contact[pair.name]
    pair = replace(pair, spec=spec)
    return replace(pair, sliding=pair_sliding(case, pair)) if spec.friction.active else pair


def pair_interface(case, model, name):
    """A pair's Interface: its fine rule and initial gaps."""
    spec = case.contact[name]
    key = f"contact.{name}"
    p1, faces1 = _surface(case, model, spec.surface1, f"{key}.surface1")
    try:
        if spec.wall:
            _check_wall(case, f"{key}.wall_point", p1, faces1, spec)
            interface = build_wall_interface(name, p1.mesh.points, faces1, p1.offset,
                                             spec.wall_point, spec.wall_normal, spec.order)
        else:
            p2, faces2 = _surface(case, model, spec.surface2, f"{key}.surface2")
            interface = build_interface(name, p1.mesh.points, faces1, p1.offset,
                                        p2.mesh.points, faces2, p2.offset, spec.order)
    except InterfaceError as exc:
        raise CaseError(case.path, key, str(exc)) from None
    return interface


def build_geometry(case, model, name, need_compatibility=False, interface=None):
    """A pair's interface, compatibility, regularization and rule (no sliding): what its
    spec's GEOMETRY fields and the model give. interface: (Interface, seconds) built
    already."""
    spec = case.contact[name]
    key = f"contact.{name}"
    if interface is None:
        t0 = time.perf_counter()
        interface = (pair_interface(case, model, name), time.perf_counter() - t0)
    interface, seconds = interface
    timings = {"interface": seconds}

    comp, eps, eps_source, primal, coarse, factors = None, None, "", None, None, None
    projections = None
    greedy = spec.rule == "greedy"
    if spec.regularized or need_compatibility:
        t0 = time.perf_counter()
        comp = compatibility(interface.fine, spec.k)
        eps, eps_source = (auto_eps(comp.normalized) if spec.eps == "auto"
                           else (spec.eps, "case"))
        timings["compatibility"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    if spec.rule == "centre" or (greedy and spec.candidates != "fine"):
        master = spec.master if spec.rule == "centre" else spec.candidates
        rule = centre_rule(interface, master)
        timings["centre_rule"] = time.perf_counter() - t0
    elif spec.rule == "gauss":
        rule = gauss_rule(interface, spec.master, spec.order)
        timings["gauss_rule"] = time.perf_counter() - t0
    else:
        rule = interface.fine
    if spec.regularized:
        t0 = time.perf_counter()
        if spec.formulation == "dual":
            F1, F2 = dual_factors(comp, eps, interface.fine, spec.project, spec.norm)
            if not greedy:
                factors = row_factors(interface, rule, F1, F2, model.ndof)
            if factors is None:
                P1, P2 = factor_projectors(comp, F1, F2)
                rule = regularized_rule(rule, P1, P2)
                fine = regularized_rule(interface.fine, P1, P2) if greedy else None
            else:
                # the projected rows C_n P_n (points x interface dofs, dense) are never
                # formed: the factors hold them (the largest arrays of a setup at scale)
                rule, projections = replace(rule, C1=None, C2=None), (F1, F2)
        else:
            primal = primal_basis(interface, comp, eps, model.ndof)
            fine = interface.fine
        timings["regularize"] = time.perf_counter() - t0
    if greedy:
        if spec.points > rule.n_points:
            raise CaseError(case.path, f"{key}.points", f"{spec.points} points asked, but "
                            f"the greedy rule selects among {rule.n_points} candidates")
        t0 = time.perf_counter()
        B1, B2 = side_bases(comp, eps)
        try:
            coarse = select(rule, fine if spec.candidates != "fine" else rule, B1, B2,
                            spec.points, spec.tolerance, spec.weights)
        except ValueError as exc:
            raise CaseError(case.path, f"{key}.weights", str(exc)) from None
        rule = coarse.rule
        timings["coarse_rule"] = time.perf_counter() - t0
    return ContactPair(name, spec, interface, comp, eps, eps_source, rule, primal, coarse,
                       timings, factors=factors, projections=projections,
                       gaps=initial_gaps(interface))


def build_contact(case, model, need_compatibility=False, geometry=None):
    """Every contact pair of the case, in file order; geometry: the pairs' geometry built
    already (build_geometry, for a case equal on GEOMETRY: a campaign's variants)."""
    check_motions(case, model.parts)
    if geometry is not None:
        for pair in geometry:
            check_gaps(case, model, pair.name, pair.interface, pair.gaps)
        return [attach(case, pair) for pair in geometry]
    return [build_pair(case, model, name, need_compatibility) for name in case.contact]


def contact_stiffness(pairs, ndof, active=None, kw=None):
    """Sum over pairs of C^T diag(k w) C on model dofs (linear penalty, all points active unless
    `active` gives a bool mask per pair); `kw` gives instead the stiffness w k_t of every point
    per pair (a nonlinear law's tangent).

    Formed on the interface normal dofs first (N1 + N2 square, dense for regularized rules),
    then lifted to the model dofs by the node normals: never a dense (points x dofs) product.
    """
    K = sp.csr_matrix((ndof, ndof))
    for i, pair in enumerate(pairs):
        kw_i = pair.k * pair.rule.weights if kw is None else kw[i]
        if active is not None:
            kw_i = kw_i * active[i]
        D = sp.vstack([pair.interface.side1.dof_map(ndof),
                       pair.interface.side2.dof_map(ndof)]).tocsr()
        K = K + (D.T @ _normal_stiffness(pair, kw_i) @ D).tocsr()
    return K


def _normal_stiffness(pair, kw):
    """[C1, -C2]^T diag(kw) [C1, -C2] on the interface normal dofs (N1 + N2 square)."""
    if pair.factors is not None:
        # [C1 P1, -C2 P2] = L Y with Y = diag(Y1, Y2) (r x N1 + N2): Y^T (L^T D L) Y, r x r
        # algebra instead of the dense points x N rows (pad_disc: 7734 points, rank 599)
        L, (F1, F2) = pair.factors[0], pair.projections
        Y = sla.block_diag(F1[1], F2[1])
        return sp.csr_matrix(Y.T @ ((L.T * kw) @ L) @ Y)
    B = sp.hstack([sp.csr_matrix(pair.rule.C1), -sp.csr_matrix(pair.rule.C2)]).tocsr()
    if B.nnz > DENSE_FILL * B.shape[0] * B.shape[1]:
        # regularized rows are dense: BLAS, not a sparse product of dense-filled matrices
        Bd = B.toarray()
        return sp.csr_matrix((Bd.T * kw) @ Bd)
    return (B.T @ sp.diags(kw) @ B).tocsr()


def contact_preload(pairs, ndof, active=None):
    """Sum over pairs of -C^T diag(k w) g0: the force of the initial gaps under linear penalty."""
    f = np.zeros(ndof)
    for i, pair in enumerate(pairs):
        C = pair.observation(ndof)
        kw = pair.k * pair.rule.weights
        if active is not None:
            kw = kw * active[i]
        f -= C.T @ (kw * pair.rule.gap0)
    return f
