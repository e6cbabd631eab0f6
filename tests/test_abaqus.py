"""Abaqus decks read by transient.mesh.abaqus, on decks written elsewhere (HyperMesh's through
AbaqusReader.jl, CalculiX's test suite, gmsh's at test time): each surface's faces checked
against the geometry the deck describes, not against this reader."""
import re
from pathlib import Path

import numpy as np
import pytest

from transient.mesh.abaqus import read_abaqus
from transient.mesh.abaqus.types import ABAQUS_FACES, FACES
from transient.mesh.elements import ELEMENTS
from transient.mesh.meshfile import MeshFileError, read_mesh
from transient.mesh.selections import find_set

DATA = Path(__file__).parent / "data" / "abaqus"


def face_geometry(points, faces):
    """(area, unit normal by the right-hand rule, centroid) of each face, exact for flat
    faces: the corners' polygon split into triangles from its first corner."""
    nc = 4 if faces.shape[1] in (4, 8) else 3
    p = points[faces[:, :nc]]
    cross = sum(np.cross(p[:, k] - p[:, 0], p[:, k + 1] - p[:, 0]) for k in range(1, nc - 1))
    norm = np.linalg.norm(cross, axis=1)
    return 0.5 * norm, cross / norm[:, None], p.mean(axis=1)


def surface_lines(path):
    """name (upper case) -> data lines of each *SURFACE of a deck, read from its text."""
    out, name = {}, None
    for line in Path(path).read_text().splitlines():
        if line.startswith("*") and not line.startswith("**"):
            match = re.search(r"\bNAME\s*=\s*([^,\s]+)", line, re.I)
            name = match.group(1).upper() if re.match(r"\*SURFACE\s*,", line, re.I) else None
            if name:
                out[name] = []
        elif name and line.strip() and not line.startswith("**"):
            out[name].append(line)
    return out


def only_faces(mesh, name):
    ((ftype, faces),) = mesh.face_sets[name].items()
    return ftype, faces


def test_the_manual_face_table_names_each_face_of_each_solid_once():
    for ctype, faces in FACES.items():
        el = ELEMENTS[ctype]
        assert len(faces) == len(ABAQUS_FACES[el.shape]) == len(el.faces)
        assert sorted(faces) == sorted(el.faces)


def test_hypermesh_two_blocks_every_surface_is_its_side_of_the_box():
    """Two blocks of the unit cube, z < 0.5 and z > 0.5, meshed apart (tet4, non-matching)
    with surfaces on each side, given by element label and face S1-S4."""
    path = DATA / "hypermesh_two_blocks_tet4.inp"
    mesh = read_mesh(path)
    lines = surface_lines(path)
    assert set(mesh.face_sets) == {n for n in lines}
    boxes = {}
    for body in ("LOWER", "UPPER"):
        nodes = np.unique(mesh.cells["tetra"][mesh.cell_sets[body]["tetra"]])
        boxes[body] = (mesh.points[nodes].min(axis=0), mesh.points[nodes].max(axis=0))
    np.testing.assert_allclose(boxes["LOWER"], [[0, 0, 0], [1, 1, 0.5]], atol=1e-12)
    np.testing.assert_allclose(boxes["UPPER"], [[0, 0, 0.5], [1, 1, 1]], atol=1e-12)
    sides = {"BOTTOM": (2, 0), "TO_UPPER": (2, 1), "TO_LOWER": (2, 0), "TOP": (2, 1),
             "SYM13": (1, 0), "SYM23": (0, 0)}         # axis, low (0) or high (1) side
    for name in lines:
        body, side = name.split("_", 1)
        axis, end = sides[side]
        lo, hi = boxes[body]
        ftype, faces = only_faces(mesh, name)
        assert ftype == "triangle" and len(faces) == len(lines[name])
        area, normal, centroid = face_geometry(mesh.points, faces)
        outward = np.zeros(3)
        outward[axis] = 1.0 if end else -1.0
        np.testing.assert_allclose(normal, np.tile(outward, (len(faces), 1)), atol=1e-12)
        np.testing.assert_allclose(centroid[:, axis], (hi if end else lo)[axis], atol=1e-12)
        extent = np.delete(hi - lo, axis)
        assert area.sum() == pytest.approx(extent.prod(), rel=1e-12)


@pytest.mark.parametrize("name", ["cube_tet4.inp", "cube_tet4_mixed_case.inp"])
def test_a_surface_of_two_labels_is_the_cube_face_z_10(name):
    mesh = read_mesh(DATA / name)
    for surface in ("LOAD", "ORDER"):
        found = find_set(mesh.face_sets, surface)
        assert found is not None
        _, faces = only_faces(mesh, found)
        area, normal, centroid = face_geometry(mesh.points, faces)
        assert area.sum() == pytest.approx(100.0)
        np.testing.assert_allclose(normal, [[0, 0, 1]] * 2, atol=1e-12)
        np.testing.assert_allclose(centroid[:, 2], 10.0)
    assert find_set(mesh.node_sets, "sym12") is not None


