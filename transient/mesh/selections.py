"""Named selections from geometry (plane, box, cylinder) and their lookup as PART.SET."""
import numpy as np

from .mesh import boundary_faces, face_nodes, faces_on_nodes, unit


def select_nodes(points, spec):
    """Node ids within tol of a plane or cylinder surface, or inside a box [m]."""
    tol = spec["tol"]
    kind = spec["kind"]
    if kind == "plane":
        n = unit(spec["normal"])
        d = np.abs((points - np.asarray(spec["point"])) @ n)
        return np.flatnonzero(d <= tol)
    if kind == "box":
        lo, hi = np.asarray(spec["min"]) - tol, np.asarray(spec["max"]) + tol
        return np.flatnonzero(np.all((points >= lo) & (points <= hi), axis=1))
    if kind == "cylinder":
        a = unit(spec["axis"])
        r = points - np.asarray(spec["point"])
        radial = np.linalg.norm(r - np.outer(r @ a, a), axis=1)
        return np.flatnonzero(np.abs(radial - spec["radius"]) <= tol)
    raise ValueError(kind)


def with_geometric_sets(mesh, specs):
    """A copy of the mesh with selections from geometry (name -> SelectionSpec) added as node
    and face sets."""
    if not specs:
        return mesh
    node_sets, face_sets = dict(mesh.node_sets), dict(mesh.face_sets)
    boundary = boundary_faces(mesh)
    for name, spec in specs.items():
        nodes = select_nodes(mesh.points, {"kind": spec.kind, **spec.params})
        node_sets[name] = nodes
        face_sets[name] = faces_on_nodes(mesh, nodes, boundary)
    return type(mesh)(mesh.points, mesh.cells, node_sets, face_sets, mesh.cell_sets)


def set_nodes(mesh, name):
    """Node ids of a named set: a node set, else the nodes of a face set or of a cell set."""
    if name in mesh.node_sets:
        return mesh.node_sets[name]
    if name in mesh.face_sets:
        return face_nodes(mesh.face_sets[name])
    if name in mesh.cell_sets:
        ids = [mesh.cells[t][i].ravel() for t, i in mesh.cell_sets[name].items()]
        return np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)
    raise KeyError(name)


def set_faces(mesh, name):
    """Faces of a named set (face type -> faces): a face set, else the faces on a node set."""
    if name in mesh.face_sets:
        return mesh.face_sets[name]
    if name in mesh.node_sets:
        return faces_on_nodes(mesh, mesh.node_sets[name])
    raise KeyError(name)


def find_set(names, name):
    """The name a set has among names: name itself, else the one name equal to it but for
    case (Abaqus compares names in upper case: PAD_FACE finds pad_face), else None."""
    if name in names:
        return name
    same = {n for n in names if n.upper() == name.upper()}
    return same.pop() if len(same) == 1 else None


def offered(names):
    """Set names to list in a message: sorted, without the internal ones (a name starting
    with '_', as Abaqus/CAE names the element sets behind its surfaces)."""
    return sorted((n for n in names if not n.startswith("_")), key=str.upper)
