"""Patch test: every element type reproduces a general linear displacement field exactly.

On a distorted 3x3x3 block the boundary nodes get u = a + B x (B general, non-symmetric), the
interior nodes are solved for; a conforming, consistent element must return the linear field at
the interior nodes and its constant stress at every quadrature point of every cell.
"""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from transient.mesh import generators
from transient.model.assembly import CellBlock, assemble, lame
from transient.mesh.elements import ELEMENTS, VOLUME_TYPES

E, NU, RHO = 2.1e11, 0.3, 7850.0
SIZE = np.array([0.9, 0.7, 0.5])
DIVISIONS = (3, 3, 3)
TOL = 1e-10


def distorted_block(cell_type, seed=0):
    """Box mesh with interior corner nodes moved by up to 20 % of the cell size per axis.

    Midside nodes sit at the midpoints of the straight perturbed edges. Returns points, conn and
    the boundary node ids (from the generator's face node sets, not from coordinates).
    """
    mesh = generators.box(SIZE, DIVISIONS, element=cell_type)
    el = ELEMENTS[cell_type]
    conn = mesh.cells[cell_type]
    boundary = np.unique(np.concatenate([mesh.node_sets[s] for s in
                                         ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")]))
    corners = np.setdiff1d(np.unique(conn[:, :el.n_corners]), boundary)
    points = mesh.points.copy()
    h = SIZE / np.array(DIVISIONS)
    rng = np.random.default_rng(seed)
    points[corners] += rng.uniform(-0.2, 0.2, (len(corners), 3)) * h
    for k, (a, b) in enumerate(el.edges):
        points[conn[:, el.n_corners + k]] = 0.5 * (points[conn[:, a]] + points[conn[:, b]])
    return points, conn, boundary


def cell_stresses(points, conn, u, cell_type, lam, mu):
    """Stress (ne, ng, 3, 3) at the stiffness quadrature points, from shape derivatives."""
    el = ELEMENTS[cell_type]
    xi, _ = el.rule(el.stiffness_degree)
    dN = el.shape_derivatives(xi)                                # (ng, nen, 3)
    J = np.einsum("eak,gad->egkd", points[conn], dN)             # dx_k / dxi_d
    G = np.einsum("gad,egdk->egak", dN, np.linalg.inv(J))        # dN_a / dx_k
    grad = np.einsum("eai,egak->egik", u[conn], G)               # du_i / dx_k
    eps = 0.5 * (grad + grad.transpose(0, 1, 3, 2))
    tr = np.trace(eps, axis1=2, axis2=3)[..., None, None]
    return lam * tr * np.eye(3) + 2 * mu * eps


@pytest.mark.parametrize("cell_type", VOLUME_TYPES)
def test_patch(cell_type):
    points, conn, boundary = distorted_block(cell_type)
    ne = len(conn)
    ops = assemble(points, [CellBlock(cell_type, conn, np.full(ne, E), np.full(ne, NU),
                                      np.full(ne, RHO))])
    assert min(d.min() for d in ops.min_det) > 0
    a = np.array([1.0e-3, -2.0e-3, 0.5e-3])
    B = np.array([[1.0, 0.3, -0.7], [-0.2, -0.5, 0.9], [0.4, 1.1, 0.6]]) * 1e-3
    exact = a + points @ B.T
    n = len(points)
    fixed = (3 * boundary[:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(3 * n), fixed)
    K = ops.K.tocsr()
    u = exact.ravel().copy()
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -K[free][:, fixed] @ u[fixed])
    u = u.reshape(n, 3)
    assert abs(u - exact).max() < TOL * abs(exact).max()
    lam, mu = lame(E, NU)
    eps = 0.5 * (B + B.T)
    sigma = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    s = cell_stresses(points, conn, u, cell_type, lam, mu)
    assert abs(s - sigma).max() < TOL * abs(sigma).max()
