"""Studies shared by tests and tools: the drilled cube against its conforming reference."""
import numpy as np

from ..case.loading import load
from ..contact.pair import build_contact
from ..model.model import build_model
from ..solve.static import solve_static

# The conforming reference: the upper cube meshed with the lower cube's plan, the hole filled.
REFERENCE = ("parts.upper.mesh.kind=drilled_box", "parts.upper.mesh.filled=true")

RULES = {
    "fine": ("contact.interface.rule=fine", "contact.interface.regularized=false"),
    "fine regularized": ("contact.interface.rule=fine", "contact.interface.regularized=true"),
    "centre": ("contact.interface.rule=centre", "contact.interface.regularized=false"),
    "centre regularized": ("contact.interface.rule=centre",
                           "contact.interface.regularized=true"),
    "centre primal": ("contact.interface.rule=centre", "contact.interface.regularized=true",
                      "contact.interface.formulation=primal"),
}


def _reference_overrides(case):
    lower = case.parts["lower"].mesh.params
    upper = case.parts["upper"].mesh.params
    return list(REFERENCE) + [
        f"parts.upper.mesh.{key}={_literal(lower[key])}"
        for key in ("divisions", "hole_center", "hole_radius", "element", "ogrid_cells")
    ] + [f"parts.upper.mesh.origin={_literal(upper['origin'])}"]


def _literal(value):
    """A TOML literal of a spec value (strings quoted, tuples as arrays)."""
    if isinstance(value, str):
        return f'"{value}"'
    return repr(list(value)) if isinstance(value, tuple) else repr(value)


def fine_side_displacement(case_path, overrides=()):
    """Static solution: displacement (n, 3) of the lower cube's top nodes, the nodes' interface
    mass weights, and the solution object."""
    case = load(case_path, overrides)
    model = build_model(case)
    pairs = build_contact(case, model)
    sol = solve_static(model, pairs)
    lower = model.parts["lower"]
    nodes = lower.mesh.node_sets["zmax"]
    u = sol.u.reshape(-1, 3)[nodes + lower.offset]
    return u, nodes, sol


def drilled_cube_errors(case_path, extra=()):
    """Relative L2 error (nodal, over the fine side's interface) of each rule's fine-side
    displacement against the conforming reference; returns (errors, reference norm)."""
    case = load(case_path, extra)
    ref, ref_nodes, _ = fine_side_displacement(case_path, list(extra)
                                               + _reference_overrides(case)
                                               + list(RULES["fine"]))
    errors = {}
    for name, rule in RULES.items():
        u, nodes, _ = fine_side_displacement(case_path, list(extra) + list(rule))
        assert np.array_equal(nodes, ref_nodes)
        errors[name] = float(np.linalg.norm(u - ref) / np.linalg.norm(ref))
    return errors, float(np.linalg.norm(ref))
