"""Tests of the structured mesh generators: geometry, validity, conformity and named sets."""
import time

import numpy as np
import pytest
from scipy.spatial import cKDTree

from transient.mesh.elements import ELEMENTS, VOLUME_TYPES
from transient.mesh.generators import annular_disc, box, brake_pad, drilled_box
from transient.mesh.mesh import all_faces, boundary_faces, face_key

LINEAR = ("hexahedron", "tetra", "wedge")


# ----------------------------------------------------------------------------- helpers

def jacobian_dets(mesh, degree=5):
    """det J at the nodes (ne, nen) and at the quadrature points (ne, nq), weights (nq,)."""
    (ctype, conn), = mesh.cells.items()
    el = ELEMENTS[ctype]
    qp, qw = el.rule(degree)
    x = mesh.points[conn]
    dets = []
    for xi in (el.nodes, qp):
        jac = np.einsum("ena,pnd->epad", x, el.shape_derivatives(xi))
        dets.append(np.linalg.det(jac))
    return dets[0], dets[1], qw


def volume(mesh, cells=None):
    """Volume [m^3] of all cells or of the given cell indices, by quadrature of det J."""
    _, det_q, w = jacobian_dets(mesh)
    if cells is not None:
        det_q = det_q[cells]
    return float((det_q @ w).sum())


def face_quadrature(points, faces, ftype, degree=4):
    """Points (n, 3) and area vectors n dA (n, 3) [m^2] at the quadrature points of the faces."""
    el = ELEMENTS[ftype]
    qp, qw = el.rule(degree)
    x = points[faces]
    at = np.einsum("fna,pn->fpa", x, el.shape_functions(qp)).reshape(-1, 3)
    tangents = np.einsum("fna,pnd->fpda", x, el.shape_derivatives(qp))
    normal = np.cross(tangents[:, :, 0], tangents[:, :, 1]) * qw[None, :, None]
    return at, normal.reshape(-1, 3)


def face_set(mesh, name):
    """Quadrature points, area vectors and total area [m^2] of a named face set (of every
    face type in it: a wedge's on z levels are triangles, the others quadrilaterals)."""
    pieces = [face_quadrature(mesh.points, faces, ftype)
              for ftype, faces in mesh.face_sets[name].items()]
    at, normal = (np.vstack(p) for p in zip(*pieces))
    return at, normal, float(np.linalg.norm(normal, axis=1).sum())


def boundary_area(mesh):
    return sum(float(np.linalg.norm(face_quadrature(mesh.points, faces, ftype)[1], axis=1).sum())
               for ftype, faces in boundary_faces(mesh).items())


def check_valid(mesh):
    """Positive det J everywhere, no face in more than two cells, no duplicate or unused node."""
    det_n, det_q, _ = jacobian_dets(mesh)
    assert det_n.min() > 0 and det_q.min() > 0
    for ftype, (faces, _, _) in all_faces(mesh).items():
        _, counts = np.unique(face_key(faces, ELEMENTS[ftype].n_corners), axis=0,
                              return_counts=True)
        assert counts.max() <= 2
    distance, _ = cKDTree(mesh.points).query(mesh.points, k=2)
    assert distance[:, 1].min() > 1e-9
    (conn,) = mesh.cells.values()
    assert np.array_equal(np.unique(conn), np.arange(mesh.n_nodes))


def check_sets(mesh):
    """Node sets are the nodes of the face sets; every face set lies on the boundary."""
    keys = {ftype: {tuple(k) for k in face_key(boundary, ELEMENTS[ftype].n_corners)}
            for ftype, boundary in boundary_faces(mesh).items()}
    for name, fs in mesh.face_sets.items():
        assert fs and all(len(faces) for faces in fs.values())
        for ftype, faces in fs.items():
            assert {tuple(k) for k in face_key(faces, ELEMENTS[ftype].n_corners)} <= keys[ftype]
        assert np.array_equal(mesh.node_sets[name],
                              np.unique(np.concatenate([f.ravel() for f in fs.values()])))


