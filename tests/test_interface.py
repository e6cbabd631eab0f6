"""The fine rule on Gamma: areas in closed form, exact integration, rigid motions, compatibility."""
import numpy as np
import pytest

from transient.contact.compatibility import FALLBACK_EPS, auto_eps, compatibility, gap_energy
from transient.mesh.generators import annular_disc, box, brake_pad, drilled_box
from transient.contact.interface import InterfaceError, build_interface


def pair(upper, lower, set1="zmin", set2="zmax", degree=4):
    return build_interface("c", upper.points, upper.face_sets[set1], 0, lower.points,
                           lower.face_sets[set2], upper.n_nodes, degree)


@pytest.mark.parametrize("e1, e2", [("hexahedron", "hexahedron20"), ("tetra10", "tetra"),
                                    ("hexahedron20", "tetra10")])
def test_offset_rectangles_area(e1, e2):
    lower = box((1.0, 0.8, 0.5), (5, 4, 2), element=e2)
    upper = box((0.7, 0.9, 0.4), (3, 7, 2), origin=(0.45, 0.3, 0.5), element=e1)
    interface = pair(upper, lower)
    assert interface.fine.area == pytest.approx((1.0 - 0.45) * (0.8 - 0.3), rel=1e-12)
    np.testing.assert_allclose(interface.fine.gap0, 0.0, atol=1e-15)


def hole_polygon_area(lower, radius):
    """Area of the drilled box's hole: the 'hole' face set's corner polygon at the top."""
    ring = lower.points[lower.node_sets["hole"]]
    top = ring[np.isclose(ring[:, 2], ring[:, 2].max())]
    centre = top[:, :2].mean(axis=0)
    # polygon vertices lie on the circle; midside nodes of straight edges lie inside it
    top = top[np.isclose(np.linalg.norm(top[:, :2] - centre, axis=1), radius, rtol=1e-9)]
    angles = np.sort(np.arctan2(top[:, 1] - centre[1], top[:, 0] - centre[0]))
    return 0.5 * radius ** 2 * np.sin(np.diff(np.r_[angles, angles[0] + 2 * np.pi])).sum()


@pytest.mark.parametrize("element", ["hexahedron", "tetra10"])
def test_drilled_face_area(element):
    lower = drilled_box((1.0, 1.0, 0.5), (12, 12, 2), (0.5, 0.5), 0.15, element=element)
    upper = box((1.0, 1.0, 0.5), (4, 4, 1), origin=(0, 0, 0.5))
    interface = pair(upper, lower)
    assert interface.fine.area == pytest.approx(1.0 - hole_polygon_area(lower, 0.15), rel=1e-12)


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron20"])
def test_pad_over_disc_area(element):
    disc = annular_disc(0.055, 0.14, 0.02, (8, 96, 1), element=element)
    n_theta, angle = 10, 50.0
    pad = brake_pad(0.09, 0.135, angle, 0.01, 0.005, (4, n_theta, 1, 1), z0=0.02,
                    element=element)
    interface = pair(pad, disc, "friction", "zmax")
    # the pad's corner polygon: n_theta trapezoids of the sector (quadratic faces are clipped by
    # their corner polygons)
    dtheta = np.radians(angle) / n_theta
    area = n_theta * 0.5 * (0.135 ** 2 - 0.09 ** 2) * np.sin(dtheta)
    assert interface.fine.area == pytest.approx(area, rel=1e-12)


def test_rule_integrates_polynomials_of_its_degree_exactly():
    lower = drilled_box((1.0, 1.0, 0.5), (6, 6, 1), (0.5, 0.5), 0.2)
    upper = box((0.9, 0.7, 0.5), (3, 5, 1), origin=(0.05, 0.2, 0.5))
    for degree in (1, 2, 4, 6):
        fine = pair(upper, lower, degree=degree).fine
        x, y, w = fine.points[:, 0], fine.points[:, 1], fine.weights
        # reference: the same integral by a rule of much higher degree
        ref = pair(upper, lower, degree=degree + 6).fine
        xr, yr, wr = ref.points[:, 0], ref.points[:, 1], ref.weights
        for a in range(degree + 1):
            b = degree - a
            assert (w * x ** a * y ** b).sum() == pytest.approx(
                (wr * xr ** a * yr ** b).sum(), rel=1e-12)
    # the centroid rule is not exact for a quadratic (the comparison can fail)
    fine = pair(upper, lower, degree=1).fine
    assert abs((fine.weights * fine.points[:, 0] ** 2).sum() / (wr * xr ** 2).sum() - 1) > 1e-6


