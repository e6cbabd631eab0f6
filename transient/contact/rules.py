"""Contact rules other than the fine one: the centre rule (one point per master face)."""
import numpy as np

from . import facemap
from ..mesh.elements import ELEMENTS
from .interface import FACE_TYPES, make_rule


def _inside(xi, ftype, tol=1e-9):
    if ELEMENTS[ftype].shape == "quad":
        return np.all(np.abs(xi) <= 1 + tol, axis=1)
    return (xi[:, 0] >= -tol) & (xi[:, 1] >= -tol) & (xi.sum(axis=1) <= 1 + tol)


def centre_rule(interface, master="surface1"):
    """One point at the centre of each interface face of the master side, weighted by the face's
    projected area; the other side observes it where the point falls (node-to-segment style).

    A centre that falls on no face of the other side (over a hole, past an edge) is dropped.
    """
    frame, origin = interface.plane, interface.origin
    sides = (interface.side1, interface.side2)
    m = 0 if master == "surface1" else 1
    own, other = sides[m], sides[1 - m]
    n_faces = len(own.faces)
    p2d = np.zeros((n_faces, 2))
    area = np.zeros(n_faces)
    for t, ftype in enumerate(FACE_TYPES):
        idx = np.flatnonzero(own.face_types == t)
        if len(idx) == 0:
            continue
        el = ELEMENTS[ftype]
        X = own.points[np.array([own.faces[f] for f in idx])]
        centre = facemap.forward(X, np.tile(facemap.reference_centre(ftype), (len(idx), 1)), ftype)
        p2d[idx] = (centre - origin) @ frame[:2].T
        xi, w = el.rule(el.mass_degree)
        for q in range(len(w)):
            t1, t2 = facemap.tangents(X, np.tile(xi[q], (len(idx), 1)), ftype)
            area[idx] += w[q] * np.abs(np.cross(t1, t2) @ frame[2])
    # candidates on the other side: the faces that overlap each master face
    hit = np.full(n_faces, -1)
    for f_own, f_other in interface.pairs[:, [m, 1 - m]]:
        if hit[f_own] >= 0:
            continue
        ftype = FACE_TYPES[other.face_types[f_other]]
        X2d = (other.points[other.faces[f_other]] - origin) @ frame[:2].T
        xi, ok = facemap.inverse(X2d[None], p2d[f_own][None], ftype)
        if ok[0] and _inside(xi, ftype)[0]:
            hit[f_own] = f_other
    keep = np.flatnonzero(hit >= 0)
    f_master, f_other = keep, hit[keep]
    f1, f2 = (f_master, f_other) if m == 0 else (f_other, f_master)
    return make_rule(frame, origin, interface.side1, interface.side2, p2d[keep], area[keep], f1, f2)
