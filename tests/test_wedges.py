"""The wedges (triangular prisms), wedge6 and wedge15: their shape functions and faces, their
rule, K and M against gmsh's own shape functions, the mass they integrate, a cantilever's
frequencies, a pad in wedges on the pad_disc scene's disc, a mesh of tets and prisms from
gmsh, and their VTU files as VTK reads them.

scikit-fem 12 has a linear wedge but no quadratic one (tests/test_assembly_reference.py
compares wedge6 with it); gmsh evaluates the shape functions of both its prisms (6 and 15
nodes), so K and M are checked against a plain NumPy assembly on gmsh's functions. The patch
test (tests/test_patch.py), the rigid modes (tests/test_assembly_reference.py), the
generators' geometry (tests/test_generators.py) and the transforms (tests/test_transform.py)
run over every volume type, wedges included.
"""
from math import factorial
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from transient.mesh import generators
from transient.mesh.elements import ELEMENTS
from transient.mesh.mesh import Mesh, boundary_faces
from transient.mesh.meshfile import jacobian_check, read_mesh, write_vtu
from transient.mesh.quadrature import rule
from transient.model.assembly import CellBlock, assemble, lame

from distorted import distorted_box

E, NU, RHO = 2.1e11, 0.3, 7850.0
WEDGES = ("wedge", "wedge15")


def face_reference_points(el, face, xi2):
    """The wedge's reference points of face points xi2 (n, 2) given in the face element's
    own reference cell: the face's corners interpolated by its linear shape functions."""
    corners = el.nodes[list(face[:3 if len(face) in (3, 6) else 4])]
    linear = ELEMENTS["triangle" if len(corners) == 3 else "quad"]
    return linear.shape_functions(xi2) @ corners


@pytest.mark.parametrize("ctype", WEDGES)
def test_shape_functions_are_nodal_complete_and_their_faces_are_the_face_elements(ctype):
    el = ELEMENTS[ctype]
    np.testing.assert_allclose(el.shape_functions(el.nodes), np.eye(el.nen), atol=1e-15)
    rng = np.random.default_rng(1)
    a, b = rng.uniform(0, 1, (2, 50))
    xi = np.column_stack([a * (1 - b), b * a * 0.999, rng.uniform(-1, 1, 50)])
    N, dN = el.shape_functions(xi), el.shape_derivatives(xi)
    # linear fields exactly (conformity's and the patch test's requirement), and for wedge15
    # the quadratic ones of the triangle times those of zeta
    X = el.nodes
    np.testing.assert_allclose(N @ X, xi, atol=1e-14)
    np.testing.assert_allclose(np.einsum("gad,ak->gkd", dN, X), np.broadcast_to(np.eye(3),
                               (50, 3, 3)), atol=1e-13)
    if ctype == "wedge15":
        for f in (lambda x: x[:, 0] * x[:, 1], lambda x: x[:, 0] ** 2,
                  lambda x: x[:, 1] * x[:, 2], lambda x: x[:, 2] ** 2,
                  lambda x: x[:, 0] * x[:, 2]):
            np.testing.assert_allclose(N @ f(X), f(xi), atol=1e-14)
    h = 1e-6
    fd = np.stack([(el.shape_functions(xi + h * e) - el.shape_functions(xi - h * e)) / (2 * h)
                   for e in np.eye(3)], axis=2)
    np.testing.assert_allclose(dN, fd, atol=1e-8)
    # on each face the element's functions are the face element's, node for node (so a
    # wedge's face meets a tet's or a hex's, and carries a pressure or a contact), and vanish
    # at the other nodes; the faces are outward (their normal leaves the centroid)
    centroid = el.nodes[:el.n_corners].mean(axis=0)
    for face, ftype in zip(el.faces, el.face_types):
        fe = ELEMENTS[ftype]
        assert fe.nen == len(face)
        at = face_reference_points(el, face, fe.nodes)
        np.testing.assert_allclose(at, el.nodes[list(face)], atol=1e-15)
        pts = fe.rule(4)[0]
        values = el.shape_functions(face_reference_points(el, face, pts))
        np.testing.assert_allclose(values[:, list(face)], fe.shape_functions(pts), atol=1e-14)
        others = np.setdiff1d(np.arange(el.nen), face)
        assert np.abs(values[:, others]).max() < 1e-14
        p = el.nodes[list(face[:3])]
        normal = np.cross(p[1] - p[0], p[2] - p[0])
        assert normal @ (p.mean(axis=0) - centroid) > 0
    tri, quad = ("triangle", "quad") if ctype == "wedge" else ("triangle6", "quad8")
    assert el.face_types == (tri, tri, quad, quad, quad)


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 5, 6])
def test_the_wedge_rule_integrates_its_degree_in_the_triangle_and_along_zeta(degree):
    xi, w = rule("wedge", degree)
    assert (w > 0).all()
    for a in range(degree + 1):
        for b in range(degree + 1 - a):
            for c in range(degree + 1):
                exact = factorial(a) * factorial(b) / factorial(a + b + 2) \
                    * (1 - (-1) ** (c + 1)) / (c + 1)
                got = w @ (xi[:, 0] ** a * xi[:, 1] ** b * xi[:, 2] ** c)
                assert abs(got - exact) < 1e-15


