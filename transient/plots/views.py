"""Geometry of the compatibility pictures: where Gamma lies and how a camera frames it.

Numbers only, nothing is drawn here (apart from setting a plotter's camera in `_frame`): the
view of Gamma (centre, principal in-plane axes, length) from the fine points, the linear
triangles and outline loops of a side's faces, the Delaunay triangles of a rule's points kept
where Gamma is, the camera direction and screen axes, the pixel size of a panel, the camera
framing, and the lifted and warped layers of a shape panel with the anchors of their names.
"""
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, cKDTree

from ..mesh.elements import ELEMENTS
from ..contact.interface import FACE_TYPES

WARP = 0.10          # largest warp of a panel as a fraction of Gamma's length
BOTTOM, TOP = 0.17, 0.07  # parts of a panel's height taken by the colour bar and the title
AZIMUTH = 30.0       # camera turn about n for a roundish Gamma [deg]
PANEL = (760, 720)   # pixels of one 3D panel

# Faces split into linear triangles through their midside nodes (VTK node order), so quadratic
# faces show the values at all their nodes; and their boundary loops for the outlines.
SUBTRIANGLES = {
    "quad": ((0, 1, 2), (0, 2, 3)),
    "quad8": ((0, 4, 7), (1, 5, 4), (2, 6, 5), (3, 7, 6), (4, 5, 6), (4, 6, 7)),
    "triangle": ((0, 1, 2),),
    "triangle6": ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)),
}
OUTLINE = {"quad": (0, 1, 2, 3), "quad8": (0, 4, 1, 5, 2, 6, 3, 7), "triangle": (0, 1, 2),
           "triangle6": (0, 3, 1, 4, 2, 5)}


@dataclass(frozen=True)
class View:
    """Where Gamma lies: its centre, in-plane axes and size, for cameras and scales."""
    centre: np.ndarray       # (3,) centre of Gamma [m]
    normal: np.ndarray       # (3,) contact normal n (surface 2 towards surface 1)
    major: np.ndarray        # (3,) in-plane direction of Gamma's largest extent
    minor: np.ndarray        # (3,) in-plane direction normal to it
    length: float            # extent of Gamma along `major` [m]
    turn: float              # camera turn from the minor axis towards the major one [deg]
    outline: np.ndarray      # (M, 3) fine points on their convex hull, for framing


def gamma_view(interface):
    """Centre, principal in-plane axes and length of Gamma from the fine points."""
    rule = interface.fine
    t, n = interface.plane[:2], interface.plane[2]
    centre = np.average(rule.points, axis=0, weights=rule.weights)
    q = (rule.points - centre) @ t.T
    cov = (q * rule.weights[:, None]).T @ q
    val, vec = np.linalg.eigh(cov)
    elongated = val[1] > 1.5 * val[0]
    # a near-round Gamma has no major axis worth the name: take t1, the same in every run;
    # an elongated one is seen square on its long side (turned, its ends would be seen
    # edge-on), a round one turned so that it does not look flat
    major = vec[:, 1] @ t if elongated else t[0]
    # a fixed sign so that the picture does not flip between runs or meshes
    major = major if major @ (t[0] + 1e-3 * t[1]) >= 0 else -major
    minor = np.cross(n, major)
    extent = (rule.points - centre) @ major
    hull = ConvexHull(q).vertices
    return View(centre, n, major, minor, float(np.ptp(extent)) or 1.0,
                0.0 if elongated else AZIMUTH, rule.points[hull])


def side_triangles(side):
    """Linear triangles (T, 3) over the faces of a side, in the side's local node numbers."""
    tris = []
    for face_type, conn in zip(side.face_types, side.faces):
        local = np.searchsorted(side.nodes, conn)
        tris += [local[list(t)] for t in SUBTRIANGLES[FACE_TYPES[face_type]]]
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def side_outlines(side):
    """Closed boundary loops of the faces of a side, local node numbers."""
    return [np.searchsorted(side.nodes, np.asarray(conn)[list(OUTLINE[FACE_TYPES[t]])])
            for t, conn in zip(side.face_types, side.faces)]


def _corner_polygons(side, frame, origin):
    """Projected corner polygons (F, 4, 2) of a side's faces (triangles repeat a corner)."""
    poly = np.zeros((len(side.faces), 4, 2))
    for f, (t, conn) in enumerate(zip(side.face_types, side.faces)):
        nc = ELEMENTS[FACE_TYPES[t]].n_corners
        c = (side.points[conn[:nc]] - origin) @ frame[:2].T
        poly[f] = np.vstack([c, np.repeat(c[-1:], 4 - nc, axis=0)])
    return poly


