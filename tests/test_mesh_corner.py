"""tools/mesh_corner.py: the brake corner's seven parts built by gmsh at a coarse size, its case
loaded as a user's would be. Every set the case names is in the files and lies where the
geometry puts it (each tied pair's two faces on one plane), every cell is a tet10 with a
positive volume (the mirrored outer pad's too), the parts' volumes are the geometry's written
from its dimensions, and the same arguments give the same files."""
import math

import numpy as np
import pytest

from brake_shapes import CORNER_LINING, CORNER_VOLUMES
from tet10_meshes import cell_volumes, named_sets
from transient.case.loading import load
from transient.mesh.meshfile import jacobian_check
from transient.model.model import part_mesh

gmsh = pytest.importorskip("gmsh")

# h = 20 mm, the coarsest --dofs picks (the disc's thickness): the caliper's bores turned
# cells inside out there before their walls had a size of their own
ARGUMENTS = ["--size", "0.02"]


@pytest.fixture(scope="module")
def mesh_corner():
    import mesh_corner      # tools/: setup.cfg's pythonpath
    return mesh_corner


@pytest.fixture(scope="module")
def corner(tmp_path_factory, mesh_corner):
    out = tmp_path_factory.mktemp("corner")
    mesh_corner.main([str(out)] + ARGUMENTS)
    case = load(out / "corner.toml")
    return out, case, {name: part_mesh(case, name) for name in case.parts}


@pytest.mark.slow
def test_every_set_the_case_names_is_in_its_file(corner):
    _, case, meshes = corner
    found = named_sets(case)
    assert len(case.contact) == 11 and len(found) == 2 * 11 + 4 + 3 + 2
    for part, name, kind in found:
        mesh = meshes[part]
        table = {"nodes": mesh.node_sets, "faces": mesh.face_sets, "cells": mesh.cell_sets}[kind]
        assert name in table, (part, name, kind)
        assert sum(len(v) for v in table[name].values()) if kind != "nodes" else len(table[name])


def set_points(mesh, name):
    return mesh.points[np.unique(mesh.face_sets[name]["triangle6"])]


def radial_offset(points, degrees):
    """The distance of points from the vertical plane through the axis at a polar angle."""
    t = math.radians(degrees)
    return np.abs(points[:, 0] * math.sin(t) - points[:, 1] * math.cos(t))


@pytest.mark.slow
def test_tied_faces_lie_on_one_plane(corner):
    # each tied pair's two faces on one plane (a gap of zero at the start, and the plane the
    # pair projects on), the friction faces on the disc's, the line pressure on the bores'
    # bottoms, each of them where the geometry says
    _, _, meshes = corner
    levels = {"piston_in.front": 0.035, "pad_in.back": 0.035, "piston_out.front": -0.015,
              "pad_out.back": -0.015, "caliper.seat": 0.05, "bracket.seat": 0.05,
              "bracket.knuckle": 0.045, "pad_in.friction": 0.02, "disc.zmax": 0.02,
              "pad_out.friction": 0.0, "disc.zmin": 0.0, "piston_in.back": 0.051,
              "piston_out.back": -0.031}
    for key, z in levels.items():
        part, name = key.split(".")
        assert np.abs(set_points(meshes[part], name)[:, 2] - z).max() < 1e-9, key
    bores = set_points(meshes["caliper"], "bores")[:, 2]
    assert np.abs(np.abs(bores - 0.01) - 0.041).max() < 1e-9 and bores.min() < 0 < bores.max()
    ends = {"end_lo": 65.0, "end_hi": 115.0, "abutment_lo": 65.0, "abutment_hi": 115.0}
    for part in ("pad_in", "pad_out", "caliper", "bracket"):
        for name, degrees in ends.items():
            if name in meshes[part].face_sets:
                points = set_points(meshes[part], name)
                assert radial_offset(points, degrees).max() < 1e-9, (part, name)
    # the pads' ends are their backplates' only: the abutments hold the steel
    assert set_points(meshes["pad_in"], "end_lo")[:, 2].min() == pytest.approx(0.03)
    assert set_points(meshes["pad_out"], "end_hi")[:, 2].max() == pytest.approx(-0.01)


def test_cells_are_tet10_with_positive_volumes_the_geometry_s(corner):
    _, _, meshes = corner
    for name, mesh in meshes.items():
        assert list(mesh.cells) == ["tetra10"], name
        assert all(det > 0 for _, _, det in jacobian_check(mesh)), name
        volumes = cell_volumes(mesh, slice(None))
        assert volumes.min() > 0, name
        # the meshes follow the cylinders at their nodes: within 1e-4 at this size
        assert volumes.sum() == pytest.approx(CORNER_VOLUMES[name], rel=2e-4), name
    for name in ("pad_in", "pad_out"):
        pad = meshes[name]
        lining = cell_volumes(pad, pad.cell_sets["lining"]["tetra10"])
        assert lining.min() > 0 and lining.sum() == pytest.approx(CORNER_LINING, rel=2e-4)


def test_the_outer_pad_is_the_inner_one_mirrored(corner):
    # the outer pad's lining faces up onto the disc's lower face, its backplate below it
    _, _, meshes = corner
    pad = meshes["pad_out"]
    conn = pad.cells["tetra10"]
    lining = pad.points[np.unique(conn[pad.cell_sets["lining"]["tetra10"]])]
    backplate = pad.points[np.unique(conn[pad.cell_sets["backplate"]["tetra10"]])]
    assert lining[:, 2].min() == pytest.approx(-0.01) and lining[:, 2].max() == pytest.approx(0)
    assert backplate[:, 2].min() == pytest.approx(-0.015)
    assert backplate[:, 2].max() == pytest.approx(-0.01)
    r = np.hypot(pad.points[:, 0], pad.points[:, 1])
    assert r.min() == pytest.approx(0.09) and r.max() == pytest.approx(0.135)


@pytest.mark.slow
def test_same_arguments_same_files(corner, mesh_corner, tmp_path):
    out, _, _ = corner
    mesh_corner.main([str(tmp_path)] + ARGUMENTS)
    names = sorted(p.name for p in out.iterdir())
    assert len(names) == 8 and "corner.toml" in names
    for name in names:
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name


@pytest.mark.parametrize("arguments, key", [
    (["--dofs", "-1"], "--dofs"),
    (["--size", "nan"], "--size"),
    (["--slot", "0.004,0.02"], "--slot"),                  # deeper than the lining
    (["--chamfer", "0.005,0.01"], "--chamfer"),            # the lining's whole thickness
])
def test_bad_arguments_are_refused_in_one_line_before_meshing(tmp_path, capsys, mesh_corner,
                                                              arguments, key):
    with pytest.raises(SystemExit) as stop:
        mesh_corner.main([str(tmp_path / "out")] + arguments)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and f": {key}: " in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out").exists()
