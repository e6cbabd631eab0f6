"""Bounds on the work of a case, checked before it is allocated: the memory its model and setup
will take, estimated from its cells (from the generators' divisions at load, from the cells
read for a mesh file), and the steps a run will make. Past a bound (limits.memory, the
machine's memory by default; limits.steps) the case is refused with the keys that drive it.

The estimate is each process's: this one's, and on the components path reduced on a Dask
cluster (the command's --workers or --scheduler, Case.cluster) the client's in this process
and each part's (or piece's) on a worker.
"""
import math
import resource
import shutil
import tempfile
from dataclasses import dataclass

from ..errors import CaseError
from .specs import physical_memory

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
# the components path's client on a cluster holds the parts' bases side by side (the
# synthesis): each part's free dofs times its columns (its modes past the cutoff, its
# interface fields and loads), which grow with the basis' cutoff: PART_COLUMNS a part at
# COLUMNS_CUTOFF, in proportion to it, above every part measured (docs/performance.md, "Each
# part reduced on its own"); its dofs from its entries at ENTRIES_PER_DOF, the fewest of the
# solid meshes measured (a coarser ratio counts more dofs)
PART_COLUMNS = 1000
COLUMNS_CUTOFF = 32000.0
ENTRIES_PER_DOF = 150
# and beside them the coupling's dense reduced matrices and the process itself
CLIENT_MARGIN = 0.5e9
# a part in pieces: a piece's stage on a worker holds the worker's process and libraries
# (PIECE_FLOOR), PIECE_SHARE times its share of the part (its factors, complex in its
# condensation, and its fixed-cut modes) and PIECE_DENSE dense matrices of the cut's dofs it
# touches (the complex Schur complement PARDISO forms and returns, its real and imaginary
# parts made S and Mh, the last piece's still to be gathered: reduce.piece); the client the
# cut's condensation dense, CUT_MATRICES of its size at once (its stiffness, then its Cholesky
# factor in its place, its mass and their inertia's LDL^T: reduce.cut); the cut's dofs
# CUT_DOFS (pieces - 1) dofs^(2/3) of the part's. Each above what was measured, on the 4x
# pad_disc's disc and the 1M pad and disc's in 4 and 5 pieces (docs/performance.md, "A part in
# pieces", "The parts' bases and the pieces' columns in files", "Where a piece's first stage
# goes")
PIECE_FLOOR = 2.2e9
PIECE_SHARE = 0.6
PIECE_DENSE = 9
CUT_MATRICES = 3
CUT_DOFS = 0.5
# an embedded cluster's worker between its tasks: its process and what its pieces' columns
# in files keep resident, which the client's stages (the cut, the synthesis) find beside them
WORKER_IDLE = 2.5e9


@dataclass(frozen=True)
class Cluster:
    """Where the components path reduces its parts, as the command says before the case
    loads: workers, those of an embedded LocalCluster on this machine (--workers N); remote,
    an existing scheduler's (--scheduler), whose workers' memory it tells once reached;
    neither: this process."""
    workers: int = 0
    remote: bool = False

    @classmethod
    def of(cls, workers=0, scheduler=None):
        """The Cluster of the commands' --workers and --scheduler (a scheduler wins, as
        cluster.client_for takes it)."""
        return cls(0, True) if scheduler else cls(int(workers or 0), False)

    def __bool__(self):
        return self.workers > 0 or self.remote


@dataclass(frozen=True)
class Need:
    """The memory a setup is estimated to take [B], by process: here, this process's (the
    client's on a cluster), the sum of its terms ((what, bytes) pairs, said); part, the part
    whose reduction that counts (None: none alone); worker, the largest part's (or piece's)
    reduction on a worker, and its part (None: no worker); disk, the parts' bases in files
    under the temporary directory (reduce.store: the components path on this machine);
    beside, what of here the client holds while an embedded cluster's workers reduce (the
    model and the process: its cuts and the waiting workers come between their tasks)."""
    here: float
    part: str = None
    worker: float = None
    worker_part: str = None
    terms: tuple = ()
    disk: float = 0.0
    beside: float = None

    def said(self):
        """The terms in words: 'the model 5.8 GB, ...'."""
        return ", ".join(f"{what} {b / 1e9:.3g} GB" for what, b in self.terms)


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