def inside_faces(side, frame, origin, q, tol=1e-9):
    """Whether plane points q (M, 2) lie in the projection of some face of the side."""
    poly = _corner_polygons(side, frame, origin)
    centres = poly.mean(axis=1)
    radius = np.linalg.norm(poly - centres[:, None], axis=2).max()
    inside = np.zeros(len(q), bool)
    for m, faces in enumerate(cKDTree(centres).query_ball_point(q, radius * (1 + 1e-9))):
        if not faces:
            continue
        c = poly[faces]
        e = np.roll(c, -1, axis=1) - c
        d = q[m] - c
        cross = e[:, :, 0] * d[:, :, 1] - e[:, :, 1] * d[:, :, 0]
        # faces may turn either way about n: inside means no edge sees the point on its
        # other side; the repeated corner of a triangle gives a zero edge, which passes
        scale = tol * radius ** 2
        inside[m] = np.any((cross >= -scale).all(axis=1) | (cross <= scale).all(axis=1))
    return inside


def gamma_triangles(interface, rule):
    """Delaunay triangles (T, 3) of a rule's points in the plane, kept where Gamma is.

    The Delaunay triangulation fills the convex hull: triangles whose centroid falls outside
    either surface (a hole, the concave side of a pad) are dropped.
    """
    q = (rule.points - interface.origin) @ interface.plane[:2].T
    tri = Delaunay(q).simplices
    g = q[tri].mean(axis=1)
    keep = (inside_faces(interface.side1, interface.plane, interface.origin, g)
            & inside_faces(interface.side2, interface.plane, interface.origin, g))
    return tri[keep]


def view_direction(view, elevation):
    """Unit vector from Gamma towards the camera: above the plane by `elevation` degrees,
    facing Gamma's long side, turned by view.turn."""
    a, e = np.radians(view.turn), np.radians(elevation)
    horizontal = np.cos(a) * (-view.minor) + np.sin(a) * view.major
    return np.cos(e) * horizontal + np.sin(e) * view.normal


def screen_axes(direction, normal):
    """Right and up unit vectors of the screen for a camera along `direction`, n up."""
    up = normal - (normal @ direction) * direction
    up /= np.linalg.norm(up)
    return np.cross(-direction, up), up


def panel_size(points, direction, normal, label_px=0, area=PANEL[0] * PANEL[1]):
    """Pixels (w, h) of a panel of about `area` pixels whose scene (points, and a column of
    `label_px` pixels for names on its left) fills it between the colour bar and the title."""
    right, up = screen_axes(direction, normal)
    aspect = np.ptp(points @ right) / (np.ptp(points @ up) / (1 - BOTTOM - TOP))
    height = np.sqrt(area / aspect)
    # not narrower than PANEL: the title has to fit
    width = max(np.clip(height * aspect + label_px, 0.6 * height, 2.6 * height), PANEL[0])
    return int(width), int(height)


def _frame(plotter, points, direction, normal, panel, label_px=0, pad=1.06):
    """Parallel projection that fits the points between the colour bar and the title, with
    `label_px` pixels free on their left."""
    right, up = screen_axes(direction, normal)
    x, y = points @ right, points @ up
    width_px, height_px = panel
    # world height of the panel, from the vertical fit or the horizontal one (labels included)
    height = pad * max(np.ptp(y) / (1 - BOTTOM - TOP),
                       np.ptp(x) * height_px / (width_px - pad * label_px))
    cx = 0.5 * (x.min() - label_px * height / height_px + x.max())
    # the middle of the free band sits (BOTTOM - TOP) / 2 above the middle of the panel
    cy = 0.5 * (y.min() + y.max()) - 0.5 * (BOTTOM - TOP) * height
    focus = cx * right + cy * up + (points.mean(axis=0) @ direction) * direction
    distance = 2 * (np.ptp(points @ direction) + height)
    plotter.camera.enable_parallel_projection()
    plotter.camera_position = [tuple(focus + distance * direction), tuple(focus), tuple(up)]
    plotter.camera.parallel_scale = 0.5 * height
    plotter.reset_camera_clipping_range()


def _side_layer(side, normal, values, lift, scale):
    """Node positions of a side lifted by `lift` along n and warped by scale * value along the
    node normals (shapes act on the normal dofs: displacement = value * node normal)."""
    return (side.points[side.nodes] + lift * normal
            + (scale * values)[:, None] * side.node_normals)


def layer_height(view, direction):
    """Height between the layers of a shape panel so that, seen along `direction`, a layer
    warped by up to WARP * length clears the next one."""
    e = np.arcsin(direction @ view.normal)
    horizontal = direction - (direction @ view.normal) * view.normal
    horizontal /= np.linalg.norm(horizontal)
    depth = np.ptp(view.outline @ horizontal)
    return 1.05 * (depth * np.tan(e) + 2 * WARP * view.length)


def _label_points(view, direction, lifts):
    """Anchors (right ends) of layer names, just left of Gamma on screen, at each layer's
    height."""
    right, _ = screen_axes(direction, view.normal)
    x = view.outline @ right
    shift = (x.min() - view.centre @ right) - 0.03 * np.ptp(x)
    return np.array([view.centre + shift * right + h * view.normal for h in lifts])
