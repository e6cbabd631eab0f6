"""Structured mesh generators: box, drilled box, annular disc and brake pad.

Each generator checks its arguments, lays out the plan of its shape (a 2-D quad mesh in parametric
coordinates: Cartesian x, y or polar r, theta), extrudes it along z and converts the hexahedra to
the requested element type with the machinery of transient.mesh.structured; the O-grid plan of
the drilled box comes from transient.mesh.drilled. Named node, face and cell sets are documented
per generator.
"""
import numpy as np

from .drilled import _drilled_plan, _ogrid_size
from .elements import VOLUME_TYPES
from .structured import _build_mesh, _extrude, _grid_plan, _identity, _polar


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
    element : 'hexahedron', 'hexahedron20', 'tetra', 'tetra10', 'wedge' or 'wedge15'.

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
    element : 'hexahedron', 'hexahedron20', 'tetra', 'tetra10', 'wedge' or 'wedge15'.
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
    element : 'hexahedron', 'hexahedron20', 'tetra', 'tetra10', 'wedge' or 'wedge15'.

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
    element : 'hexahedron', 'hexahedron20', 'tetra', 'tetra10', 'wedge' or 'wedge15'.

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
