"""The design's rules that a change could quietly break: stage homes stay small, kernels stay
self-contained, a case loads without Numba, and cross-key errors come before any stage."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

from transient.cli import main

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "transient"
CASES = ROOT / "cases"


def test_no_module_over_400_lines_and_integration_under_200():
    sizes = {p.relative_to(ROOT): len(p.read_text().splitlines()) for p in PACKAGE.rglob("*.py")}
    assert {p: n for p, n in sizes.items() if n > 400} == {}
    assert sizes[Path("transient/integration.py")] < 200


def test_the_command_line_computes_through_the_api():
    """cli/ takes its numbers from transient.api and its pictures from transient/plots: the
    stages, the history's readers and the studies stay behind the API (a notebook gets what
    the command prints). Besides, the errors, the settings, the check of an output file
    before a long computation (io.lock), the campaigns' bound on their values and where the
    setup's bars are drawn (progress.shown)."""
    allowed = {"api", "errors", "settings", "plots", "io.lock", "campaign.variants", "progress"}
    found = set()
    for path in (PACKAGE / "cli").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 2:
                names = [node.module] if node.module else [a.name for a in node.names]
                found |= {(path.name, n) for n in names
                          if n not in allowed and n.split(".")[0] != "plots"}
    assert found == {("parser.py", "__version__")}


def test_kernels_import_nothing_but_numba_numpy_and_jit():
    for path in (PACKAGE / "kernels").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                assert all(a.name.split(".")[0] in ("numba", "numpy") for a in node.names), path
            elif isinstance(node, ast.ImportFrom):
                # siblings (.laws), ..jit, numba and numpy only
                ok = (node.level == 1 or (node.level == 2 and node.module == "jit")
                      or (node.level == 0 and node.module.split(".")[0] in ("numba", "numpy")))
                assert ok, f"{path.name}: from {'.' * node.level}{node.module}"


def test_loading_a_case_does_not_import_numba():
    code = ("import sys; from transient.case import load; load(sys.argv[1]); "
            "print('numba' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code, str(CASES / "pad_disc.toml")],
                          capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


@pytest.mark.parametrize("overrides, key", [
    (["solver.reduction.enabled=false"], "contact.pad_disc.rule"),
    (["solver.reduction.enabled=false", 'contact.pad_disc.rule="fine"'], "solver.scheme"),
    (['solver.scheme="explicit"', "solver.reduction.enabled=false",
      'contact.pad_disc.rule="fine"', 'solver.mass="consistent"'], "solver.mass"),
    (['contact.pad_disc.rule="greedy"', "contact.pad_disc.regularized=false"],
     "contact.pad_disc.regularized"),
    (['contact.pad_disc.surface2="pad.lining"'], "contact.pad_disc.surface2"),
    (['sensors.pad_back.part="rotor"'], "sensors.pad_back.part"),
])
def test_cross_key_errors_come_before_the_model_is_built(monkeypatch, capsys, overrides, key):
    # a wrong combination on pad_disc is refused before the first stage: the model is never
    # built (it takes seconds there), whatever the machine's speed
    import transient.stages

    def no_model(case):
        raise AssertionError("the model was built before the case was refused")
    monkeypatch.setattr(transient.stages, "build_model", no_model)
    args = ["run", str(CASES / "pad_disc.toml"), "-o", "/nonexistent/never.h5"]
    assert main(args + [a for o in overrides for a in ("--set", o)]) == 2
    err = capsys.readouterr().err
    assert f": {key}: " in err and len(err.strip().splitlines()) == 1
