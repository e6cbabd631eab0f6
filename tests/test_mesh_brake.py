"""tools/mesh_brake.py: a small tet10 pad and disc built by gmsh, its case loaded as a user's
would be. Every set the case names is in the files, the cells are tet10 and not inverted, the
dofs are near the target, and the parts weigh what their volumes and materials say (so the
pad's lining got the lining's material and the mesh follows the curved faces)."""
import math

import numpy as np
import pytest

from tet10_meshes import cell_volumes, named_sets
from transient.case.loading import load
from transient.mesh import generators
from transient.mesh.meshfile import jacobian_check
from transient.model.model import build_model, part_mesh

gmsh = pytest.importorskip("gmsh")

import mesh_brake  # tools/: pytest's pythonpath (setup.cfg)

# 30k dofs: meshed in about a second, the model assembled in a few
TARGET = 30000


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("brake")
    mesh_brake.main([str(out), "--dofs", str(TARGET)])
    case = load(out / "brake.toml")
    return out, case, {name: part_mesh(case, name) for name in case.parts}


def test_every_set_the_case_names_is_in_the_files(built):
    _, case, meshes = built
    found = named_sets(case)
    assert {("disc", "hub"), ("pad", "ends"), ("pad", "back"), ("pad", "friction"),
            ("disc", "zmax"), ("pad", "lining")} <= {(p, s) for p, s, _ in found}
    for part, name, kind in found:
        mesh = meshes[part]
        table = {"nodes": mesh.node_sets, "faces": mesh.face_sets, "cells": mesh.cell_sets}[kind]
        assert name in table, (part, name, kind)
        assert sum(len(v) for v in table[name].values()) if kind != "nodes" else len(table[name])


def test_the_files_carry_the_generators_set_names(built):
    # the generator meshes' names, so any case written for them finds its sets in the files
    _, case, meshes = built
    for name, part in case.parts.items():
        kind = {"disc": "annular_disc", "pad": "brake_pad"}[name]
        small = {"annular_disc": dict(inner_radius=0.055, outer_radius=0.14, thickness=0.02,
                                      divisions=[1, 3, 1]),
                 "brake_pad": dict(inner_radius=0.09, outer_radius=0.135, angle=50.0,
                                   lining_thickness=0.01, backplate_thickness=0.005,
                                   divisions=[1, 1, 1, 1])}[kind]
        generated = getattr(generators, kind)(**small)
        mesh = meshes[name]
        assert set(generated.face_sets) <= set(mesh.face_sets), name
        assert set(generated.cell_sets) <= set(mesh.cell_sets), name
        assert all(len(f) for f in mesh.face_sets.values())


def test_tet10_not_inverted_and_near_the_target_dofs(built):
    _, _, meshes = built
    for mesh in meshes.values():
        assert list(mesh.cells) == ["tetra10"]
        assert {t for f in mesh.face_sets.values() for t in f} == {"triangle6"}
        assert all(det > 0 for _, _, det in jacobian_check(mesh))
    dofs = sum(3 * m.n_nodes for m in meshes.values())
    assert abs(dofs / TARGET - 1) < 0.25
    # the pad's two layers share their nodes (fragment): the lining's top nodes are the
    # backplate's bottom ones
    pad = meshes["pad"]
    conn = pad.cells["tetra10"]
    lining = np.unique(conn[pad.cell_sets["lining"]["tetra10"]])
    backplate = np.unique(conn[pad.cell_sets["backplate"]["tetra10"]])
    shared = pad.points[np.intersect1d(lining, backplate)]
    assert len(shared) > 100 and np.allclose(shared[:, 2], 0.03)


def test_same_arguments_same_files(built, tmp_path):
    out, _, _ = built
    mesh_brake.main([str(tmp_path), "--dofs", str(TARGET)])
    for name in ("disc.msh", "pad.msh", "brake.toml"):
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name


