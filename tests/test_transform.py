"""A part's placement (parts.NAME.transform): translate, rotate and mirror carry every element
type with positive volumes, its node and face sets with it, and leave its frequencies as they
were; bad keys are one error line before any stage."""
import warnings

import numpy as np
import pytest
import scipy.linalg

from transient.case.loading import parse
from transient.cli import main
from transient.mesh import generators
from transient.mesh.elements import ELEMENTS, VOLUME_TYPES
from transient.mesh.meshfile import jacobian_check
from transient.mesh.placement import place, rotation_matrix
from transient.mesh.selections import select_nodes
from transient.model.loads import face_normals
from transient.model.model import build_model

ROTATE = ((1.0, -2.0, 0.5), 37.0, (0.01, 0.02, -0.03))
MIRROR = ((0.0, 0.01, 0.002), (0.3, -1.0, 2.0))
TRANSLATE = (0.1, -0.05, 0.2)


def _mirror_matrix(normal):
    n = np.asarray(normal) / np.linalg.norm(normal)
    return np.eye(3) - 2.0 * np.outer(n, n)


def _cell_volumes(points, ctype, conn):
    """Volume of each cell and the least det J over its nodes and stiffness points."""
    el = ELEMENTS[ctype]
    xi, w = el.rule(el.mass_degree)
    at = np.vstack([xi, el.nodes, el.rule(el.stiffness_degree)[0]])
    J = np.swapaxes(points[conn], 1, 2)[:, None] @ el.shape_derivatives(at)[None]
    det = np.linalg.det(J)
    return det[:, :len(xi)] @ w, det.min(axis=1)


def _midsides(ctype, conn):
    """Per cell, its edges (corner pairs) -> midside node: the topology a reordering keeps."""
    el = ELEMENTS[ctype]
    return [{frozenset((c[a], c[b])): c[el.n_corners + k] for k, (a, b) in enumerate(el.edges)}
            for c in conn]


@pytest.mark.parametrize("ctype", VOLUME_TYPES)
@pytest.mark.parametrize("how", ["rotate", "mirror", "both"])
def test_every_element_type_keeps_positive_volumes_and_outward_faces(ctype, how):
    # a disc: curved edges, so the midside nodes of hex20 and tet10 are not edge midpoints
    mesh = generators.annular_disc(0.05, 0.1, 0.01, (2, 6, 2), element=ctype)
    rotate = ROTATE if how != "mirror" else None
    mirror = MIRROR if how != "rotate" else None
    moved = place(mesh, TRANSLATE, rotate, mirror)
    Q = np.eye(3)
    if rotate:
        Q = rotation_matrix(rotate[0], rotate[1]) @ Q
    if mirror:
        Q = _mirror_matrix(mirror[1]) @ Q

    conn, new = mesh.cells[ctype], moved.cells[ctype]
    volume, _ = _cell_volumes(mesh.points, ctype, conn)
    moved_volume, least = _cell_volumes(moved.points, ctype, new)
    assert least.min() > 0.0 and jacobian_check(moved)[0][2] > 0.0
    np.testing.assert_allclose(moved_volume, volume, rtol=1e-12)
    assert not mirror or not np.array_equal(new, conn)     # a mirror had to reorder
    if ELEMENTS[ctype].edges:
        assert _midsides(ctype, new) == _midsides(ctype, conn)
    assert np.array_equal(np.sort(new, axis=1), np.sort(conn, axis=1))

    # face sets stay outward: each face's area vector is the original's, turned (and mirrored)
    assert moved.node_sets.keys() == mesh.node_sets.keys()
    for name, by_type in mesh.face_sets.items():
        for ftype, faces in by_type.items():
            before = face_normals(mesh.points, faces, ftype)[1].sum(axis=1)
            after = face_normals(moved.points, moved.face_sets[name][ftype], ftype)[1].sum(1)
            scale = np.abs(before).max()
            np.testing.assert_allclose(after, before @ Q.T, rtol=0, atol=1e-12 * scale)


