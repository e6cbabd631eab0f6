"""Abaqus decks in cases: a deck written elsewhere runs `transient modes` and `cea` with its
surfaces named as the deck names them (in any case), gmsh's own .inp loads, and a bad deck is
one error line naming the file, the keyword and what was expected."""
import json
from pathlib import Path

import numpy as np
import pytest

from transient.cli import main
from transient.mesh.meshfile import read_mesh

DATA = Path(__file__).parent / "data" / "abaqus"
TWO_BLOCKS = DATA / "hypermesh_two_blocks_tet4.inp"

# The two blocks of a HyperMesh deck as two parts (its element sets UPPER and LOWER), 10 cm
# wide, the upper one pressed on the lower one, which slides under it.
BLOCKS = f"""
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0

[parts.block]
material = "steel"
[parts.block.mesh]
kind = "file"
path = "{TWO_BLOCKS}"
scale = 0.1
body = "upper"

[parts.base]
material = "steel"
[parts.base.mesh]
kind = "file"
path = "{TWO_BLOCKS}"
scale = 0.1
body = "LOWER"

[constraints.ground]
set = "base.LOWER_BOTTOM"

[constraints.guide_x]
set = "block.Upper_Sym23"
dofs = ["x"]

[constraints.guide_y]
set = "block.upper_sym13"
dofs = ["y"]

[loads.press]
kind = "pressure"
set = "block.UPPER_TOP"
value = 1.0e6

[contact.interface]
surface1 = "block.upper_to_lower"
surface2 = "base.LOWER_TO_UPPER"
k = 5.0e11

[contact.interface.law]
kind = "exponential"
p0 = 1.0e4
lambda = 5.0e5

[contact.interface.friction]
mu = 0.4

[motion.belt]
kind = "translation"
part = "base"
velocity = [0.5, 0.0, 0.0]

[solver]
scheme = "exponential"
t_end = 0.001

[solver.reduction]
enabled = true
fmax = 40000.0

[solver.modes]
fmax = 40000.0
"""


def write_case(tmp_path, text=BLOCKS):
    path = tmp_path / "case.toml"
    path.write_text(text)
    return str(path)


