"""The contact interface between two face sets: the fine integration rule and gap observation.

Gamma, the effective contact domain, is the intersection of the two surfaces projected on the
contact plane. For each pair of overlapping faces (broad phase: KD-tree on face centres), the
projected corner polygons are clipped, the intersection is split into triangles, a triangle Gauss
rule is placed on each, and every point is mapped back into both faces.

Sign conventions: n is the unit normal of surface 2, pointing out of part 2 towards part 1. The
gap at point i is g_i = C1_i q1 - C2_i q2 + g0_i, positive when open; C^s_i holds the shape
functions of face s at point i acting on the normal dofs u_n = nbar_a . u_a of the interface nodes
(nbar_a: node normals along +n). The contact force on the dofs is f = C^T diag(w) p(g) with
C = [C1, -C2] and p >= 0 the contact pressure.

Normal dofs keep the gap energy free of the tangential dofs (which would add spurious zero
singular values). On planar interfaces every normal is n and rigid motions give a zero gap to
round-off; on curved ones the node normals of the two meshes differ, and a rigid motion leaves a
gap of second order in the slope: fine for surfaces close to planar, as brake interfaces are.
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from . import facemap
from ..mesh.elements import ELEMENTS
from ..mesh.mesh import unit
from ..kernels.clipping import clip_pairs
from ..mesh.quadrature import triangle


class InterfaceError(ValueError):
    pass


@dataclass(frozen=True)
class Side:
    """The interface faces of one part: those that overlap the other surface."""
    points: np.ndarray       # (n, 3) node coordinates of the part [m]
    face_types: np.ndarray   # (F,) index into FACE_TYPES of each face
    faces: list              # per face: node ids (part numbering)
    nodes: np.ndarray        # (N,) sorted part node ids of the interface faces
    node_normals: np.ndarray  # (N, 3) unit normals along +n
    offset: int              # global id of the part's node 0

    @property
    def n(self):
        return len(self.nodes)

    def dof_map(self, ndof):
        """(N, ndof) sparse map from model dofs to the normal dofs of the interface nodes."""
        return self.direction_map(self.node_normals, ndof)

    def direction_map(self, directions, ndof):
        """(N, ndof) sparse map from model dofs to the nodes' components along directions
        (N, 3): the normals, or the sliding directions of friction."""
        rows = np.repeat(np.arange(self.n), 3)
        cols = (3 * (self.nodes + self.offset))[:, None] + np.arange(3)
        return sp.csr_matrix((np.asarray(directions).ravel(), (rows, cols.ravel())),
                             shape=(self.n, ndof))


@dataclass(frozen=True)
class Rule:
    """Points on Gamma with their weights and where they fall in the faces of both sides."""
    points: np.ndarray       # (P, 3) position on surface 2 [m]
    weights: np.ndarray      # (P,) w_i J_i [m^2], area of Gamma carried by each point
    normals: np.ndarray      # (P, 3) unit normal of surface 2 at the point
    gap0: np.ndarray         # (P,) initial gap [m]
    face1: np.ndarray        # (P,) face of side 1 holding the point
    face2: np.ndarray
    C1: sp.csr_matrix        # (P, N1) observation of the normal dofs of side 1
    C2: sp.csr_matrix        # (P, N2)

    @property
    def n_points(self):
        return len(self.weights)

    @property
    def area(self):
        return float(self.weights.sum())


@dataclass(frozen=True)
class Interface:
    name: str
    plane: np.ndarray        # (3, 3): rows t1, t2, n (right-handed, n along surface 2's normal)
    origin: np.ndarray       # (3,) a point of the plane
    side1: Side
    side2: Side
    fine: Rule               # the fine rule
    pairs: np.ndarray        # (K, 2) overlapping faces (side 1, side 2)
    order: int               # degree of the triangle rule
    timings: dict

    def observation(self, rule, ndof):
        """(P, ndof) gap observation of a rule in model dofs: C1 T1 - C2 T2."""
        return rule.C1 @ self.side1.dof_map(ndof) - rule.C2 @ self.side2.dof_map(ndof)


FACE_TYPES = ("quad", "quad8", "triangle", "triangle6")


def _flatten(face_set):
    types, faces = [], []
    for ftype, conn in face_set.items():
        types += [FACE_TYPES.index(ftype)] * len(conn)
        faces += list(conn)
    return np.array(types, dtype=np.int64), faces


def _area_vector(points, face_set):
    total = np.zeros(3)
    for ftype, conn in face_set.items():
        X = points[conn]
        nc = ELEMENTS[ftype].n_corners
        c = X[:, :nc]
        # area vector of the corner polygon (exact for planar straight-edged faces)
        total += 0.5 * np.cross(c, np.roll(c, -1, axis=1)).sum(axis=(0, 1))
    return total


def contact_plane(points1, faces1, points2, faces2):
    """Orthonormal frame (t1, t2, n) and origin of the contact plane."""
    a2 = _area_vector(points2, faces2)
    a1 = _area_vector(points1, faces1)
    if np.linalg.norm(a2) == 0 or np.linalg.norm(a1) == 0:
        raise InterfaceError("a surface has zero projected area")
    n = a2 / np.linalg.norm(a2)
    if a1 @ n >= 0:
        raise InterfaceError("the surfaces do not face each other (their outward normals agree)")
    t1 = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(n, t1)
    origin = np.vstack([points2[c].reshape(-1, 3) for c in faces2.values()]).mean(axis=0)
    return np.vstack([t1, t2, n]), origin


def _polygons(points, types, faces, frame, origin, reverse):
    """Projected corner polygons (F, 4, 2) counterclockwise about n, counts, centres, radii."""
    F = len(faces)
    poly = np.zeros((F, 4, 2))
    counts = np.zeros(F, np.int64)
    for f, (t, conn) in enumerate(zip(types, faces)):
        nc = ELEMENTS[FACE_TYPES[t]].n_corners
        c = (points[conn[:nc]] - origin) @ frame[:2].T
        poly[f, :nc] = c[::-1] if reverse else c
        counts[f] = nc
    mask = np.arange(4)[None, :] < counts[:, None]
    centres = (poly * mask[:, :, None]).sum(axis=1) / counts[:, None]
    radii = (np.linalg.norm(poly - centres[:, None], axis=2) * mask).max(axis=1)
    return poly, counts, centres, radii


def _polygon_area(v, m):
    """Signed areas of polygons v (P, V, 2) with m (P,) vertices."""
    idx = np.arange(v.shape[1])
    nxt = np.where(idx[None, :] + 1 < m[:, None], idx[None, :] + 1, 0)
    x, y = v[:, :, 0], v[:, :, 1]
    xn = np.take_along_axis(x, nxt, axis=1)
    yn = np.take_along_axis(y, nxt, axis=1)
    valid = idx[None, :] < m[:, None]
    return 0.5 * ((x * yn - xn * y) * valid).sum(axis=1)


def overlap_pairs(poly1, n1, c1, r1, poly2, n2, c2, r2):
    """Clipped intersection polygons of all overlapping face pairs (broad phase: KD-tree)."""
    tree = cKDTree(c2)
    near = tree.query_ball_point(c1, r1 + r2.max() * (1 + 1e-9))
    counts = np.array([len(x) for x in near])
    pairs = np.empty((counts.sum(), 2), np.int64)
    pairs[:, 0] = np.repeat(np.arange(len(c1)), counts)
    pairs[:, 1] = np.concatenate([np.asarray(x, np.int64) for x in near]) if len(pairs) else []
    # exact circle test before clipping: most candidates of the radius query are too far
    d = np.linalg.norm(c1[pairs[:, 0]] - c2[pairs[:, 1]], axis=1)
    pairs = pairs[d <= (r1[pairs[:, 0]] + r2[pairs[:, 1]]) * (1 + 1e-9)]
    verts, m = clip_pairs(poly1, n1, poly2, n2, pairs)
    area = _polygon_area(verts, m)
    # slivers from round-off on shared edges carry no area: drop them
    a1 = np.abs(_polygon_area(poly1, n1))
    keep = (m >= 3) & (area > 1e-12 * a1[pairs[:, 0]])
    return pairs[keep], verts[keep], m[keep], area[keep]


def triangle_points(verts, m, degree):
    """Gauss points (Q, 2) and weights (Q,) on the fan triangulation of convex polygons.

    Returns also the polygon index of each point.
    """
    xi, w = triangle(degree)
    tri_poly = np.concatenate([np.full(k - 2, p) for p, k in enumerate(m)])
    tri_k = np.concatenate([np.arange(1, k - 1) for k in m])
    a = verts[tri_poly, 0]
    b = verts[tri_poly, tri_k]
    c = verts[tri_poly, tri_k + 1]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    # clipping leaves collinear or repeated vertices: their fan triangles carry no area
    polygon = np.bincount(tri_poly, weights=np.abs(det), minlength=len(m))
    keep = np.abs(det) > 1e-12 * polygon[tri_poly]
    a, b, c, det, tri_poly = a[keep], b[keep], c[keep], det[keep], tri_poly[keep]
    pts = (a[:, None, :] + xi[None, :, 0:1] * (b - a)[:, None, :]
           + xi[None, :, 1:2] * (c - a)[:, None, :])
    wts = np.abs(det)[:, None] * w[None, :]
    owner = np.repeat(tri_poly, len(w))
    return pts.reshape(-1, 2), wts.ravel(), owner


def _map_points(points, types, faces, face_of_point, p2d, frame, origin):
    """Reference coordinates, 3D positions and unit normals of points in their faces."""
    P = len(face_of_point)
    xi = np.zeros((P, 2))
    x = np.zeros((P, 3))
    normal = np.zeros((P, 3))
    for t, ftype in enumerate(FACE_TYPES):
        sel = np.flatnonzero(types[face_of_point] == t)
        if len(sel) == 0:
            continue
        conn = np.array([faces[f] for f in face_of_point[sel]])
        X = points[conn]
        X2d = (X - origin) @ frame[:2].T
        xi_t, ok = facemap.inverse(X2d, p2d[sel], ftype)
        if not ok.all():
            raise InterfaceError(f"inverse map of {ftype} faces did not converge "
                                 f"({(~ok).sum()} points): distorted or folded faces?")
        xi[sel] = xi_t
        x[sel] = facemap.forward(X, xi_t, ftype)
        normal[sel] = facemap.unit_normals(X, xi_t, ftype)
    return xi, x, normal


def _observation(types, faces, face_of_point, xi, nodes):
    """(P, N) shape functions of each point's face on the interface nodes."""
    rows, cols, vals = [], [], []
    where = {int(v): i for i, v in enumerate(nodes)}
    for t, ftype in enumerate(FACE_TYPES):
        sel = np.flatnonzero(types[face_of_point] == t)
        if len(sel) == 0:
            continue
        conn = np.array([faces[f] for f in face_of_point[sel]])
        N = ELEMENTS[ftype].shape_functions(xi[sel])
        rows.append(np.repeat(sel, conn.shape[1]))
        cols.append(np.vectorize(where.__getitem__, otypes=[np.int64])(conn).ravel())
        vals.append(N.ravel())
    P = len(face_of_point)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(P, len(nodes)))


