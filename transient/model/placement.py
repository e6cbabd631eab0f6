"""Where the case puts things, checked on the meshes before any factorization: a mesh file
read in millimetres as metres (before the assembly), and a sensor, a force or a rotation's
axis placed off its part (once the cells are found sound), are one-line errors with the
distance measured, not modes at 1 Hz or a nearest node taken without a word."""
import numpy as np

from ..errors import CaseError
from ..mesh.mesh import unit

def check_scale(case, parts):
    """A file mesh taken at scale 1 whose bounding box spans more than limits.part_span (10 m
    by default: no brake part, a disc, a caliper, a wind turbine's yaw ring, spans that many
    metres, and a mesh of a 10 mm clip read in millimetres as metres already does): its
    coordinates are millimetres read as metres."""
    largest = case.limits.part_span
    for name, part in parts.items():
        spec = case.parts[name].mesh
        if spec.kind != "file" or spec.params["scale"] != 1.0:
            continue
        span = float(np.ptp(part.mesh.points, axis=0).max())
        if span > largest:
            raise CaseError(case.path, f"parts.{name}.mesh.scale", f"the mesh of part '{name}' "
                            f"spans {span:.4g} m at scale 1, more than limits.part_span "
                            f"({largest:g} m): a file in millimetres? set "
                            f"parts.{name}.mesh.scale = 1e-3 (or raise limits.part_span for "
                            "a part that large)")


def cell_span(mesh):
    """The largest cell's extent [m]: the diagonal of the box of its nodes. Every point of the
    part lies within it of one of the part's nodes."""
    span = 0.0
    for conn in mesh.cells.values():
        x = mesh.points[conn]
        span = max(span, float(np.hypot.reduce(np.ptp(x, axis=1), axis=1).max()))
    return span


def _distance(a, b):
    """|a - b| for points of any magnitude (hypot: the square of 1e160 m overflows; past
    1.8e308 m, inf)."""
    with np.errstate(over="ignore"):
        return float(np.hypot.reduce(np.asarray(a, float) - np.asarray(b, float)))


def check_points(case, parts):
    """Each sensor's and point force's point lies within the largest cell's extent of its
    part's nearest node (where it is applied or measured): farther, it is off the part."""
    points = [(f"sensors.{n}.point", s.part, s.point) for n, s in case.sensors.items()]
    points += [(f"loads.{n}.point", s.part, s.point) for n, s in case.loads.items()
               if s.kind == "force"]
    spans = {}
    for key, name, point in points:
        mesh = parts[name].mesh
        x = mesh.points
        lo, hi = x.min(axis=0), x.max(axis=0)
        if name not in spans:
            spans[name] = cell_span(mesh)
        tol = spans[name]
        p = np.asarray(point, float)
        # the box first, by coordinate (no magnitude overflows), then the nearest node
        with np.errstate(over="ignore"):
            outside = np.maximum(np.maximum(lo - p, p - hi), 0.0)
        away = (_distance(outside, 0.0) if np.any(outside > tol)
                else float(np.hypot.reduce(x - p, axis=1).min()))
        if not away <= tol:
            raise CaseError(case.path, key, f"{list(point)} lies {away:.3g} m from part "
                            f"'{name}' (its nearest node; its largest cell spans {tol:.3g} m, "
                            f"its nodes the box {lo.tolist()} to {hi.tolist()}): expected a "
                            "point on the part")


def check_motions(case, parts):
    """A rotation's axis passes through the sphere that holds its part's box: one farther
    turns the part about somewhere else (a point in millimetres, a wrong origin)."""
    for name, motion in case.motion.items():
        if motion.kind != "rotation":
            continue
        x = parts[motion.part].mesh.points
        lo, hi = x.min(axis=0), x.max(axis=0)
        centre, radius = 0.5 * (lo + hi), 0.5 * _distance(hi, lo)
        with np.errstate(over="ignore", invalid="ignore"):
            r = centre - np.asarray(motion.point, float)
            arm = r - (r @ unit(motion.axis)) * unit(motion.axis)
        away = _distance(arm, 0.0) if np.isfinite(arm).all() else float("inf")
        if not away <= radius:
            raise CaseError(case.path, f"motion.{name}.point", f"{list(motion.point)}: the "
                            f"axis passes {away:.3g} m from the centre of part "
                            f"'{motion.part}', outside the {radius:.3g} m that hold its "
                            "nodes: expected an axis through the part")