def contact_pairs(path):
    """(slave, master) of each *CONTACT PAIR of a deck, read from its text."""
    text = Path(path).read_text().splitlines()
    return [tuple(text[i + 1].replace(" ", "").upper().split(",")[:2])
            for i, line in enumerate(text) if line.upper().startswith("*CONTACT PAIR")]


@pytest.mark.parametrize("name, pairs", [
    ("ccx_contact4.inp", 1),           # C3D20: S3 and S5, elements over two lines
    ("ccx_beamcontact.inp", 2),        # C3D20R: S4, S6 against C3D8: S2, S1
])
def test_calculix_contact_pairs_face_each_other(name, pairs):
    """Each pair's two surfaces lie in one plane, with opposite outward normals, and the
    smaller one's face centres lie within the other's extent."""
    path = DATA / name
    mesh = read_mesh(path)
    found = contact_pairs(path)
    assert len(found) == pairs
    for slave, master in found:
        geometry = {}
        for surface in (slave, master):
            ftype, faces = only_faces(mesh, find_set(mesh.face_sets, surface))
            assert len(faces) == len(surface_lines(path)[surface])
            area, normal, centroid = face_geometry(mesh.points, faces)
            np.testing.assert_allclose(normal, np.tile(normal[0], (len(faces), 1)), atol=1e-12)
            geometry[surface] = (area.sum(), normal[0], centroid, mesh.points[faces.ravel()])
        (a_s, n_s, c_s, p_s), (a_m, n_m, c_m, p_m) = geometry[slave], geometry[master]
        np.testing.assert_allclose(n_s, -n_m, atol=1e-12)
        plane = np.abs(n_m).argmax()
        assert np.ptp(np.concatenate([p_s, p_m])[:, plane]) < 1e-12
        small, large = (c_s, p_m) if a_s <= a_m else (c_m, p_s)
        inside = np.delete(small, plane, axis=1)
        box = np.delete(large, plane, axis=1)
        assert (inside >= box.min(axis=0) - 1e-12).all()
        assert (inside <= box.max(axis=0) + 1e-12).all()


def test_calculix_c3d20_contact_faces_by_the_numbers():
    mesh = read_mesh(DATA / "ccx_contact4.inp")
    for name, area, normal, z in (("SMAST", 1.0, [0, 0, 1], 1.0),
                                  ("SSLAV", 0.25, [0, 0, -1], 1.0)):
        ftype, faces = only_faces(mesh, find_set(mesh.face_sets, name))
        a, n, c = face_geometry(mesh.points, faces)
        assert ftype == "quad8" and a.sum() == pytest.approx(area)
        np.testing.assert_allclose(n[0], normal, atol=1e-12)
        np.testing.assert_allclose(c[:, 2], z)
        # midside nodes at the middle of their face's edges (a face's own edge order)
        p = mesh.points[faces[0]]
        for k in range(4):
            np.testing.assert_allclose(p[4 + k], 0.5 * (p[k] + p[(k + 1) % 4]))


def test_parts_and_instances_placed_as_the_manual_says():
    """*INSTANCE's data lines: a translation, then a turn by the angle about the axis from
    point a to point b: Block-2 is moved by (2, 0, 0), then turned 90 deg about the vertical
    through (2, 0, 0), so a node of the part at (x, y, z) lands at (2 - y, x, z)."""
    mesh, notes = read_abaqus(DATA / "placed_blocks.inp")
    assert notes == []
    part = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0, 2.0)])
    np.testing.assert_array_equal(mesh.points[:12], part)
    np.testing.assert_array_equal(mesh.points[12:], np.column_stack(
        [2 - part[:, 1], part[:, 0], part[:, 2]]))
    np.testing.assert_array_equal(mesh.points[12 + 1], [2.0, 1.0, 0.0])    # part's (1, 0, 0)
    assert {n: sorted(c["hexahedron"]) for n, c in mesh.cell_sets.items()} == {
        "Block-1": [0, 1], "Block-2": [2, 3], "Block-1.Whole": [0, 1], "Block-2.Whole": [2, 3]}
    names = set(mesh.set_names())
    assert not [n for n in names if "_" in n.split(".")[-1][:1]]       # internal sets left out
    for inst in ("Block-1", "Block-2"):
        _, top = only_faces(mesh, f"{inst}.Top")
        area, normal, centroid = face_geometry(mesh.points, top)
        assert area.sum() == 2.0 and (normal == [0, 0, 1]).all() and (centroid[:, 2] == 1).all()
        _, bottom = only_faces(mesh, f"{inst}.Bottom")
        area, normal, _ = face_geometry(mesh.points, bottom)
        assert area.sum() == 2.0 and (normal == [0, 0, -1]).all()
        assert len(mesh.node_sets[f"{inst}.corner"]) == 1
    # Block-2's element 2, face S4: x = 2 in the part, y = 2 once placed
    _, contact = only_faces(mesh, "Contact")
    area, normal, centroid = face_geometry(mesh.points, contact)
    assert area.sum() == 1.0
    np.testing.assert_array_equal(normal, [[0.0, 1.0, 0.0]])
    np.testing.assert_array_equal(centroid, [[1.5, 2.0, 0.5]])
    np.testing.assert_array_equal(mesh.points[mesh.node_sets["Pinned"]], [[0, 0, 0], [0, 1, 0]])
    tops = mesh.node_sets["BOTH_TOPS"]
    assert len(tops) == 12 and (mesh.points[tops][:, 2] == 1).all()
    assert find_set(names, "block-2.TOP") == "Block-2.Top"