def _node_normals(points, types, faces, nodes, sign):
    """Area-weighted mean unit normals at the nodes, along sign * outward."""
    acc = np.zeros((len(nodes), 3))
    where = {int(v): i for i, v in enumerate(nodes)}
    for t, ftype in enumerate(FACE_TYPES):
        idx = np.flatnonzero(types == t)
        if len(idx) == 0:
            continue
        el = ELEMENTS[ftype]
        conn = np.array([faces[f] for f in idx])
        X = points[conn]
        for a in range(el.nen):
            xi = np.tile(el.nodes[a], (len(idx), 1))
            t1, t2 = facemap.tangents(X, xi, ftype)
            nvec = np.cross(t1, t2)
            np.add.at(acc, [where[int(v)] for v in conn[:, a]], nvec)
    return sign * acc / np.linalg.norm(acc, axis=1)[:, None]


def _side(points, types, faces, used, offset, sign):
    types = types[used]
    faces = [faces[f] for f in used]
    nodes = np.unique(np.concatenate(faces))
    return Side(points, types, faces, nodes, _node_normals(points, types, faces, nodes, sign),
                offset)


def make_rule(frame, origin, side1, side2, p2d, weights, f1, f2):
    """Rule of points p2d (P, 2) in the plane lying in faces f1 of side 1 and f2 of side 2."""
    xi1, x1, _ = _map_points(side1.points, side1.face_types, side1.faces, f1, p2d, frame, origin)
    xi2, x2, normal = _map_points(side2.points, side2.face_types, side2.faces, f2, p2d, frame,
                                  origin)
    gap0 = np.einsum("ij,ij->i", x1 - x2, normal)
    C1 = _observation(side1.face_types, side1.faces, f1, xi1, side1.nodes)
    C2 = _observation(side2.face_types, side2.faces, f2, xi2, side2.nodes)
    return Rule(x2, weights, normal, gap0, f1, f2, C1, C2)