def test_rigid_motions_of_both_parts_give_zero_gap_energy():
    lower = drilled_box((1.0, 1.0, 0.5), (6, 6, 1), (0.5, 0.5), 0.2, element="tetra10")
    upper = box((0.9, 0.7, 0.5), (3, 5, 1), origin=(0.05, 0.2, 0.5), element="hexahedron20")
    interface = pair(upper, lower)
    A = gap_energy(interface.fine, 1e12)
    X = np.vstack([upper.points, lower.points])
    ndof = 3 * len(X)
    D = np.vstack([interface.side1.dof_map(ndof).toarray(),
                   interface.side2.dof_map(ndof).toarray()])
    C = interface.observation(interface.fine, ndof)
    k_w = 1e12 * interface.fine.weights
    rng = np.random.default_rng(0)
    for _ in range(3):
        omega, v = rng.standard_normal(3), rng.standard_normal(3)
        u = (np.cross(omega, X) + v).ravel()
        g = C @ u
        assert np.abs(g).max() <= 1e-14 * np.abs(u).max()
        q = D @ u     # the same through A on the interface normal dofs
        assert q @ A @ q <= 1e-14 * (k_w * (np.abs(u).max()) ** 2).sum()
    # a relative motion does cost energy (the test could fail)
    u = np.zeros(ndof)
    u[2:3 * upper.n_nodes:3] = 1.0
    q = D @ u
    assert q @ A @ q == pytest.approx(k_w.sum(), rel=1e-12)


def test_no_overlap_is_a_clear_error():
    lower = box((1.0, 1.0, 0.5), (2, 2, 1))
    upper = box((1.0, 1.0, 0.5), (2, 2, 1), origin=(3.0, 0.0, 0.5))
    with pytest.raises(InterfaceError, match="do not overlap"):
        pair(upper, lower)


def test_surfaces_that_do_not_face_each_other_are_an_error():
    lower = box((1.0, 1.0, 0.5), (2, 2, 1))
    upper = box((1.0, 1.0, 0.5), (2, 2, 1), origin=(0.0, 0.0, 0.5))
    with pytest.raises(InterfaceError, match="do not face"):
        pair(upper, lower, set1="zmax")


def drilled_cube_spectrum(lower_div=(12, 12, 2), upper_div=(4, 4, 1)):
    lower = drilled_box((0.1, 0.1, 0.1), lower_div, (0.05, 0.05), 0.015, element="tetra10")
    upper = box((0.1, 0.1, 0.1), upper_div, origin=(0, 0, 0.1))
    comp = compatibility(pair(upper, lower).fine, 1e13)
    return comp, (upper_div[0] + 1) * (upper_div[1] + 1)


def largest_jump(s, lo, hi):
    ratio = s[lo:hi] / np.maximum(s[lo - 1:hi - 1], 1e-300)
    return lo + int(np.argmax(ratio)), float(ratio.max())


def test_drilled_cube_nested_spectrum_jumps_after_the_coarse_node_count():
    comp, n_coarse = drilled_cube_spectrum()
    s = comp.normalized
    assert n_coarse == 25 and comp.n1 == 25
    assert np.all(s[:25] < 1e-10)                  # nested: compatible to round-off
    index, ratio = largest_jump(s, 15, 41)
    assert index == 25 and s[25] / s[24] >= 10     # sigma_26 / sigma_25, 1-based
    assert comp.curve([1e-10])[0] == 1.0            # C(eps) = 25 / min(25, N2)


@pytest.mark.parametrize("lower_div, upper_div", [((12, 12, 2), (3, 3, 1)),
                                                  ((13, 13, 2), (4, 4, 1)),
                                                  ((12, 12, 2), (5, 5, 1))])