def part_bytes(cells, pieces=1, dofs=None):
    """Estimated peak memory [bytes] of one part's reduction on a worker: cells (count, nodes)
    pairs of the part (dofs: its mesh's, where read); in pieces (reduce.pieces), each piece's
    stage on a worker holds the worker's own PIECE_FLOOR, PIECE_SHARE times its share of the
    part, and PIECE_DENSE dense matrices of the cut's dofs it touches (piece_cut_dofs), never
    more than the part whole. In one process a part in pieces takes no less than whole (its
    pieces' columns and the cut's model beside each piece's stage): memory_need counts it
    whole."""
    whole = PART_BYTES_FLOOR + PART_BYTES_PER_ENTRY * entries(cells)
    if pieces == 1:
        return whole
    n = dofs if dofs is not None else entries(cells) / ENTRIES_PER_DOF
    return min(whole, PIECE_FLOOR + PART_BYTES_PER_ENTRY * entries(cells) * PIECE_SHARE
               / pieces + PIECE_DENSE * 8.0 * piece_cut_dofs(n, pieces) ** 2)


def piece_cut_dofs(dofs, pieces):
    """The cut's dofs a piece of a part of dofs touches: its share of the cut's two sides."""
    return 2.0 * CUT_DOFS * (pieces - 1) * dofs ** (2.0 / 3.0) / pieces


def cut_bytes(dofs, pieces):
    """Estimated memory [bytes] of the cut's dense model on the client, of a part of dofs in
    pieces (none whole)."""
    if pieces == 1:
        return 0.0
    return CUT_MATRICES * 8.0 * (CUT_DOFS * (pieces - 1) * dofs ** (2.0 / 3.0)) ** 2


def synthesis_bytes(cells, cutoff, dofs=None):
    """Estimated memory [bytes] of the parts' bases side by side, cells (count, nodes) pairs
    by part: each part's dofs (part_dofs) times its columns to the basis' cutoff [Hz] (at most
    its dofs), 8 bytes each."""
    columns = PART_COLUMNS * cutoff / COLUMNS_CUTOFF
    return sum(8.0 * n * min(n, columns) for n in part_dofs(cells, dofs).values())


def part_dofs(cells, dofs=None):
    """Each part's dofs, by part: dofs' where its mesh is read, else from its entries."""
    return {name: (dofs or {}).get(name, entries(c) / ENTRIES_PER_DOF)
            for name, c in cells.items()}


def parts_cells(parts):
    """(count, nodes per cell) of each cell block of the parts' meshes (model.Part by name)."""
    return sum(cells_by_part(parts).values(), [])


def cells_by_part(parts):
    """parts_cells of each part, by name."""
    return {name: mesh_cells(part.mesh) for name, part in parts.items()}


def dofs_by_part(parts):
    """The dofs of each part's mesh, by name."""
    return {name: 3 * part.mesh.n_nodes for name, part in parts.items()}


def mesh_cells(mesh):
    """(count, nodes per cell) of each cell block of a mesh."""
    return [(len(c), c.shape[1]) for c in mesh.cells.values()]


def check_memory(case, cells, keys, dofs=None):
    """Refuse (CaseError) a model whose estimated setup exceeds limits.memory in this process,
    or a part whose reduction exceeds the workers' share of it on an embedded cluster
    (worker_budget). cells: (count, nodes) of each cell block, by part; keys: the case key
    that sets each part's cells (divisions, a mesh file), by part; dofs: as memory_need's."""
    have = case.limits.memory_bytes
    need = memory_need(case, cells, dofs)
    named = [keys[need.part]] if need.part in keys else list(keys.values())
    if need.here > have and named:
        auto = f" ({case.reduction_auto})" if case.reduction_auto else ""
        fix = ("coarsen the mesh, raise limits.memory, or reduce the parts on workers "
               "(--workers, --scheduler)" if need.part is not None
               else "coarsen the mesh, or raise limits.memory")
        what = ("this process, the cluster's client," if need.worker is not None
                else "the model")
        terms = f": {need.said()}" if need.terms else ""
        raise CaseError(case.path, named[0], f"{what} would take about {need.here / 1e9:.3g} "
                        f"GB (set by {', '.join(named)}{terms}), more than limits.memory "
                        f"allows ({have / 1e9:.3g} GB): {fix}{auto}")
    if need.disk:
        check_disk(case, need.disk, named[0] if named else "solver.reduction.method")
    if worker_budget(case, need) is not None:
        pieces = {name: case.parts[name].pieces for name in cells}

        def budget(name, count):
            return worker_budget(case, memory_need(case, cells, dofs, {**pieces, name: count}))
        check_workers(case, {n: c for n, c in cells.items() if n in keys}, budget,
                      f"a worker's share of limits.memory beside this process, "
                      f"{case.cluster.workers} workers", dofs)


