"""Plan of a drilled block: a Cartesian background with an O-grid around a polygonal hole.

A square of 2k x 2k background cells around the hole is replaced by an O-grid ring of 8k x k
quads between the square's boundary nodes and the hole polygon; filled, the hole polygon is
meshed too, by a scaled-down core grid and an inner O-grid ring. The result is a plan in the
sense of transient.mesh.structured, extruded and converted to elements by drilled_box in
transient.mesh.generators.
"""
import numpy as np

from .structured import _Plan, _grid_quads


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
