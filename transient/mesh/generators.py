"""Structured mesh generators: box, drilled box, annular disc and brake pad.

Every generator builds a plan (a 2-D quad mesh in parametric coordinates) and extrudes it along z
into hexahedra stored as 'corners in index order': corners[e, a, b, c] is the node at index offset
(a, b, c) of hex e. The element types are derived from that in shared helpers:

* hexahedron / hexahedron20: VTK ordering, reflected through c when the index frame is left-handed;
* tetra / tetra10: 6 tetrahedra per hex (Kuhn split along the index-space diagonal), each made
  positive afterwards. Neighbouring hexes traverse every shared face in the same index directions,
  so the face diagonals of the split match and the tetrahedral mesh is conforming;
* quadratic midside nodes are unique per edge (keyed by sorted corner ids) and placed by mapping
  the parametric midpoint of the edge, taken from one cell's own corner parameters, to space.

Named face sets are taken from index faces (hex, axis, side), never from coordinate tests, so
they hold however coarse the mesh is; node sets are the nodes of the face sets.
"""
from dataclasses import dataclass
from itertools import permutations

import numpy as np

from .elements import ELEMENTS, VOLUME_TYPES
from .mesh import Mesh, face_nodes

# Flat index a*4 + b*2 + c of the corners in VTK hexahedron order, and the same reflected in c
# (which turns a left-handed index frame into a positive cell).
_HEX_VTK = np.array([0, 4, 6, 2, 1, 5, 7, 3])
_HEX_VTK_REFLECTED = np.array([1, 5, 7, 3, 0, 4, 6, 2])
# VTK hexahedron face number of the reference face (axis, side) (see elements._HEX_FACES).
_HEX_FACE = {(2, 0): 0, (2, 1): 1, (1, 0): 2, (0, 1): 3, (1, 1): 4, (0, 0): 5}

_PERMUTATIONS = tuple(permutations(range(3)))


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
    flip = np.linalg.det(jac) < 0
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


def _build_mesh(hexes, element, mapping, cell_groups):
    """Mesh of the given element type; cell_groups: name -> hex indices."""
    points = mapping(hexes.params)
    if element in ("hexahedron", "hexahedron20"):
        conn, points, faces = _hex_cells(hexes, points, element, mapping)
        per_hex = 1
    else:
        conn, points, faces = _tet_cells(hexes, points, element, mapping)
        per_hex = 6
    ftype = ELEMENTS[element].face_type
    face_sets = {name: {ftype: np.vstack(parts)} for name, parts in faces.items()}
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


def _check_element(element):
    if element not in VOLUME_TYPES:
        raise ValueError(f"element must be one of {VOLUME_TYPES}, got {element!r}")


def _check_divisions(divisions, n):
    divisions = tuple(int(d) for d in divisions)
    if len(divisions) != n or min(divisions) < 1:
        raise ValueError(f"divisions must be {n} positive integers, got {divisions}")
    return divisions


def _check_positive(**lengths):
    for name, value in lengths.items():
        if not np.all(np.asarray(value, dtype=float) > 0):
            raise ValueError(f"{name} must be positive, got {value}")


def box(size, divisions, origin=(0.0, 0.0, 0.0), element="hexahedron"):
    """Cartesian block [origin, origin + size].

    Parameters
    ----------
    size : (3,) edge lengths [m].
    divisions : (nx, ny, nz) cells per direction.
    origin : (3,) lowest corner [m].
    element : 'hexahedron', 'hexahedron20', 'tetra' or 'tetra10'.

    Returns
    -------
    Mesh with node and face sets 'xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax' and cell set 'all'.
    """
    _check_element(element)
    _check_positive(size=size)
    nx, ny, nz = _check_divisions(divisions, 3)
    x, y, z = (o + np.linspace(0.0, s, n + 1) for o, s, n in zip(origin, size, (nx, ny, nz)))
    plan = _grid_plan(x, y, ("xmin", "xmax", "ymin", "ymax"))
    hexes = _extrude(plan, z, "zmin", "zmax")
    return _build_mesh(hexes, element, _identity, {"all": np.arange(len(hexes.corners))})


def _ogrid_size(ogrid_cells, spacing, hole_radius):
    """Half-width k of the O-grid square in background cells (default: k h >= 1.5 radius)."""
    if ogrid_cells is not None:
        k = int(ogrid_cells)
        if k < 1:
            raise ValueError(f"ogrid_cells must be a positive integer, got {ogrid_cells}")
        return k
    # The relative slack keeps an exact multiple (e.g. 1.5 r = 3 h) from rounding up.
    return max(1, int(np.ceil(1.5 * hole_radius / min(spacing) * (1 - 1e-12))))