def test_input_files_cylindrical_nodes_node_surfaces_and_faces_on_the_boundary(tmp_path):
    """A *NODE whose data is in a file of its own (INPUT=), in r, theta, z (SYSTEM=C); a
    TYPE=NODE surface; a TYPE=ELEMENT line without a face: the elements' boundary faces."""
    (tmp_path / "nodes.txt").write_text("1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 90, 0\n4, 1, 0, 1\n")
    (tmp_path / "deck.inp").write_text(
        "*NODE, SYSTEM=C, INPUT=nodes.txt\n*ELEMENT, TYPE=C3D4, ELSET=\"One Tet\"\n"
        "7, 1, 2, 3, 4\n*NSET, NSET=BASE\n1, 2, 3\n*SURFACE, TYPE=NODE, NAME=Base Nodes\n"
        "BASE\n*SURFACE, NAME=Skin\n\"One Tet\"\n")
    mesh = read_mesh(tmp_path / "deck.inp")
    np.testing.assert_allclose(mesh.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 1]],
                               atol=1e-15)
    assert set(mesh.cell_sets) == {"One Tet"}
    np.testing.assert_array_equal(mesh.node_sets["Base Nodes"], [0, 1, 2])
    assert "Base Nodes" not in mesh.face_sets
    _, skin = only_faces(mesh, "Skin")
    area, normal, centroid = face_geometry(mesh.points, skin)
    assert len(skin) == 4
    # every face points away from the tet's centroid
    assert (np.einsum("ij,ij->i", normal, centroid - mesh.points.mean(axis=0)) > 0).all()


@pytest.mark.parametrize("text, words", [
    ("*Part, name=P\n*Node\n1, 0, 0, 0\n*End Part\n",
     "no solid elements: expected C3D4, C3D10, C3D8, C3D20, C3D6 and C3D15, with any "
     "formulation letters (C3D8R, C3D10M, C3D20R, C3D6H) (the deck defines parts but no "
     "*INSTANCE of them)"),
    ("*Part, name=P\n*End Part\n*Assembly, name=A\n*Instance, name=I, part=Q\n*End Instance\n",
     "line 4: *Instance, name=I, part=Q: no part 'Q' (parts: P)"),
    ("*Part, name=P\n*End Instance\n", "line 2: *End Instance: out of place"),
    ("*Part, name=P\n*End Part\n*Assembly, name=A\n*Instance, name=I, part=P\n0, 0, 0\n"
     "0, 0, 0, 0, 0, 1\n", "line 4: *Instance, name=I, part=P: expected at most two data "
     "lines: a translation x, y, z, then a rotation xa, ya, za, xb, yb, zb, angle [deg]"),
    ("*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n*ELEMENT, TYPE=C3D10\n"
     "1, 1, 2, 3, 4\n", "line 7: *ELEMENT, TYPE=C3D10: element 1: 4 node labels, expected 10"),
])
def test_a_deck_out_of_shape_is_refused_naming_what_was_expected(tmp_path, text, words):
    path = tmp_path / "deck.inp"
    path.write_text(text)
    with pytest.raises(MeshFileError) as info:
        read_mesh(path)
    assert info.value.path == str(path) and words in info.value.message


def test_an_error_in_an_included_file_names_that_file_and_its_line(tmp_path):
    (tmp_path / "deck.inp").write_text("*NODE\n*INCLUDE, INPUT=nodes.inp\n")
    (tmp_path / "nodes.inp").write_text("** the nodes\n1, 0, 0, 0\n2, 1, x, 0\n")
    with pytest.raises(MeshFileError) as info:
        read_mesh(tmp_path / "deck.inp")
    assert info.value.path == str(tmp_path / "nodes.inp")
    assert info.value.message == ("line 3: *NODE: expected a node label and its coordinates, "
                                  "got 2, 1, x, 0")
