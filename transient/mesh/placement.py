"""A part's placement (parts.NAME.transform): a translation, a rotation and a mirror that carry
its mesh, with its node, face and cell sets, from where it was meshed to where the case puts it.

Node ids and cell order are kept, so node and cell sets follow as they are. A mirror turns
every cell and face inside out; their node lists are reordered so that volumes stay positive
and face sets keep their outward normals (the contact's normal and a pressure's sign).
"""
import math

import numpy as np

from .elements import ELEMENTS
from .mesh import Mesh, unit

# A corner order of the other orientation per reference shape: each swaps the reference axes
# xi and eta, which reverses the sign of det J and keeps the element's topology.
_SWAPPED_CORNERS = {"tet": (0, 2, 1, 3), "hex": (0, 3, 2, 1, 4, 7, 6, 5),
                    "wedge": (0, 2, 1, 3, 5, 4), "tri": (0, 2, 1), "quad": (0, 3, 2, 1)}


def reversed_order(ctype):
    """Node order (an index array) that gives a cell or face of type ctype (meshio name) the
    other orientation: corners by its shape, each midside node following its edge."""
    el = ELEMENTS[ctype]
    corners = _SWAPPED_CORNERS[el.shape]
    on_edge = {frozenset(e): el.n_corners + k for k, e in enumerate(el.edges)}
    mids = [on_edge[frozenset((corners[a], corners[b]))] for a, b in el.edges]
    return np.array(corners + tuple(mids), dtype=np.int64)


def _cos_sin(angle):
    """cos and sin of an angle in degrees; a multiple of a quarter turn gives them exactly, so
    a part turned by 90 or 180 deg lands on the coordinates a mesh built there would have."""
    quarters = angle / 90.0
    if quarters == round(quarters):
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[int(round(quarters)) % 4]
    return math.cos(math.radians(angle)), math.sin(math.radians(angle))


def rotation_matrix(axis, angle):
    """(3, 3) rotation by angle [deg] about a nonzero axis, right-handed (Rodrigues)."""
    k = unit(axis)
    c, s = _cos_sin(float(angle))
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return c * np.eye(3) + s * cross + (1.0 - c) * np.outer(k, k)


def place(mesh, translate=(0.0, 0.0, 0.0), rotate=None, mirror=None):
    """The mesh moved by a translation, then a rotation, then a mirror.

    Parameters
    ----------
    mesh : Mesh
    translate : (3,) translation [m].
    rotate : (axis (3,), angle [deg], point (3,) of the axis [m]), or None.
    mirror : (point (3,) of the plane [m], normal (3,) of the plane), or None.

    Returns
    -------
    Mesh with the same node ids, cell order and sets. Mirrored, each cell's and each face
    set's node lists are reordered (reversed_order): volumes stay positive, faces outward.
    A transform that moves nothing returns the mesh itself, bit for bit.
    """
    # a point or a translation far out of range overflows to inf silently here: the caller
    # refuses the placed coordinates with the key that took them there (model.part_mesh)
    with np.errstate(over="ignore", invalid="ignore"):
        points = _moved(mesh.points, translate, rotate, mirror)
    if mirror is None:
        if points is mesh.points:
            return mesh
        return Mesh(points, mesh.cells, mesh.node_sets, mesh.face_sets, mesh.cell_sets)
    cells = {t: conn[:, reversed_order(t)] for t, conn in mesh.cells.items()}
    face_sets = {name: {t: faces[:, reversed_order(t)] for t, faces in by_type.items()}
                 for name, by_type in mesh.face_sets.items()}
    return Mesh(points, cells, mesh.node_sets, face_sets, mesh.cell_sets)


def _moved(points, translate, rotate, mirror):
    """The coordinates translated, rotated and mirrored (place); unmoved, the same array."""
    if any(x != 0.0 for x in translate):
        points = points + np.asarray(translate, dtype=float)
    if rotate is not None and rotate[1] != 0.0:
        axis, angle, point = rotate
        p = np.asarray(point, dtype=float)
        points = (points - p) @ rotation_matrix(axis, angle).T + p
    if mirror is not None:
        point, normal = mirror
        n = unit(normal)
        points = points - 2.0 * np.outer((points - np.asarray(point, dtype=float)) @ n, n)
    return points