def build_interface(name, points1, faces1, offset1, points2, faces2, offset2, degree=4):
    """Fine rule of degree `degree` on Gamma between face sets of part 1 and part 2.

    points1, points2: node coordinates of each part [m]; faces1, faces2: face type -> outward
    faces (part node ids); offset1, offset2: global id of each part's node 0.
    """
    t0 = time.perf_counter()
    frame, origin = contact_plane(points1, faces1, points2, faces2)
    types1, list1 = _flatten(faces1)
    types2, list2 = _flatten(faces2)
    # surface 1 faces outward along -n: reverse them so both are counterclockwise about n
    poly1, n1, c1, r1 = _polygons(points1, types1, list1, frame, origin, reverse=True)
    poly2, n2, c2, r2 = _polygons(points2, types2, list2, frame, origin, reverse=False)
    pairs, verts, m, _ = overlap_pairs(poly1, n1, c1, r1, poly2, n2, c2, r2)
    if len(pairs) == 0:
        raise InterfaceError("the two surfaces do not overlap")
    t_clip = time.perf_counter()
    p2d, w, owner = triangle_points(verts, m, degree)
    used1, local1 = np.unique(pairs[:, 0], return_inverse=True)
    used2, local2 = np.unique(pairs[:, 1], return_inverse=True)
    local = np.stack([local1.ravel(), local2.ravel()], axis=1)
    side1 = _side(points1, types1, list1, used1, offset1, -1.0)
    side2 = _side(points2, types2, list2, used2, offset2, 1.0)
    rule = make_rule(frame, origin, side1, side2, p2d, w, local[owner, 0], local[owner, 1])
    timings = {"clipping": t_clip - t0, "fine_rule": time.perf_counter() - t_clip}
    return Interface(name, frame, origin, side1, side2, rule, local, degree, timings)


