"""Case files: defaults, --set overrides and one-line errors naming the file and the key."""
import json
import subprocess
import sys

import pytest

from transient.case.loading import load
from transient.cli import main
from transient.errors import CaseError

BLOCK = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0

[parts.block]
material = "steel"
[parts.block.mesh]
kind = "box"
size = [0.1, 0.02, 0.02]
divisions = [5, 1, 1]

[constraints.root]
set = "block.xmin"

[solver.modes]
count = 4
"""


def write(tmp_path, text=BLOCK, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(tmp_path, text, overrides=()):
    path = write(tmp_path, text)
    with pytest.raises(CaseError) as info:
        case = load(path, overrides)
        from transient.model.model import build_model
        build_model(case)
    return str(info.value)


def test_defaults_are_filled(tmp_path):
    case = load(write(tmp_path))
    assert case.parts["block"].mesh.params["origin"] == (0.0, 0.0, 0.0)
    assert case.constraints["root"].dofs == ("x", "y", "z")
    assert case.solver.linear_solver == "auto"
    assert case.loads == {}


def test_set_overrides_any_value_with_a_toml_literal(tmp_path):
    case = load(write(tmp_path), ["parts.block.mesh.divisions=[3,3,3]", "materials.steel.E=1e9",
                                  "parts.block.mesh.element=hex20", "solver.modes.count = 7"])
    assert case.parts["block"].mesh.params["divisions"] == (3, 3, 3)
    assert case.materials["steel"].E == 1e9
    assert case.parts["block"].mesh.params["element"] == "hex20"
    assert case.solver.modes.count == 7


@pytest.mark.parametrize("change, key, words", [
    (("nu = 0.3", "nuu = 0.3"), "materials.steel.nuu", "did you mean 'nu'"),
    (("nu = 0.3", "nu = 0.5"), "materials.steel.nu", "< 0.5"),
    (("nu = 0.3", "nu = -1.0"), "materials.steel.nu", "> -1"),
    (("E = 2.1e11", "E = -5.0"), "materials.steel.E", "> 0"),
    (("rho = 7800.0", "rho = 0.0"), "materials.steel.rho", "> 0"),
    (("rho = 7800.0", 'rho = "heavy"'), "materials.steel.rho", "expected a number"),
    (("rho = 7800.0\n", ""), "materials.steel.rho", "missing key"),
    (("divisions = [5, 1, 1]", "divisions = [5, 1]"), "parts.block.mesh.divisions", "list of 3"),
    (('kind = "box"', 'kind = "bx"'), "parts.block.mesh.kind", "did you mean 'box'"),
    (('material = "steel"', 'material = "stel"'), "parts.block.material", "unknown material"),
    (('set = "block.xmin"', 'set = "block.nowhere"'), "constraints.root.set", "has no set"),
    (('set = "block.xmin"', 'set = "other.xmin"'), "constraints.root.set", "unknown part"),
])
def test_bad_input_names_file_key_and_expectation(tmp_path, change, key, words):
    message = error_of(tmp_path, BLOCK.replace(*change))
    assert message.startswith(str(tmp_path / "case.toml") + ": " + key + ": "), message
    assert words in message
    assert "\n" not in message


def test_selection_matching_nothing_is_an_error(tmp_path):
    text = BLOCK + """
[parts.block.sets.nothing]
kind = "plane"
point = [5.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]

[constraints.none]
set = "block.nothing"
"""
    assert "matches no node" in error_of(tmp_path, text)


def test_missing_mesh_file_is_an_error(tmp_path):
    text = BLOCK.replace('kind = "box"\nsize = [0.1, 0.02, 0.02]\ndivisions = [5, 1, 1]',
                         'kind = "file"\npath = "missing.msh"')
    message = error_of(tmp_path, text)
    assert "parts.block.mesh.path" in message and "missing.msh" in message


def test_inverted_element_is_an_error(tmp_path):
    # a negative scale mirrors the mesh, which turns every cell inside out
    text = BLOCK.replace('kind = "box"\nsize = [0.1, 0.02, 0.02]\ndivisions = [5, 1, 1]',
                         'kind = "file"\npath = "block.vtu"\nscale = -1.0')
    from transient.mesh.generators import box
    from transient.mesh.meshfile import write_vtu
    write_vtu(tmp_path / "block.vtu", box((0.1, 0.02, 0.02), (5, 1, 1)))
    message = error_of(tmp_path, text)
    assert "parts.block.mesh" in message and "inverted" in message


def test_override_errors_name_the_key(tmp_path):
    message = error_of(tmp_path, BLOCK, ["materials.steel.E=[1]"])
    assert "materials.steel.E" in message and "expected a number" in message
    message = error_of(tmp_path, BLOCK, ["parts.block.mesh.divisons=[1,1,1]"])
    assert "did you mean 'divisions'" in message


def test_a_model_past_limits_memory_is_refused_at_load_naming_its_divisions(tmp_path):
    # 130 bytes per element-matrix entry: the block's 5 hex8 cells (576 entries each) ask
    # 0.37 MB, within a limit of 1 MB and not of 0.3 MB
    from transient.case.sizes import BYTES_PER_ENTRY, setup_bytes
    assert setup_bytes([(5, 8)]) == 5 * 24 ** 2 * BYTES_PER_ENTRY
    assert load(write(tmp_path, BLOCK), ["limits.memory=1e-3"]).limits.memory == 1e-3
    message = error_of(tmp_path, BLOCK, ["limits.memory=3e-4"])
    assert message.startswith(str(tmp_path / "case.toml") + ": parts.block.mesh.divisions: ")
    assert "more than limits.memory allows" in message and "\n" not in message


def test_cli_exit_code_2_one_line_no_traceback(tmp_path):
    path = write(tmp_path, BLOCK.replace("nu = 0.3", "nu = 0.7"))
    proc = subprocess.run([sys.executable, "-m", "transient", "modes", str(path)],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "materials.steel.nu" in lines[0]


def test_cli_missing_case_file(tmp_path, capsys):
    assert main(["modes", str(tmp_path / "nope.toml")]) == 2
    assert "file not found" in capsys.readouterr().err


def test_modes_json(tmp_path, capsys):
    assert main(["modes", str(write(tmp_path)), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ndof"] == 3 * 6 * 2 * 2 and len(out["frequencies_hz"]) == 4
    assert all(f > 0 for f in out["frequencies_hz"])


def test_modes_export_to_vtu(tmp_path, capsys):
    import meshio
    path = write(tmp_path)
    assert main(["modes", str(path), "--set", 'output.vtu="modes.vtu"']) == 0
    mesh = meshio.read(tmp_path / "modes.vtu")
    assert len(mesh.points) == 6 * 2 * 2
    shapes = [k for k in mesh.point_data if k.startswith("mode_")]
    assert len(shapes) == 4 and mesh.point_data[shapes[0]].shape == (24, 3)


def test_a_schema_key_without_a_spec_field_is_refused_not_dropped(tmp_path, monkeypatch):
    """case/specs.py builds each spec from its validated table: a key the schema declares but
    the dataclass lacks (a setting no stage would read) stops the first load, by name."""
    import dataclasses
    from transient.case import specs
    fewer = dataclasses.make_dataclass(
        "LimitsSpec", [(f.name, f.type) for f in dataclasses.fields(specs.LimitsSpec)
                       if f.name != "steps"])
    monkeypatch.setattr(specs, "LimitsSpec", fewer)
    with pytest.raises(TypeError, match="LimitsSpec has no field for the case key.s. steps"):
        load(write(tmp_path))
