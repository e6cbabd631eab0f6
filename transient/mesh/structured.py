"""Shared machinery of the structured generators: plans, extrusion and element conversion.

Every generator builds a plan (a 2-D quad mesh in parametric coordinates) and extrudes it along z
into hexahedra stored as 'corners in index order': corners[e, a, b, c] is the node at index offset
(a, b, c) of hex e. The element types are derived from that here:

* hexahedron / hexahedron20: VTK ordering, reflected through c when the index frame is left-handed;
* tetra / tetra10: 6 tetrahedra per hex (Kuhn split along the index-space diagonal), each made
  positive afterwards. Neighbouring hexes traverse every shared face in the same index directions,
  so the face diagonals of the split match and the tetrahedral mesh is conforming;
* wedge / wedge15: 2 prisms per hex, its plan quad split along the diagonal (0, 0)-(1, 1) and
  swept along z, reflected through c where the index frame is left-handed. The diagonals lie
  inside the quads and the prisms' triangles are those of the layer above and below, so the
  prism mesh is conforming; its faces on z levels are triangles, the others quadrilaterals;
* quadratic midside nodes are unique per edge (keyed by sorted corner ids) and placed by mapping
  the parametric midpoint of the edge, taken from one cell's own corner parameters, to space.

Named face sets are taken from index faces (hex, axis, side), never from coordinate tests, so
they hold however coarse the mesh is; node sets are the nodes of the face sets. The parametric
maps (identity, polar) that take plan parameters to space live here too.
"""
from dataclasses import dataclass
from itertools import permutations

import numpy as np

from .elements import ELEMENTS, FACE_TYPE_OF
from .mesh import Mesh, face_nodes

# Flat index a*4 + b*2 + c of the corners in VTK hexahedron order, and the same reflected in c
# (which turns a left-handed index frame into a positive cell).
_HEX_VTK = np.array([0, 4, 6, 2, 1, 5, 7, 3])
_HEX_VTK_REFLECTED = np.array([1, 5, 7, 3, 0, 4, 6, 2])
# VTK hexahedron face number of the reference face (axis, side) (see elements._HEX_FACES).
_HEX_FACE = {(2, 0): 0, (2, 1): 1, (1, 0): 2, (0, 1): 3, (1, 1): 4, (0, 0): 5}

_PERMUTATIONS = tuple(permutations(range(3)))

# Flat corner indices of the two prisms of a hex: bottom triangle (c = 0) then top, the plan
# quad's triangles (0, 0), (1, 0), (1, 1) and (0, 0), (1, 1), (0, 1), both counterclockwise in
# index space; and the same reflected through c.
_PRISMS = np.array([[0, 4, 6, 1, 5, 7], [0, 6, 2, 1, 7, 3]])
_PRISMS_REFLECTED = _PRISMS[:, [3, 4, 5, 0, 1, 2]]
# (prism of the hex, its face in elements._WEDGE_FACES) of the hex's lateral face (axis, side);
# the faces on z levels are faces 0 (c = 0) and 1 (c = 1) of both prisms.
_PRISM_FACE = {(0, 0): (1, 4), (0, 1): (0, 3), (1, 0): (0, 2), (1, 1): (1, 3)}


def _kuhn_tets():
    """Flat corner indices (6, 4) of the Kuhn tetrahedra: monotone paths from corner 0 to 7."""
    tets = []
    for perm in _PERMUTATIONS:
        offset = np.zeros(3, int)
        path = [0]
        for axis in perm:
            offset[axis] = 1
            path.append(offset[0] * 4 + offset[1] * 2 + offset[2])
        tets.append(path)
    return np.array(tets)


_KUHN = _kuhn_tets()


@dataclass(frozen=True)
class _Plan:
    """Quad mesh of the xy plan in parametric coordinates (x, y or r, theta).

    params : (n, 2) canonical parameters of the plan nodes.
    quads : (nq, 2, 2) node ids, corners in index order [a, b].
    quad_params : (nq, 2, 2, 2) corner parameters per quad, unwrapped across a periodic seam.
    sides : name -> list of (quad indices, axis, side) lateral boundary pieces.
    """
    params: np.ndarray
    quads: np.ndarray
    quad_params: np.ndarray
    sides: dict


@dataclass(frozen=True)
class _Hexes:
    """Hexahedra in index order, before conversion to an element type.

    params : (n, 3) parameters of the corner nodes.
    corners : (ne, 2, 2, 2) node ids, corners[e, a, b, c] at index offset (a, b, c).
    corner_params : (ne, 2, 2, 2, 3) corner parameters per hex (unwrapped across a seam).
    faces : name -> list of (hex indices, axis, side) boundary pieces.
    """
    params: np.ndarray
    corners: np.ndarray
    corner_params: np.ndarray
    faces: dict


def _grid_quads(grid):
    """Quads of a structured grid (n1 + 1, n2 + 1, ...) as (n1 * n2, 2, 2, ...), [a, b] corners."""
    quads = np.stack([np.stack([grid[:-1, :-1], grid[:-1, 1:]], axis=2),
                      np.stack([grid[1:, :-1], grid[1:, 1:]], axis=2)], axis=2)
    return quads.reshape((-1, 2, 2) + grid.shape[2:])


