"""One body of a mesh file that holds several (a deck's instances, a flat deck's element
sets, a gmsh file's physical volumes): the cells of one cell set alone, with the part of
every set that lies on them."""
import numpy as np

from .mesh import Mesh, all_faces, face_key
from .elements import ELEMENTS


def take_body(mesh, name):
    """The Mesh of the cells of cell set `name` alone: nodes renumbered, node and cell sets
    cut to them, face sets to the faces of those cells; sets left empty are dropped."""
    chosen = mesh.cell_sets[name]
    cells, rows = {}, {}
    for ctype, conn in mesh.cells.items():
        keep = np.unique(chosen.get(ctype, np.zeros(0, np.int64)))
        if len(keep):
            cells[ctype] = conn[keep]
            rows[ctype] = np.full(len(conn), -1, dtype=np.int64)
            rows[ctype][keep] = np.arange(len(keep))
    used = np.unique(np.concatenate([c.ravel() for c in cells.values()]))
    new = np.full(mesh.n_nodes, -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    node_sets = {}
    for set_name, ids in mesh.node_sets.items():
        kept = new[ids]
        if (kept >= 0).any():
            node_sets[set_name] = np.sort(kept[kept >= 0])
    cell_sets = {}
    for set_name, by_type in mesh.cell_sets.items():
        kept = {t: rows[t][i][rows[t][i] >= 0] for t, i in by_type.items() if t in rows}
        kept = {t: i for t, i in kept.items() if len(i)}
        if kept:
            cell_sets[set_name] = kept
    own = {ft: faces for ft, (faces, _, _) in all_faces(Mesh(mesh.points, cells)).items()}
    face_sets = {}
    for set_name, by_type in mesh.face_sets.items():
        kept = {}
        for ftype, faces in by_type.items():
            if ftype in own:
                inside = _member(face_key(faces, ELEMENTS[ftype].n_corners),
                                 face_key(own[ftype], ELEMENTS[ftype].n_corners))
                if inside.any():
                    kept[ftype] = new[faces[inside]]
        if kept:
            face_sets[set_name] = kept
    return Mesh(mesh.points[used], {t: new[c] for t, c in cells.items()}, node_sets,
                face_sets, cell_sets)


def _member(rows, pool):
    """Mask of the rows (k, m) that are rows of pool (p, m)."""
    both = np.vstack([pool, rows])
    _, inverse = np.unique(both, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    present = np.zeros(inverse.max() + 1, bool)
    present[inverse[:len(pool)]] = True
    return present[inverse[len(pool):]]
