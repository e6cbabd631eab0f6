"""The finite element model of a case: parts meshed, K and M assembled, constraints, loads, sensors.

Parts keep their own meshes and node numbering; the model numbers the nodes of all parts one
after the other (part p's node i is global node offset_p + i) and the dofs as 3 node + component.
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..mesh import generators
from .assembly import CellBlock, assemble
from .elasticity import anisotropy
from ..mesh.elements import ALIASES, ELEMENTS
from ..case.sizes import cells_by_part, check_memory, dofs_by_part
from ..errors import CaseError
from .loads import nearest_node, pressure_forces
from .placement import check_points, check_scale
from ..mesh.mesh import Mesh, unit
from ..mesh.placement import place
from ..mesh.partfile import read_part_file
from ..mesh.selections import find_set, offered, set_faces, set_nodes, with_geometric_sets

AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class Part:
    name: str
    mesh: Mesh
    offset: int          # global id of the part's node 0


@dataclass(frozen=True)
class Model:
    points: np.ndarray           # (nn, 3) global node coordinates [m]
    parts: dict                  # name -> Part
    K: sp.csr_matrix             # stiffness [N/m] on all dofs
    M: sp.csr_matrix             # consistent mass [kg] on all dofs
    lumped_mass: np.ndarray      # (ndof,) HRZ-lumped mass [kg]
    fixed: np.ndarray            # (ndof,) bool, dofs clamped to zero
    load: np.ndarray             # (ndof,) sum of the loads [N]
    load_patterns: dict          # load name -> (ndof,) its nodal forces [N]
    sensor_names: tuple
    sensors: sp.csr_matrix       # (n_sensors, ndof) observation of the sensors [-]
    timings: dict                # stage -> seconds
    loss: sp.csr_matrix = None   # H = sum_m eta_m K_m, the materials' loss factors times
    #                              their cells' stiffness [N/m]; None: no material has one
    cells: tuple = ()            # (part name, assembly.CellBlock in global node ids): what K
    #                              and M were assembled from, a part's again where it is reduced

    @property
    def ndof(self):
        return 3 * len(self.points)

    @property
    def free(self):
        return np.flatnonzero(~self.fixed)

    def mesh(self):
        """All parts as one mesh in global node ids (no sets)."""
        cells = {}
        for part in self.parts.values():
            for ctype, conn in part.mesh.cells.items():
                cells.setdefault(ctype, []).append(conn + part.offset)
        return Mesh(self.points, {t: np.vstack(c) for t, c in cells.items()})

    def part_dofs(self, name):
        p = self.parts[name]
        n = len(p.mesh.points)
        return np.arange(3 * p.offset, 3 * (p.offset + n))


def part_mesh(case, name):
    """Mesh of a part from its generator or file, with its geometric selections, placed by
    its transform. The selections are made in the mesh's own frame, as a file's sets are, so
    a part's table copied and mirrored keeps its sets."""
    spec = case.parts[name].mesh
    key = f"parts.{name}.mesh"
    kind = spec.kind
    if kind == "file":
        mesh = read_part_file(case, name)
        points = mesh.points * spec.params["scale"] + np.asarray(spec.params["translate"])
        mesh = Mesh(points, mesh.cells, mesh.node_sets, mesh.face_sets, mesh.cell_sets)
    else:
        args = dict(spec.params)
        args["element"] = ALIASES[args["element"]]
        if kind == "drilled_box":
            args["ogrid_cells"] = args["ogrid_cells"] or None
        try:
            mesh = getattr(generators, kind)(**args)
        except ValueError as exc:
            raise CaseError(case.path, key, str(exc)) from None
    mesh = with_geometric_sets(mesh, case.parts[name].sets)
    rotate, mirror = case.parts[name].transform.rotate, case.parts[name].transform.mirror
    placed = place(mesh, case.parts[name].transform.translate,
                   (rotate.axis, rotate.angle, rotate.point) if rotate.angle else None,
                   (mirror.point, mirror.normal) if mirror.normal else None)
    if placed is not mesh and not np.isfinite(placed.points).all():
        raise CaseError(case.path, f"parts.{name}.transform", "places the part's nodes "
                        "beyond double precision: a translation or a point far out of range")
    return placed


def resolve_set(case, parts, ref, key, surface=False):
    """(part, set name) of a 'PART.SET' reference, with errors naming the key; a surface
    (contact, pressure) takes a face or node set, not a cell set."""
    if not isinstance(ref, str) or "." not in ref:
        raise CaseError(case.path, key, f"expected PART.SET, got '{ref}'")
    part, name = ref.split(".", 1)
    if part not in parts:
        raise CaseError(case.path, key, f"unknown part '{part}' (parts: {', '.join(parts)})")
    mesh = parts[part].mesh
    found = find_set(mesh.set_names(), name)
    if found is None:
        raise CaseError(case.path, key, f"part '{part}' has no set '{name}' (sets: "
                        f"{', '.join(offered(mesh.set_names())) or 'none'})")
    if surface and found not in mesh.face_sets and found not in mesh.node_sets:
        raise CaseError(case.path, key, f"'{ref}' is a cell set: a surface is a face or node "
                        f"set (face sets of part '{part}': "
                        f"{', '.join(offered(mesh.face_sets)) or 'none'})")
    return parts[part], found


