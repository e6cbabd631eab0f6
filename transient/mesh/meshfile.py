"""Mesh files: read any meshio format or an Abaqus deck into a Mesh, write VTU for ParaView,
check Jacobians.

Reading keeps the volume cells as elements and turns surface cells into outward-oriented face
sets. Named selections come from meshio point_sets and cell_sets, from Gmsh physical groups and
from the 0/1 'set:<name>' arrays that write_vtu adds, so a VTU written here reads back with its
node and cell sets. Abaqus and CalculiX decks (.inp) are read by transient.mesh.abaqus, which
reads their surfaces, parts and instances, as meshio's reader does not.
"""
import contextlib
import io
import sys
import warnings
from pathlib import Path

import meshio
import numpy as np

from .abaqus import read_abaqus
from .elements import ELEMENTS, FACE_TYPES, VOLUME_TYPES
from .fileerror import MeshFileError
from .mesh import Mesh, face_nodes, orient_faces

SET_PREFIX = "set:"
_JACOBIAN_CHUNK = 8192   # cells per vectorized batch: bounds memory to a few tens of MB
# meshio 5 turns a linear wedge's triangles over between its order (gmsh's) and VTK's as VTK's
# documentation long described it (triangle 0-1-2 facing out); VTK itself takes gmsh's order
# (its cell validator passes it and flags meshio's as inverted), so for VTK files the turn is
# undone, reading and writing. VTK's quadratic wedge is left in gmsh's order by meshio.
_MESHIO_VTK_WEDGE = np.array([0, 2, 1, 3, 5, 4])
_VTK_SUFFIXES = (".vtu", ".vtk")


def _meshio_knows_wedge15():
    """meshio 5.3 maps gmsh's prism15 and VTK's quadratic wedge to 'wedge15' but leaves it
    out of its table of cell dimensions, so that it can neither read nor write one (meshio
    issues 1247, 1505); the missing entry is added, and a meshio that has it is left as it is."""
    table = getattr(getattr(meshio, "_mesh", None), "topological_dimension", None)
    if isinstance(table, dict):
        table.setdefault("wedge15", 3)


_meshio_knows_wedge15()


def read_mesh(path):
    """Read a mesh file (Gmsh .msh v2/v4, Abaqus .inp, VTU, ...) into a Mesh.

    Parameters
    ----------
    path : str or Path
        Any file meshio can read, or an Abaqus deck (.inp: transient.mesh.abaqus, whose notes
        on what it leaves out are printed on standard error); coordinates are taken as metres.

    Returns
    -------
    Mesh
        Volume cells of the supported types, nodes used by no volume cell removed, duplicate
        volume cells (Gmsh v2 repeats a cell once per physical group) merged, and the named
        selections as node, face and cell sets. Sets that end up empty are dropped. Inverted
        cells are kept as they are: see jacobian_check.

    Raises
    ------
    MeshFileError
        Missing or unreadable file, unsupported cell type, no volume cells, or a named surface
        cell that is not on the boundary of the volume mesh.
    """
    path = Path(path)
    if not path.is_file():
        raise MeshFileError(path, "no such file")
    if path.suffix.lower() == ".inp":
        mesh, notes = read_abaqus(path)
        for note in notes:
            print(f"note: {path}: {note}", file=sys.stderr)
        return mesh
    raw, said = _meshio_read(path)
    if path.suffix.lower() in _VTK_SUFFIXES:
        for block in raw.cells:
            if block.type == "wedge" and np.ndim(block.data) == 2 and block.data.shape[1] == 6:
                block.data = np.asarray(block.data)[:, _MESHIO_VTK_WEDGE]
    # what meshio said is held until the mesh is taken: a refused one gets one error line,
    # which carries it (a truncated file often explains the refusal)
    try:
        # a section not closed: the file is cut short, and what meshio made of it need not
        # be its mesh (cells left out, or with fewer nodes)
        if "not closed by $End" in said:
            raise MeshFileError(path, "cut short: a section is not closed")
        mesh = _convert(raw, path)
    except MeshFileError as exc:
        if not said:
            raise
        raise MeshFileError(path, f"{exc.message} (meshio: {said})") from None
    if said:
        warnings.warn(f"meshio reading {path}: {said}", stacklevel=2)
    return mesh


