"""Tests of transient.meshfile: reading Gmsh, Abaqus and VTU files, writing VTU, Jacobian check."""
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest

from transient.mesh.elements import ELEMENTS
from transient.mesh.mesh import Mesh
from transient.mesh.meshfile import MeshFileError, jacobian_check, read_mesh, write_vtu

DATA = Path(__file__).parent / "data"

# Unit cube corners in VTK order (positive volume).
CUBE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                 [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)


def quad_normal(points, face):
    """Unit normal of a quad by the cross product of its diagonals (right-hand rule)."""
    p = points[face[:4]]
    n = np.cross(p[2] - p[0], p[3] - p[1])
    return n / np.linalg.norm(n)


def tri_normal(points, face):
    p = points[face[:3]]
    n = np.cross(p[1] - p[0], p[2] - p[0])
    return n / np.linalg.norm(n)


def with_midsides(corners, conn, ctype):
    """Points and connectivity of a quadratic mesh made from linear cells, one node per edge."""
    points = [tuple(p) for p in corners]
    index = {}
    rows = []
    for cell in conn:
        row = list(cell)
        for a, b in ELEMENTS[ctype].edges:
            key = frozenset((cell[a], cell[b]))
            if key not in index:
                index[key] = len(points)
                points.append(tuple(0.5 * (corners[cell[a]] + corners[cell[b]])))
            row.append(index[key])
        rows.append(row)
    return np.array(points), np.array(rows, dtype=np.int64)