def test_changing_a_division_moves_the_jump_to_the_coarse_node_count(lower_div, upper_div):
    comp, n_coarse = drilled_cube_spectrum(lower_div, upper_div)
    s = comp.normalized
    index, ratio = largest_jump(s, max(2, n_coarse - 10), n_coarse + 16)
    assert index == n_coarse and ratio >= 10
    eps, how = auto_eps(s)
    assert comp.kept(eps) == n_coarse, how


def test_auto_eps_ignores_the_few_exactly_shared_fields_and_falls_back_without_a_jump():
    # non-nested meshes share a few fields exactly (round-off zeros), then spread up to the jump
    s = np.r_[np.full(4, 1e-17), np.geomspace(2e-7, 3e-5, 21), np.geomspace(8e-4, 1.0, 100)]
    eps, _ = auto_eps(s)
    assert 3e-5 < eps < 8e-4
    eps, how = auto_eps(np.r_[np.full(4, 1e-17), np.geomspace(1e-9, 1.0, 500)])
    assert eps == FALLBACK_EPS and "fallback" in how
    # a jump below CLEAN is round-off and nearly shared fields, not a level: the bottom of a
    # 1M-dof tet10 pad and disc's spectrum (14 shapes kept before, of a continuous spectrum)
    tet10 = [0.0, 0.0, 0.0, 1.47e-15, 1.77e-15, 3.25e-14, 3.63e-14, 8.87e-14, 1.47e-13, 2.0e-13,
             2.93e-13, 5.24e-13, 6.32e-13, 1.77e-12, 2.14e-11, 2.41e-11, 4.3e-11, 5.15e-11]
    eps, how = auto_eps(np.r_[tet10, np.geomspace(6.7e-11, 1.0, 5585)])
    assert eps == FALLBACK_EPS and "fallback" in how


def bump(mesh, amplitude, z_surface):
    """The mesh with nodes moved along z by a smooth bump that vanishes at x, y = 0 and 1 and
    fades away from the plane z = z_surface (both parts describe the same curved surface)."""
    p = mesh.points.copy()
    fade = np.clip(1 - np.abs(p[:, 2] - z_surface) / 0.5, 0, 1)
    p[:, 2] += amplitude * np.sin(np.pi * p[:, 0]) * np.sin(np.pi * p[:, 1]) * fade
    return type(mesh)(p, mesh.cells, mesh.node_sets, mesh.face_sets, mesh.cell_sets)


def test_curved_quadratic_faces_close_to_planar():
    a = 0.01      # bump height over a unit square: slopes up to 3%
    lower = bump(box((1.0, 1.0, 0.5), (6, 6, 1), element="hexahedron20"), a, 0.5)
    upper = bump(box((1.0, 1.0, 0.5), (4, 4, 1), origin=(0, 0, 0.5), element="tetra10"), a, 0.5)
    interface = pair(upper, lower)
    fine = interface.fine
    # projected area exact; the two discretizations of the same surface agree to their
    # quadratic interpolation error (~ (pi h)^3 a / 24 for the coarse side: 2% of a)
    assert fine.area == pytest.approx(1.0, rel=1e-12)
    assert np.abs(fine.gap0).max() < 0.02 * a
    # normals follow the surface
    assert np.abs(fine.normals[:, :2]).max() > 0.5 * np.pi * a
    # normal dofs use node normals, which the two meshes approximate differently: a rigid
    # translation leaves a gap of second order in the slope (exactly zero on planar interfaces)
    X = np.vstack([upper.points, lower.points])
    C = interface.observation(fine, 3 * len(X))
    g = C @ np.tile([0.0, 0.0, 1.0], len(X))
    assert np.abs(g).max() < (np.pi * a) ** 2


def test_fine_points_all_carry_weight():
    # clipped polygons have collinear vertices; their degenerate fan triangles are dropped
    lower = drilled_box((0.1, 0.1, 0.1), (12, 12, 2), (0.05, 0.05), 0.015, element="tetra10")
    upper = box((0.1, 0.1, 0.1), (4, 4, 1), origin=(0, 0, 0.1))
    fine = pair(upper, lower).fine
    assert fine.weights.min() > 1e-9 * fine.weights.max()