def check_plane(mesh, name, normal, area, rtol=1e-12):
    """A planar face set: its area [m^2] and its outward unit normal."""
    _, n, a = face_set(mesh, name)
    assert a == pytest.approx(area, rel=rtol)
    unit = n / np.linalg.norm(n, axis=1)[:, None]
    assert np.allclose(unit, normal, atol=1e-9)


def polygon_area(xy):
    x, y = xy.T
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def polygon_perimeter(xy):
    return float(np.linalg.norm(xy - np.roll(xy, -1, axis=0), axis=1).sum())


def ogrid_hole(x, y, center, radius, k):
    """The hole polygon as specified: circle points at the polar angles of the square's nodes."""
    i0, j0 = np.argmin(np.abs(x - center[0])), np.argmin(np.abs(y - center[1]))
    xs, ys = x[i0 - k:i0 + k + 1], y[j0 - k:j0 + k + 1]
    square = np.vstack([np.column_stack([xs[:-1], np.full(2 * k, ys[0])]),
                        np.column_stack([np.full(2 * k, xs[-1]), ys[:-1]]),
                        np.column_stack([xs[:0:-1], np.full(2 * k, ys[-1])]),
                        np.column_stack([np.full(2 * k, xs[0]), ys[:0:-1]])])
    angle = np.arctan2(square[:, 1] - center[1], square[:, 0] - center[0])
    return np.asarray(center) + radius * np.column_stack([np.cos(angle), np.sin(angle)])


# ----------------------------------------------------------------------------- box

@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_box(element):
    size, origin = (0.3, 0.2, 0.1), (-0.1, 0.05, 0.2)
    mesh = box(size, (3, 2, 2), origin=origin, element=element)
    a, b, c = size
    check_valid(mesh)
    check_sets(mesh)
    assert volume(mesh) == pytest.approx(a * b * c, rel=1e-12)
    assert boundary_area(mesh) == pytest.approx(2 * (a * b + b * c + c * a), rel=1e-12)
    lo, hi = np.array(origin), np.array(origin) + size
    for axis, (low, high) in enumerate((("xmin", "xmax"), ("ymin", "ymax"), ("zmin", "zmax"))):
        area = np.prod(np.delete(size, axis))
        e = np.eye(3)[axis]
        check_plane(mesh, low, -e, area)
        check_plane(mesh, high, e, area)
        on = mesh.points[:, axis]
        assert np.array_equal(mesh.node_sets[low], np.flatnonzero(on == lo[axis]))
        assert np.array_equal(mesh.node_sets[high], np.flatnonzero(on == hi[axis]))
    assert np.array_equal(mesh.cell_sets["all"][element], np.arange(mesh.n_cells))


def test_box_hex20_speed():
    start = time.perf_counter()
    mesh = box((1.0, 1.0, 1.0), (30, 30, 30), element="hexahedron20")
    assert time.perf_counter() - start < 2.0
    assert mesh.cells["hexahedron20"].shape == (27000, 20)


@pytest.mark.parametrize("bad", [dict(element="hex8"), dict(divisions=(2, 0, 1)),
                                 dict(size=(1.0, -1.0, 1.0))])
def test_box_rejects_bad_input(bad):
    args = dict(size=(1.0, 1.0, 1.0), divisions=(2, 2, 2)) | bad
    with pytest.raises(ValueError):
        box(**args)


# ----------------------------------------------------------------------------- drilled box