def test_parts_weigh_their_volume_times_density(built):
    # the mass the model assembles against the analytical volumes: a pad all of steel (the
    # lining's material lost) would be 1.83 times as heavy, a mesh of straight-sided tets
    # (midside nodes off the cylinders) or a missing layer would be off the volumes
    _, case, meshes = built
    disc_v = math.pi * (0.14 ** 2 - 0.055 ** 2) * 0.02
    area = math.radians(50.0) / 2 * (0.135 ** 2 - 0.09 ** 2)
    volumes = {"lining": area * 0.01, "backplate": area * 0.005}
    pad = meshes["pad"]
    for name, v in volumes.items():
        assert cell_volumes(pad, pad.cell_sets[name]["tetra10"]).sum() == pytest.approx(v, rel=1e-4)
    assert cell_volumes(meshes["disc"], slice(None)).sum() == pytest.approx(disc_v, rel=1e-4)

    model = build_model(case)
    rho = {m: spec.rho for m, spec in case.materials.items()}
    expected = {"disc": rho["steel"] * disc_v,
                "pad": rho["lining"] * volumes["lining"] + rho["steel"] * volumes["backplate"]}
    for name, part in model.parts.items():
        x = np.zeros(model.ndof)
        x[3 * (part.offset + np.arange(part.mesh.n_nodes))] = 1.0   # a rigid x translation
        assert x @ (model.M @ x) == pytest.approx(expected[name], rel=0.01), name


# The slotted, chamfered pad of cases/slotted_pad.toml at the size of tests/data/slotted_pad:
# a 240 mm disc 11 mm thick, the pad over its mid radius, a slot 4 mm wide down to the
# backplate, chamfers 5 mm x 3 mm
SLOTTED_SHAPE = ["--set", "parts.disc.mesh.outer_radius=0.12",
                 "--set", "parts.disc.mesh.inner_radius=0.06",
                 "--set", "parts.disc.mesh.thickness=0.011",
                 "--set", "parts.pad.mesh.inner_radius=0.0675",
                 "--set", "parts.pad.mesh.outer_radius=0.1125",
                 "--set", "parts.pad.mesh.angle=52.0", "--set", "parts.pad.mesh.z0=0.011",
                 "--slot", "0.004", "--chamfer", "0.005,0.003"]
SLOTTED_SIZE = ["--size", "0.03", "--interface", "0.012", "--growth", "0.8"]
# pad_disc's sensors and tap moved onto the smaller parts
SLOTTED_POINTS = ["--set", "sensors.disc_rim.point=[0.12,0.0,0.011]",
                  "--set", "sensors.pad_back.point=[0.0,0.09,0.026]",
                  "--set", "loads.tap.point=[0.0,0.09,0.026]"]
SLOTTED = SLOTTED_SHAPE + SLOTTED_SIZE + SLOTTED_POINTS


@pytest.fixture(scope="module")
def slotted(tmp_path_factory):
    out = tmp_path_factory.mktemp("slotted")
    mesh_brake.main([str(out)] + SLOTTED)
    case = load(out / "brake.toml")
    return out, case, {name: part_mesh(case, name) for name in case.parts}


