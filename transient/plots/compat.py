"""Pictures of the compatibility of contact pairs (the paper's figures 3, 4, 5, 8 and 9).

For each pair, three PNG files:
- `<pair>_shapes.png`: a few shapes of the gap energy, each as its trace on surface 1 (above),
  the gap it opens at the points of the fine rule on Gamma (middle) and its trace on surface 2
  (below), warped along the contact normal and coloured by the value;
- `<pair>_singular_values.png`: the normalized spectrum with eps and the count kept, and C(eps);
- `<pair>_observation.png`: the gap observation of one fine point as a field on the finer surface,
  raw (local to the faces holding the point) and regularized (spread by the projection).

This module only reads the dataclasses of `interface`, `compatibility` and `contact`: it applies
their observation matrices to the shapes and takes the projectors from
`regularize.dual_projectors`, and computes no contact quantity of its own. 3D panels use
pyvista off screen (EGL or OSMesa when there is no display), 2D plots matplotlib through its Agg
canvas (no pyplot state).
"""
import ctypes.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, cKDTree

from ..mesh.elements import ELEMENTS
from ..contact.interface import FACE_TYPES
from ..contact.regularize import dual_projectors

FLOOR = 1e-17        # normalized singular values below this (round-off zeros) are drawn here
WARP = 0.10          # largest warp of a panel as a fraction of Gamma's length
ELEVATION = 30.0     # camera elevation above the contact plane in shape panels [deg]
OBSERVATION_ELEVATION = 35.0  # and in observation panels (one layer: look more from above)
LABEL_PX = 150       # pixels left of a shape panel's scene for the names of the layers
BOTTOM, TOP = 0.17, 0.07  # parts of a panel's height taken by the colour bar and the title
LIFT = 0.003         # outlines drawn this far (fraction of the length) above their faces
AZIMUTH = 30.0       # camera turn about n for a roundish Gamma [deg]
PANEL = (760, 720)   # pixels of one 3D panel
CMAP = "coolwarm"    # diverging: the colour of zero is neutral, signs read at a glance

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


class RenderingUnavailable(RuntimeError):
    """No OpenGL that renders without a display: a system library is missing."""


# ---------------------------------------------------------------------------------------------
# Data of the pictures (numbers only, no drawing)

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


