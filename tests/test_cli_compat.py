"""`transient compat`: the contract of its JSON, and --set moving the compatibility jump."""
import json
from pathlib import Path

import numpy as np

from transient.cli import main

CUBE = str(Path(__file__).resolve().parent.parent / "cases" / "drilled_cube.toml")


def compat_json(capsys, *overrides):
    args = ["compat", CUBE, "--json"]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


def test_compat_json_contract(capsys):
    out = compat_json(capsys)
    for key in ("n_points", "area", "n_dof_1", "n_dof_2", "singular_values", "compatibility",
                "setup_s"):
        assert key in out
    s = np.array(out["singular_values"])
    assert len(s) == out["n_dof_1"] + out["n_dof_2"] and np.all(np.diff(s) >= 0)
    assert out["n_dof_1"] == 25 and out["kept"] == 25
    C = np.array(out["compatibility"]["C"])
    assert np.all(np.diff(C) >= 0) and len(C) == len(out["compatibility"]["eps"])
    assert out["setup_s"] > 0


def test_set_moves_the_jump_with_the_coarse_division(capsys):
    out = compat_json(capsys, "parts.upper.mesh.divisions=[3,3,4]")
    assert out["n_dof_1"] == 16 and out["kept"] == 16


def test_compat_without_contact_is_a_clear_error(tmp_path, capsys):
    text = Path(CUBE).read_text()
    text = text[:text.index("[contact.interface]")]
    path = tmp_path / "nocontact.toml"
    path.write_text(text)
    assert main(["compat", str(path)]) == 2
    assert "no [contact.NAME] pair" in capsys.readouterr().err