def _meshio_read(path):
    """meshio.read with its failures turned into errors; returns the mesh and, in one line,
    what meshio said on the console and in warnings while reading it.

    meshio 5.3 prints to the console and calls sys.exit(1) when no reader accepts the file, so
    SystemExit is caught as well; other malformed input raises all kinds of exceptions.
    """
    console = io.StringIO()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(console), contextlib.redirect_stderr(console):
                raw = meshio.read(path)
        except (Exception, SystemExit) as exc:
            detail = _one_line(console.getvalue() if isinstance(exc, SystemExit) else str(exc))
            raise MeshFileError(path, f"cannot read: {detail or type(exc).__name__}") from exc
    return raw, _one_line(" ".join([console.getvalue()] + [str(w.message) for w in caught]))


def _one_line(text):
    return " ".join(text.split())


def _convert(raw, path):
    """Mesh from a meshio.Mesh read from path."""
    cells, where = _group_blocks(raw, path)
    volume = {t: cells[t] for t in VOLUME_TYPES if t in cells}
    if not volume:
        raise MeshFileError(path, "no volume cells of a supported type ("
                            + ", ".join(VOLUME_TYPES) + ")")
    points = np.asarray(raw.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshFileError(path, f"points must be 3-D, got shape {points.shape}")
    for ctype, conn in cells.items():
        if len(conn) and (conn.min() < 0 or conn.max() >= len(points)):
            raise MeshFileError(path, f"{ctype} cells name nodes beyond the {len(points)} "
                                "points of the file")

    selections = _cell_selections(raw, where, path)
    volume, cell_map = _merge_duplicates(volume)
    used = np.unique(np.concatenate([c.ravel() for c in volume.values()]))
    new_id = np.full(len(points), -1, dtype=np.int64)
    new_id[used] = np.arange(len(used))
    mesh = Mesh(points[used], {t: new_id[c] for t, c in volume.items()})

    cell_sets = {}
    for name, by_type in selections.items():
        chosen = {t: np.unique(cell_map[t][idx]) for t, idx in by_type.items() if t in volume}
        if chosen:
            cell_sets[name] = chosen
    face_sets = _face_sets(mesh, cells, selections, new_id, path)
    node_sets = _node_sets(raw, new_id, path)
    for name, faces in face_sets.items():
        node_sets.setdefault(name, face_nodes(faces))
    return Mesh(mesh.points, mesh.cells, node_sets, face_sets, cell_sets)


def _group_blocks(raw, path):
    """Concatenate the cell blocks by type.

    Returns the cells (type -> (ne, nen) file node ids) and, per meshio block, (type, offset of
    the block in the concatenation), or None for vertex and line blocks, which are ignored.
    """
    parts, where = {}, []
    for block in raw.cells:
        ctype = block.type
        if ctype in VOLUME_TYPES or ctype in FACE_TYPES:
            data = np.asarray(block.data, dtype=np.int64)
            # meshio reads a file cut short as cells with fewer nodes
            nen = ELEMENTS[ctype].nen
            if data.ndim != 2 or data.shape[1] != nen:
                raise MeshFileError(path, f"{ctype} cells of shape {data.shape}, expected "
                                    f"{nen} nodes each (a file cut short?)")
            blocks = parts.setdefault(ctype, [])
            where.append((ctype, sum(len(b) for b in blocks)))
            blocks.append(data)
        elif ctype == "vertex" or ctype.startswith("line"):
            where.append(None)
        else:
            raise MeshFileError(path, f"unsupported cell type '{ctype}' (supported volumes: "
                                + ", ".join(VOLUME_TYPES) + ")")
    return {t: np.vstack(b) for t, b in parts.items()}, where


def _cell_selections(raw, where, path):
    """Named cell selections: name -> cell type -> indices into the concatenated cells."""
    per_block = {}   # name -> [(block, indices into the block)]

    for name, arrays in raw.cell_sets.items():
        _check_name(name, "cell", path)
        # 'gmsh:bounding_entities' holds entity tags, not cell indices
        if name.startswith("gmsh:"):
            continue
        for b, idx in enumerate(arrays):
            if idx is not None:
                per_block.setdefault(name, []).append((b, _block_indices(idx, name, path)))

    physical = raw.cell_data.get("gmsh:physical")
    if physical is not None:
        # Gmsh numbers physical groups per dimension; unnamed ones are known by their number.
        names = {(int(v[0]), int(v[1])): k for k, v in raw.field_data.items() if np.size(v) == 2}
        for b, tags in enumerate(physical):
            if where[b] is None:
                continue
            dim = 3 if where[b][0] in VOLUME_TYPES else 2
            for tag in np.unique(tags):
                if tag != 0:   # Gmsh v2 writes 0 for a cell in no physical group
                    name = names.get((int(tag), dim), str(tag))
                    per_block.setdefault(name, []).append((b, np.flatnonzero(tags == tag)))

    for key, arrays in raw.cell_data.items():
        if key.startswith(SET_PREFIX):
            for b, values in enumerate(arrays):
                per_block.setdefault(key[len(SET_PREFIX):], []).append((b, np.flatnonzero(values)))

    out = {}
    for name, pieces in per_block.items():
        for b, idx in pieces:
            if where[b] is not None and len(idx):
                ctype, offset = where[b]
                out.setdefault(name, {}).setdefault(ctype, []).append(idx + offset)
    return {name: {t: np.concatenate(v) for t, v in by_type.items()}
            for name, by_type in out.items()}


def _check_name(name, kind, path):
    # meshio names a set None when the file gives it no name (Abaqus: '*ELSET, ELSET')
    if not isinstance(name, str):
        keyword = {"cell": "ELSET", "node": "NSET"}[kind]
        raise MeshFileError(path, f"a {kind} set without a name (an Abaqus {keyword} with no "
                            "=NAME)")


def _block_indices(idx, name, path):
    """Indices of a meshio cell set into one cell block, checked to be a flat integer array."""
    # meshio 5.3 nests the lists of an Abaqus *ELSET given by set names.
    try:
        idx = np.asarray(idx, dtype=np.int64)
    except (TypeError, ValueError):
        idx = None
    if idx is None or idx.ndim != 1:
        raise MeshFileError(path, f"cell set '{name}' as read by meshio is not one index array "
                            "per cell block")
    return idx


def _merge_duplicates(volume):
    """Keep the first of identical volume cells.

    Returns the cells and, per type, the map old cell index -> new cell index.
    """
    cells, cell_map = {}, {}
    for ctype, conn in volume.items():
        _, first, inverse = np.unique(conn, axis=0, return_index=True, return_inverse=True)
        order = np.argsort(first)
        rank = np.empty(len(first), dtype=np.int64)
        rank[order] = np.arange(len(first))
        cells[ctype] = conn[first[order]]
        cell_map[ctype] = rank[inverse.ravel()]
    return cells, cell_map


def _face_sets(mesh, cells, selections, new_id, path):
    """Surface cells of the selections as outward-oriented boundary faces: name -> type -> faces."""
    out = {}
    for ftype in FACE_TYPES:
        named = [(name, by_type[ftype]) for name, by_type in selections.items() if ftype in by_type]
        if not named:
            continue
        idx = np.concatenate([i for _, i in named])
        # Nodes used by no volume cell map to -1, which matches no boundary face.
        oriented, found = orient_faces(mesh, new_id[cells[ftype][idx]], ftype)
        if not found.all():
            k = int(np.flatnonzero(~found)[0])
            owner = np.repeat(np.arange(len(named)), [len(i) for _, i in named])[k]
            name = named[owner][0]
            raise MeshFileError(path, f"set '{name}': {ftype} cell with file nodes (0-based) "
                                f"{cells[ftype][idx[k]].tolist()} is not on the boundary of the "
                                "volume mesh")
        start = 0
        for name, i in named:
            out.setdefault(name, {})[ftype] = np.unique(oriented[start:start + len(i)], axis=0)
            start += len(i)
    return out


def _node_sets(raw, new_id, path):
    """meshio point sets and 'set:<name>' point data as node sets in the new numbering."""
    for name in raw.point_sets:
        _check_name(name, "node", path)
    found = {name: np.asarray(ids, dtype=np.int64) for name, ids in raw.point_sets.items()}
    for key, values in raw.point_data.items():
        if key.startswith(SET_PREFIX):
            found[key[len(SET_PREFIX):]] = np.flatnonzero(values)
    out = {}
    for name, ids in found.items():
        kept = np.unique(new_id[ids])
        kept = kept[kept >= 0]
        if len(kept):
            out[name] = kept
    return out


def write_vtu(path, mesh, point_data=None, cell_data=None):
    """Write the volume cells to a VTU file for ParaView.

    Every node set is added as a 0/1 point array 'set:<name>' and every cell set as a 0/1 cell
    array 'set:<name>', so the sets can be seen and read_mesh gets them back.

    Parameters
    ----------
    path : str or Path
        Output file, usually ending in .vtu (each cell in VTK's own node order).
    mesh : Mesh
    point_data : dict, optional
        name -> (n_nodes,) or (n_nodes, k) array, e.g. displacement [m].
    cell_data : dict, optional
        name -> cell type -> (ne,) or (ne, k) array, one entry for every cell type of the mesh.
    """
    pdata = {SET_PREFIX + name: _indicator(mesh.n_nodes, ids)
             for name, ids in mesh.node_sets.items()}
    cdata = {SET_PREFIX + name: [_indicator(len(conn), by_type.get(t, []))
                                 for t, conn in mesh.cells.items()]
             for name, by_type in mesh.cell_sets.items()}
    for name, values in (point_data or {}).items():
        values = np.asarray(values)
        if len(values) != mesh.n_nodes:
            raise ValueError(f"point data '{name}' has {len(values)} rows for {mesh.n_nodes} nodes")
        _add_new(pdata, name, values)
    for name, by_type in (cell_data or {}).items():
        blocks = [np.asarray(by_type[t]) for t in mesh.cells]
        if any(len(b) != len(conn) for b, conn in zip(blocks, mesh.cells.values())):
            raise ValueError(f"cell data '{name}' does not have one row per cell")
        _add_new(cdata, name, blocks)
    out = meshio.Mesh(mesh.points, for_meshio_vtk(mesh.cells.items()), point_data=pdata,
                      cell_data=cdata)
    meshio.write(path, out, file_format="vtu")


def for_meshio_vtk(cells):
    """[(cell type, conn)] of cells (type, conn) pairs, ready for meshio's VTU and VTK
    writers: its reordering of linear wedges undone, so that VTK reads them in its own
    order (_MESHIO_VTK_WEDGE)."""
    return [(t, np.asarray(conn)[:, _MESHIO_VTK_WEDGE] if t == "wedge" else conn)
            for t, conn in cells]


def _indicator(n, ids):
    flag = np.zeros(n, dtype=np.uint8)
    flag[np.asarray(ids, dtype=np.int64)] = 1
    return flag


def _add_new(data, name, values):
    if name in data:
        raise ValueError(f"data name '{name}' is already used by a set")
    data[name] = values


def jacobian_check(mesh):
    """Worst cell of each type by the determinant of the Jacobian dx/dxi.

    det J is evaluated at the element nodes and at the stiffness quadrature points; a cell with a
    value <= 0 is inverted or degenerate (for instance read from a file with the other orientation
    convention).

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    list of (str, int, float)
        (cell type, index into mesh.cells[type], min det J [m^3 per unit reference volume]),
        one entry per non-empty cell type.
    """
    out = []
    for ctype, conn in mesh.cells.items():
        if len(conn) == 0:
            continue
        el = ELEMENTS[ctype]
        xi = np.vstack([el.nodes, el.rule(el.stiffness_degree)[0]])
        dN = el.shape_derivatives(xi)                    # (nq, nen, 3)
        worst_det, worst_cell = np.inf, -1
        for start in range(0, len(conn), _JACOBIAN_CHUNK):
            X = mesh.points[conn[start:start + _JACOBIAN_CHUNK]]       # (ne, nen, 3)
            J = np.swapaxes(X, 1, 2)[:, None] @ dN[None]              # (ne, nq, 3, 3)
            det = np.linalg.det(J).min(axis=1)
            k = int(np.argmin(det))
            if det[k] < worst_det:
                worst_det, worst_cell = float(det[k]), start + k
        out.append((ctype, worst_cell, worst_det))
    return out
