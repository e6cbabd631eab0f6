"""Bounds on the work of a case, checked before it is allocated: the memory its model and setup
will take, estimated from its cells (from the generators' divisions at load, from the cells
read for a mesh file), and the steps a run will make. Past a bound (limits.memory, the
machine's memory by default; limits.steps) the case is refused with the keys that drive it.
"""
import math
import resource

from ..errors import CaseError

NODES = {"hex8": 8, "hex20": 20, "tet4": 4, "tet10": 10, "wedge6": 6, "wedge15": 15}
# the generators split each hex in six tets (Kuhn) or in two prisms
CELLS_PER_HEX = {"tet4": 6, "tet10": 6, "wedge6": 2, "wedge15": 2}
# bytes per entry of the element matrices (COO rows, columns, values; K and M), times the
# setup's multiple of them (factorization, basis, contact): the largest of the setups' measured
# peaks per entry, from pad_disc to a 1M-dof tet10 brake (docs/performance.md, "Memory")
BYTES_PER_ENTRY = 130
# a part's reduction alone, on a worker of the components path (its interface fields, its
# factorization, modes and statics, its basis formed in place): a floor for the small parts
# (a piston's or a pad's interface columns weigh more than its entries), and per entry above
# the largest measured, which grows with the part (the factor's fill-in, the Lanczos' length:
# docs/performance.md, "A part's reduction alone")
PART_BYTES_FLOOR = 0.1e9
PART_BYTES_PER_ENTRY = 110
# the model alone (K and M assembled, and their COO triplets while they are): the components
# path's process holds it whole beside one part's setup at a time (docs/performance.md)
MODEL_BYTES_PER_ENTRY = 30


def peak_rss_gb():
    """This process's peak resident memory so far [GB] (Linux ru_maxrss, in KiB): read after
    each stage, the stage where it jumps is the one that set the peak."""
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9, 3)


def generated_cells(mesh):
    """(cells, nodes per cell) of a generated mesh spec, None for a file (counted once read)."""
    p = mesh.params
    if mesh.kind == "file":
        return None
    d = [int(x) for x in p["divisions"]]
    cells = math.prod(d[:3]) if mesh.kind != "brake_pad" else d[0] * d[1] * (d[2] + d[3])
    element = p["element"]
    return cells * CELLS_PER_HEX.get(element, 1), NODES[element]


def setup_bytes(cells):
    """Estimated peak memory [bytes] of the model and its setup: cells (count, nodes) pairs."""
    return BYTES_PER_ENTRY * entries(cells)


def part_bytes(cells, pieces=1):
    """Estimated peak memory [bytes] of one part's reduction on a worker: cells (count, nodes)
    pairs of the part; in pieces (reduce.pieces), each piece's stage on a worker holds its
    share of the part."""
    return PART_BYTES_FLOOR + PART_BYTES_PER_ENTRY * entries(cells) / pieces


def parts_cells(parts):
    """(count, nodes per cell) of each cell block of the parts' meshes (model.Part by name)."""
    return sum(cells_by_part(parts).values(), [])


def cells_by_part(parts):
    """parts_cells of each part, by name."""
    return {name: [(len(c), c.shape[1]) for c in part.mesh.cells.values()]
            for name, part in parts.items()}


def check_memory(case, cells, keys):
    """Refuse (CaseError) a model whose estimated setup exceeds limits.memory. cells: (count,
    nodes) of each cell block, by part; keys: the case key that sets each part's cells
    (divisions, a mesh file), by part. The components path (solver.reduction.method) holds
    the model whole but factorizes one part at a time: its need is the model's and the
    largest part's setup."""
    have = case.limits.memory_bytes
    need, largest = memory_need(case, cells)
    named = [keys[largest]] if largest in keys else list(keys.values())
    if need > have and named:
        raise CaseError(case.path, named[0], f"the model would take about {need / 1e9:.3g} GB "
                        f"(set by {', '.join(named)}), more than limits.memory allows "
                        f"({have / 1e9:.3g} GB): coarsen the mesh, or raise limits.memory")


def memory_need(case, cells):
    """(bytes, part or None) the setup of a model of these cells (count, nodes) by part is
    estimated to take: the whole setup's, or on the components path the model whole and its
    largest part's reduction (in this process as on a worker), named."""
    if case.solver.reduction.components:
        largest = max(cells, key=lambda name: entries(cells[name]))
        return (MODEL_BYTES_PER_ENTRY * entries(sum(cells.values(), []))
                + part_bytes(cells[largest])), largest
    return setup_bytes(sum(cells.values(), [])), None


def entries(cells):
    """Entries of the element matrices of cells, (count, nodes) pairs."""
    return sum(n * (3 * nodes) ** 2 for n, nodes in cells)


def check_generated(case):
    """The memory bound on the generated meshes, before any is meshed."""
    counted = {name: generated_cells(part.mesh) for name, part in case.parts.items()}
    counted = {name: [c] for name, c in counted.items() if c is not None}
    if counted:
        check_memory(case, counted, {name: f"parts.{name}.mesh.divisions" for name in counted})


def check_steps(case, dt):
    """Refuse a run shorter than one step, or longer than limits.steps."""
    t_end = case.solver.t_end
    steps = t_end / dt
    if round(steps) < 1:
        raise CaseError(case.path, "solver.t_end", f"{t_end:g} s is shorter than one step "
                        f"({dt:.3g} s): nothing to integrate")
    if steps > case.limits.steps:
        raise CaseError(case.path, "solver.t_end", f"{t_end:g} s at dt = {dt:.3g} s is "
                        f"{steps:.3g} steps, more than limits.steps ({case.limits.steps}): "
                        "shorten solver.t_end, lengthen solver.dt (or coarsen the mesh that "
                        "sets the critical step), or raise limits.steps")