def gmsh_functions(ctype, xi):
    """gmsh's shape functions (ng, nen) and reference gradients (ng, nen, 3) of its prism of
    ctype's nodes at our reference points xi (gmsh's prism is the same cell), its nodes put
    in our order by their reference coordinates."""
    gmsh = pytest.importorskip("gmsh")
    code = {"wedge": 6, "wedge15": 18}[ctype]
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        _, _, _, nen, local, _ = gmsh.model.mesh.getElementProperties(code)
        flat = np.asarray(xi, float).ravel().tolist()
        _, N, _ = gmsh.model.mesh.getBasisFunctions(code, flat, "Lagrange")
        _, G, _ = gmsh.model.mesh.getBasisFunctions(code, flat, "GradLagrange")
    finally:
        gmsh.finalize()
    local = np.reshape(local, (nen, 3))
    d = np.linalg.norm(ELEMENTS[ctype].nodes[:, None] - local[None], axis=2)
    order = d.argmin(axis=1)
    assert np.allclose(d.min(axis=1), 0.0) and len(set(order)) == nen
    return (np.reshape(N, (len(xi), nen))[:, order],
            np.reshape(G, (len(xi), nen, 3))[:, order])


def reference_operators(points, conn, ctype):
    """Dense K and M by plain NumPy from gmsh's shape functions at our rule's points."""
    el = ELEMENTS[ctype]
    ne, nen = conn.shape
    lam, mu = lame(E, NU)
    D = lam * np.outer([1, 1, 1, 0, 0, 0], [1, 1, 1, 0, 0, 0]) + mu * np.diag([2, 2, 2, 1, 1, 1])
    ndof = 3 * len(points)
    K, M = np.zeros((ndof, ndof)), np.zeros((ndof, ndof))
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(ne, -1)
    for degree, target in ((el.stiffness_degree, K), (el.mass_degree, M)):
        xi, w = el.rule(degree)
        N, G = gmsh_functions(ctype, xi)
        J = np.einsum("eak,gad->egkd", points[conn], G)
        det = np.linalg.det(J)
        dx = np.einsum("gad,egdk->egak", G, np.linalg.inv(J))      # dN_a / dx_k
        if target is K:
            B = np.zeros((ne, len(w), 6, nen, 3))
            for i in range(3):
                B[:, :, i, :, i] = dx[..., i]
            for row, (i, j) in zip((3, 4, 5), ((1, 2), (0, 2), (0, 1))):
                B[:, :, row, :, i] = dx[..., j]
                B[:, :, row, :, j] = dx[..., i]
            B = B.reshape(ne, len(w), 6, 3 * nen)
            blocks = np.einsum("egia,ij,egjb,eg,g->eab", B, D, B, det, w)
        else:
            scalar = RHO * np.einsum("ga,gb,eg,g->eab", N, N, det, w)
            blocks = np.einsum("eab,ij->eaibj", scalar, np.eye(3)).reshape(ne, 3 * nen,
                                                                            3 * nen)
        for e in range(ne):
            target[np.ix_(dofs[e], dofs[e])] += blocks[e]
    return K, M


