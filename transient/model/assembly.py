"""Assembly of the stiffness K and mass M of linear elasticity as CSR matrices, and of the
materials' loss H = sum_m eta_m K_m on K's pattern."""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..mesh.elements import ELEMENTS
from ..kernels import assembly as kern


@dataclass(frozen=True)
class CellBlock:
    """Cells of one type with their material: conn (ne, nen) in global node ids, SI constants."""
    cell_type: str
    conn: np.ndarray
    young: np.ndarray      # (ne,) Young's modulus [Pa]
    poisson: np.ndarray    # (ne,) Poisson's ratio [-]
    density: np.ndarray    # (ne,) mass density [kg/m^3]
    anisotropy: object = None   # model.elasticity.Anisotropy of the cells (None: isotropic,
    #                             young and poisson's Lame constants)
    loss: np.ndarray = None     # (ne,) loss factor of each cell's material (None: none)


@dataclass(frozen=True)
class Operators:
    K: sp.csr_matrix          # stiffness [N/m], dof = 3 node + component
    M: sp.csr_matrix          # consistent mass [kg]
    lumped_mass: np.ndarray   # (ndof,) HRZ-lumped diagonal mass [kg]
    min_det: list             # per block: (ne,) minimum det J over the stiffness rule
    H: sp.csr_matrix = None   # sum over cells of their loss factor times their stiffness
    #                           [N/m] (None: no cell has a loss factor)


def lame(young, poisson):
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu = young / (2 * (1 + poisson))
    return lam, mu


def tabulate(cell_type, degree):
    """Shape values (ng, nen), reference derivatives (ng, nen, 3) and weights of a rule."""
    el = ELEMENTS[cell_type]
    xi, w = el.rule(degree)
    return (np.ascontiguousarray(el.shape_functions(xi)),
            np.ascontiguousarray(el.shape_derivatives(xi)), np.ascontiguousarray(w))


def sparsity(n_nodes, conns):
    """Node graph (ptr, idx) and dof CSR pattern (indptr, indices) of cells given per block."""
    cell_ptr = np.concatenate([[0], np.cumsum(np.concatenate(
        [np.full(len(c), c.shape[1]) for c in conns]))]).astype(np.int64)
    cell_nodes = np.concatenate([c.ravel() for c in conns]).astype(np.int64)
    ptr, idx = kern.node_graph(cell_ptr, cell_nodes, n_nodes)
    indptr, indices = kern.block_csr_pattern(ptr, idx)
    return ptr, idx, indptr, indices


def assemble(points, blocks, stiffness_degree=None, mass_degree=None):
    """K, M (CSR) and the lumped mass of cell blocks on shared points (nn, 3) [m].

    Degrees default to each element's own (exact for K and M on affine cells).
    """
    points = np.ascontiguousarray(points, dtype=float)
    n_nodes = len(points)
    conns = [np.ascontiguousarray(b.conn, dtype=np.int64) for b in blocks]
    ptr, idx, indptr, indices = sparsity(n_nodes, conns)
    k_data = np.zeros(len(indices))
    m_data = np.zeros(len(indices))
    lossy = any(b.loss is not None and np.any(b.loss) for b in blocks)
    h_data = np.zeros(len(indices)) if lossy else None
    lumped = np.zeros(n_nodes)
    min_det = []
    for block, conn in zip(blocks, conns):
        el = ELEMENTS[block.cell_type]
        ne, nen = conn.shape
        N, dN, w = tabulate(block.cell_type, stiffness_degree or el.stiffness_degree)
        Ke = np.empty((ne, 3 * nen, 3 * nen))
        det = np.empty(ne)
        if block.anisotropy is None:
            lam, mu = lame(np.asarray(block.young, float), np.asarray(block.poisson, float))
            lam, mu = np.broadcast_to(lam, ne).copy(), np.broadcast_to(mu, ne).copy()
            D = np.empty((0, 1, 6, 6))
        else:
            lam = mu = np.empty(0)
            D = np.ascontiguousarray(block.anisotropy.at(np.einsum("ga,eai->egi", N,
                                                                   points[conn])))
        kern.stiffness_blocks(points, conn, dN, w, lam, mu, D, Ke, det)
        kern.add_blocks(ptr, idx, conn, Ke, k_data)
        if block.loss is not None and np.any(block.loss):
            Ke *= np.asarray(block.loss, float)[:, None, None]
            kern.add_blocks(ptr, idx, conn, Ke, h_data)
        del Ke
        N, dN, w = tabulate(block.cell_type, mass_degree or el.mass_degree)
        Me = np.empty((ne, nen, nen))
        kern.mass_blocks(points, conn, N, dN, w,
                         np.broadcast_to(np.asarray(block.density, float), ne).copy(), Me)
        kern.add_blocks(ptr, idx, conn, Me, m_data)
        kern.lumped_mass_hrz(conn, Me, lumped)
        min_det.append(det)
    index_type = np.int32 if len(indices) < 2 ** 31 - 1 else np.int64
    indptr = indptr.astype(index_type)
    indices = indices.astype(index_type)
    shape = (3 * n_nodes, 3 * n_nodes)
    K = sp.csr_matrix((k_data, indices, indptr), shape=shape)
    # one pattern for both (0.31 GB at 1M dofs): nothing edits a model's pattern in place
    M = sp.csr_matrix((m_data, indices, indptr), shape=shape)
    H = sp.csr_matrix((h_data, indices, indptr), shape=shape) if lossy else None
    return Operators(K, M, np.repeat(lumped, 3), min_det, H)
