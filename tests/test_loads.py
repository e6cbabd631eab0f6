"""Loads and selections: resultants against closed forms, consistent nodal forces, geometry sets."""
import numpy as np
import pytest

from transient.case.loading import load
from transient.mesh.generators import annular_disc, box, brake_pad
from transient.model.loads import face_area, pressure_forces
from transient.model.model import build_model
from transient.mesh.selections import select_nodes

ELEMENTS = ["hexahedron", "hexahedron20", "tetra", "tetra10"]


@pytest.mark.parametrize("element", ELEMENTS)
def test_pressure_resultant_and_moment(element):
    mesh = box((0.3, 0.2, 0.1), (3, 2, 2), element=element)
    p = 2.5e6
    f = pressure_forces(mesh.points, mesh.face_sets["zmax"], p)
    np.testing.assert_allclose(f.sum(axis=0), [0, 0, -p * 0.06], rtol=1e-12, atol=1e-6)
    # a uniform pressure acts at the centroid of the face: moment about it vanishes
    centroid = np.array([0.15, 0.1, 0.1])
    moment = np.cross(mesh.points - centroid, f).sum(axis=0)
    np.testing.assert_allclose(moment, 0, atol=1e-9 * p)
    assert face_area(mesh.points, mesh.face_sets["zmax"]) == pytest.approx(0.06, rel=1e-12)


def test_consistent_quad8_forces_are_negative_at_corners():
    # the serendipity quad8 under uniform pressure: corners -1/12, midsides 1/3 of p A
    mesh = box((1.0, 1.0, 1.0), (1, 1, 1), element="hexahedron20")
    f = pressure_forces(mesh.points, mesh.face_sets["zmax"], 1.0)[:, 2]
    top = mesh.node_sets["zmax"]
    corners = top[np.isin(top, mesh.cells["hexahedron20"][0, :8])]
    mids = np.setdiff1d(top, corners)
    np.testing.assert_allclose(f[corners], 1 / 12, rtol=1e-12)
    np.testing.assert_allclose(f[mids], -1 / 3, rtol=1e-12)


def test_pressure_on_a_curved_face_pushes_inward():
    disc = annular_disc(0.05, 0.1, 0.01, (2, 24, 1), element="hexahedron20")
    f = pressure_forces(disc.points, disc.face_sets["outer"], 1e5)
    # the resultant of a uniform pressure on a closed cylinder vanishes; its work in the radial
    # field u = (x, y, 0) is -p R A (A = 2 pi R t), up to the quadratic geometry's error
    np.testing.assert_allclose(f.sum(axis=0), 0, atol=1e-9)
    work = np.einsum("ij,ij->", f[:, :2], disc.points[:, :2])
    assert work == pytest.approx(-1e5 * 0.1 * 2 * np.pi * 0.1 * 0.01, rel=1e-3)


def test_geometric_selections_match_generator_sets():
    disc = annular_disc(0.05, 0.1, 0.01, (2, 24, 1), element="hexahedron20")
    hub = select_nodes(disc.points, {"kind": "cylinder", "point": [0, 0, 0], "axis": [0, 0, 1],
                                     "radius": 0.05, "tol": 1e-9})
    np.testing.assert_array_equal(hub, disc.node_sets["hub"])
    top = select_nodes(disc.points, {"kind": "plane", "point": [0, 0, 0.01],
                                     "normal": [0, 0, 2.0], "tol": 1e-9})
    np.testing.assert_array_equal(top, disc.node_sets["zmax"])
    pad = brake_pad(0.06, 0.09, 40.0, 0.01, 0.005, (2, 4, 1, 1), z0=0.01)
    inside = select_nodes(pad.points, {"kind": "box", "min": [-1, -1, 0.0], "max": [1, 1, 0.01],
                                       "tol": 1e-9})
    np.testing.assert_array_equal(inside, pad.node_sets["friction"])


CASE = """
[materials.steel]
E = 2.0e11
nu = 0.3
rho = 8000.0

[parts.block]
material = "steel"
[parts.block.mesh]
kind = "box"
size = [0.2, 0.1, 0.1]
divisions = [2, 1, 1]
element = "hex20"

[parts.block.sets.top]
kind = "box"
min = [0.0, 0.0, 0.1]
max = [0.2, 0.1, 0.1]

[loads.press]
kind = "pressure"
set = "block.top"
value = 1.0e5

[loads.weight]
kind = "gravity"
vector = [0.0, 0.0, -9.81]

[loads.push]
kind = "force"
part = "block"
point = [0.2, 0.05, 0.05]
vector = [10.0, 0.0, 0.0]
"""


def test_case_loads_sum_to_their_resultants(tmp_path):
    path = tmp_path / "loads.toml"
    path.write_text(CASE)
    model = build_model(load(path))
    resultant = model.load.reshape(-1, 3).sum(axis=0)
    mass = 8000.0 * 0.2 * 0.1 * 0.1
    np.testing.assert_allclose(resultant, [10.0, 0.0, -1e5 * 0.02 - 9.81 * mass], rtol=1e-12,
                               atol=1e-9)