def check_disk(case, need, key):
    """Refuse (CaseError) the components path where its parts' bases (need [B], in files under
    the temporary directory: reduce.store) would not fit the disk that holds it."""
    folder = tempfile.gettempdir()
    free = shutil.disk_usage(folder).free
    if need > free:
        raise CaseError(case.path, key, f"the parts' bases would take about {need / 1e9:.3g} GB "
                        f"of disk in {folder}, which has {free / 1e9:.3g} GB free: set TMPDIR "
                        "to a folder on a larger disk, or coarsen the mesh")


def memory_need(case, cells, dofs=None, pieces=None):
    """The Need of a setup of a model of these cells (count, nodes) by part: the whole
    setup's in this process; on the components path the model whole and its largest part's
    reduction, whole even in pieces (part_bytes); on a cluster (case.cluster) the client's
    model and synthesis (dofs: of each part's mesh, where read) in this process, and the
    largest part's or piece's on a worker (pieces: their count by part, the case's by
    default)."""
    if not case.solver.reduction.components:
        return Need(setup_bytes(sum(cells.values(), [])))
    terms = [("the model", MODEL_BYTES_PER_ENTRY * entries(sum(cells.values(), [])))]
    # the parts' bases: in files this process maps (reduce.store), but from a remote
    # cluster's workers, handed back whole
    bases = synthesis_bytes(cells, case.solver.reduction.modes_fmax, dofs)
    disk = 0.0 if case.cluster.remote else bases
    if not case.cluster:
        largest = max(cells, key=lambda name: entries(cells[name]))
        terms.append((f"the reduction of {largest}", part_bytes(cells[largest])))
        return Need(sum(b for _, b in terms), largest, terms=tuple(terms), disk=disk)
    pieces = pieces or {name: case.parts[name].pieces for name in cells}
    n = part_dofs(cells, dofs)
    worker = {name: part_bytes(c, pieces[name], n[name]) for name, c in cells.items()}
    largest = max(worker, key=worker.get)
    if case.cluster.remote:
        terms.append(("the parts' bases side by side", bases))
    between = [(f"the cut of {name} in {pieces[name]} pieces", cut_bytes(n[name], pieces[name]))
               for name in cells if pieces[name] > 1]
    if case.cluster.workers:
        between.append((f"{case.cluster.workers} workers waiting",
                        case.cluster.workers * WORKER_IDLE))
    terms += between + [("the coupling and the process", CLIENT_MARGIN)]
    here = sum(b for _, b in terms)
    return Need(here, None, worker[largest], largest, tuple(terms), disk,
                here - sum(b for _, b in between))


def worker_budget(case, need):
    """The memory [B] each worker of an embedded cluster may take: what limits.memory leaves
    beside this process while the workers reduce (need.beside: the client cuts a part in
    pieces and synthesizes between their tasks), shared by the workers, and no more than the
    LocalCluster gives each (the machine's memory shared by them); None without workers on
    this machine (a scheduler's tell their own: reduce.components.check_parts)."""
    workers = case.cluster.workers
    if not workers or not case.solver.reduction.components:
        return None
    return min(case.limits.memory_bytes - need.beside, physical_memory()) / workers


def check_workers(case, cells, budget, whose="a worker's memory", dofs=None):
    """Refuse a part whose reduction's estimated memory (cells: (count, nodes) by part)
    exceeds budget(part, pieces) [B], a worker's with the part in that many pieces (whose:
    what bounds it, said), naming parts.NAME.pieces and the count that fits, if any."""
    n = part_dofs(cells, dofs)
    for name, c in cells.items():
        pieces = case.parts[name].pieces
        need, have = part_bytes(c, pieces, n[name]), budget(name, pieces)
        if need > have:
            fits = next((k for k in range(pieces + 1, 65)
                         if part_bytes(c, k, n[name]) <= budget(name, k)), None)
            more = (f"parts.{name}.pieces = {fits}" if fits else "workers with more memory")
            raise CaseError(case.path, f"parts.{name}.pieces", f"the part's reduction would "
                            f"take about {need / 1e9:.3g} GB{' a piece' if pieces > 1 else ''}, "
                            f"more than {whose} ({have / 1e9:.3g} GB): {more}, or a "
                            "coarser mesh of the part")


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