def _ogrid_square(x, y, hole_center, hole_radius, k):
    """Grid indices (i0, j0) of the square's centre node; ValueError if square or hole misfit."""
    i0 = int(np.argmin(np.abs(x - hole_center[0])))
    j0 = int(np.argmin(np.abs(y - hole_center[1])))
    nx, ny = len(x) - 1, len(y) - 1
    if not (k <= i0 <= nx - k and k <= j0 <= ny - k):
        raise ValueError(
            f"the O-grid square of {2 * k} x {2 * k} cells around grid node ({i0}, {j0}) does "
            f"not fit in the {nx} x {ny} background grid: refine the grid, move the hole or "
            f"lower ogrid_cells")
    clearance = min(hole_center[0] - x[i0 - k], x[i0 + k] - hole_center[0],
                    hole_center[1] - y[j0 - k], y[j0 + k] - hole_center[1])
    if not hole_radius < clearance:
        raise ValueError(
            f"the hole (radius {hole_radius}) does not fit in the O-grid square (clearance "
            f"{clearance} from the hole centre): raise ogrid_cells or coarsen the grid")
    return i0, j0


def _square_boundary(i0, j0, k):
    """Grid indices (8k, 2) of the square's boundary nodes, counterclockwise from its low corner."""
    t = np.arange(2 * k)
    i = np.concatenate([i0 - k + t, np.full(2 * k, i0 + k), i0 + k - t, np.full(2 * k, i0 - k)])
    j = np.concatenate([np.full(2 * k, j0 - k), j0 - k + t, np.full(2 * k, j0 + k), j0 + k - t])
    return np.column_stack([i, j])


def _ring_quads(ring):
    """Quads (8k n, 2, 2) of an O-grid ring; ring[m, s] is node s of ray m, s = 0..n outwards.

    Quads are ordered ray by ray (quad m n + s between rays m, m + 1 and layers s, s + 1).
    """
    nm, n = ring.shape[0], ring.shape[1] - 1
    # Tangential index direction +x or +y on every side, as in the background grid, so that
    # shared faces are split alike: counterclockwise on the bottom and right sides (m < 4k),
    # clockwise on the top and left sides.
    m = np.arange(nm)
    m_next = (m + 1) % nm
    ccw = m < nm // 2
    tangential = np.stack([np.where(ccw, m, m_next), np.where(ccw, m_next, m)], axis=1)
    radial = np.arange(n)[:, None] + np.arange(2)
    return ring[tangential[:, None, :, None], radial[None, :, None, :]].reshape(-1, 2, 2)


def _ray_layers(inner, outer, n):
    """Points (n, 8k, 2) at fractions 0, 1/n, ..., (n - 1)/n of the way from inner to outer."""
    s = np.arange(n)[:, None, None] / n
    return inner + s * (outer - inner)


def _plug(square_xy, center, radius, circle, circle_ids, first_id):
    """Nodes and quads filling the hole polygon: a core grid and an inner O-grid ring.

    The core is the O-grid square (grid square_xy, (2k + 1, 2k + 1, 2) [m]) scaled about the hole
    centre until its farthest node lies at radius / sqrt(2), the corner of a centred square of
    half-width radius / 2. Every core boundary node thus lies on the ray from the hole centre
    through its circle node, so the k layers of the inner ring, like the outer ring, are convex
    quads between rays, whatever the hole's offset from the square's centre node.

    center : (2,) hole centre [m]; radius : hole radius [m]; circle : (8k, 2) hole polygon [m];
    circle_ids : (8k,) its node ids; first_id : id of the first new node.
    Returns the new nodes' parameters (n, 2) [m] and the quads (nq, 2, 2).
    """
    k = (len(square_xy) - 1) // 2
    offset = square_xy - center
    scale = radius / np.sqrt(2) / np.linalg.norm(offset, axis=-1).max()
    core_xy = center + scale * offset
    core = first_id + np.arange(core_xy[..., 0].size).reshape(core_xy.shape[:2])
    boundary = _square_boundary(k, k, k)
    inner = core[boundary[:, 0], boundary[:, 1]]
    layers = _ray_layers(core_xy[boundary[:, 0], boundary[:, 1]], circle, k)[1:]
    nm = 8 * k
    ring = np.empty((nm, k + 1), dtype=np.int64)
    ring[:, 0] = inner
    ring[:, 1:k] = core.max() + 1 + np.arange(k - 1) * nm + np.arange(nm)[:, None]
    ring[:, k] = circle_ids
    params = np.vstack([core_xy.reshape(-1, 2), layers.reshape(-1, 2)])
    return params, np.vstack([_grid_quads(core), _ring_quads(ring)])


