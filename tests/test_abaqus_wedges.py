"""Abaqus decks of wedges, C3D6 and C3D15, as gmsh writes them (its node order, not this
reader's): they read as gmsh's own .msh of the same mesh does, their faces S1 to S5 are the
faces the Abaqus manual names by corner nodes, and a deck of a C3D15 block and a C3D6 pad
whose *SURFACE, TYPE=ELEMENT lines name wedge faces runs `transient modes`: contact, clamp
and pressure on those faces."""
import json
import re

import numpy as np
import pytest

from transient import api
from transient.cli import main
from transient.mesh.elements import ELEMENTS
from transient.mesh.meshfile import jacobian_check, read_mesh
from transient.mesh.selections import find_set
from transient.model.model import build_model

# The faces of C3D6 and C3D15 by their corner nodes (1-based), as the Abaqus Analysis User's
# Guide lists them for the triangular prisms: S1 1-2-3, S2 4-6-5, S3 1-4-5-2, S4 2-5-6-3,
# S5 3-6-4-1. C3D15's midside nodes 7 to 15 lie on the edges 1-2, 2-3, 3-1, 4-5, 5-6, 6-4,
# 1-4, 2-5, 3-6.
MANUAL = {1: (1, 2, 3), 2: (4, 6, 5), 3: (1, 4, 5, 2), 4: (2, 5, 6, 3), 5: (3, 6, 4, 1)}
EDGES = ((1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4), (1, 4), (2, 5), (3, 6))