def ours(points, conn, ctype):
    ne = len(conn)
    return assemble(points, [CellBlock(ctype, conn, np.full(ne, E), np.full(ne, NU),
                                       np.full(ne, RHO))])


@pytest.mark.parametrize("ctype, curved", [("wedge", False), ("wedge15", False),
                                           ("wedge15", True)])
def test_k_and_m_match_a_numpy_assembly_on_gmsh_s_shape_functions(ctype, curved):
    points, conn = distorted_box(ctype, curved, seed=3, divisions=(2, 2, 2),
                                 size=(0.3, 0.2, 0.1))
    ops = ours(points, conn, ctype)
    assert min(d.min() for d in ops.min_det) > 0
    K, M = reference_operators(points, conn, ctype)
    assert abs(ops.K.toarray() - K).max() < 1e-12 * abs(K).max()
    assert abs(ops.M.toarray() - M).max() < 1e-12 * abs(M).max()


@pytest.mark.parametrize("ctype", WEDGES)
def test_the_mass_is_the_density_times_the_volume_and_lumps_positive(ctype):
    # interior corners moved: the cells are distorted, the block's volume is still its size's
    size = np.array([0.3, 0.2, 0.1])
    mesh = generators.box(size, (3, 3, 3), element=ctype)
    el, conn = ELEMENTS[ctype], mesh.cells[ctype]
    boundary = np.unique(np.concatenate([f.ravel() for f in boundary_faces(mesh).values()]))
    corners = np.setdiff1d(np.unique(conn[:, :el.n_corners]), boundary)
    points = mesh.points.copy()
    points[corners] += np.random.default_rng(0).uniform(-0.2, 0.2, (len(corners), 3)) * size / 3
    for k, (a, b) in enumerate(el.edges):
        points[conn[:, el.n_corners + k]] = 0.5 * (points[conn[:, a]] + points[conn[:, b]])
    ops = ours(points, conn, ctype)
    mass = RHO * size.prod()
    x = np.zeros(ops.M.shape[0])
    x[0::3] = 1.0                                       # a unit translation along x
    assert x @ (ops.M @ x) == pytest.approx(mass, rel=1e-12)
    assert ops.lumped_mass.min() > 0
    assert ops.lumped_mass[0::3].sum() == pytest.approx(mass, rel=1e-12)
    assert jacobian_check(Mesh(points, {ctype: conn}))[0][2] > 0


def cantilever_frequencies(element, divisions, count=6):
    """The six lowest frequencies [Hz] of a steel bar 200 x 20 x 20 mm clamped at x = 0."""
    mesh = generators.box((0.2, 0.02, 0.02), divisions, element=element)
    ops = ours(mesh.points, mesh.cells[element], element)
    free = np.ones(ops.K.shape[0], bool)
    free[(3 * mesh.node_sets["xmin"][:, None] + np.arange(3)).ravel()] = False
    lam = spla.eigsh(ops.K[free][:, free].tocsc(), count, ops.M[free][:, free].tocsc(),
                     sigma=0, return_eigenvectors=False)
    return np.sqrt(np.sort(lam)) / (2 * np.pi)


