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
pyvista off screen (EGL or OSMesa when there is no display, set up in `render`) and are framed
with the geometry of `views`; 2D plots use matplotlib through its Agg canvas (no pyplot state).
"""
from pathlib import Path

import numpy as np

from ..contact.regularize import dual_projectors
from .render import RenderingUnavailable, _bar, _loops, _plotter, _surface, offscreen
from .views import (WARP, _frame, _label_points, _side_layer, gamma_triangles, gamma_view,
                    layer_height, panel_size, side_outlines, side_triangles, view_direction)

__all__ = ["RenderingUnavailable", "default_shapes", "parse_shapes", "check_shapes",
           "shape_fields", "centre_point", "observation_side", "observation_rows",
           "shapes_figure", "observation_figure", "spectrum_figure", "plot_compat"]

FLOOR = 1e-17        # normalized singular values below this (round-off zeros) are drawn here
ELEVATION = 30.0     # camera elevation above the contact plane in shape panels [deg]
OBSERVATION_ELEVATION = 35.0  # and in observation panels (one layer: look more from above)
LABEL_PX = 150       # pixels left of a shape panel's scene for the names of the layers
CMAP = "coolwarm"    # diverging: the colour of zero is neutral, signs read at a glance


# ---------------------------------------------------------------------------------------------
# Data of the pictures (numbers only, no drawing)

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
    project = pair.spec.project
    if project in ("surface1", "surface2"):
        return int(project[-1])
    return 1 if pair.compat.n1 > pair.compat.n2 else 2


def observation_rows(pair, point, side):
    """Raw row C_s[point] (N_s,) and regularized row (C_s P_s)[point] on side s."""
    fine = pair.interface.fine
    norm = pair.spec.norm
    P1, P2 = dual_projectors(pair.compat, pair.eps, fine, "both", norm)
    C, P = (fine.C1, P1) if side == 1 else (fine.C2, P2)
    raw = C[point].toarray().ravel()
    return raw, raw @ P


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
              f"{pair.spec.norm} norm")
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