def test_slotted_pad_faces_and_layers_are_the_geometry_s(slotted):
    # the friction face is the lining's face less the slot and the chamfers (the slot's walls
    # and roof, the chamfers and the ends are sets of their own), the layers' volumes are the
    # sector's less what was cut, and every cell has a positive volume
    from brake_shapes import pad_geometry
    from transient.model.loads import face_area
    _, case, meshes = slotted
    pad = meshes["pad"]
    expected = pad_geometry(0.0675, 0.1125, math.radians(52.0), 0.01, 0.004, 0.01, 0.005, 0.003)
    for name in ("friction", "slot", "chamfer"):
        area = face_area(pad.points, pad.face_sets[name])
        assert area == pytest.approx(expected[name], rel=1e-4), name
    # the ends are the two radial planes at +-26 degrees from the y axis, nothing else
    ends = pad.points[np.unique(pad.face_sets["ends"]["triangle6"])]
    half = math.radians(26.0)
    offset = np.abs(ends[:, 0] * math.cos(half)) - np.abs(ends[:, 1] * math.sin(half))
    assert np.abs(offset).max() < 1e-9
    assert np.allclose(pad.points[pad.face_sets["friction"]["triangle6"]][..., 2], 0.011)
    lining = cell_volumes(pad, pad.cell_sets["lining"]["tetra10"])
    backplate = cell_volumes(pad, pad.cell_sets["backplate"]["tetra10"])
    assert lining.min() > 0 and backplate.min() > 0
    assert lining.sum() == pytest.approx(expected["lining"], rel=1e-4)
    assert backplate.sum() == pytest.approx(expected["sector"] * 0.005, rel=1e-4)
    assert all(det > 0 for mesh in meshes.values() for _, _, det in jacobian_check(mesh))
    disc = cell_volumes(meshes["disc"], slice(None))
    assert disc.min() > 0
    assert disc.sum() == pytest.approx(math.pi * (0.12 ** 2 - 0.06 ** 2) * 0.011, rel=1e-4)


def test_slotted_pad_has_its_two_materials(slotted):
    # the pad's mass is the lining's volume at the lining's density and the backplate's at
    # steel's: all of steel it would be 1.8 times as heavy
    from brake_shapes import pad_geometry
    _, case, _ = slotted
    expected = pad_geometry(0.0675, 0.1125, math.radians(52.0), 0.01, 0.004, 0.01, 0.005, 0.003)
    model = build_model(case)
    pad = model.parts["pad"]
    x = np.zeros(model.ndof)
    x[3 * (pad.offset + np.arange(pad.mesh.n_nodes))] = 1.0
    mass = 2500.0 * expected["lining"] + 7850.0 * expected["sector"] * 0.005
    assert x @ (model.M @ x) == pytest.approx(mass, rel=1e-4)


def test_points_the_new_sizes_leave_off_their_parts_are_told(slotted, tmp_path, capsys):
    # pad_disc's points are off the smaller disc and pad; the case would take their nearest
    # nodes without a word
    mesh_brake.main([str(tmp_path)] + SLOTTED_SHAPE + SLOTTED_SIZE)
    notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note:")]
    assert [n.split()[1] for n in notes] == ["sensors.disc_rim.point", "sensors.pad_back.point",
                                             "loads.tap.point"]
    # and the case written carries the points set
    assert slotted[1].sensors["disc_rim"].point == (0.12, 0.0, 0.011)


def test_slotted_pad_same_arguments_same_files(slotted, tmp_path, capsys):
    out, _, _ = slotted
    mesh_brake.main([str(tmp_path)] + SLOTTED)
    assert "note:" not in capsys.readouterr().out
    for name in ("disc.msh", "pad.msh", "brake.toml"):
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name


@pytest.mark.parametrize("arguments, key", [
    (["--slot", "0.004,0.02"], "--slot"),                  # deeper than the lining
    (["--slot", "0.004,-1"], "--slot"),
    (["--chamfer", "0.005"], "--chamfer"),
    (["--chamfer", "0.005,0.01"], "--chamfer"),            # the lining's whole thickness
    (["--chamfer", "0.06,0.003"], "--slot, --chamfer"),    # the chamfers meet
    (["--set", "parts.disc.mesh.thickness=0.011"], "parts.pad.mesh.z0"),
    (["--set", "parts.disc.mesh.thickness=[1]"], "parts.disc.mesh.thickness"),
])
def test_bad_shapes_are_refused_in_one_line_before_meshing(tmp_path, capsys, arguments, key):
    with pytest.raises(SystemExit) as stop:
        mesh_brake.main([str(tmp_path / "out")] + arguments)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and f": {key}: " in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out").exists()
