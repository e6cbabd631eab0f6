"""tools/mesh_brake.py: a small tet10 pad and disc built by gmsh, its case loaded as a user's
would be. Every set the case names is in the files, the cells are tet10 and not inverted, the
dofs are near the target, and the parts weigh what their volumes and materials say (so the
pad's lining got the lining's material and the mesh follows the curved faces)."""
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.mesh import generators
from transient.mesh.elements import ELEMENTS
from transient.mesh.meshfile import jacobian_check
from transient.model.model import build_model, part_mesh

gmsh = pytest.importorskip("gmsh")

TOOL = Path(__file__).resolve().parent.parent / "tools" / "mesh_brake.py"
spec = importlib.util.spec_from_file_location("mesh_brake", TOOL)
mesh_brake = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mesh_brake)

# 30k dofs: meshed in about a second, the model assembled in a few
TARGET = 30000


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("brake")
    mesh_brake.main([str(out), "--dofs", str(TARGET)])
    case = load(out / "brake.toml")
    return out, case, {name: part_mesh(case, name) for name in case.parts}


def named_sets(case):
    """(part, set, kind) of every set the case names: constraints, pressure loads, contact
    surfaces, region materials."""
    refs = [(c.set, "nodes") for c in case.constraints.values()]
    refs += [(load.set, "faces") for load in case.loads.values() if load.set]
    for pair in case.contact.values():
        refs += [(pair.surface1, "faces"), (pair.surface2, "faces")]
    out = [tuple(ref.split(".", 1)) + (kind,) for ref, kind in refs]
    out += [(name, cset, "cells") for name, part in case.parts.items()
            for cset in part.region_materials]
    return out


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


def cell_volumes(mesh, cells):
    """Volumes of tet10 cells by the element's own mass quadrature (exact for curved cells up
    to its degree)."""
    el = ELEMENTS["tetra10"]
    xi, w = el.rule(el.mass_degree)
    dN = el.shape_derivatives(xi)
    X = mesh.points[mesh.cells["tetra10"][cells]]
    J = np.swapaxes(X, 1, 2)[:, None] @ dN[None]
    return np.linalg.det(J) @ w


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