def _check_quadrature(case, ctypes):
    """A stiffness rule too coarse for an element leaves K with zero-energy (hourglass) modes,
    which no loss damps: each point gives 6 strains, and K needs 3 nen - 6 (one point on hex8
    made the mode search of drilled_cube run past fmax for minutes). A mass rule of fewer
    points than nodes leaves M singular (a dense eigensolver's traceback in the cea)."""
    quad = case.solver.quadrature
    for key, degree, per_point, need, what in (
            ("stiffness", quad.stiffness, 6, lambda e: 3 * e.nen - 6, "deformation modes "
             "(zero-energy modes)"),
            ("mass", quad.mass, 1, lambda e: e.nen, "nodes (a singular mass)")):
        for ctype in sorted(ctypes) if degree else ():
            element = ELEMENTS[ctype]

            def enough(d):
                return per_point * len(element.rule(d)[0]) >= need(element)
            if not enough(degree):
                least = next(d for d in range(degree + 1, 20) if enough(d))
                raise CaseError(case.path, f"solver.quadrature.{key}", f"degree {degree} gives "
                                f"{ctype} {len(element.rule(degree)[0])} point(s), too few for "
                                f"its {need(element)} {what}: expected at least {least}, or 0 "
                                "for the element's default")


def _cell_blocks(case, parts):
    """Cell blocks in global node ids with the material of every cell."""
    materials = case.materials
    blocks = []
    for name, part in parts.items():
        spec = case.parts[name]
        key = f"parts.{name}"
        for ctype, conn in part.mesh.cells.items():
            mat = np.full(len(conn), spec.material, dtype=object)
            for cset, mname in spec.region_materials.items():
                found = find_set(part.mesh.cell_sets, cset)
                if found is None:
                    raise CaseError(case.path, f"{key}.region_materials.{cset}",
                                    f"part '{name}' has no cell set '{cset}' (cell sets: "
                                    f"{', '.join(offered(part.mesh.cell_sets)) or 'none'})")
                mat[part.mesh.cell_sets[found].get(ctype, [])] = mname
            props = {k: np.array([getattr(materials[m], k) for m in mat])
                     for k in ("E", "nu", "rho", "loss_factor")}
            blocks.append((name, ctype, CellBlock(ctype, conn + part.offset, props["E"],
                                                  props["nu"], props["rho"],
                                                  anisotropy(materials, mat, case.path),
                                                  props["loss_factor"])))
    return blocks


def _check_cells(case, blocks, min_det, parts):
    for (name, ctype, block), det in zip(blocks, min_det):
        # an overflowing det J (cells 1e100 m wide) is left to _check_finite
        finite = np.abs(det[np.isfinite(det)])
        scale = np.median(finite) if len(finite) else 1.0
        bad = np.flatnonzero(det <= 1e-10 * scale)
        if len(bad):
            e = int(bad[np.argmin(det[bad])])
            what = "inverted" if det[e] < 0 else "degenerate"
            raise CaseError(case.path, f"parts.{name}.mesh",
                            f"{ctype} cell {e} is {what} (det J = {det[e]:.3g}; "
                            f"{len(bad)} bad cell(s))")