def _grid_sides(n1, n2, names):
    """Boundary pieces of an n1 x n2 quad grid.

    names : set names of the (axis 0 low, axis 0 high, axis 1 low, axis 1 high) sides; None for a
        side that is no boundary (a periodic seam).
    """
    q = np.arange(n1 * n2).reshape(n1, n2)
    pieces = ((q[0, :], 0, 0), (q[-1, :], 0, 1), (q[:, 0], 1, 0), (q[:, -1], 1, 1))
    sides = {}
    for name, piece in zip(names, pieces):
        if name is not None:
            sides.setdefault(name, []).append(piece)
    return sides


def _grid_plan(u, v, names, periodic=False):
    """Structured plan on the tensor grid u x v; periodic joins the last v line to the first."""
    params = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1)
    nodes = params[:, :-1] if periodic else params
    node_params = nodes.reshape(-1, 2)
    ids = np.arange(len(node_params)).reshape(nodes.shape[:2])
    if periodic:
        # v[-1] is the seam image of v[0]: quads of the last column keep it as their own
        # (unwrapped) parameter but use the node ids of the first column.
        ids = np.hstack([ids, ids[:, :1]])
    return _Plan(node_params, _grid_quads(ids), _grid_quads(params),
                 _grid_sides(len(u) - 1, len(v) - 1, names))


def _extrude(plan, z, bottom, top):
    """Hexes of the plan extruded through the z levels (nz + 1,), ordered layer by layer."""
    nq, npl, nz = len(plan.quads), len(plan.params), len(z) - 1
    params = np.column_stack([np.tile(plan.params, (nz + 1, 1)), np.repeat(z, npl)])
    level = np.arange(nz)[:, None, None, None, None] + np.arange(2)   # (nz, 1, 1, 1, 2)
    corners = plan.quads[None, :, :, :, None] + level * npl
    cp = np.empty((nz, nq, 2, 2, 2, 3))
    cp[..., :2] = plan.quad_params[None, :, :, :, None, :]
    cp[..., 2] = z[level]
    layers = np.arange(nz)[:, None] * nq
    faces = {name: [((layers + quads).ravel(), axis, side) for quads, axis, side in pieces]
             for name, pieces in plan.sides.items()}
    faces[bottom] = [(np.arange(nq), 2, 0)]
    faces[top] = [((nz - 1) * nq + np.arange(nq), 2, 1)]
    return _Hexes(params, corners.reshape(-1, 2, 2, 2), cp.reshape(-1, 2, 2, 2, 3), faces)


def _add_midsides(conn, params, edges, points, mapping):
    """Append one node per distinct edge, at the mapped parametric midpoint of the edge.

    conn : (ne, nc) corner ids; params : (ne, nc, 3) their parameters in each cell;
    edges : local corner pairs; points : (n, 3) corner coordinates [m].
    Returns the connectivity (ne, nc + len(edges)) and the extended points.
    """
    a, b = np.array(edges).T
    lo = np.minimum(conn[:, a], conn[:, b])
    hi = np.maximum(conn[:, a], conn[:, b])
    _, first, inverse = np.unique((lo * len(points) + hi).ravel(),
                                  return_index=True, return_inverse=True)
    mid = (0.5 * (params[:, a] + params[:, b])).reshape(-1, 3)[first]
    mids = len(points) + inverse.reshape(lo.shape)
    return np.hstack([conn, mids]), np.vstack([points, mapping(mid)])


def _hex_cells(hexes, points, element, mapping):
    """Hexahedra in VTK order; faces (name -> list of faces) of the named boundary pieces."""
    ids = hexes.corners.reshape(-1, 8)
    par = hexes.corner_params.reshape(-1, 8, 3)
    x = points[hexes.corners]
    # The Jacobian at the cell centre: mean corner difference along each index axis.
    jac = np.stack([np.diff(x, axis=1 + d).mean(axis=(1, 2, 3)) for d in range(3)], axis=2)
    # the sign alone, which slogdet gives where det overflows (cells 1e150 m wide)
    flip = np.linalg.slogdet(jac)[0] < 0
    local = np.where(flip[:, None], _HEX_VTK_REFLECTED, _HEX_VTK)
    conn = np.take_along_axis(ids, local, axis=1)
    if element == "hexahedron20":
        params = np.take_along_axis(par, local[:, :, None], axis=1)
        conn, points = _add_midsides(conn, params, ELEMENTS[element].edges, points, mapping)
    local_faces = np.array(ELEMENTS[element].faces)
    faces = {}
    for name, pieces in hexes.faces.items():
        for cells, axis, side in pieces:
            # Reflection through c swaps the two faces normal to axis 2.
            ref_side = np.where(flip[cells] & (axis == 2), 1 - side, side)
            number = np.array([_HEX_FACE[axis, 0], _HEX_FACE[axis, 1]])[ref_side]
            faces.setdefault(name, []).append(
                np.take_along_axis(conn[cells], local_faces[number], axis=1))
    return conn, points, faces