@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_drilled_box(element):
    mesh = drilled_box((1.0, 1.0, 1.0), (12, 12, 4), (0.5, 0.5), 0.15, element=element)
    grid = np.linspace(0.0, 1.0, 13)
    hole = ogrid_hole(grid, grid, (0.5, 0.5), 0.15, 3)   # default k: 3 / 12 >= 1.5 * 0.15
    area, perimeter = polygon_area(hole), polygon_perimeter(hole)
    check_valid(mesh)
    check_sets(mesh)
    assert volume(mesh) == pytest.approx(1.0 - area, rel=1e-12)
    assert boundary_area(mesh) == pytest.approx(6.0 + perimeter - 2 * area, rel=1e-12)
    check_plane(mesh, "zmax", (0, 0, 1), 1.0 - area)
    check_plane(mesh, "zmin", (0, 0, -1), 1.0 - area)
    check_plane(mesh, "xmin", (-1, 0, 0), 1.0)
    check_plane(mesh, "ymax", (0, 1, 0), 1.0)
    at, normal, hole_area = face_set(mesh, "hole")
    assert hole_area == pytest.approx(perimeter, rel=1e-12)
    radial = at[:, :2] - 0.5
    assert np.all(np.einsum("ij,ij->i", normal[:, :2], radial) < 0)   # into the hole
    # Polygonal hole: corners on the circle, midside nodes (if any) on the chords.
    (ftype, faces), = mesh.face_sets["hole"].items()
    corners = np.unique(faces[:, :ELEMENTS[ftype].n_corners])
    assert np.allclose(np.linalg.norm(mesh.points[corners, :2] - 0.5, axis=1), 0.15)


@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_drilled_box_top_face_respects_coarse_lines(element):
    """The lines x, y = 0.25, 0.5, 0.75 are unions of element edges on the top face."""
    mesh = drilled_box((1.0, 1.0, 1.0), (12, 12, 4), (0.5, 0.5), 0.15, element=element)
    (faces,) = mesh.face_sets["zmax"].values()
    xy = mesh.points[faces, :2]
    for axis in (0, 1):
        lo, hi = xy[:, :, axis].min(axis=1), xy[:, :, axis].max(axis=1)
        for line in (0.25, 0.5, 0.75):
            assert not np.any((lo < line - 1e-12) & (hi > line + 1e-12))


@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_drilled_box_off_centre_square_on_boundary(element):
    """Hole off the grid node, explicit k, O-grid square touching xmin: sets still complete."""
    size, origin = (0.6, 0.4, 0.05), (1.0, -0.2, 0.0)
    center, radius = (1.13, 0.01), 0.05
    mesh = drilled_box(size, (6, 4, 2), center, radius, origin=origin, element=element,
                       ogrid_cells=1)
    x = origin[0] + np.linspace(0.0, size[0], 7)
    y = origin[1] + np.linspace(0.0, size[1], 5)
    hole = ogrid_hole(x, y, center, radius, 1)
    area, perimeter = polygon_area(hole), polygon_perimeter(hole)
    plan = size[0] * size[1]
    check_valid(mesh)
    check_sets(mesh)
    assert volume(mesh) == pytest.approx((plan - area) * size[2], rel=1e-12)
    surface = 2 * (plan + size[2] * (size[0] + size[1]))
    assert boundary_area(mesh) == pytest.approx(surface + perimeter * size[2] - 2 * area, rel=1e-12)
    check_plane(mesh, "xmin", (-1, 0, 0), size[1] * size[2])
    check_plane(mesh, "zmax", (0, 0, 1), plan - area)
    _, _, hole_area = face_set(mesh, "hole")
    assert hole_area == pytest.approx(perimeter * size[2], rel=1e-12)


@pytest.mark.parametrize("center, radius, k", [((0.1, 0.5), 0.1, None),   # square leaves box
                                               ((0.5, 0.5), 0.15, 1)])      # hole leaves square
def test_drilled_box_rejects_misfit(center, radius, k):
    with pytest.raises(ValueError, match="does not fit"):
        drilled_box((1.0, 1.0, 1.0), (12, 12, 2), center, radius, ogrid_cells=k)


# (size, divisions, hole centre, radius, origin, ogrid_cells): centred hole with the default k;
# off-centre hole with k = 1 and the O-grid square on xmin (the most skewed plug).
FILLED_PLANS = [((1.0, 1.0, 1.0), (12, 12, 4), (0.5, 0.5), 0.15, (0.0, 0.0, 0.0), 3),
                ((0.6, 0.4, 0.05), (6, 4, 2), (1.13, 0.01), 0.05, (1.0, -0.2, 0.0), 1)]