def _drilled_plan(x, y, hole_center, hole_radius, k, filled):
    """Cartesian plan with an O-grid of 8k x k quads around a polygonal hole.

    Returns the plan and the indices of the quads filling the hole (none unless filled).
    """
    nx, ny = len(x) - 1, len(y) - 1
    i0, j0 = _ogrid_square(x, y, hole_center, hole_radius, k)
    gi, gj = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), indexing="ij")
    inside = (np.abs(gi - i0) < k) & (np.abs(gj - j0) < k)
    ids = np.cumsum(~inside).reshape(inside.shape) - 1
    grid_xy = np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1)
    qi, qj = gi[:-1, :-1].ravel(), gj[:-1, :-1].ravel()
    keep = ~((np.abs(qi - i0 + 0.5) < k) & (np.abs(qj - j0 + 0.5) < k))
    background, qi, qj = _grid_quads(ids)[keep], qi[keep], qj[keep]

    # Ring nodes: layer s of ray m lies at s/k of the way from the circle to the square node.
    bij = _square_boundary(i0, j0, k)
    square = grid_xy[bij[:, 0], bij[:, 1]]
    center = np.asarray(hole_center, dtype=float)
    offset = square - center
    circle = center + hole_radius * offset / np.linalg.norm(offset, axis=1)[:, None]
    layers = _ray_layers(circle, square, k).reshape(-1, 2)
    n_background = int(ids.max()) + 1
    nm = 8 * k
    ring = np.empty((nm, k + 1), dtype=np.int64)
    ring[:, :k] = n_background + np.arange(k) * nm + np.arange(nm)[:, None]
    ring[:, k] = ids[bij[:, 0], bij[:, 1]]
    ogrid = _ring_quads(ring)

    params = np.vstack([grid_xy.reshape(-1, 2)[~inside.ravel()], layers])
    quads = np.vstack([background, ogrid])
    plug = np.arange(0)
    if filled:
        square_xy = grid_xy[i0 - k:i0 + k + 1, j0 - k:j0 + k + 1]
        plug_params, plug_quads = _plug(square_xy, center, hole_radius, circle, ring[:, 0],
                                         len(params))
        plug = len(quads) + np.arange(len(plug_quads))
        params = np.vstack([params, plug_params])
        quads = np.vstack([quads, plug_quads])
    sides = {}
    for name, cells, axis, side in (("xmin", qi == 0, 0, 0), ("xmax", qi == nx - 1, 0, 1),
                                    ("ymin", qj == 0, 1, 0), ("ymax", qj == ny - 1, 1, 1)):
        sides[name] = [(np.flatnonzero(cells), axis, side)]
    ogrid_index = len(background) + np.arange(nm * k).reshape(nm, k)
    if not filled:
        sides["hole"] = [(ogrid_index[:, 0], 1, 0)]
    # A square side on the box boundary: its outer ring quads carry that boundary.
    outer = ogrid_index[:, k - 1].reshape(4, 2 * k)
    for sector, name, touches in ((0, "ymin", j0 == k), (1, "xmax", i0 == nx - k),
                                  (2, "ymax", j0 == ny - k), (3, "xmin", i0 == k)):
        if touches:
            sides[name].append((outer[sector], 1, 1))
    return _Plan(params, quads, params[quads], sides), plug


def drilled_box(size, divisions, hole_center, hole_radius, origin=(0.0, 0.0, 0.0),
                element="hexahedron", ogrid_cells=None, filled=False):
    """Block with a cylindrical hole along z through its full height, or that block's plan filled.

    The plan is a Cartesian background of nx x ny cells in which a square of 2k x 2k cells,
    centred on the background grid node nearest the hole centre, is replaced by an O-grid:
    each of the 8k boundary nodes of the square is joined to the point of the circle at the same
    polar angle about the hole centre, with k radial layers in between. The hole is the polygon
    of those circle points; all edges are straight (quadratic midside nodes at edge midpoints).

    Filled, the hole polygon is meshed too, by a core of 2k x 2k cells (the O-grid square scaled
    down about the hole centre to a half-width of about radius / 2) joined to the polygon by an
    inner O-grid ring of k layers. Outside the hole the nodes and faces are those of the drilled
    block, so a filled block on a drilled one of the same plan meets it conformingly.

    Parameters
    ----------
    size : (3,) edge lengths [m].
    divisions : (nx, ny, nz) background cells per direction.
    hole_center : (x, y) hole axis [m].
    hole_radius : hole radius [m].
    origin : (3,) lowest corner [m].
    element : 'hexahedron', 'hexahedron20', 'tetra' or 'tetra10'.
    ogrid_cells : k, half-width of the O-grid square in background cells; by default the
        smallest k with k * min(dx, dy) >= 1.5 * hole_radius.
    filled : mesh the hole too: a plain block with the drilled block's plan.

    Returns
    -------
    Mesh with node and face sets 'xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax' and cell set
    'all'; drilled, also the face set 'hole'; filled, also the cell set 'plug' (the cells in the
    hole polygon).

    Raises
    ------
    ValueError if the O-grid square does not fit in the box or the hole not in the square.
    """
    _check_element(element)
    _check_positive(size=size, hole_radius=hole_radius)
    nx, ny, nz = _check_divisions(divisions, 3)
    x, y, z = (o + np.linspace(0.0, s, n + 1) for o, s, n in zip(origin, size, (nx, ny, nz)))
    k = _ogrid_size(ogrid_cells, (size[0] / nx, size[1] / ny), hole_radius)
    plan, plug = _drilled_plan(x, y, hole_center, hole_radius, k, filled)
    hexes = _extrude(plan, z, "zmin", "zmax")
    groups = {"all": np.arange(len(hexes.corners))}
    if filled:
        groups["plug"] = (np.arange(nz)[:, None] * len(plan.quads) + plug).ravel()
    return _build_mesh(hexes, element, _identity, groups)