def _check_finite(case, parts, ops):
    """K, M and the lumped mass in double precision: sizes or material constants far out of
    range overflow the cell integrals, which no later stage (an eigensolver) would explain."""
    for what, A in (("stiffness", ops.K), ("mass", ops.M), ("lumped mass", ops.lumped_mass)):
        values = A.data if sp.issparse(A) else A
        if np.isfinite(values).all():
            continue
        first = int(np.argmin(np.isfinite(values)))
        dof = np.searchsorted(A.indptr, first, side="right") - 1 if sp.issparse(A) else first
        name = next(n for n, p in parts.items()
                    if p.offset <= dof // 3 < p.offset + p.mesh.n_nodes)
        raise CaseError(case.path, f"parts.{name}.mesh", f"the {what} of its cells overflows "
                        "double precision: a size or scale, or the material's E or rho, far "
                        "out of range")


def _fixed(case, parts, ndof):
    fixed = np.zeros(ndof, bool)
    for cname, spec in case.constraints.items():
        part, sname = resolve_set(case, parts, spec.set, f"constraints.{cname}.set")
        nodes = set_nodes(part.mesh, sname) + part.offset
        if len(nodes) == 0:
            raise CaseError(case.path, f"constraints.{cname}.set",
                            f"selection '{spec.set}' matches no node")
        for d in spec.dofs:
            fixed[3 * nodes + AXES[d]] = True
        if fixed.all():
            raise CaseError(case.path, f"constraints.{cname}.set", f"'{spec.set}' clamps the "
                            "last free dofs of the model: expected constraints that leave "
                            "something to move")
    return fixed


def _loads(case, parts, points, M):
    """Nodal forces of every load, by name."""
    out = {}
    for lname, spec in case.loads.items():
        f = np.zeros(3 * len(points))
        key = f"loads.{lname}"
        if spec.kind == "pressure":
            part, sname = resolve_set(case, parts, spec.set, f"{key}.set", surface=True)
            faces = set_faces(part.mesh, sname)
            if not faces:
                raise CaseError(case.path, f"{key}.set",
                                f"selection '{spec.set}' matches no boundary face")
            local = pressure_forces(part.mesh.points, faces, spec.value)
            f[3 * part.offset:3 * part.offset + local.size] += local.ravel()
        elif spec.kind == "force":
            part = parts[spec.part]
            node = _nearest(part, spec.point)
            f[3 * node:3 * node + 3] += spec.vector
        else:
            acc = np.zeros((len(points), 3))
            for pname in spec.parts or list(parts):
                p = parts[pname]
                acc[p.offset:p.offset + p.mesh.n_nodes] = spec.vector
            f += M @ acc.ravel()
        out[lname] = f
    return out


def _nearest(part, point):
    """Global id of the part's node nearest point (placement.check_points has refused a point
    off its part)."""
    return nearest_node(part.mesh.points, point) + part.offset


def _sensors(case, parts, ndof):
    names, rows, cols, vals = [], [], [], []
    for i, (sname, spec) in enumerate(case.sensors.items()):
        part = parts[spec.part]
        node = _nearest(part, spec.point)
        names.append(sname)
        rows += [i] * 3
        cols += list(range(3 * node, 3 * node + 3))
        vals += list(unit(spec.direction))
    return tuple(names), sp.csr_matrix((vals, (rows, cols)), shape=(len(names), ndof))


def build_model(case, structure=None):
    """Mesh every part, assemble K and M, and apply constraints (the structure), then loads and
    sensors. structure: a Model built for a case equal on the structure's fields (those of
    shared.READS['model']), whose meshes, K, M and constraints are taken as they are: only the
    loads and sensors are this case's (a campaign's pressure sweep shares the rest)."""
    if structure is not None:
        s = structure
        check_points(case, s.parts)
        return _loaded(case, s.points, s.parts, s.K, s.M, s.lumped_mass, s.fixed, {}, s.loss,
                       s.cells)
    timings = {}
    t0 = time.perf_counter()
    parts, offset = {}, 0
    for name in case.parts:
        mesh = part_mesh(case, name)
        parts[name] = Part(name, mesh, offset)
        offset += mesh.n_nodes
    points = np.vstack([p.mesh.points for p in parts.values()])
    timings["mesh"] = time.perf_counter() - t0
    # a mesh in millimetres: said before the assembly's seconds
    check_scale(case, parts)
    files = [n for n in case.parts if case.parts[n].mesh.kind == "file"]
    if files:
        # the cells read: the memory bound before any matrix is assembled
        check_memory(case, cells_by_part(parts), {n: f"parts.{n}.mesh.path" for n in files},
                     dofs_by_part(parts))

    t0 = time.perf_counter()
    blocks = _cell_blocks(case, parts)
    _check_quadrature(case, {ctype for _, ctype, _ in blocks})
    quad = case.solver.quadrature
    ops = assemble(points, [b for _, _, b in blocks], quad.stiffness or None,
                   quad.mass or None)
    _check_cells(case, blocks, ops.min_det, parts)
    _check_finite(case, parts, ops)
    timings["assembly"] = time.perf_counter() - t0
    # after the cells' own checks: a point is off a part only if the part is sound
    check_points(case, parts)

    fixed = _fixed(case, parts, 3 * len(points))
    return _loaded(case, points, parts, ops.K, ops.M, ops.lumped_mass, fixed, timings, ops.H,
                   tuple((name, b) for name, _, b in blocks))


def _loaded(case, points, parts, K, M, lumped_mass, fixed, timings, loss, cells):
    """The Model of a structure with the case's loads and sensors."""
    patterns = _loads(case, parts, points, M)
    load = sum(patterns.values(), np.zeros(3 * len(points)))
    names, sensors = _sensors(case, parts, 3 * len(points))
    return Model(points, parts, K, M, lumped_mass, fixed, load, patterns, names, sensors,
                 timings, loss, cells)


def constant_load(case, model):
    """(ndof,) the sum of the loads whose signal is constant: what the preload equilibrates."""
    return sum((model.load_patterns[name] for name, load in case.loads.items()
                if load.signal["kind"] == "constant"), np.zeros(model.ndof))