def test_nothing_moved_is_the_mesh_itself():
    mesh = generators.box((1.0, 1.0, 1.0), (1, 1, 1))
    assert place(mesh) is mesh
    assert place(mesh, rotate=((0.0, 0.0, 1.0), 0.0, (5.0, 0.0, 0.0))) is mesh


PAD_CASE = """
[materials.lining]
E = 2.0e9
nu = 0.25
rho = 2500.0

[parts.pad]
material = "lining"
[parts.pad.mesh]
kind = "brake_pad"
inner_radius = 0.08
outer_radius = 0.12
angle = 50.0
lining_thickness = 0.006
backplate_thickness = 0.004
divisions = [2, 3, 1, 1]
z0 = 0.011
element = "{element}"
[parts.pad.sets.rim]
kind = "plane"
point = [0.0, 0.0, 0.011]
normal = [0.0, 0.0, 1.0]

[loads.piston]
kind = "pressure"
set = "pad.friction"
value = 1.0e6
"""
TRANSFORMS = {
    "translate": "translate = [0.3, -0.2, 0.05]\n",
    "rotate": "rotate = {axis = [1.0, 1.0, 0.0], angle = -75.0, point = [0.0, 0.1, 0.0]}\n",
    "mirror": "mirror = {point = [0.0, 0.0, 0.0055], normal = [0.0, 0.0, 1.0]}\n",
    "all": "translate = [0.3, -0.2, 0.05]\n"
           "rotate = {axis = [0.0, 0.0, 1.0], angle = 90.0, point = [0.05, 0.1, 0.0]}\n"
           "mirror = {point = [0.2, 0.0, 0.0], normal = [1.0, 0.0, 0.0]}\n",
}


def _pad(element, transform="", clamp="", mass=0):
    text = PAD_CASE.format(element=element) + f"\n[solver.quadrature]\nmass = {mass}\n"
    text += f"\n[parts.pad.transform]\n{transform}" if transform else ""
    text += f'\n[constraints.back]\nset = "pad.{clamp}"\n' if clamp else ""
    return build_model(parse(text, "pad.toml"))


def _frequencies(model, count=8):
    free = model.free
    K = model.K[free][:, free].toarray()
    M = model.M[free][:, free].toarray()
    values = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, count - 1])
    return np.sqrt(values) / (2 * np.pi)


@pytest.mark.parametrize("element", ["hex8", "hex20", "tet4", "tet10", "wedge6", "wedge15"])
def test_a_clamped_parts_frequencies_do_not_move_with_it(element):
    # a mirror swaps two reference axes of every cell: at the default rules (symmetric under
    # the cell's permutations, a curved tet10's mass too) the part is integrated at the same
    # points, wherever it went (a conical product moved the tet10's by 6e-7)
    reference = _pad(element, clamp="back")
    f0 = _frequencies(reference)
    for name, transform in TRANSFORMS.items():
        model = _pad(element, transform, clamp="back")
        # the clamp followed the back face it names, wherever the part went
        assert model.fixed.sum() == reference.fixed.sum()
        np.testing.assert_allclose(_frequencies(model), f0, rtol=1e-8, err_msg=name)


