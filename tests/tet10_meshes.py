"""What the tests of the gmsh tools (tools/mesh_brake.py, tools/mesh_corner.py) check on a
case's tet10 meshes: the sets it names, the cells' volumes."""
import numpy as np

from transient.mesh.elements import ELEMENTS


def named_sets(case):
    """(part, set, kind) of every set the case names: constraints, pressure loads, contact
    surfaces, region materials."""
    refs = [(c.set, "nodes") for c in case.constraints.values()]
    refs += [(load.set, "faces") for load in case.loads.values() if load.set]
    for pair in case.contact.values():
        refs += [(pair.surface1, "faces"), (pair.surface2, "faces")]
    out = [tuple(ref.split(".", 1)) + (kind,) for ref, kind in refs]
    out += [(name, cset, "cells") for name, part in case.parts.items()
            for cset in part.region_materials]
    return out


def cell_volumes(mesh, cells):
    """Volumes of tet10 cells by the element's own mass quadrature (exact for curved cells up
    to its degree)."""
    el = ELEMENTS["tetra10"]
    xi, w = el.rule(el.mass_degree)
    dN = el.shape_derivatives(xi)
    X = mesh.points[mesh.cells["tetra10"][cells]]
    J = np.swapaxes(X, 1, 2)[:, None] @ dN[None]
    return np.linalg.det(J) @ w