def two_tet10():
    """Two straight-sided tet10 cells sharing a face."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    return with_midsides(corners, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), "tetra10")


def quadratic(x):
    """A full quadratic polynomial in x (n, 3)."""
    X, Y, Z = x.T
    return 1 + X + 2 * Y - Z + X * X + 3 * X * Y - Y * Z + 2 * Z * Z


@pytest.mark.parametrize("name", ["two_hex_v2.msh", "two_hex_v4.msh"])
def test_gmsh_hex8_physical_groups_and_outward_faces(name):
    mesh = read_mesh(DATA / name)
    assert mesh.points.shape == (12, 3)
    assert list(mesh.cells) == ["hexahedron"]
    assert len(mesh.cells["hexahedron"]) == 2
    assert set(mesh.cell_sets) == {"solid"}
    np.testing.assert_array_equal(mesh.cell_sets["solid"]["hexahedron"], [0, 1])
    # The physical curve 'edge' holds only a line cell: ignored.
    assert set(mesh.face_sets) == {"top", "end"}
    assert set(mesh.node_sets) == {"top", "end"}
    np.testing.assert_array_equal(mesh.node_sets["top"], np.flatnonzero(mesh.points[:, 2] == 1))
    np.testing.assert_array_equal(mesh.node_sets["end"], np.flatnonzero(mesh.points[:, 0] == 2))
    # One 'top' quad is written clockwise seen from above (inward) in the file.
    for name, outward in (("top", [0, 0, 1]), ("end", [1, 0, 0])):
        faces = mesh.face_sets[name]["quad"]
        assert len(faces) == (2 if name == "top" else 1)
        for face in faces:
            np.testing.assert_allclose(quad_normal(mesh.points, face), outward, atol=1e-12)


def test_abaqus_tet10_sets_and_positive_jacobian():
    mesh = read_mesh(DATA / "two_tet10.inp")
    # Node 199 is used by no cell: removed, also from the node set 'base' that lists it.
    assert mesh.points.shape == (14, 3)
    assert not np.any(np.all(mesh.points == 7.0, axis=1))
    assert list(mesh.cells) == ["tetra10"]
    np.testing.assert_array_equal(mesh.cell_sets["solid"]["tetra10"], [0, 1])
    np.testing.assert_array_equal(mesh.cell_sets["cap"]["tetra10"], [1])
    np.testing.assert_array_equal(mesh.cell_sets["mixed"]["tetra10"], [0])
    assert "skin" not in mesh.cell_sets
    base = np.flatnonzero(mesh.points[:, 2] == 0)
    np.testing.assert_array_equal(mesh.node_sets["base"], base)
    np.testing.assert_array_equal(mesh.node_sets["corners"], [0, 1, 2, 3, 4])
    # The STRI65 skin, written inward, is both a face set and (by its nodes) a node set.
    for name in ("skin", "mixed"):
        (face,) = mesh.face_sets[name]["triangle6"]
        np.testing.assert_allclose(tri_normal(mesh.points, face), [0, 0, -1], atol=1e-12)
        edges = ((0, 1), (1, 2), (2, 0))
        for k, (a, b) in enumerate(edges):
            np.testing.assert_allclose(mesh.points[face[3 + k]],
                                       0.5 * (mesh.points[face[a]] + mesh.points[face[b]]))
        np.testing.assert_array_equal(mesh.node_sets[name], base)
    ((ctype, _, det),) = jacobian_check(mesh)
    assert ctype == "tetra10" and det > 0


def test_vtu_round_trip(tmp_path):
    hex_points = 0.5 * (ELEMENTS["hexahedron20"].nodes + 1)                # unit cube
    tet_points = ELEMENTS["tetra10"].nodes + [2.0, 0.0, 0.0]               # beside it
    points = np.vstack([hex_points, tet_points])
    mesh = Mesh(points, {"hexahedron20": np.arange(20)[None], "tetra10": 20 + np.arange(10)[None]},
                node_sets={"left": np.flatnonzero(points[:, 0] == 0)},
                cell_sets={"tet": {"tetra10": np.array([0])}})
    u = np.column_stack([points[:, 0], -points[:, 1], 2 * points[:, 2]])
    path = tmp_path / "out.vtu"
    write_vtu(path, mesh, point_data={"u": u, "T": points[:, 2]},
              cell_data={"id": {"hexahedron20": np.array([7]), "tetra10": np.array([8])}})

    back = read_mesh(path)
    np.testing.assert_array_equal(back.points, mesh.points)
    assert list(back.cells) == list(mesh.cells)
    for ctype in mesh.cells:
        np.testing.assert_array_equal(back.cells[ctype], mesh.cells[ctype])
    np.testing.assert_array_equal(back.node_sets["left"], mesh.node_sets["left"])
    assert set(back.node_sets) == {"left"}
    assert set(back.cell_sets) == {"tet"}
    np.testing.assert_array_equal(back.cell_sets["tet"]["tetra10"], [0])

    raw = meshio.read(path)
    np.testing.assert_array_equal(raw.point_data["u"], u)
    assert list(raw.point_data["set:left"]) == [1 if x == 0 else 0 for x in points[:, 0]]


def test_vtu_opens_in_vtk(tmp_path):
    pyvista = pytest.importorskip("pyvista")
    points, conn = two_tet10()
    path = tmp_path / "tets.vtu"
    write_vtu(path, Mesh(points, {"tetra10": conn}, node_sets={"a": np.array([0, 4])}))
    grid = pyvista.read(path)
    assert grid.n_cells == 2
    assert list(grid.celltypes) == [24, 24]     # VTK_QUADRATIC_TETRA
    assert list(np.flatnonzero(grid.point_data["set:a"])) == [0, 4]


def tet10_gmsh_files(tmp_path):
    points, conn = two_tet10()
    source = meshio.Mesh(points, [("tetra10", conn)],
                         cell_data={"gmsh:physical": [np.ones(2, int)],
                                    "gmsh:geometrical": [np.ones(2, int)]})
    paths = [DATA / "one_tet10_gmsh_order.msh"]
    for fmt in ("gmsh22", "gmsh"):
        paths.append(tmp_path / f"{fmt}.msh")
        meshio.write(paths[-1], source, file_format=fmt, binary=False)
    return paths


def test_gmsh_tet10_midside_ordering(tmp_path):
    el = ELEMENTS["tetra10"]
    rng = np.random.default_rng(1)
    xi = rng.dirichlet(np.ones(4), size=30)[:, 1:]       # points inside the reference tet
    N = el.shape_functions(xi)
    for path in tet10_gmsh_files(tmp_path):
        mesh = read_mesh(path)
        for cell in mesh.cells["tetra10"]:
            X = mesh.points[cell]
            for k, (a, b) in enumerate(el.edges):
                np.testing.assert_allclose(X[4 + k], 0.5 * (X[a] + X[b]), err_msg=str(path))
            # A quadratic field is interpolated exactly only with the right node order.
            np.testing.assert_allclose(N @ quadratic(X), quadratic(N @ X), rtol=1e-12,
                                       err_msg=str(path))


def test_gmsh_tet10_numbering_and_unnamed_physical_groups(tmp_path):
    points, conn = two_tet10()
    by_hand, v2, v4 = tet10_gmsh_files(tmp_path)
    # Physical tag 0 means no physical group.
    assert read_mesh(by_hand).set_names() == []
    for path in (v2, v4):
        mesh = read_mesh(path)
        np.testing.assert_array_equal(mesh.points, points)
        np.testing.assert_array_equal(mesh.cells["tetra10"], conn)
    # A physical group without a name is known by its number. (meshio's v4.1 writer drops
    # physical groups, so only the v2 file has it.)
    mesh = read_mesh(v2)
    assert mesh.set_names() == ["1"]
    np.testing.assert_array_equal(mesh.cell_sets["1"]["tetra10"], [0, 1])


def write_pyramid(path):
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]])
    meshio.write(path, meshio.Mesh(points, [("pyramid", np.array([[0, 1, 2, 3, 4]]))]))


def write_garbage(path):
    path.write_text("$MeshFormat\nthis is not a mesh\n")


def write_triangles_only(path):
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    meshio.write(path, meshio.Mesh(points, [("triangle", np.array([[0, 1, 2]]))]))


@pytest.mark.parametrize("name, write, words", [
    ("missing.msh", None, "no such file"),
    ("garbage.msh", write_garbage, "cannot read"),
    ("pyramid.vtu", write_pyramid, "unsupported cell type 'pyramid'"),
    ("triangles.vtu", write_triangles_only, "no volume cells"),
])
def test_errors(tmp_path, name, write, words):
    path = tmp_path / name
    if write:
        write(path)
    with pytest.raises(MeshFileError) as info:
        read_mesh(path)
    assert info.value.path == str(path)
    assert str(path) in str(info.value)
    assert words in info.value.message
    assert "\n" not in str(info.value)


def two_hex_meshio(orphans):
    """Two unit hexes along x with orphan nodes inserted before the given point indices."""
    base = np.vstack([CUBE, CUBE[[1, 2, 5, 6]] + [1, 0, 0]])
    conn = np.array([[0, 1, 2, 3, 4, 5, 6, 7], [1, 8, 9, 2, 5, 10, 11, 6]])
    keep = np.insert(np.arange(len(base)), orphans, -1)   # -1 marks an orphan
    old_to_new = np.flatnonzero(keep >= 0)
    points = np.full((len(keep), 3), 99.0)
    points[old_to_new] = base
    return points, old_to_new[conn], old_to_new


def test_unused_nodes_removed_and_sets_remapped(tmp_path):
    points, conn, renum = two_hex_meshio(orphans=[0, 5, 12])
    orphan = 0
    top = np.array([[4, 5, 6, 7], [5, 10, 11, 6]])          # base numbering, z = 1
    path = tmp_path / "orphans.inp"
    meshio.write(path, meshio.Mesh(
        points, [("hexahedron", conn), ("quad", renum[top])],
        point_sets={"x0": np.append(renum[[0, 3, 4, 7]], orphan)},
        cell_sets={"second": [np.array([1]), np.array([], int)],
                   "top": [np.array([], int), np.array([0, 1])]}))
    mesh = read_mesh(path)
    assert mesh.n_nodes == 12
    np.testing.assert_array_equal(mesh.node_sets["x0"], np.flatnonzero(mesh.points[:, 0] == 0))
    np.testing.assert_array_equal(mesh.node_sets["top"], np.flatnonzero(mesh.points[:, 2] == 1))
    np.testing.assert_array_equal(mesh.cell_sets["second"]["hexahedron"], [1])
    np.testing.assert_allclose(mesh.points[mesh.cells["hexahedron"][1]].mean(axis=0), [1.5, .5, .5])
    for face in mesh.face_sets["top"]["quad"]:
        np.testing.assert_allclose(quad_normal(mesh.points, face), [0, 0, 1], atol=1e-12)


def test_interior_surface_cell_is_an_error(tmp_path):
    points, conn, _ = two_hex_meshio(orphans=[])
    path = tmp_path / "interior.inp"
    meshio.write(path, meshio.Mesh(
        points, [("hexahedron", conn), ("quad", np.array([[1, 2, 6, 5]]))],
        cell_sets={"middle": [np.array([], int), np.array([0])]}))
    with pytest.raises(MeshFileError, match="'middle'.*not on the boundary"):
        read_mesh(path)


def test_duplicate_volume_cells_from_gmsh_v2_are_merged(tmp_path):
    # Gmsh v2 writes a cell once per physical group it belongs to.
    points, conn, _ = two_hex_meshio(orphans=[])
    path = tmp_path / "dup.msh"
    meshio.write(path, meshio.Mesh(
        points, [("hexahedron", conn), ("hexahedron", conn[:1])],
        cell_data={"gmsh:physical": [np.array([1, 1]), np.array([2])],
                   "gmsh:geometrical": [np.array([1, 1]), np.array([1])]},
        field_data={"body": np.array([1, 3]), "first": np.array([2, 3])}),
        file_format="gmsh22", binary=False)
    mesh = read_mesh(path)
    np.testing.assert_array_equal(mesh.cells["hexahedron"], conn)
    np.testing.assert_array_equal(mesh.cell_sets["body"]["hexahedron"], [0, 1])
    np.testing.assert_array_equal(mesh.cell_sets["first"]["hexahedron"], [0])


def test_inverted_cell_is_kept_and_reported(tmp_path):
    points, conn, _ = two_hex_meshio(orphans=[])
    flipped = conn.copy()
    flipped[1] = conn[1][[4, 5, 6, 7, 0, 1, 2, 3]]          # top and bottom swapped
    path = tmp_path / "flipped.vtu"
    meshio.write(path, meshio.Mesh(points, [("hexahedron", flipped)]))
    mesh = read_mesh(path)
    np.testing.assert_array_equal(mesh.cells["hexahedron"], flipped)
    ((ctype, index, det),) = jacobian_check(mesh)
    assert (ctype, index) == ("hexahedron", 1)
    assert det == pytest.approx(-0.125)


@pytest.mark.parametrize("old, new, words", [
    ("*ELSET, ELSET=cap", "*ELSET, ELSET", "cell set without a name"),
    ("TYPE=C3D10, ELSET=solid", "TYPE=C3D10, ELSET", "cell set without a name"),
    ("*NSET, NSET=base", "*NSET, NSET", "node set without a name"),
])
def test_an_abaqus_set_without_a_name_is_an_error(tmp_path, old, new, words):
    path = tmp_path / "unnamed.inp"
    path.write_text((DATA / "two_tet10.inp").read_text().replace(old, new))
    with pytest.raises(MeshFileError, match=words):
        read_mesh(path)


@pytest.mark.parametrize("name, size", [("two_hex_v2.msh", 19), ("two_hex_v4.msh", 477)])
def test_a_file_cut_short_is_one_error_that_carries_what_meshio_said(tmp_path, name, size):
    # meshio warns of an unclosed section; what it reads has no cells, or hexahedra of 4 nodes
    path = tmp_path / name
    path.write_bytes((DATA / name).read_bytes()[:size])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(MeshFileError) as info:
            read_mesh(path)
    assert not caught, [str(w.message) for w in caught]
    assert info.value.path == str(path) and "\n" not in str(info.value)
    assert info.value.message.startswith("cut short")
    assert "(meshio: Warning: $" in info.value.message and "not closed" in info.value.message


def test_a_section_not_closed_is_refused_though_meshio_reads_cells(tmp_path):
    # two hexahedra and the faces before them: a later cut could have dropped some
    path = tmp_path / "unclosed.msh"
    path.write_text((DATA / "two_hex_v2.msh").read_text().replace("$EndElements\n", "", 1))
    assert len(meshio.read(path).cells_dict["hexahedron"]) == 2
    with pytest.raises(MeshFileError, match="cut short.*meshio: Warning: \\$Elements not"):
        read_mesh(path)


def test_what_meshio_said_of_a_mesh_that_is_taken_is_one_warning(tmp_path):
    # a third tag on a line cell, which meshio's Gmsh 2.2 reader leaves out
    path = tmp_path / "tags.msh"
    path.write_text((DATA / "two_hex_v2.msh").read_text().replace("\n1 1 2 4 1 1 2\n",
                                                                   "\n1 1 3 4 1 7 1 2\n"))
    with pytest.warns(UserWarning, match="meshio reading .*tag data") as caught:
        mesh = read_mesh(path)
    assert len(caught) == 1 and len(mesh.cells["hexahedron"]) == 2