def test_sets_and_loads_follow_the_part_exactly():
    reference = _pad("hex20")
    model = _pad("hex20", TRANSFORMS["all"])
    mesh0, mesh = reference.parts["pad"].mesh, model.parts["pad"].mesh
    # translate, then a quarter turn about z through (0.05, 0.1), then the mirror x -> 0.4 - x
    x, y, z = (mesh0.points + [0.3, -0.2, 0.05]).T
    expected = np.stack([0.4 - (0.05 - (y - 0.1)), 0.1 + (x - 0.05), z], axis=1)
    for name in ("friction", "rim", "back"):
        ids = mesh.node_sets[name]
        assert np.array_equal(ids, mesh0.node_sets[name])
        # to the last bits of coordinates of 0.4 m (a mirror's round-off)
        np.testing.assert_allclose(mesh.points[ids], expected[ids], rtol=0, atol=1e-15)
    # the plane selection made before the placement is the plane's image after it
    rim = {"kind": "plane", "point": [0.0, 0.0, 0.061], "normal": [0.0, 0.0, 1.0], "tol": 1e-9}
    assert np.array_equal(select_nodes(mesh.points, rim), mesh.node_sets["rim"])
    # the pressure still pushes into the friction face: its resultant is the image of the
    # original one (a face turned inside out would pull)
    Q = _mirror_matrix([1.0, 0.0, 0.0]) @ rotation_matrix([0.0, 0.0, 1.0], 90.0)
    total0 = reference.load.reshape(-1, 3).sum(axis=0)
    total = model.load.reshape(-1, 3).sum(axis=0)
    assert total0[2] > 0.0
    np.testing.assert_allclose(total, Q @ total0, rtol=0, atol=1e-12 * np.abs(total0).max())


BAR = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
[parts.bar]
material = "steel"
[parts.bar.mesh]
kind = "box"
size = [0.1, 0.01, 0.01]
divisions = [4, 1, 1]
[constraints.root]
set = "bar.xmin"
"""


@pytest.mark.parametrize("overrides, key", [
    (["parts.bar.transform.rotate.axis=[0,0,0]", "parts.bar.transform.rotate.angle=30"],
     "parts.bar.transform.rotate.axis"),
    (["parts.bar.transform.rotate.angle=30"], "parts.bar.transform.rotate.axis"),
    (["parts.bar.transform.rotate.angle=400", "parts.bar.transform.rotate.axis=[0,0,1]"],
     "parts.bar.transform.rotate.angle"),
    (["parts.bar.transform.rotate.axis=[0,1]"], "parts.bar.transform.rotate.axis"),
    (["parts.bar.transform.rotate.angel=30"], "parts.bar.transform.rotate.angel"),
    (["parts.bar.transform.mirror.normal=[0.0,0.0,0.0]"], "parts.bar.transform.mirror.normal"),
    (["parts.bar.transform.mirror.normal=[0,0,1,0]"], "parts.bar.transform.mirror.normal"),
    (["parts.bar.transform.mirror.point=[0,0]", "parts.bar.transform.mirror.normal=[1,0,0]"],
     "parts.bar.transform.mirror.point"),
    (["parts.bar.transform.translate=[1.0,2.0]"], "parts.bar.transform.translate"),
    (["parts.bar.transform.translate=[1.0,2.0,inf]"], "parts.bar.transform.translate"),
    (["parts.bar.transform.scale=2.0"], "parts.bar.transform.scale"),
    (["parts.bar.transform.mirror=true"], "parts.bar.transform.mirror"),
])
def test_bad_transforms_are_one_line_naming_the_file_and_key(tmp_path, capsys, monkeypatch,
                                                             overrides, key):
    import transient.stages

    def no_model(case):
        raise AssertionError("the model was built before the case was refused")
    monkeypatch.setattr(transient.stages, "build_model", no_model)
    path = tmp_path / "bar.toml"
    path.write_text(BAR)
    args = ["run", str(path), "-o", str(tmp_path / "out.h5"), "--quiet"]
    args += [a for o in overrides for a in ("--set", o)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert not caught and len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.startswith(f"error: {path}: {key}: "), err


def test_a_placement_beyond_double_precision_is_one_line(tmp_path, capsys):
    # found once the mesh is built (its extent is not known before), with no overflow warning
    path = tmp_path / "bar.toml"
    path.write_text(BAR + "[parts.bar.transform.mirror]\npoint = [1e308, 0.0, 0.0]\n"
                    "normal = [1.0, 0.0, 0.0]\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert not caught and len(err.splitlines()) == 1
    assert err.startswith(f"error: {path}: parts.bar.transform: "), err
