"""This machine's speed at a setup, measured: what a setup's time is estimated from before any
setup of its kind was timed here (setuptimes.estimate, which runs this module in a child
process: `python -m transient.calibration KIND`, one line of JSON on standard output).

The workload is the package's own setup, on the path asked (assembled, components or full, for
a run or a cea; modes), of a coarse pad and disc (pad_disc's scene at 1/64 of its dofs): the
element assembly, the contact's fine rule, PARDISO's factorization and shift-invert solves,
the Lanczos and the dense algebra of the basis, timed by stages.prepare's stages as a real
setup is (for `modes`, the command's work whole), the median of TIMES. Most of so small a
setup's time does not grow with the entries; a real setup's seconds are nonetheless near its
own times the entries' ratio to a power within setuptimes.GROWTH (docs/performance.md).
"""
import json
import sys
import time
from pathlib import Path

# the coarse pad and disc: cases/pad_disc.toml at 1/64 of its dofs (its divisions quartered),
# with friction, so that a cea's setup linearizes it as a real one does
DISC, PAD = [3, 36, 1], [2, 6, 1, 1]
# the setups timed, their median kept: the first also loads the kernels (or compiles them,
# once after an install: no speed of the machine's), and one disturbed by a burst of the
# machine's other work is outvoted
TIMES = 3
# cases/pad_disc.toml's scene (case_of fills in the divisions and the path's keys)
SCENE = {
    "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0},
                  "lining": {"E": 5.0e9, "nu": 0.25, "rho": 2500.0}},
    "parts": {
        "disc": {"material": "steel", "mesh": {
            "kind": "annular_disc", "inner_radius": 0.055, "outer_radius": 0.14,
            "thickness": 0.02, "element": "hex20"}},
        "pad": {"material": "steel", "region_materials": {"lining": "lining"}, "mesh": {
            "kind": "brake_pad", "inner_radius": 0.09, "outer_radius": 0.135, "angle": 50.0,
            "center_angle": 90.0, "lining_thickness": 0.01, "backplate_thickness": 0.005,
            "z0": 0.02, "element": "hex20"}}},
    "constraints": {"hub": {"set": "disc.hub"},
                    "abutment": {"set": "pad.ends", "dofs": ["x", "y"]}},
    "loads": {"piston": {"kind": "pressure", "set": "pad.back", "value": 1.0e6}},
    "solver": {"t_end": 1.0e-3, "reduction": {"fmax": 16000.0},
               "damping": {"residual": 0.05}, "modes": {"fmax": 16000.0}},
    "contact": {"pad_disc": {
        "surface1": "pad.friction", "surface2": "disc.zmax", "k": 5.0e11, "regularized": True,
        "law": {"kind": "exponential", "p0": 1.0e4, "lambda": 5.0e5},
        "friction": {"mu": 0.4}}},
    "motion": {"disc": {"kind": "rotation", "part": "disc", "axis": [0.0, 0.0, 1.0],
                        "point": [0.0, 0.0, 0.0], "omega": 5.0}},
}


def case_of(path_kind):
    """The calibration's case for a kind of setup (setuptimes.kind's names)."""
    from .case.loading import literal, parse
    method = path_kind.split("/")[0]
    full = method == "full"
    keys = {"parts.disc.mesh.divisions": DISC, "parts.pad.mesh.divisions": PAD,
            "solver.scheme": "explicit" if full else "exponential",
            "solver.reduction.enabled": not full,
            "solver.reduction.method": method if method == "components" else "assembled",
            "contact.pad_disc.rule": "fine" if full else "sampled"}
    return parse(_toml(SCENE), Path("<calibration>"),
                 [f"{key}={literal(value)}" for key, value in keys.items()])


def _toml(table, name=""):
    """TOML text of nested dicts: each table's values, then its tables under their headers."""
    from .case.loading import literal
    values = [f"{k} = {literal(v)}" for k, v in table.items() if not isinstance(v, dict)]
    tables = [_toml(v, f"{name}.{k}" if name else k) for k, v in table.items()
              if isinstance(v, dict)]
    return "\n".join(([f"[{name}]"] if name else []) + values + tables)


def setup_stages(path_kind):
    """(entries, {stage: seconds}) of the calibration's setup of a kind, in this process: its
    stages as stages.prepare times them (for `modes`, the command's work whole)."""
    from .case.sizes import entries, generated_cells
    case = case_of(path_kind)
    size = entries([generated_cells(part.mesh) for part in case.parts.values()])
    if path_kind == "modes":
        from .solve.tied import case_modes
        t0 = time.perf_counter()
        case_modes(case)
        return size, {"modes": time.perf_counter() - t0}
    from .stages import prepare
    analysis = path_kind.endswith("/cea")
    if analysis:
        from .stability.stage import analysed_case
        case = analysed_case(case)
    return size, dict(prepare(case, analysis=analysis).stages)


def median_setup(path_kind, times=TIMES):
    """{"entries", "seconds", "stages", "all"} of the median of `times` setups of a kind, in
    this process (all: each one's seconds, in turn)."""
    runs = [setup_stages(path_kind) for _ in range(times)]
    seconds = [sum(stages.values()) for _, stages in runs]
    middle = sorted(range(times), key=seconds.__getitem__)[times // 2]
    return {"entries": runs[0][0], "seconds": seconds[middle], "stages": runs[middle][1],
            "all": seconds}


if __name__ == "__main__":
    from .settings import configure
    configure()         # as the command line runs
    found = median_setup(sys.argv[1])
    print(json.dumps({"path": sys.argv[1], **found}))