def build_wall_interface(name, points1, faces1, offset1, wall_point, wall_normal, degree=4):
    """Fine rule between a surface of part 1 and a rigid plane (the wall): a triangle Gauss rule
    on each face's projection; side 2 is empty. wall_normal points out of the wall."""
    t0 = time.perf_counter()
    n = unit(wall_normal)
    t1 = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    t1 /= np.linalg.norm(t1)
    frame = np.vstack([t1, np.cross(n, t1), n])
    origin = np.asarray(wall_point, float)
    types1, list1 = _flatten(faces1)
    poly, counts, _, _ = _polygons(points1, types1, list1, frame, origin, reverse=True)
    area = _polygon_area(poly, counts)
    faces = np.flatnonzero(area > 0)       # faces turned away from the wall cannot touch it
    if len(faces) == 0:
        raise InterfaceError("no face of the surface faces the wall")
    p2d, w, owner = triangle_points(poly[faces], counts[faces], degree)
    side1 = _side(points1, types1, list1, faces, offset1, -1.0)
    # on a wall every normal is the wall's: node normals included
    side1 = Side(side1.points, side1.face_types, side1.faces, side1.nodes,
                 np.tile(n, (side1.n, 1)), offset1)
    side2 = Side(np.zeros((0, 3)), np.zeros(0, np.int64), [], np.zeros(0, np.int64),
                 np.zeros((0, 3)), 0)
    xi1, x1, _ = _map_points(points1, side1.face_types, side1.faces, owner, p2d, frame, origin)
    gap0 = (x1 - origin) @ n
    C1 = _observation(side1.face_types, side1.faces, owner, xi1, side1.nodes)
    C2 = sp.csr_matrix((len(w), 0))
    rule = Rule(x1, w, np.tile(n, (len(w), 1)), gap0, owner, np.zeros(len(w), np.int64), C1, C2)
    pairs = np.stack([np.arange(len(faces)), np.zeros(len(faces), np.int64)], axis=1)
    timings = {"fine_rule": time.perf_counter() - t0}
    return Interface(name, frame, origin, side1, side2, rule, pairs, degree, timings)