def test_a_cantilever_in_wedges_has_the_frequencies_of_hex20_and_of_beam_theory():
    f20 = cantilever_frequencies("hexahedron20", (20, 2, 2))
    f15 = cantilever_frequencies("wedge15", (20, 2, 2))
    # two bending pairs (y and z), the torsion, the axial mode, in that order; both
    # quadratic meshes have 2 cells across: they share their discretization error, and the
    # wedges' split of each hex adds little to it
    np.testing.assert_allclose(f15, f20, rtol=1e-3)
    # the first bending pair (Euler-Bernoulli), the torsion (Saint-Venant's, a square: J =
    # 0.1406 h^4, polar moment h^4 / 6) and the axial mode (a bar): the theories leave out the
    # clamp's 3-D restraint, shear and the section's warping, each a percent or less at
    # L / h = 10 on these modes (the second bending pair's shear is several percent:
    # tests/test_modes.py checks it against Timoshenko's beam)
    h, L = 0.02, 0.2
    G = E / (2 * (1 + NU))
    closed = [1.875104 ** 2 / (2 * np.pi * L ** 2) * np.sqrt(E * h ** 2 / 12 / RHO),
              np.sqrt(G * 0.1406 * 6 / RHO) / (4 * L), np.sqrt(E / RHO) / (4 * L)]
    np.testing.assert_allclose(f15[[0, 1, 4, 5]], np.array(closed)[[0, 0, 1, 2]], rtol=0.02)
    # wedge6: second order convergence, the error quartering when the cells halve (against
    # hex20 here, whose own error is a small part of the wedge6's); the axial mode, already
    # near hex20's own error, is left out of the rate
    e1 = np.abs(cantilever_frequencies("wedge", (20, 2, 2)) / f20 - 1)[:5]
    e2 = np.abs(cantilever_frequencies("wedge", (40, 4, 4)) / f20 - 1)[:5]
    assert (e1 / e2 > 3.0).all() and e2.max() < 0.15


@pytest.mark.slow
def test_a_pad_in_wedge15_on_the_disc_has_the_modes_of_a_pad_in_hex20():
    """The pad_disc scene, its pad's friction face triangles in contact with the disc's
    quadrilaterals: the same divisions in hex20 and in wedge15 give the same modes but for
    their discretization errors, small on the disc's modes, larger on the coarse pad's own."""
    from small_cases import PAD_DISC

    from transient import api
    case = Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml"
    f = {el: api.modes(api.load(case, PAD_DISC + [f'parts.pad.mesh.element="{el}"']))
         .frequencies for el in ("hex20", "wedge15")}
    assert len(f["wedge15"]) == len(f["hex20"]) > 20
    np.testing.assert_allclose(f["wedge15"][:12], f["hex20"][:12], rtol=1e-3)
    np.testing.assert_allclose(f["wedge15"], f["hex20"], rtol=0.02)


def gmsh_mixed(path, order):
    """A 40 x 20 x 10 mm block from gmsh: a layer of prisms 4 mm thick swept from a triangle
    mesh of its base (a boundary layer), tetrahedra above it on the prisms' top triangles;
    physical groups 'block' (the volume) and 'base' (the bottom face)."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mixed")
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0.0) for x, y in ((0, 0), (0.04, 0), (0.04, 0.02), (0, 0.02))]
        lines = [geo.addLine(p[k], p[(k + 1) % 4]) for k in range(4)]
        base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        prisms = geo.extrude([(2, base)], 0, 0, 0.004, numElements=[2], recombine=True)
        top = [e for e in prisms if e[0] == 2][0]
        tets = geo.extrude([top], 0, 0, 0.006)
        geo.synchronize()
        volumes = [e[1] for e in prisms + tets if e[0] == 3]
        gmsh.model.addPhysicalGroup(3, volumes, name="block")
        gmsh.model.addPhysicalGroup(2, [base], name="base")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.006)
        gmsh.option.setNumber("Mesh.ElementOrder", order)
        # 15-node prisms (the 18-node ones add nodes at the centres of the quadrilaterals)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


@pytest.mark.parametrize("order, types, base", [(1, ("tetra", "wedge"), "triangle"),
                                                (2, ("tetra10", "wedge15"), "triangle6")])
def test_a_mesh_of_tets_on_a_layer_of_prisms_is_conforming_and_passes_the_patch_test(
        tmp_path, order, types, base):
    mesh = read_mesh(gmsh_mixed(tmp_path / "mixed.msh", order))
    assert sorted(mesh.cells) == sorted(types)
    assert all(det > 0 for _, _, det in jacobian_check(mesh))
    # the triangles between prisms and tets are inside: the boundary is the block's surface,
    # the prisms' sides quadrilaterals, every other face a triangle
    boundary = boundary_faces(mesh)
    area = {}
    for ftype, faces in boundary.items():
        p = mesh.points[faces[:, :ELEMENTS[ftype].n_corners]]
        a = sum(np.cross(p[:, k] - p[:, 0], p[:, k + 1] - p[:, 0])
                for k in range(1, p.shape[1] - 1))
        area[ELEMENTS[ftype].shape] = 0.5 * np.linalg.norm(a, axis=1).sum()
    assert area["quad"] == pytest.approx(2 * (0.04 + 0.02) * 0.004, rel=1e-12)
    assert sum(area.values()) == pytest.approx(2 * (0.04 * 0.02 + 0.06 * 0.01), rel=1e-12)
    assert list(mesh.face_sets["base"]) == [base]
    # patch test: the boundary nodes carry a linear field, the interior ones are solved for
    blocks = [CellBlock(t, c, np.full(len(c), E), np.full(len(c), NU), np.full(len(c), RHO))
              for t, c in mesh.cells.items()]
    ops = assemble(mesh.points, blocks)
    B = np.array([[1.0, 0.3, -0.7], [-0.2, -0.5, 0.9], [0.4, 1.1, 0.6]]) * 1e-3
    exact = (np.array([1e-3, -2e-3, 5e-4]) + mesh.points @ B.T).ravel()
    outer = np.unique(np.concatenate([f.ravel() for f in boundary.values()]))
    fixed = (3 * outer[:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(len(exact)), fixed)
    assert len(free) > 0
    K = ops.K.tocsr()
    u = exact.copy()
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -K[free][:, fixed] @ exact[fixed])
    assert abs(u - exact).max() < 1e-10 * abs(exact).max()


BLOCK = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0
[parts.block]
material = "steel"
[parts.block.mesh]
{mesh}
[constraints.clamp]
set = "block.{clamp}"
[solver.modes]
count = 8
"""