def gmsh_prisms(path, size, origin, mesh_size, layers, order):
    """A box meshed by gmsh in prisms (a triangle mesh of its base swept in layers along z),
    written by gmsh as an Abaqus deck (C3D6 or C3D15) and as a .msh; returns the deck's path."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("prisms")
        base = gmsh.model.occ.addRectangle(*origin, *size[:2])
        volume = gmsh.model.occ.extrude([(2, base)], 0, 0, size[2], numElements=[layers],
                                        recombine=True)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [e[1] for e in volume if e[0] == 3], name="solid")
        gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
        gmsh.option.setNumber("Mesh.ElementOrder", order)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
        gmsh.write(str(path.with_suffix(".msh")))
    finally:
        gmsh.finalize()
    return path


def deck_tables(text):
    """Node coordinates by label and the solid elements' node labels, read from a deck's text:
    ({label: (x, y, z)}, {element label: node labels}, its element type)."""
    nodes, elements, kind, ctype = {}, {}, None, None
    for line in text.splitlines():
        if line.startswith("*"):
            match = re.match(r"\*ELEMENT\s*,\s*TYPE\s*=\s*(C3D\d+)", line, re.I)
            kind = "node" if re.match(r"\*NODE\b", line, re.I) else \
                "element" if match else None
            ctype = match.group(1).upper() if match else ctype
        elif kind and line.strip():
            values = [v for v in line.replace(" ", "").split(",") if v]
            if kind == "node":
                nodes[int(values[0])] = tuple(float(v) for v in values[1:4])
            else:
                elements[int(values[0])] = [int(v) for v in values[1:]]
    return nodes, elements, ctype


def face_corners(elements, labels, k):
    """Corner node labels (m, nc) of face Sk of the elements with the given labels."""
    return np.array([[elements[e][c - 1] for c in MANUAL[k]] for e in labels])


def on_plane(nodes, corners, axis, value):
    xyz = np.array([[nodes[n] for n in row] for row in corners])
    return np.all(np.abs(xyz[..., axis] - value) < 1e-12, axis=1)


@pytest.mark.parametrize("order", [1, 2])
def test_gmsh_s_c3d6_and_c3d15_decks_read_as_its_msh_files(tmp_path, order):
    size = (0.04, 0.02, 0.005)
    deck = gmsh_prisms(tmp_path / "prisms.inp", size, (0.0, 0.0, 0.0), 0.006, 2, order)
    ctype = ("wedge", "wedge15")[order - 1]
    assert f"type=C3D{(6, 15)[order - 1]}" in deck.read_text()
    mesh, msh = read_mesh(deck), read_mesh(deck.with_suffix(".msh"))
    assert list(mesh.cells) == [ctype] and list(msh.cells) == [ctype]
    # the same cells, node for node, through gmsh's two writers and two readers (the deck
    # holds its coordinates to 14 digits)
    np.testing.assert_allclose(mesh.points[mesh.cells[ctype]], msh.points[msh.cells[ctype]],
                               rtol=0, atol=1e-14)
    el = ELEMENTS[ctype]
    x = mesh.points[mesh.cells[ctype]]
    (_, _, least), = jacobian_check(mesh)
    assert least > 0
    xi, w = el.rule(el.mass_degree)
    J = np.einsum("eak,gad->egkd", x, el.shape_derivatives(xi))
    assert np.linalg.det(J) @ w @ np.ones(len(x)) == pytest.approx(np.prod(size), rel=1e-12)
    for k, (a, b) in enumerate(el.edges):        # straight edges: midsides at their middles
        np.testing.assert_allclose(x[:, el.n_corners + k], 0.5 * (x[:, a] + x[:, b]),
                                   atol=1e-15)


@pytest.mark.parametrize("order", [1, 2])
def test_faces_s1_to_s5_are_the_manual_s_faces_and_outward(tmp_path, order):
    deck = gmsh_prisms(tmp_path / "prisms.inp", (0.03, 0.02, 0.01), (0.0, 0.0, 0.0), 0.008, 2,
                       order)
    text = deck.read_text()
    nodes, elements, abaqus_type = deck_tables(text)
    assert abaqus_type == ("C3D6", "C3D15")[order - 1]
    labels = sorted(elements)
    text += "".join(f"*SURFACE, NAME=FACE{k}, TYPE=ELEMENT\nsolid, S{k}\n" for k in MANUAL)
    text += "*SURFACE, NAME=WHOLE, TYPE=ELEMENT\nsolid\n"
    deck.write_text(text)
    mesh = read_mesh(deck)
    # a line without a face: the elements' faces on the boundary, of both kinds
    whole = mesh.face_sets[find_set(mesh.face_sets, "whole")]
    assert sorted(whole) == sorted(set(ELEMENTS[("wedge", "wedge15")[order - 1]].face_types))
    area = 0.0
    for ftype, faces in whole.items():
        p = mesh.points[faces[:, :ELEMENTS[ftype].n_corners]]
        cross = sum(np.cross(p[:, i] - p[:, 0], p[:, i + 1] - p[:, 0])
                    for i in range(1, p.shape[1] - 1))
        area += 0.5 * np.linalg.norm(cross, axis=1).sum()
    assert area == pytest.approx(2 * (0.03 * 0.02 + 0.05 * 0.01), rel=1e-12)
    coordinates = np.array([nodes[n] for n in sorted(nodes)])
    label_of = {tuple(p): n for n, p in zip(sorted(nodes), coordinates)}
    ctype = ("wedge", "wedge15")[order - 1]
    centroid = {e: np.mean([nodes[n] for n in elements[e][:6]], axis=0) for e in labels}
    for k in MANUAL:
        found = mesh.face_sets[find_set(mesh.face_sets, f"face{k}")]
        (ftype, faces), = found.items()
        assert ftype == ELEMENTS[ctype].face_types[0 if k < 3 else 2]
        # each element's face Sk, by its corner labels, is one of the faces read
        nc = len(MANUAL[k])
        read = [frozenset(label_of[tuple(p)] for p in mesh.points[f[:nc]]) for f in faces]
        owners = {}
        for e, c in zip(labels, face_corners(elements, labels, k)):
            owners.setdefault(frozenset(c), []).append(e)
        # (a face that is the same Sk of two elements is read once, outward from one of them)
        assert len(set(read)) == len(read) and set(read) == set(owners)
        for f, corner_set in zip(faces, read):
            p = mesh.points[f]
            # outward: the right-hand normal of its corners leaves the element's centroid
            normal = sum(np.cross(p[i] - p[0], p[i + 1] - p[0]) for i in range(1, nc - 1))
            out = [e for e in owners[corner_set]
                   if normal @ (p[:nc].mean(axis=0) - centroid[e]) > 0]
            assert out
            owner = out[0]
            if order == 2:
                # the midside nodes are the element's on the face's edges, in its edge order
                on_edge = {frozenset((elements[owner][a - 1], elements[owner][b - 1])):
                           elements[owner][6 + i] for i, (a, b) in enumerate(EDGES)}
                corners = [label_of[tuple(q)] for q in p[:nc]]
                mids = [label_of[tuple(q)] for q in p[nc:]]
                assert mids == [on_edge[frozenset((corners[i], corners[(i + 1) % nc]))]
                                for i in range(nc)]


def two_block_deck(tmp_path):
    """One deck of two bodies meshed apart by gmsh: a 40 x 20 x 5 mm base in C3D15 and a
    20 x 10 x 4 mm pad in C3D6 on its middle, their labels apart, and surfaces of element
    faces chosen by the manual's face table: the base's top (S1 or S2 on z = 5 mm) and the
    pad's bottom (z = 5 mm), the base's end x = 0 (S3 to S5) and the pad's top."""
    parts = {"BASE": gmsh_prisms(tmp_path / "base.inp", (0.04, 0.02, 0.005), (0.0, 0.0, 0.0),
                                 0.006, 2, 2),
             "PAD": gmsh_prisms(tmp_path / "pad.inp", (0.02, 0.01, 0.004), (0.01, 0.005, 0.0),
                                0.004, 2, 1)}
    out = ["*HEADING", "a C3D15 base and a C3D6 pad, meshed apart by gmsh"]
    surfaces = {}
    for offset, (name, path) in zip((0, 100000), parts.items()):
        nodes, elements, abaqus_type = deck_tables(path.read_text())
        z0 = 0.0 if name == "BASE" else 0.005
        nodes = {n + offset: (x, y, z + z0) for n, (x, y, z) in nodes.items()}
        elements = {e + offset: [n + offset for n in row] for e, row in elements.items()}
        out.append("*NODE")
        out += [f"{n}, {x!r}, {y!r}, {z!r}" for n, (x, y, z) in nodes.items()]
        out.append(f"*ELEMENT, TYPE={abaqus_type}, ELSET={name}")
        out += [f"{e}, " + ", ".join(map(str, row)) for e, row in elements.items()]
        top = 0.005 if name == "BASE" else 0.009
        planes = {"BASE": {"TO_PAD": (2, top, (1, 2)), "END": (0, 0.0, (3, 4, 5))},
                  "PAD": {"TO_BASE": (2, 0.005, (1, 2)), "TOP": (2, top, (1, 2))}}[name]
        for surface, (axis, value, faces) in planes.items():
            lines = []
            for k in faces:
                labels = sorted(elements)
                hit = on_plane(nodes, face_corners(elements, labels, k), axis, value)
                if hit.any():
                    out.append(f"*ELSET, ELSET=_{surface}_S{k}, INTERNAL")
                    out += [", ".join(map(str, np.array(labels)[hit][i:i + 8]))
                            for i in range(0, int(hit.sum()), 8)]
                    lines.append(f"_{surface}_S{k}, S{k}")
            surfaces[surface] = lines
    for surface, lines in surfaces.items():
        out.append(f"*SURFACE, NAME={surface}, TYPE=ELEMENT")
        out += lines
    deck = tmp_path / "blocks.inp"
    deck.write_text("\n".join(out) + "\n")
    return deck