def test_a_hypermesh_deck_runs_modes_with_its_surfaces_named_as_it_names_them(tmp_path, capsys):
    assert main(["modes", write_case(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    (pair,) = out["contact"]
    # the two blocks' faces at z = 0.5 overlap on the whole 10 cm square, and touch
    assert pair["area"] == pytest.approx(0.01, rel=1e-12)
    assert abs(pair["gap0"]["min"]) < 1e-12 and abs(pair["gap0"]["max"]) < 1e-12
    assert out["ndof"] == 3 * 116 and len(out["frequencies_hz"]) > 10


def test_the_deck_s_contact_faces_carry_friction_in_cea(tmp_path, capsys):
    assert main(["cea", write_case(tmp_path), "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    # friction on the deck's faces couples the modes: without it every real part is zero
    assert max(abs(m["damping_ratio"]) for m in modes) > 1e-4


def gmsh_inp(path, groups):
    """A pad of two materials (two boxes, lining under backplate) meshed in tet10 by gmsh and
    written as its own .inp: CPS6 faces, and T3D3 lines without physical groups."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("pad")
        lining = gmsh.model.occ.addBox(0, 0, 0, 0.04, 0.02, 0.004)
        back = gmsh.model.occ.addBox(0, 0, 0.004, 0.04, 0.02, 0.003)
        gmsh.model.occ.fragment([(3, lining)], [(3, back)])
        gmsh.model.occ.synchronize()
        if groups:
            bottom = [s for _, s in gmsh.model.getEntities(2)
                      if abs(gmsh.model.occ.getCenterOfMass(2, s)[2]) < 1e-9]
            gmsh.model.addPhysicalGroup(3, [lining], name="lining")
            gmsh.model.addPhysicalGroup(3, [back], name="backplate")
            gmsh.model.addPhysicalGroup(2, bottom, name="friction")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.006)
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


def test_gmsh_s_own_inp_with_cps6_faces_loads(tmp_path, capsys):
    mesh = read_mesh(gmsh_inp(tmp_path / "pad.inp", groups=True))
    assert list(mesh.cells) == ["tetra10"] and set(mesh.cell_sets) >= {"lining", "backplate"}
    ((ftype, faces),) = mesh.face_sets["friction"].items()
    assert ftype == "triangle6"
    p = mesh.points[faces[:, :3]]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert 0.5 * np.linalg.norm(cross, axis=1).sum() == pytest.approx(0.04 * 0.02)
    assert (cross[:, 2] < 0).all() and np.allclose(p[..., 2], 0.0)       # outward: -z
    # its CPS6 are all faces of its physical surfaces: nothing of the model is left out
    assert capsys.readouterr().err == ""


def test_gmsh_s_inp_without_groups_leaves_lines_and_the_inner_face_out(tmp_path, capsys):
    path = gmsh_inp(tmp_path / "pad.inp", groups=False)
    mesh = read_mesh(path)
    # every surface of the model is a set of CPS6; the one between the two boxes is inside
    surfaces = [n for n in mesh.face_sets if n.startswith("Surface")]
    assert len(surfaces) == 10 and set(mesh.cell_sets) == {"Volume1", "Volume2"}
    blocks = path.read_text().split("*ELEMENT, type=")[1:]
    written = sum(len(b.strip().splitlines()) - 1 for b in blocks if b.startswith("CPS6"))
    faces = sum(len(f) for n in surfaces for f in mesh.face_sets[n].values())
    (note,) = capsys.readouterr().err.strip().splitlines()
    assert note.startswith(f"note: {path}: ") and note.endswith(" T3D3)")
    assert f"({written - faces} CPS6, " in note and written > faces


SOLID = """*NODE
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
9, 3, 3, 3
*ELEMENT, TYPE=C3D4, ELSET=TETS
1, 1, 2, 4, 5
"""


@pytest.mark.parametrize("tail, line, words", [
    ("*ELEMENT, TYPE=C3D27\n2, 1, 2, 3, 4, 5, 6, 7, 8, 1, 2, 3, 4\n", 13,
     "*ELEMENT, TYPE=C3D27: element type C3D27 cannot be used: expected solids C3D4, C3D10"),
    ("*ELEMENT, TYPE=C3D15V\n2, 1, 2, 3, 5, 6, 7\n", 13, "element type C3D15V cannot be used"),
    ("*SURFACE, NAME=Pad\nNOPE, S1\n", 14,
     "*SURFACE, NAME=Pad: element set 'NOPE' is not defined (element sets: TETS)"),
    ("*SURFACE, NAME=Pad\n1, S7\n", 14,
     "*SURFACE, NAME=Pad: face S7 of C3D4 element 1: expected S1 to S4"),
    ("*SURFACE, NAME=Pad\nTETS, S5\n", 14, "face S5 of C3D4 element 1: expected S1 to S4"),
    ("*ELSET, ELSET=A\nB\n*ELSET, ELSET=B\nA\n", 15, "*ELSET, ELSET=B: set 'A' includes itself"),
    ("*NSET, NSET=A, GENERATE\n1, 9, 0\n", 14, "GENERATE: expected first, last, increment"),
    ("*INCLUDE, INPUT=missing.inp\n", 13, "*INCLUDE, INPUT=missing.inp: no such file"),
    ("*NGEN, NSET=X\n1, 9\n", 13, "*NGEN, NSET=X: not read here"),
    ("*ELEMENT, TYPE=C3D4\n2, 1, 2, 3, 99\n", 14, "element 2: node 99 is not defined"),
    ("*NODE\n3, 5, 5, 5\n", 14, "node 3 is defined twice"),
])
def test_a_bad_deck_is_one_error_line_naming_file_keyword_and_expectation(
        tmp_path, capsys, tail, line, words):
    deck = tmp_path / "bad.inp"
    deck.write_text(SOLID + tail)
    case = write_case(tmp_path, BLOCKS.replace(str(TWO_BLOCKS), str(deck)))
    assert main(["modes", case]) == 2
    captured = capsys.readouterr()
    (err,) = captured.err.strip().splitlines()
    assert err.startswith(f"error: {case}: parts.block.mesh.path: {deck}: line {line}: ")
    assert words in err, err


def test_a_deck_with_only_an_unknown_element_type_names_it(tmp_path, capsys):
    deck = tmp_path / "unknown.inp"
    deck.write_text("*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n*ELEMENT, TYPE=USER8\n1, 1, 2\n")
    case = write_case(tmp_path, BLOCKS.replace(str(TWO_BLOCKS), str(deck)))
    assert main(["modes", case]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert err == (f"error: {case}: parts.block.mesh.path: {deck}: line 4: *ELEMENT, "
                   "TYPE=USER8: element type USER8 cannot be used: expected solids C3D4, C3D10, "
                   "C3D8, C3D20, C3D6 and C3D15, with any formulation letters (C3D8R, C3D10M, "
                   "C3D20R, C3D6H) (shells, membranes, beams, springs and masses are left out "
                   "with a note)")


def test_shells_beams_springs_and_masses_are_left_out_with_one_note(tmp_path, capsys):
    deck = tmp_path / "mixed.inp"
    deck.write_text(SOLID.replace("9, 3, 3, 3", "9, 3, 3, 3\n10, 4, 4, 4") + """
*ELEMENT, TYPE=C3D8R, ELSET=BRICK
2, 1, 2, 3, 4, 5, 6, 7, 8
*ELEMENT, TYPE=S4R, ELSET=SKIN
3, 5, 6, 7, 8
*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL
0.001
*ELEMENT, TYPE=SFM3D4, ELSET=BASE
8, 1, 2, 3, 4
*SURFACE SECTION, ELSET=BASE
*ELEMENT, TYPE=B31
4, 8, 9
*ELEMENT, TYPE=SPRINGA
5, 9, 10
*ELEMENT, TYPE=MASS, ELSET=M
6, 9
*ELEMENT, TYPE=T3D2
7, 9, 10
""")
    mesh = read_mesh(deck)
    assert set(mesh.cells) == {"tetra", "hexahedron"} and mesh.n_nodes == 8
    # the shell lies on the brick's top, the surface element on its bottom: both give faces
    assert list(mesh.face_sets["SKIN"]) == ["quad"] and list(mesh.face_sets["BASE"]) == ["quad"]
    (note,) = capsys.readouterr().err.strip().splitlines()
    # the shell is structure (a shell section): left out; the surface element only a face
    assert note == (f"note: {deck}: 5 elements that are not solids are left out of the model "
                    "(1 B31, 1 MASS, 1 S4R, 1 SPRINGA, 1 T3D2); the S4R on the solids' "
                    "boundary still give their sets' faces")


def test_a_set_not_found_lists_the_deck_s_sets_but_not_its_internal_ones(tmp_path, capsys):
    deck = tmp_path / "cae.inp"
    deck.write_text(SOLID + "*ELSET, ELSET=_Surf-1_S2\n1\n*SURFACE, TYPE=ELEMENT, NAME=Surf-1\n"
                    "_Surf-1_S2, S2\n")
    case = write_case(tmp_path, BLOCKS.replace(str(TWO_BLOCKS), str(deck))
                      .replace('body = "upper"', "").replace('body = "LOWER"', ""))
    assert main(["modes", case]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert err == (f"error: {case}: constraints.ground.set: part 'base' has no set "
                   "'LOWER_BOTTOM' (sets: Surf-1, TETS)")