@pytest.mark.slow
def test_a_clamped_block_of_tets_on_prisms_has_the_modes_of_hex20(tmp_path):
    """The mixed mesh through a case file (two cell blocks in one part) against the same
    block in hex20 cells half as large: quadratic cells of either size are a fraction of a
    percent off the converged frequencies here, so the two agree to a percent."""
    from transient import api
    mixed = gmsh_mixed(tmp_path / "mixed.msh", 2)
    found = {}
    for name, mesh, clamp in (("mixed", f'kind = "file"\npath = "{mixed}"', "base"),
                              ("hex20", 'kind = "box"\nsize = [0.04, 0.02, 0.01]\n'
                                        'divisions = [16, 8, 4]\nelement = "hex20"', "zmin")):
        case = tmp_path / f"{name}.toml"
        case.write_text(BLOCK.format(mesh=mesh, clamp=clamp))
        found[name] = api.modes(api.load(case)).frequencies
    np.testing.assert_allclose(found["mixed"], found["hex20"], rtol=0.01)


@pytest.mark.parametrize("ctype", WEDGES)
def test_vtu_wedges_are_valid_cells_for_vtk_and_read_back(tmp_path, ctype):
    pyvista = pytest.importorskip("pyvista")
    vtk = pytest.importorskip("vtk")
    mesh = generators.box((0.3, 0.2, 0.1), (3, 2, 2), element=ctype)
    path = tmp_path / "wedges.vtu"
    write_vtu(path, mesh)
    grid = pyvista.read(path)
    assert set(grid.celltypes) == {13 if ctype == "wedge" else 26}   # VTK_(QUADRATIC_)WEDGE
    volumes = grid.compute_cell_sizes()["Volume"]
    assert volumes.min() > 0 and volumes.sum() == pytest.approx(0.006, rel=1e-12)
    validator = vtk.vtkCellValidator()
    validator.SetInputData(grid)
    validator.Update()
    assert set(pyvista.wrap(validator.GetOutput())["ValidityState"]) == {0}   # valid
    back = read_mesh(path)
    np.testing.assert_array_equal(back.cells[ctype], mesh.cells[ctype])
    assert set(back.node_sets) == set(mesh.node_sets)
