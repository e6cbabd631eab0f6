"""Static contact with linear penalty: the contact patch test, and regularization on the
drilled cube against a conforming reference."""
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.contact.pair import build_contact
from transient.model.model import build_model
from transient.solve.static import solve_static
from transient.studies.drilled_cube import drilled_cube_errors

E, NU, P, K = 2.1e11, 0.3, 1.0e6, 1.0e13

PATCH = f"""
[materials.steel]
E = {E}
nu = {NU}
rho = 7800.0

[parts.lower]
material = "steel"
[parts.lower.mesh]
kind = "box"
size = [1.0, 1.0, 0.5]
divisions = [5, 5, 2]
element = "hex8"

[parts.upper]
material = "steel"
[parts.upper.mesh]
kind = "box"
size = [1.0, 1.0, 0.5]
origin = [0.0, 0.0, 0.5]
divisions = [3, 3, 2]
element = "hex8"

# rollers: the exact solution is a uniform stress -p e_z e_z, which both meshes represent
[constraints.base]
set = "lower.zmin"
dofs = ["z"]
[constraints.lower_x]
set = "lower.xmin"
dofs = ["x"]
[constraints.lower_y]
set = "lower.ymin"
dofs = ["y"]
[constraints.upper_x]
set = "upper.xmin"
dofs = ["x"]
[constraints.upper_y]
set = "upper.ymin"
dofs = ["y"]

[loads.top]
kind = "pressure"
set = "upper.zmax"
value = {P}

[contact.c]
surface1 = "upper.zmin"
surface2 = "lower.zmax"
k = {K}
"""


def solve(tmp_path, text, overrides=()):
    path = tmp_path / "case.toml"
    path.write_text(text)
    case = load(path, overrides)
    model = build_model(case)
    pairs = build_contact(case, model)
    return model, pairs, solve_static(model, pairs)


def lower_top_uz(model, solution):
    part = model.parts["lower"]
    nodes = part.mesh.node_sets["zmax"] + part.offset
    return solution.u[3 * nodes + 2]


@pytest.mark.parametrize("elements", [("hex8", "hex8"), ("hex20", "tet10"), ("tet4", "hex20")])
def test_fine_rule_passes_the_contact_patch_test(tmp_path, elements):
    overrides = [f"parts.lower.mesh.element={elements[0]}",
                 f"parts.upper.mesh.element={elements[1]}"]
    model, pairs, sol = solve(tmp_path, PATCH, overrides)
    np.testing.assert_allclose(sol.pressures[0], P, rtol=1e-8)
    np.testing.assert_allclose(sol.gaps[0], -P / K, rtol=1e-8)
    # the lower block's top is flat: uz = -p h / E everywhere (uniaxial stress)
    np.testing.assert_allclose(lower_top_uz(model, sol), -P * 0.5 / E, rtol=1e-8)


def test_centre_rule_with_coarse_master_fails_the_patch_test(tmp_path):
    model, pairs, sol = solve(tmp_path, PATCH, ["contact.c.rule=centre",
                                                "contact.c.master=surface1"])
    uz = lower_top_uz(model, sol)
    exact = -P * 0.5 / E
    # each of the 9 contact points pushes a dimple into the fine surface
    assert len(sol.pressures[0]) == 9
    assert np.abs(uz / exact - 1).max() > 0.05
    assert uz.min() < exact


def test_regularized_centre_rule_passes_it(tmp_path):
    # the uniform field is compatible: regularizing keeps it and removes the dimples
    model, pairs, sol = solve(tmp_path, PATCH, ["contact.c.rule=centre",
                                                "contact.c.regularized=true"])
    np.testing.assert_allclose(lower_top_uz(model, sol), -P * 0.5 / E, rtol=1e-6)


CUBE = Path(__file__).resolve().parent.parent / "cases" / "drilled_cube.toml"


@pytest.mark.slow
def test_drilled_cube_regularization_against_the_conforming_reference():
    errors, _ = drilled_cube_errors(CUBE)
    # the paper's ordering: the coarse centre rule dimples the fine side; regularized, it is at
    # least 2x closer to the reference (measured 3.4x); the fine rule is closest
    assert errors["centre regularized"] <= 0.5 * errors["centre"]
    assert errors["fine"] < errors["centre regularized"]
    assert errors["fine regularized"] < 2 * errors["fine"]
    # the interface mass norm regularizes better than the identity norm (the default is mass)
    identity, _ = drilled_cube_errors(CUBE, ["contact.interface.norm=identity"])
    assert errors["centre regularized"] < identity["centre regularized"]
    assert errors["fine regularized"] < identity["fine regularized"]


@pytest.mark.parametrize("rule", ["fine", "centre"])
def test_primal_formulation_passes_the_patch_test(tmp_path, rule):
    model, pairs, sol = solve(tmp_path, PATCH, [f"contact.c.rule={rule}",
                                                "contact.c.regularized=true",
                                                "contact.c.formulation=primal"])
    pair = pairs[0]
    r = pair.compat.kept(pair.eps)
    n1, n2 = pair.interface.side1.n, pair.interface.side2.n
    # eq. 11: the interface normal dofs are replaced by the traces of the r kept shapes
    assert model.ndof - n1 - n2 < pair.primal.shape[1] <= model.ndof - n1 - n2 + 2 * r
    np.testing.assert_allclose(lower_top_uz(model, sol), -P * 0.5 / E, rtol=1e-6)