@pytest.mark.parametrize("plan", FILLED_PLANS)
@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_filled_drilled_box(element, plan):
    size, divisions, center, radius, origin, k = plan
    mesh = drilled_box(size, divisions, center, radius, origin=origin, element=element,
                       ogrid_cells=k, filled=True)
    x, y, _ = (o + np.linspace(0.0, s, n + 1) for o, s, n in zip(origin, size, divisions))
    hole = polygon_area(ogrid_hole(x, y, center, radius, k))
    a, b, c = size
    check_valid(mesh)
    check_sets(mesh)
    assert "hole" not in mesh.face_sets
    assert volume(mesh) == pytest.approx(a * b * c, rel=1e-12)
    assert boundary_area(mesh) == pytest.approx(2 * (a * b + b * c + c * a), rel=1e-12)
    check_plane(mesh, "zmax", (0, 0, 1), a * b)
    check_plane(mesh, "zmin", (0, 0, -1), a * b)
    check_plane(mesh, "xmin", (-1, 0, 0), b * c)
    plug = mesh.cell_sets["plug"][element]
    assert volume(mesh, plug) == pytest.approx(hole * c, rel=1e-12)
    # The plug is the hole polygon's prism: its nodes lie within the hole's radius.
    (conn,) = mesh.cells.values()
    assert np.linalg.norm(mesh.points[conn[plug], :2] - center, axis=-1).max() < radius + 1e-12
    assert np.array_equal(mesh.cell_sets["all"][element], np.arange(mesh.n_cells))


@pytest.mark.parametrize("plan", FILLED_PLANS)
@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_filled_top_face_contains_drilled_top_face(element, plan):
    """Every top face of the drilled block, midside nodes included, is one of the filled block:
    a filled block placed on a drilled one meets it conformingly."""
    size, divisions, center, radius, origin, k = plan
    drilled, filled = (drilled_box(size, divisions, center, radius, origin=origin,
                                   element=element, ogrid_cells=k, filled=f) for f in (False, True))
    (top,) = drilled.face_sets["zmax"].values()
    (filled_top,) = filled.face_sets["zmax"].values()
    distance, image = cKDTree(filled.points).query(drilled.points[top.ravel()])
    assert distance.max() < 1e-12 * max(size)
    keys = {tuple(sorted(face)) for face in filled_top}
    assert all(tuple(sorted(face)) in keys for face in image.reshape(top.shape))
    assert len(filled_top) > len(top)


# ----------------------------------------------------------------------------- disc

@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_annular_disc(element):
    ri, ro, t, nt = 0.08, 0.15, 0.02, 12
    center = (0.01, -0.02, 0.005)
    mesh = annular_disc(ri, ro, t, (2, nt, 2), center=center, element=element)
    check_valid(mesh)
    check_sets(mesh)
    exact = np.pi * (ro ** 2 - ri ** 2) * t
    polygon = 0.5 * nt * np.sin(2 * np.pi / nt) * (ro ** 2 - ri ** 2) * t
    if element in LINEAR:
        assert volume(mesh) == pytest.approx(polygon, rel=1e-12)
    else:
        # Curved arcs: far closer to the annulus than the polygon is (about 4.5 % off here).
        linear_error = abs(polygon - exact) / exact
        assert abs(volume(mesh) - exact) / exact < linear_error / 100
    rtol = 1e-12 if element in LINEAR else 1e-3   # the polygon is 1.1 % short on lengths
    side = 2 * nt * np.sin(np.pi / nt) if element in LINEAR else 2 * np.pi
    annulus = polygon / t if element in LINEAR else np.pi * (ro ** 2 - ri ** 2)
    assert boundary_area(mesh) == pytest.approx(2 * annulus + side * (ri + ro) * t, rel=rtol)
    check_plane(mesh, "zmin", (0, 0, -1), annulus, rtol)
    check_plane(mesh, "zmax", (0, 0, 1), annulus, rtol)
    assert np.allclose(mesh.points[mesh.node_sets["zmin"], 2], center[2])
    assert np.allclose(mesh.points[mesh.node_sets["zmax"], 2], center[2] + t)
    for name, radius, sign in (("hub", ri, -1), ("outer", ro, 1)):
        at, normal, area = face_set(mesh, name)
        assert area == pytest.approx(side * radius * t, rel=rtol)
        radial = at[:, :2] - center[:2]
        assert np.all(sign * np.einsum("ij,ij->i", normal[:, :2], radial) > 0)
        assert np.allclose(np.abs(normal[:, 2]), 0.0, atol=1e-15)
        r = np.linalg.norm(mesh.points[mesh.node_sets[name], :2] - center[:2], axis=1)
        assert np.allclose(r, radius, rtol=1e-12)


