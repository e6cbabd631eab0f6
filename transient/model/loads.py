"""Consistent nodal forces of pressures on faces, point forces and gravity."""
import numpy as np

from ..mesh.elements import ELEMENTS


def face_normals(points, faces, ftype, degree=None):
    """Shape values (ng, nfn) and area vectors n dA (nf, ng, 3) of faces at a rule's points.

    n dA = (dx/dxi x dx/deta) w: outward for outward-oriented faces; sums to the area vector.
    """
    el = ELEMENTS[ftype]
    xi, w = el.rule(el.mass_degree + 1 if degree is None else degree)
    N, dN = el.shape_functions(xi), el.shape_derivatives(xi)
    X = points[faces]                                   # (nf, nfn, 3)
    t1 = np.einsum("gn,fnk->fgk", dN[:, :, 0], X)
    t2 = np.einsum("gn,fnk->fgk", dN[:, :, 1], X)
    return N, np.cross(t1, t2) * w[None, :, None]


def pressure_forces(points, face_set, value):
    """Nodal forces (nn, 3) [N] of a pressure value [Pa] pushing into the faces (f = -p n dA)."""
    f = np.zeros_like(points)
    for ftype, faces in face_set.items():
        N, ndA = face_normals(points, faces, ftype)
        fe = -value * np.einsum("gn,fgk->fnk", N, ndA)   # (nf, nfn, 3)
        np.add.at(f, faces.ravel(), fe.reshape(-1, 3))
    return f


def face_area(points, face_set):
    """Total area [m^2] of a face set."""
    total = 0.0
    for ftype, faces in face_set.items():
        _, ndA = face_normals(points, faces, ftype)
        total += np.linalg.norm(ndA, axis=2).sum()
    return total


def nearest_node(points, point, candidates=None):
    """Id of the node nearest a point, among candidates (all nodes if None)."""
    ids = np.arange(len(points)) if candidates is None else np.asarray(candidates)
    d = points[ids] - np.asarray(point)
    scale = np.abs(d).max(initial=0.0)
    # squared distances overflow past 1e154 m: scaled then, which keeps the nearest
    return int(ids[np.argmin(np.linalg.norm(d / scale if scale > 1e100 else d, axis=1))])