def annular_disc(inner_radius, outer_radius, thickness, divisions, center=(0.0, 0.0, 0.0),
                 element="hexahedron"):
    """Annulus about the z axis through center, from z = center[2] to center[2] + thickness.

    Periodic in theta (no seam duplicates). Quadratic midside nodes lie on the true geometry:
    arc edges are curved.

    Parameters
    ----------
    inner_radius, outer_radius : radii [m].
    thickness : axial thickness [m].
    divisions : (nr, ntheta, nz) cells per direction, ntheta >= 3.
    center : (3,) centre of the bottom face [m].
    element : 'hexahedron', 'hexahedron20', 'tetra' or 'tetra10'.

    Returns
    -------
    Mesh with node and face sets 'hub' (r = inner_radius), 'outer', 'zmin', 'zmax' and cell set
    'all'.
    """
    _check_element(element)
    _check_positive(inner_radius=inner_radius, thickness=thickness,
                    radial_width=outer_radius - inner_radius)
    nr, nt, nz = _check_divisions(divisions, 3)
    if nt < 3:
        raise ValueError(f"ntheta must be at least 3, got {nt}")
    r = np.linspace(inner_radius, outer_radius, nr + 1)
    theta = np.linspace(0.0, 2 * np.pi, nt + 1)
    z = center[2] + np.linspace(0.0, thickness, nz + 1)
    plan = _grid_plan(r, theta, ("hub", "outer", None, None), periodic=True)
    hexes = _extrude(plan, z, "zmin", "zmax")
    return _build_mesh(hexes, element, _polar(center[:2]), {"all": np.arange(len(hexes.corners))})


def brake_pad(inner_radius, outer_radius, angle, lining_thickness, backplate_thickness,
              divisions, z0=0.0, center=(0.0, 0.0), center_angle=90.0, element="hexahedron"):
    """Annular-sector brake pad: friction lining with a steel backplate on top, one mesh.

    Parameters
    ----------
    inner_radius, outer_radius : radii of the sector about the axis through center [m].
    angle : opening angle of the sector [deg], in (0, 360).
    lining_thickness : lining thickness, from z0 [m].
    backplate_thickness : backplate thickness, above the lining [m].
    divisions : (nr, ntheta, nz_lining, nz_backplate) cells per direction.
    z0 : height of the friction surface [m].
    center : (x, y) axis of the sector [m].
    center_angle : polar angle of the sector's middle about center [deg].
    element : 'hexahedron', 'hexahedron20', 'tetra' or 'tetra10'.

    Returns
    -------
    Mesh with cell sets 'lining', 'backplate', 'all' and node and face sets 'friction'
    (z = z0, outward normal -z), 'back' (top of the backplate), 'inner', 'outer' and 'ends'
    (the two radial faces).
    """
    _check_element(element)
    _check_positive(inner_radius=inner_radius, radial_width=outer_radius - inner_radius,
                    lining_thickness=lining_thickness, backplate_thickness=backplate_thickness)
    if not 0 < angle < 360:
        raise ValueError(f"angle must lie in (0, 360) degrees, got {angle}")
    nr, nt, nzl, nzb = _check_divisions(divisions, 4)
    r = np.linspace(inner_radius, outer_radius, nr + 1)
    half = 0.5 * np.radians(angle)
    theta = np.radians(center_angle) + np.linspace(-half, half, nt + 1)
    z_top = z0 + lining_thickness
    z = np.concatenate([np.linspace(z0, z_top, nzl + 1),
                        np.linspace(z_top, z_top + backplate_thickness, nzb + 1)[1:]])
    plan = _grid_plan(r, theta, ("inner", "outer", "ends", "ends"))
    hexes = _extrude(plan, z, "friction", "back")
    n_lining = nzl * len(plan.quads)
    groups = {"lining": np.arange(n_lining),
              "backplate": np.arange(n_lining, len(hexes.corners)),
              "all": np.arange(len(hexes.corners))}
    return _build_mesh(hexes, element, _polar(center), groups)
