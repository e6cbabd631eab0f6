"""The mesh of one part: nodes, volume cells by type, and named node, face and cell sets."""
from dataclasses import dataclass, field

import numpy as np

from .elements import ELEMENTS, VOLUME_TYPES


@dataclass(frozen=True)
class Mesh:
    """Mesh of one part (SI units).

    points : (n, 3) node coordinates [m].
    cells : volume cell type (meshio name) -> (ne, nen) node ids, VTK ordering, positive volume.
    node_sets : name -> sorted unique node ids.
    face_sets : name -> face type -> (nf, nfn) node ids, oriented with the outward normal.
    cell_sets : name -> cell type -> indices into cells[type].
    """
    points: np.ndarray
    cells: dict
    node_sets: dict = field(default_factory=dict)
    face_sets: dict = field(default_factory=dict)
    cell_sets: dict = field(default_factory=dict)

    @property
    def n_nodes(self):
        return len(self.points)

    @property
    def n_cells(self):
        return sum(len(c) for c in self.cells.values())

    def set_names(self):
        return sorted(set(self.node_sets) | set(self.face_sets) | set(self.cell_sets))


def face_key(faces, n_corners):
    """Sorted corner ids of each face: equal keys mean the same geometric face."""
    return np.sort(faces[:, :n_corners], axis=1)


def all_faces(mesh):
    """Every face of every cell: face type -> (faces (nf, nfn), cell type, cell index)."""
    out = {}
    for ctype, conn in mesh.cells.items():
        for ftype, local in ELEMENTS[ctype].face_groups.items():
            faces = conn[:, local].reshape(-1, local.shape[1])
            owner = np.repeat(np.arange(len(conn)), len(local))
            f, types, owners = out.setdefault(ftype, ([], [], []))
            f.append(faces)
            types += [ctype] * len(faces)
            owners.append(owner)
    return {ft: (np.vstack(f), np.array(t), np.concatenate(o)) for ft, (f, t, o) in out.items()}


def boundary_faces(mesh):
    """Faces that belong to exactly one cell, outward oriented: face type -> (nf, nfn)."""
    out = {}
    for ftype, (faces, _, _) in all_faces(mesh).items():
        nc = ELEMENTS[ftype].n_corners
        key = face_key(faces, nc)
        _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        out[ftype] = faces[counts[inverse.ravel()] == 1]
    return out


def faces_on_nodes(mesh, nodes, boundary=None):
    """Boundary faces whose nodes all lie in the node set: face type -> (nf, nfn)."""
    boundary = boundary_faces(mesh) if boundary is None else boundary
    inside = np.zeros(mesh.n_nodes, bool)
    inside[nodes] = True
    out = {}
    for ftype, faces in boundary.items():
        sel = faces[inside[faces].all(axis=1)]
        if len(sel):
            out[ftype] = sel
    return out


def face_nodes(face_set):
    """Sorted unique node ids of a face set (face type -> faces)."""
    if not face_set:
        return np.zeros(0, dtype=np.int64)
    return np.unique(np.concatenate([f.ravel() for f in face_set.values()]))


def orient_faces(mesh, faces, ftype):
    """Match faces given in any orientation to the outward boundary faces of the mesh.

    Returns the outward-oriented boundary faces and a mask of the input faces that matched.
    """
    boundary = boundary_faces(mesh).get(ftype)
    nc = ELEMENTS[ftype].n_corners
    if boundary is None or len(faces) == 0:
        return np.zeros((0, faces.shape[1]), dtype=np.int64), np.zeros(len(faces), bool)
    bkey = face_key(boundary, nc)
    fkey = face_key(faces, nc)
    both = np.vstack([bkey, fkey])
    _, inverse = np.unique(both, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    where = np.full(inverse.max() + 1, -1)
    where[inverse[:len(bkey)]] = np.arange(len(bkey))
    hit = where[inverse[len(bkey):]]
    return boundary[hit[hit >= 0]], hit >= 0


def volume_cell_types(cells):
    return [t for t in cells if t in VOLUME_TYPES]


def unit(vector):
    """The unit vector along a nonzero vector given in a case (a normal, an axis, a direction)
    of any magnitude."""
    v = np.asarray(vector, float)
    scale = np.abs(v).max()
    # |v|^2 under- or overflows for components near 1e-160 or 1e160; others are left as they
    # are, so that their unit vector keeps its last bits
    if not 1e-100 < scale < 1e100:
        v = v / scale
    return v / np.linalg.norm(v)