def _tet_cells(hexes, points, element, mapping):
    """Kuhn tetrahedra (6 per hex, hex e -> tets 6e..6e+5); faces of the named boundary pieces."""
    conn = hexes.corners.reshape(-1, 8)[:, _KUHN].reshape(-1, 4)
    x = points[conn]
    negative = np.linalg.det(x[:, 1:] - x[:, :1]) < 0
    # Swapping vertices 1 and 2 keeps vertices 0 and 3, so the boundary faces below stay valid.
    conn[negative, 1:3] = conn[negative, 2:0:-1]
    if element == "tetra10":
        par = hexes.corner_params.reshape(-1, 8, 3)[:, _KUHN].reshape(-1, 4, 3)
        par[negative, 1:3] = par[negative, 2:0:-1]
        conn, points = _add_midsides(conn, par, ELEMENTS[element].edges, points, mapping)
    local_faces = ELEMENTS[element].faces
    faces = {}
    for name, pieces in hexes.faces.items():
        for cells, axis, side in pieces:
            # On the low side of an axis lie the tets whose path steps along it last (vertices
            # 0-2 on it: local face 0); on the high side those stepping along it first (vertices
            # 1-3: local face 2).
            pos, face = (2, 0) if side == 0 else (0, 2)
            which = [p for p, perm in enumerate(_PERMUTATIONS) if perm[pos] == axis]
            tets = (6 * cells[:, None] + np.array(which)).ravel()
            faces.setdefault(name, []).append(conn[tets][:, list(local_faces[face])])
    return conn, points, faces


def _wedge_cells(hexes, points, element, mapping):
    """Prisms (2 per hex, hex e -> prisms 2e, 2e + 1); faces of the named boundary pieces."""
    local = np.broadcast_to(_PRISMS, (len(hexes.corners), 2, 6)).reshape(-1, 6)
    ids = hexes.corners.reshape(-1, 8)[np.repeat(np.arange(len(hexes.corners)), 2)]
    x = points[np.take_along_axis(ids, local, axis=1)]
    centre = ELEMENTS["wedge"].shape_derivatives(np.array([[1 / 3, 1 / 3, 0.0]]))[0]
    # the sign alone, which slogdet gives where det overflows
    flip = np.linalg.slogdet(np.einsum("eak,ad->ekd", x, centre))[0] < 0
    local = np.where(flip[:, None], np.tile(_PRISMS_REFLECTED, (len(hexes.corners), 1)), local)
    conn = np.take_along_axis(ids, local, axis=1)
    if element == "wedge15":
        par = hexes.corner_params.reshape(-1, 8, 3)[np.repeat(np.arange(len(hexes.corners)), 2)]
        params = np.take_along_axis(par, local[:, :, None], axis=1)
        conn, points = _add_midsides(conn, params, ELEMENTS[element].edges, points, mapping)
    local_faces = ELEMENTS[element].faces
    faces = {}
    for name, pieces in hexes.faces.items():
        for cells, axis, side in pieces:
            if axis == 2:
                prisms = (2 * cells[:, None] + np.arange(2)).ravel()
                # reflection through c swaps the bottom and top triangles
                number = np.where(flip[prisms], 1 - side, side)
                for k in (0, 1):
                    mine = prisms[number == k]
                    faces.setdefault(name, []).append(conn[mine][:, list(local_faces[k])])
            else:
                which, k = _PRISM_FACE[axis, side]
                faces.setdefault(name, []).append(
                    conn[2 * cells + which][:, list(local_faces[k])])
    return conn, points, faces


def _build_mesh(hexes, element, mapping, cell_groups):
    """Mesh of the given element type; cell_groups: name -> hex indices."""
    points = mapping(hexes.params)
    if element in ("hexahedron", "hexahedron20"):
        conn, points, faces = _hex_cells(hexes, points, element, mapping)
        per_hex = 1
    elif element in ("wedge", "wedge15"):
        conn, points, faces = _wedge_cells(hexes, points, element, mapping)
        per_hex = 2
    else:
        conn, points, faces = _tet_cells(hexes, points, element, mapping)
        per_hex = 6
    face_sets = {}
    for name, parts in faces.items():
        by_type = face_sets.setdefault(name, {})
        for part in parts:
            by_type.setdefault(FACE_TYPE_OF[part.shape[1]], []).append(part)
    face_sets = {name: {t: np.vstack(p) for t, p in by_type.items() if sum(map(len, p))}
                 for name, by_type in face_sets.items()}
    node_sets = {name: face_nodes(fs) for name, fs in face_sets.items()}
    cell_sets = {name: {element: (per_hex * cells[:, None] + np.arange(per_hex)).ravel()}
                 for name, cells in cell_groups.items()}
    return Mesh(points, {element: conn}, node_sets, face_sets, cell_sets)


def _identity(params):
    return params


def _polar(center):
    """Map (r [m], theta [rad], z [m]) to Cartesian coordinates about the axis through center."""
    cx, cy = center

    def mapping(params):
        r, t, z = params.T
        return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t), z])
    return mapping