CASE = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0

[parts.base]
material = "steel"
[parts.base.mesh]
kind = "file"
path = "{deck}"
body = "base"

[parts.pad]
material = "steel"
[parts.pad.mesh]
kind = "file"
path = "{deck}"
body = "pad"

[constraints.clamp]
set = "base.end"

[loads.press]
kind = "pressure"
set = "pad.top"
value = 1.0e6

[contact.interface]
surface1 = "pad.to_base"
surface2 = "base.to_pad"
k = 1.0e14

[contact.interface.law]
kind = "bilateral"

[solver.modes]
count = 8
tie = "exact"
"""


def test_a_deck_of_c3d15_and_c3d6_runs_modes_on_its_wedge_surfaces(tmp_path, capsys):
    deck = two_block_deck(tmp_path)
    # the surfaces are the faces the deck names: the end x = 0 quadrilaterals, the others
    # triangles, each of the area of its side
    mesh = read_mesh(deck)
    for name, ftype, area, normal in (("END", "quad8", 0.02 * 0.005, (-1, 0, 0)),
                                      ("TO_PAD", "triangle6", 0.04 * 0.02, (0, 0, 1)),
                                      ("TO_BASE", "triangle", 0.02 * 0.01, (0, 0, -1)),
                                      ("TOP", "triangle", 0.02 * 0.01, (0, 0, 1))):
        (found, faces), = mesh.face_sets[name].items()
        assert found == ftype
        p = mesh.points[faces[:, :ELEMENTS[ftype].n_corners]]
        a = sum(np.cross(p[:, i] - p[:, 0], p[:, i + 1] - p[:, 0])
                for i in range(1, p.shape[1] - 1)) / 2
        assert np.linalg.norm(a, axis=1).sum() == pytest.approx(area, rel=1e-12)
        np.testing.assert_allclose(a / np.linalg.norm(a, axis=1)[:, None],
                                   np.tile(normal, (len(a), 1)), atol=1e-12)
    case = tmp_path / "case.toml"
    case.write_text(CASE.format(deck=deck))
    assert main(["modes", str(case), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    (pair,) = out["contact"]
    # the pad's bottom lies on the base's top, whole: the overlap is its area, the gaps zero
    assert pair["area"] == pytest.approx(0.02 * 0.01, rel=1e-12)
    assert abs(pair["gap0"]["min"]) < 1e-12 and abs(pair["gap0"]["max"]) < 1e-12
    assert out["ndof"] == 3 * mesh.n_nodes
    # the pair holds the normal gap alone: the pad slides along x and y and turns about z,
    # three rigid modes, and the clamped base has none
    f = np.abs(out["frequencies_hz"])
    assert f[:3].max() < 1e-3 * f[3] and f[3] > 1000.0
    # the pressure on the pad's top: on flat 3-node triangles, a third of each triangle's
    # force at each of its corners, along -z
    model = build_model(api.load(case))
    forces = model.load_patterns["press"].reshape(-1, 3)
    pad = model.parts["pad"]
    (top,) = pad.mesh.face_sets[find_set(pad.mesh.face_sets, "top")].values()
    p = pad.mesh.points[top]
    third = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1) / 6
    expected = np.zeros(model.ndof // 3)
    np.add.at(expected, pad.offset + top.ravel(), np.repeat(third, 3))
    assert expected.sum() == pytest.approx(0.02 * 0.01, rel=1e-12)
    np.testing.assert_allclose(forces, np.outer(expected, [0, 0, -1.0e6]), rtol=0, atol=1e-9)
