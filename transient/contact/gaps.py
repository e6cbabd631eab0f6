"""A contact pair's initial gaps, measured on its fine rule and judged against its own law and
the load it must carry, before any stage that costs (compatibility, factorization, preload).

The bounds, for the unilateral laws (a bilateral pair is tied: its gaps are only reported):
- p_ref, the preload's mean pressure on the pair: the constant loads' resultant along the
  normal that pushes either side onto the other, over the rule's area. A side is its part
  and the parts tied to it by bilateral pairs facing the same way (a piston on a pad's back);
  a side held along the normal by its constraints (a disc at its hub) pushes nothing.
- Open: with p_ref > 0, a pair whose every gap exceeds the gap where the law's pressure falls
  to NEGLIGIBLE p_ref (exponential: ln(p0 / (NEGLIGIBLE p_ref)) / lambda; linear: p_ref / k,
  the penetration that carries the load, since its pressure is zero at any opening) cannot
  carry the load: refused (its preload Newton would fail, or find no contact). Without p_ref
  an open pair is a scene's own (an impact).
- Overclosed: deeper than where the law's pressure reaches OVERPRESSED p_ref (exponential:
  or p_lin, where it leaves its exponential range, whichever is shallower; without p_ref,
  p_lin, and for the linear law any overclosure: a force from nothing) is a warning; deeper
  than ABSURD_STRAIN of the thinner part along the normal, an error (a strain no linear
  elastic model means).
Gaps within TOUCHING of the rule's extent are round-off of touching meshes.
"""
import sys
from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from ..mesh.selections import set_faces
from ..model.model import constant_load, resolve_set
from .interface import InterfaceError, contact_plane

TOUCHING = 1e-9
NEGLIGIBLE = 1e-6
OVERPRESSED = 1e3
ABSURD_STRAIN = 0.1
ALIGNED = 0.9        # |n . n'| of a bilateral pair that ties a side along the normal n
HOLDS = 0.1          # |n_a| of a fixed axis a that holds a side along n


@dataclass(frozen=True)
class InitialGaps:
    """The initial gaps g0 of a pair's fine rule [m]."""
    min: float
    max: float
    overclosed: float        # share of the rule's area where g0 < -tolerance
    tolerance: float         # [m] round-off of touching meshes

    def meta(self):
        """What the history's meta and the model line say of them."""
        return {"min": self.min, "max": self.max, "overclosed": self.overclosed}


def initial_gaps(interface):
    """The InitialGaps of an interface's fine rule."""
    rule = interface.fine
    g, w = rule.gap0, rule.weights
    tol = TOUCHING * float(np.ptp(rule.points, axis=0).max())
    return InitialGaps(float(g.min()), float(g.max()), float(w[g < -tol].sum() / w.sum()),
                       tol)


def gap_at(law, k, p):
    """The gap [m] where a unilateral law's pressure is p > 0 [Pa]."""
    if law.kind == "linear":
        return -p / k
    if p <= law.p_lin:
        return float(np.log(law.p0 / p) / law.lam)
    g_lin = float(np.log(law.p0 / law.p_lin) / law.lam)
    return g_lin - (p - law.p_lin) / (law.lam * law.p_lin)


def bounds(law, k, p_ref, tol):
    """(open, deep) [m]: the opening beyond which the law carries nothing of p_ref (inf
    without p_ref), and the overclosure beyond which it carries more than it sensibly can."""
    if law.kind == "exponential":
        top = min(OVERPRESSED * p_ref, law.p_lin) if p_ref > 0 else law.p_lin
        deep = -gap_at(law, k, top)
        opened = gap_at(law, k, NEGLIGIBLE * p_ref) if p_ref > 0 else np.inf
    else:
        deep = OVERPRESSED * p_ref / k
        opened = p_ref / k if p_ref > 0 else np.inf
    return max(opened, tol), max(deep, tol)


