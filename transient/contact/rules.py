"""Contact rules other than the fine one, on the faces of one side (the master): the centre rule
(one point per face, node-to-segment style) and the Gauss rule (each face's own Gauss points:
the paper's rich "6 points for a 6-node triangle" at degree 4)."""
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
    return face_rule(interface, master)


def gauss_rule(interface, master="surface1", degree=4):
    """The Gauss points of degree `degree` of each interface face of the master side (6 on a
    triangle at degree 4, 9 on a quadrangle), weighted by w |J| projected on the contact plane;
    the other side observes each where it falls. Over incompatible meshes such a rich rule
    holds the gap at many more points than the interface has shapes that can close it: the
    paper's locking (its section 4.2).

    A point that falls on no face of the other side is dropped, with its weight.
    """
    return face_rule(interface, master, degree)


def face_rule(interface, master="surface1", degree=None):
    """Points on the master side's faces: their centres weighted by the projected area (degree
    None), or their Gauss points of that degree weighted by w |J| projected; each point kept
    in the first overlapping face of the other side that holds it."""
    frame, origin = interface.plane, interface.origin
    sides = (interface.side1, interface.side2)
    m = 0 if master == "surface1" else 1
    own, other = sides[m], sides[1 - m]
    p2d, weight, face = [], [], []
    for t, ftype in enumerate(FACE_TYPES):
        idx = np.flatnonzero(own.face_types == t)
        if len(idx) == 0:
            continue
        el = ELEMENTS[ftype]
        X = own.points[np.array([own.faces[f] for f in idx])]

        def projected_jacobian(xi):
            t1, t2 = facemap.tangents(X, np.tile(xi, (len(idx), 1)), ftype)
            return np.abs(np.cross(t1, t2) @ frame[2])
        if degree is None:
            xi_q = facemap.reference_centre(ftype)[None]
            xi_m, w_m = el.rule(el.mass_degree)
            w_q = sum(w * projected_jacobian(x) for x, w in zip(xi_m, w_m))[:, None]
        else:
            xi_q, w = el.rule(degree)
            w_q = np.stack([wq * projected_jacobian(x) for x, wq in zip(xi_q, w)], axis=1)
        for q, xi in enumerate(xi_q):
            centre = facemap.forward(X, np.tile(xi, (len(idx), 1)), ftype)
            p2d.append((centre - origin) @ frame[:2].T)
            weight.append(w_q[:, q])
            face.append(idx)
    p2d, weight, face = np.vstack(p2d), np.concatenate(weight), np.concatenate(face)
    # points ordered face by face, then by Gauss point
    order = np.lexsort((np.arange(len(face)), face))
    p2d, weight, face = p2d[order], weight[order], face[order]
    hit = _locate(interface, other, m, p2d, face)
    keep = np.flatnonzero(hit >= 0)
    f_master, f_other = face[keep], hit[keep]
    f1, f2 = (f_master, f_other) if m == 0 else (f_other, f_master)
    return make_rule(frame, origin, interface.side1, interface.side2, p2d[keep], weight[keep],
                     f1, f2)


def _locate(interface, other, m, p2d, face):
    """For each point (p2d, on master face `face`), the first face of the other side, in the
    interface's pair order, that holds it; -1 for none."""
    frame, origin = interface.plane, interface.origin
    pairs = interface.pairs[:, [m, 1 - m]]
    # every (point, candidate) of a pair whose master face holds the point, in pair order
    by_face = np.argsort(face, kind="stable")
    start = np.searchsorted(face[by_face], pairs[:, 0], side="left")
    stop = np.searchsorted(face[by_face], pairs[:, 0], side="right")
    counts = stop - start
    rank = np.repeat(np.arange(len(pairs)), counts)
    within = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    point = by_face[np.repeat(start, counts) + within]
    candidate = pairs[rank, 1]
    inside = np.zeros(len(point), bool)
    for t, ftype in enumerate(FACE_TYPES):
        sel = np.flatnonzero(other.face_types[candidate] == t)
        if len(sel) == 0:
            continue
        X2d = (other.points[np.array([other.faces[f] for f in candidate[sel]])] - origin) \
            @ frame[:2].T
        xi, ok = facemap.inverse(X2d, p2d[point[sel]], ftype)
        inside[sel] = ok & _inside(xi, ftype)
    hit = np.full(len(p2d), -1)
    # the first candidate in pair order: write the hits in reverse, the first one last
    found = np.flatnonzero(inside)[::-1]
    hit[point[found]] = candidate[found]
    return hit