def test_annular_disc_rejects_too_few_sectors():
    with pytest.raises(ValueError):
        annular_disc(0.1, 0.2, 0.01, (1, 2, 1))


# ----------------------------------------------------------------------------- pad

@pytest.mark.parametrize("element", VOLUME_TYPES)
def test_brake_pad(element):
    ri, ro, angle, tl, tb, nt = 0.1, 0.15, 60.0, 0.01, 0.005, 4
    center, z0, middle = (0.02, -0.01), 0.003, 30.0
    mesh = brake_pad(ri, ro, angle, tl, tb, (2, nt, 2, 1), z0=z0, center=center,
                     center_angle=middle, element=element)
    check_valid(mesh)
    check_sets(mesh)
    sector = 0.5 * np.radians(angle) * (ro ** 2 - ri ** 2)
    polygon = 0.5 * nt * np.sin(np.radians(angle) / nt) * (ro ** 2 - ri ** 2)
    if element in LINEAR:
        plan, rtol = polygon, 1e-12
    else:
        plan, rtol = sector, abs(polygon - sector) / sector / 100
    lining, backplate = mesh.cell_sets["lining"][element], mesh.cell_sets["backplate"][element]
    assert len(lining) + len(backplate) == mesh.n_cells == len(mesh.cell_sets["all"][element])
    assert volume(mesh, lining) == pytest.approx(plan * tl, rel=rtol)
    assert volume(mesh, backplate) == pytest.approx(plan * tb, rel=rtol)
    check_plane(mesh, "friction", (0, 0, -1), plan, rtol)
    check_plane(mesh, "back", (0, 0, 1), plan, rtol)
    assert np.allclose(mesh.points[mesh.node_sets["friction"], 2], z0)
    assert np.allclose(mesh.points[mesh.node_sets["back"], 2], z0 + tl + tb)
    # Friction lining below the backplate.
    (conn,) = mesh.cells.values()
    assert mesh.points[conn[lining], 2].max() == pytest.approx(z0 + tl)
    assert mesh.points[conn[backplate], 2].min() == pytest.approx(z0 + tl)
    # Lateral sets: inner normal towards the axis, outer away, ends along -/+ theta.
    for name, sign in (("inner", -1), ("outer", 1)):
        at, normal, _ = face_set(mesh, name)
        assert np.all(sign * np.einsum("ij,ij->i", normal[:, :2], at[:, :2] - center) > 0)
    at, normal, area = face_set(mesh, "ends")
    assert area == pytest.approx(2 * (ro - ri) * (tl + tb), rel=1e-12)
    theta = np.degrees(np.arctan2(at[:, 1] - center[1], at[:, 0] - center[0])) - middle
    assert np.allclose(np.abs(theta), angle / 2)
    polar = np.radians(theta + middle)
    tangent = np.column_stack([-np.sin(polar), np.cos(polar)])
    assert np.all(np.sign(np.einsum("ij,ij->i", normal[:, :2], tangent)) == np.sign(theta))