def default_shapes(comp, eps):
    """Shape numbers (1-based) to draw: the first, the last kept, and two beyond the cut."""
    n = len(comp.sigma)
    r = max(comp.kept(eps), 1)
    # beyond the cut: the first, and one well inside the incompatible range (the paper draws
    # #96 and #166 past 25 kept)
    picks = [1, r, r + 1, min(4 * r, (r + 1 + n) // 2)]
    return sorted({min(max(i, 1), n) for i in picks})


def parse_shapes(text):
    """'1,22,96' -> [1, 22, 96]; ValueError with a one-line reason otherwise."""
    try:
        numbers = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise ValueError(f"expected shape numbers separated by commas, got '{text}'") from None
    if not numbers:
        raise ValueError("expected at least one shape number")
    if min(numbers) < 1:
        raise ValueError(f"shape numbers start at 1, got {min(numbers)}")
    return numbers


def check_shapes(numbers, comp):
    """ValueError unless every shape number is in 1..N1+N2."""
    n = len(comp.sigma)
    bad = [i for i in numbers if not 1 <= i <= n]
    if bad:
        raise ValueError(f"shape {bad[0]} out of range: this pair has shapes 1..{n}")


def shape_fields(pair, number):
    """Normal displacements of shape `number` (1-based) on each side, and its gap at the fine
    points: u1 (N1,), u2 (N2,), gap (P,) = C1 u1 - C2 u2."""
    comp, rule = pair.compat, pair.interface.fine
    v = comp.shapes[:, number - 1]
    u1, u2 = v[:comp.n1], v[comp.n1:]
    return u1, u2, rule.C1 @ u1 - rule.C2 @ u2


def centre_point(rule):
    """Index of the fine point nearest the centre of Gamma (area-weighted), among those that
    carry area (a point of weight zero observes nothing the contact uses)."""
    centre = np.average(rule.points, axis=0, weights=rule.weights)
    distance = np.linalg.norm(rule.points - centre, axis=1)
    return int(np.argmin(np.where(rule.weights > 0, distance, np.inf)))


def observation_side(pair):
    """1 or 2: the side whose observation row is drawn, the finer one unless only one side is
    projected (the other one's row would not change)."""
    project = pair.spec.get("project", "both")
    if project in ("surface1", "surface2"):
        return int(project[-1])
    return 1 if pair.compat.n1 > pair.compat.n2 else 2


def observation_rows(pair, point, side):
    """Raw row C_s[point] (N_s,) and regularized row (C_s P_s)[point] on side s."""
    fine = pair.interface.fine
    norm = pair.spec.get("norm", "mass")
    P1, P2 = dual_projectors(pair.compat, pair.eps, fine, "both", norm)
    C, P = (fine.C1, P1) if side == 1 else (fine.C2, P2)
    raw = C[point].toarray().ravel()
    return raw, raw @ P


# ---------------------------------------------------------------------------------------------
# Rendering set-up

def offscreen():
    """Import pyvista set for off-screen rendering, choosing an OpenGL that needs no display.

    VTK's wheels try X first and fall back to EGL, then OSMesa, printing a warning at each
    failure; without a display, ask for EGL (or OSMesa) directly. With none of them VTK
    crashes, so fail here with the packages to install.
    """
    headless = sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if headless and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ:
        if ctypes.util.find_library("EGL"):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
        elif ctypes.util.find_library("OSMesa"):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkOSOpenGLRenderWindow"
        else:
            raise RenderingUnavailable(
                "no display and no off-screen OpenGL: install libegl1 and libegl-mesa0 "
                "(or libosmesa6), or run under xvfb-run")
    import pyvista
    pyvista.OFF_SCREEN = True
    return pyvista


def _plotter(pv, shape, panel):
    rows, cols = shape
    return pv.Plotter(shape=shape, off_screen=True, border=False,
                      window_size=(panel[0] * cols, panel[1] * rows),
                      theme=pv.themes.DocumentTheme())


def _bar(title):
    # horizontal bar at the bottom of its panel; titles must differ between panels, pyvista
    # shares one bar between all meshes of a plotter with the same title
    return dict(title=title, vertical=False, position_x=0.2, position_y=0.02, width=0.6,
                height=0.12, fmt="%.2g", n_labels=5, title_font_size=16, label_font_size=14,
                color="black")


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


def _surface(pv, points, triangles, values, name):
    mesh = pv.PolyData(np.asarray(points, float),
                       np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
    mesh.point_data[name] = values
    return mesh


def _loops(pv, points, loops, view):
    # lifted towards the camera (always above the plane): lines lying exactly on their faces
    # would be half hidden by them
    points = points + LIFT * view.length * view.normal
    cells = np.concatenate([np.r_[len(lp) + 1, lp, lp[0]] for lp in loops])
    return pv.PolyData(np.asarray(points, float), lines=cells)


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


# ---------------------------------------------------------------------------------------------
# Figures

def shapes_figure(pair, numbers, path):
    """Panels of shapes: surface 1 above, the gap on Gamma in the middle, surface 2 below."""
    pv = offscreen()
    interface, comp = pair.interface, pair.compat
    view = gamma_view(interface)
    direction = view_direction(view, ELEVATION)
    tri1, tri2 = side_triangles(interface.side1), side_triangles(interface.side2)
    loops1, loops2 = side_outlines(interface.side1), side_outlines(interface.side2)
    tri_gamma = gamma_triangles(interface, interface.fine)
    h = layer_height(view, direction)
    labels = _label_points(view, direction, (h, 0.0, -h))
    # the largest scene a panel can hold: flat layers, warps up to WARP * length, labels
    warp = WARP * view.length * view.normal
    bound = np.vstack([view.outline + d * view.normal + s * warp
                       for d in (h, -h) for s in (1, -1)] + [labels])
    cols = min(len(numbers), 2)
    rows = -(-len(numbers) // cols)
    panel = panel_size(bound, direction, view.normal, LABEL_PX)
    plotter = _plotter(pv, (rows, cols), panel)
    kept = comp.kept(pair.eps)
    for k, number in enumerate(numbers):
        plotter.subplot(k // cols, k % cols)
        u1, u2, gap = shape_fields(pair, number)
        top = max(np.abs(u1).max(), np.abs(u2).max(), np.abs(gap).max()) or 1.0
        scale = WARP * view.length / top
        name = f"u_n and gap (#{number})"
        x1 = _side_layer(interface.side1, view.normal, u1, h, scale)
        x2 = _side_layer(interface.side2, view.normal, u2, -h, scale)
        xg = interface.fine.points + (scale * gap)[:, None] * interface.fine.normals
        common = dict(scalars=name, cmap=CMAP, clim=(-top, top))
        plotter.add_mesh(_surface(pv, x1, tri1, u1, name), scalar_bar_args=_bar(name), **common)
        plotter.add_mesh(_surface(pv, xg, tri_gamma, gap, name), show_scalar_bar=False, **common)
        plotter.add_mesh(_surface(pv, x2, tri2, u2, name), show_scalar_bar=False, **common)
        for x, loops in ((x1, loops1), (x2, loops2)):
            plotter.add_mesh(_loops(pv, x, loops, view), color="black", line_width=1,
                             opacity=0.35)
        plotter.add_point_labels(labels, ["surface 1", "gap on Gamma", "surface 2"],
                                 font_size=16, shape=None, show_points=False,
                                 always_visible=True, text_color="black",
                                 justification_horizontal="right",
                                 justification_vertical="center")
        status = "kept" if number <= kept else "beyond eps"
        plotter.add_text(f"shape #{number}: sigma/max = {comp.normalized[number - 1]:.2g}, "
                         f"{status}", position="upper_edge", font_size=12, color="black")
        _frame(plotter, bound, direction, view.normal, panel, LABEL_PX)
    plotter.screenshot(str(path))
    plotter.close()


def observation_figure(pair, path, point=None):
    """Raw and regularized observation row of one fine point, on the finer surface."""
    pv = offscreen()
    interface = pair.interface
    rule = interface.fine
    point = centre_point(rule) if point is None else point
    s = observation_side(pair)
    side, other = ((interface.side1, interface.side2) if s == 1
                   else (interface.side2, interface.side1))
    raw, reg = observation_rows(pair, point, s)
    view = gamma_view(interface)
    direction = view_direction(view, OBSERVATION_ELEVATION)
    tri, loops, other_loops = side_triangles(side), side_outlines(side), side_outlines(other)
    amplitude = 1.5 * WARP * view.length
    flat = side.points[side.nodes]
    pin = rule.points[point] + 1.25 * amplitude * view.normal
    bound = np.vstack([flat, flat + amplitude * view.normal, flat - amplitude * view.normal,
                       pin + 0.02 * view.length * view.normal])
    panel = panel_size(bound, direction, view.normal)
    plotter = _plotter(pv, (1, 2), panel)
    titles = (f"raw: row i = {point} of C{s}",
              f"regularized: row i of C{s} P{s}, eps = {pair.eps:.2g}, "
              f"{pair.spec.get('norm', 'mass')} norm")
    for k, (row, title) in enumerate(zip((raw, reg), titles)):
        plotter.subplot(0, k)
        top = np.abs(row).max() or 1.0
        scale = amplitude / top
        x = _side_layer(side, view.normal, row, 0.0, scale)
        name = f"row on surface {s}" + (" (regularized)" if k else "")
        plotter.add_mesh(_surface(pv, x, tri, row, name), scalars=name, cmap=CMAP,
                         clim=(-top, top), scalar_bar_args=_bar(name))
        plotter.add_mesh(_loops(pv, x, loops, view), color="black", line_width=1, opacity=0.25)
        # the other surface's faces, flat, show how far the projection spreads the row
        plotter.add_mesh(_loops(pv, other.points[other.nodes], other_loops, view),
                         color="darkgreen", line_width=2, opacity=0.6)
        # a pin standing on the point, its head above every warp: a marker on the warped
        # surface would hide behind the peak of a node next to the point
        plotter.add_mesh(pv.Line(rule.points[point], pin), color="black", line_width=3)
        plotter.add_mesh(pv.Sphere(radius=0.015 * view.length, center=pin), color="black")
        plotter.add_text(title, position="upper_edge", font_size=11, color="black")
        _frame(plotter, bound, direction, view.normal, panel)
    plotter.screenshot(str(path))
    plotter.close()


def spectrum_figure(pair, path, numbers=()):
    """Normalized singular values by increasing incompatibility, and C(eps)."""
    from matplotlib.figure import Figure
    comp, eps = pair.compat, pair.eps
    s = comp.normalized
    kept = comp.kept(eps)
    i = np.arange(1, len(s) + 1)
    fig = Figure(figsize=(12, 4.6), layout="constrained")
    ax, bx = fig.subplots(1, 2)
    ax.semilogy(i, np.maximum(s, FLOOR), ".", ms=3, color="tab:blue",
                label=f"sigma_i / max sigma (below {FLOOR:.0e}: drawn at it)")
    ax.axhline(eps, color="tab:red", ls="--", lw=1, label=f"eps = {eps:.2g}")
    ax.axvline(kept + 0.5, color="tab:gray", ls=":", lw=1,
               label=f"{kept} kept (min(N1, N2) = {min(comp.n1, comp.n2)})")
    if len(numbers):
        sel = np.asarray(numbers)
        ax.plot(sel, np.maximum(s[sel - 1], FLOOR), "o", mfc="none", color="black", ms=7,
                label="drawn shapes")
        for k, j in enumerate(sel):
            # alternately above and below: neighbours (the last kept, the first beyond) would
            # write over each other
            ax.annotate(f"#{j}", (j, max(s[j - 1], FLOOR)), xytext=(6, 6 if k % 2 else -12),
                        textcoords="offset points", fontsize=8)
    ax.set(xlabel="shapes by increasing incompatibility", ylabel="sigma_i / max sigma",
           ylim=(FLOOR / 5, 5), xlim=(0, len(s) + 1),
           title=f"{pair.name}: singular values of the gap energy (N1 = {comp.n1}, "
                 f"N2 = {comp.n2})")
    ax.legend(loc="lower right", fontsize=8)
    e = np.logspace(np.log10(FLOOR), 0, 400)
    bx.semilogx(e, comp.curve(e), color="tab:blue", lw=1.5)
    c = float(comp.curve(eps))
    bx.axvline(eps, color="tab:red", ls="--", lw=1, label=f"eps = {eps:.2g}")
    bx.axhline(1.0, color="tab:gray", ls=":", lw=1, label="min(N1, N2) shapes")
    bx.plot([eps], [c], "o", color="tab:red")
    bx.annotate(f"C(eps) = {c:.3g}", (eps, c), xytext=(8, -14), textcoords="offset points",
                fontsize=9)
    # C counts every shape below eps, up to (N1 + N2) / min(N1, N2) at eps = 1; the range of
    # interest is C <= 1 (at most min(N1, N2) quasi-compatible shapes), the rest goes off scale
    top = max(1.25, 1.25 * c)
    end = float(comp.curve(1.0))
    title = "(1-eps)-compatibility"
    if end > top:
        title += f" (off scale above: C(1) = {end:.3g})"
    bx.set(xlabel="eps", ylabel="C(eps)", title=title, ylim=(0, top))
    bx.legend(loc="upper left", fontsize=8)
    fig.savefig(path, dpi=110)


def plot_compat(pair, out, numbers=None):
    """The three pictures of a pair (built with its compatibility) in directory `out`.

    numbers: shape numbers (1-based) for the shapes panel; default `default_shapes`.
    Returns the paths written. ValueError on a bad shape number.
    """
    if pair.compat is None:
        raise ValueError(f"pair '{pair.name}' has no compatibility (build it with "
                         "need_compatibility=True)")
    numbers = default_shapes(pair.compat, pair.eps) if numbers is None else list(numbers)
    check_shapes(numbers, pair.compat)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{pair.name}_{kind}.png" for kind in
             ("shapes", "singular_values", "observation")]
    shapes_figure(pair, numbers, paths[0])
    spectrum_figure(pair, paths[1], numbers)
    observation_figure(pair, paths[2])
    return paths