def check_gaps(case, model, name, interface, gaps):
    """Refuse a unilateral pair that does not touch or is overclosed through a part; say on
    stderr when it is overclosed deeper than its law carries sensibly."""
    spec = case.contact[name]
    if spec.law.kind == "bilateral":
        return
    key, n = f"contact.{name}", interface.plane[2]
    parts = [spec.surface1.split(".", 1)[0]] + ([] if spec.wall else
                                                [spec.surface2.split(".", 1)[0]])
    depth = -gaps.min
    thin = min(float(np.ptp(model.parts[p].mesh.points @ n)) for p in parts)
    if depth > ABSURD_STRAIN * thin:
        raise CaseError(case.path, key, f"the surfaces overlap by up to {depth:.3g} m on "
                        f"{100 * gaps.overclosed:.3g}% of the contact's area, more than "
                        f"{ABSURD_STRAIN:g} of the thinner part's {thin:.3g} m along the "
                        "normal: expected surfaces that touch (parts.NAME.mesh.translate, "
                        "the sets of surface1 and surface2)")
    p_ref = preload_pressure(case, model, spec, n, interface.fine.area)
    opened, deep = bounds(spec.law, spec.k, p_ref, gaps.tolerance)
    if gaps.min > opened:
        raise CaseError(case.path, key, f"the surfaces do not touch: the initial gap is "
                        f"{gaps.min:.3g} to {gaps.max:.3g} m over all of the contact's area, "
                        f"beyond {opened:.3g} m, where the {spec.law.kind} law's pressure is "
                        f"under {NEGLIGIBLE:g} of the {p_ref:.3g} Pa the preload presses them "
                        "with: expected surfaces that touch (parts.NAME.mesh.translate, the "
                        "sets of surface1 and surface2)")
    if depth > deep:
        print(f"warning: {case.path}: {key}: the surfaces overlap by up to {depth:.3g} m on "
              f"{100 * gaps.overclosed:.3g}% of the contact's area, deeper than the "
              f"{spec.law.kind} law carries sensibly ({deep:.3g} m): the preload starts from "
              "that interference", file=sys.stderr)


def preload_pressure(case, model, spec, n, area):
    """p_ref [Pa]: the constant loads' push of either side onto the other, over the area."""
    force = constant_load(case, model).reshape(-1, 3)
    fixed = model.fixed.reshape(-1, 3)[:, np.abs(n) >= HOLDS]
    tied = _tied_along(case, model, n)
    sides = [_side(spec.surface1.split(".", 1)[0], tied)]
    if not spec.wall:
        sides.append(_side(spec.surface2.split(".", 1)[0], tied))
    if len(sides) == 2 and sides[0] & sides[1]:
        return 0.0             # tied to each other: the loads between them are internal
    push = 0.0
    for sign, side in zip((-1.0, 1.0), sides):
        nodes = np.concatenate([np.arange(model.parts[p].offset, model.parts[p].offset
                                          + model.parts[p].mesh.n_nodes) for p in side])
        if not fixed[nodes].any():
            push = max(push, sign * float(force[nodes].sum(axis=0) @ n))
    return push / area


def _side(part, tied):
    side, todo = {part}, [part]
    while todo:
        for other in tied.get(todo.pop(), ()):
            if other not in side:
                side.add(other)
                todo.append(other)
    return side


def _tied_along(case, model, n):
    """part -> the parts a bilateral pair ties it to along n (not across it)."""
    tied = {}
    for name, c in case.contact.items():
        if c.law.kind != "bilateral" or c.wall:
            continue
        ends = []
        for which in ("surface1", "surface2"):
            part, sname = resolve_set(case, model.parts, getattr(c, which),
                                      f"contact.{name}.{which}", surface=True)
            ends.append((part, set_faces(part.mesh, sname)))
        try:
            plane = contact_plane(ends[0][0].mesh.points, ends[0][1], ends[1][0].mesh.points,
                                  ends[1][1])[0]
        except InterfaceError:
            continue            # its own build says so
        if abs(plane[2] @ n) >= ALIGNED:
            a, b = ends[0][0].name, ends[1][0].name
            tied.setdefault(a, set()).add(b)
            tied.setdefault(b, set()).add(a)
    return tied
