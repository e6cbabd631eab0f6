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


def import_graph(taken=None):
    """{module: {modules it imports}} over the package's modules (dotted names below
    transient, "" the package itself), every import counted: at module level and inside a
    function (a deferred import is still a dependency). taken (a dict, filled if given):
    {module: the names it takes from the package itself, "*" for the package whole}."""
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        modules[name] = path
    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                found |= {a.name[len("transient."):] if a.name != "transient" else ""
                          for a in node.names if a.name.split(".")[0] == "transient"}
                if "" in found and taken is not None:
                    taken.setdefault(name, set()).add("*")
            elif isinstance(node, ast.ImportFrom):
                if node.level == 0:
                    if (node.module or "").split(".")[0] != "transient":
                        continue
                    base = node.module[len("transient."):] if node.module != "transient" else ""
                else:
                    up = package.split(".") if package else []
                    up = up[:len(up) - (node.level - 1)]
                    base = ".".join(up + ([node.module] if node.module else []))
                for a in node.names:
                    sub = f"{base}.{a.name}" if base else a.name
                    found.add(sub if sub in modules else base)
                    if sub not in modules and base == "" and taken is not None:
                        taken.setdefault(name, set()).add(a.name)
        graph[name] = {m for m in found if m in modules and m != name}
    return graph


def test_the_modules_import_one_another_without_a_circle():
    """No circle among the package's modules: each stage imports only those below it. The
    one deferred edge allowed is the package's own PEP 562 door to the API (transient.X
    imports transient.api on first use), which nothing below the API may lean on: no module
    but the command line and the package imports the API."""
    taken = {}
    graph = import_graph(taken)
    assert graph[""] == {"settings", "api"}
    graph[""].discard("api")
    # through the package's door a module takes its version, nothing else: the settings
    # from their home, the API not at all
    assert {m: names for m, names in taken.items() if names != {"__version__"}} == {}
    leaning = {m for m, deps in graph.items() if "api" in deps and m.split(".")[0] != "cli"}
    assert leaning == set()
    # the strongly connected components (Tarjan): each a circle if more than one module
    index, low, stack, on, circles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert circles == []


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
