"""Element matrices of linear elasticity (isotropic, or any D) and their summation into CSR.

Element matrices are COO triplets in compact form: the value of entry (3a+i, 3b+j) of cell e sits
at blocks[e, 3a+i, 3b+j]; its row and column are the dofs 3 conn[e,a]+i and 3 conn[e,b]+j. The
summation kernel builds the node graph once, then adds every block in place (no sort of triplets).
"""
import numpy as np

from ..jit import njit


@njit
def _jacobian(X, nodes, dN, J):
    """J[i, d] = dx_i / dxi_d at one point; returns det J and overwrites J with inv(J)^T."""
    for i in range(3):
        for d in range(3):
            s = 0.0
            for a in range(nodes.shape[0]):
                s += X[nodes[a], i] * dN[a, d]
            J[i, d] = s
    det = (J[0, 0] * (J[1, 1] * J[2, 2] - J[1, 2] * J[2, 1])
           - J[0, 1] * (J[1, 0] * J[2, 2] - J[1, 2] * J[2, 0])
           + J[0, 2] * (J[1, 0] * J[2, 1] - J[1, 1] * J[2, 0]))
    c00 = J[1, 1] * J[2, 2] - J[1, 2] * J[2, 1]
    c01 = J[1, 2] * J[2, 0] - J[1, 0] * J[2, 2]
    c02 = J[1, 0] * J[2, 1] - J[1, 1] * J[2, 0]
    c10 = J[0, 2] * J[2, 1] - J[0, 1] * J[2, 2]
    c11 = J[0, 0] * J[2, 2] - J[0, 2] * J[2, 0]
    c12 = J[0, 1] * J[2, 0] - J[0, 0] * J[2, 1]
    c20 = J[0, 1] * J[1, 2] - J[0, 2] * J[1, 1]
    c21 = J[0, 2] * J[1, 0] - J[0, 0] * J[1, 2]
    c22 = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
    inv = 1.0 / det if det != 0.0 else 0.0
    # inv(J)^T equals the cofactor matrix divided by det J
    J[0, 0], J[0, 1], J[0, 2] = c00 * inv, c01 * inv, c02 * inv
    J[1, 0], J[1, 1], J[1, 2] = c10 * inv, c11 * inv, c12 * inv
    J[2, 0], J[2, 1], J[2, 2] = c20 * inv, c21 * inv, c22 * inv
    return det


@njit
def _gradients(X, nodes, dN, J, G):
    """G[a, i] = dN_a / dx_i at one point (G (nen, 3)); returns det J (J: _jacobian's)."""
    det = _jacobian(X, nodes, dN, J)
    for a in range(nodes.shape[0]):
        for i in range(3):
            G[a, i] = dN[a, 0] * J[i, 0] + dN[a, 1] * J[i, 1] + dN[a, 2] * J[i, 2]
    return det


@njit
def _mirror(Ke, nen):
    """The blocks below the diagonal from those above: the kernels fill b >= a only."""
    for a in range(nen):
        for b in range(a + 1, nen):
            for i in range(3):
                for j in range(3):
                    Ke[3 * b + j, 3 * a + i] = Ke[3 * a + i, 3 * b + j]


@njit
def _isotropic_point(Ke, G, cl, cm):
    """Ke's blocks b >= a += the isotropic term of one rule point: G its gradients (nen, 3),
    cl and cm the Lame constants times the point's weight and det J."""
    nen = G.shape[0]
    for a in range(nen):
        ga0, ga1, ga2 = G[a, 0], G[a, 1], G[a, 2]
        for b in range(a, nen):
            gb0, gb1, gb2 = G[b, 0], G[b, 1], G[b, 2]
            s = cm * (ga0 * gb0 + ga1 * gb1 + ga2 * gb2)
            r, q = 3 * a, 3 * b
            Ke[r, q] += cl * ga0 * gb0 + cm * ga0 * gb0 + s
            Ke[r, q + 1] += cl * ga0 * gb1 + cm * ga1 * gb0
            Ke[r, q + 2] += cl * ga0 * gb2 + cm * ga2 * gb0
            Ke[r + 1, q] += cl * ga1 * gb0 + cm * ga0 * gb1
            Ke[r + 1, q + 1] += cl * ga1 * gb1 + cm * ga1 * gb1 + s
            Ke[r + 1, q + 2] += cl * ga1 * gb2 + cm * ga2 * gb1
            Ke[r + 2, q] += cl * ga2 * gb0 + cm * ga0 * gb2
            Ke[r + 2, q + 1] += cl * ga2 * gb1 + cm * ga1 * gb2
            Ke[r + 2, q + 2] += cl * ga2 * gb2 + cm * ga2 * gb2 + s


@njit
def _anisotropic_point(Ke, G, Dg, c, DB):
    """Ke's blocks b >= a += c B^T Dg B of one rule point: G its gradients (nen, 3), Dg (6, 6),
    c its weight times det J; DB (nen, 6, 3) is scratch."""
    nen = G.shape[0]
    for b in range(nen):
        g0, g1, g2 = G[b, 0], G[b, 1], G[b, 2]
        # D B_b: B_b's columns are (g0, 0, 0, 0, g2, g1), (0, g1, 0, g2, 0, g0) and
        # (0, 0, g2, g1, g0, 0)
        for r in range(6):
            DB[b, r, 0] = c * (Dg[r, 0] * g0 + Dg[r, 4] * g2 + Dg[r, 5] * g1)
            DB[b, r, 1] = c * (Dg[r, 1] * g1 + Dg[r, 3] * g2 + Dg[r, 5] * g0)
            DB[b, r, 2] = c * (Dg[r, 2] * g2 + Dg[r, 3] * g1 + Dg[r, 4] * g0)
    for a in range(nen):
        g0, g1, g2 = G[a, 0], G[a, 1], G[a, 2]
        for b in range(a, nen):
            for j in range(3):
                Ke[3 * a, 3 * b + j] += (g0 * DB[b, 0, j] + g2 * DB[b, 4, j]
                                         + g1 * DB[b, 5, j])
                Ke[3 * a + 1, 3 * b + j] += (g1 * DB[b, 1, j] + g2 * DB[b, 3, j]
                                             + g0 * DB[b, 5, j])
                Ke[3 * a + 2, 3 * b + j] += (g2 * DB[b, 2, j] + g1 * DB[b, 3, j]
                                             + g0 * DB[b, 4, j])


@njit
def stiffness_blocks(X, conn, dN, w, lam, mu, D, blocks, min_det):
    """Stiffness of every cell into blocks (ne, 3 nen, 3 nen); min det J per cell into min_det.

    X (nn, 3) coordinates; conn (ne, nen); dN (ng, nen, 3) reference derivatives and w (ng)
    weights of the quadrature rule. The material: isotropic, lam, mu (ne) Lame constants [Pa],
    where D has no cell; else D (ne, ng or 1, 6, 6) [Pa], an elasticity matrix per cell and
    rule point (or per cell), Voigt order 11, 22, 33, 23, 13, 12 with engineering shears:
    Ke = sum_g w_g det J_g B_g^T D_g B_g (lam and mu unused).
    """
    ne, nen = conn.shape
    ng = w.shape[0]
    isotropic = D.shape[0] == 0
    per_point = D.shape[1] > 1
    J = np.empty((3, 3))
    G = np.empty((nen, 3))
    DB = np.empty((nen, 6, 3))
    for e in range(ne):
        nodes = conn[e]
        Ke = blocks[e]
        Ke[:, :] = 0.0
        md = np.inf
        for g in range(ng):
            det = _gradients(X, nodes, dN[g], J, G)
            md = min(md, det)
            c = w[g] * det
            if isotropic:
                _isotropic_point(Ke, G, c * lam[e], c * mu[e])
            else:
                _anisotropic_point(Ke, G, D[e, g if per_point else 0], c, DB)
        _mirror(Ke, nen)
        min_det[e] = md


@njit
def mass_blocks(X, conn, N, dN, w, rho, blocks):
    """Scalar consistent mass of every cell into blocks (ne, nen, nen): rho int N_a N_b dV [kg]."""
    ne, nen = conn.shape
    ng = w.shape[0]
    J = np.empty((3, 3))
    for e in range(ne):
        nodes = conn[e]
        Me = blocks[e]
        Me[:, :] = 0.0
        for g in range(ng):
            c = w[g] * _jacobian(X, nodes, dN[g], J) * rho[e]
            for a in range(nen):
                ca = c * N[g, a]
                for b in range(a, nen):
                    Me[a, b] += ca * N[g, b]
        for a in range(nen):
            for b in range(a + 1, nen):
                Me[b, a] = Me[a, b]


@njit
def node_graph(cell_ptr, cell_nodes, n_nodes):
    """Sorted neighbours of every node through shared cells, as CSR (ptr, idx).

    Cells of any types are given as one flat list: the nodes of cell c are
    cell_nodes[cell_ptr[c]:cell_ptr[c + 1]].
    """
    n_cells = cell_ptr.shape[0] - 1
    count = np.zeros(n_nodes + 1, np.int64)
    for c in range(n_cells):
        for k in range(cell_ptr[c], cell_ptr[c + 1]):
            count[cell_nodes[k] + 1] += 1
    nc_ptr = np.cumsum(count)
    nc_idx = np.empty(nc_ptr[-1], np.int64)
    fill = nc_ptr[:-1].copy()
    for c in range(n_cells):
        for k in range(cell_ptr[c], cell_ptr[c + 1]):
            n = cell_nodes[k]
            nc_idx[fill[n]] = c
            fill[n] += 1
    mark = np.full(n_nodes, -1, np.int64)
    ptr = np.zeros(n_nodes + 1, np.int64)
    bound = 0
    for n in range(n_nodes):
        for k in range(nc_ptr[n], nc_ptr[n + 1]):
            c = nc_idx[k]
            bound += cell_ptr[c + 1] - cell_ptr[c]
    idx = np.empty(bound, np.int64)
    pos = 0
    for n in range(n_nodes):
        start = pos
        for k in range(nc_ptr[n], nc_ptr[n + 1]):
            c = nc_idx[k]
            for q in range(cell_ptr[c], cell_ptr[c + 1]):
                m = cell_nodes[q]
                if mark[m] != n:
                    mark[m] = n
                    idx[pos] = m
                    pos += 1
        idx[start:pos].sort()
        ptr[n + 1] = pos
    return ptr, idx[:pos].copy()


@njit
def block_csr_pattern(ptr, idx):
    """CSR pattern of the 3 x 3 dof blocks of a node graph (dof = 3 node + component)."""
    n_nodes = ptr.shape[0] - 1
    indptr = np.empty(3 * n_nodes + 1, np.int64)
    indices = np.empty(9 * ptr[-1], np.int64)
    indptr[0] = 0
    for n in range(n_nodes):
        deg = ptr[n + 1] - ptr[n]
        for i in range(3):
            r = 3 * n + i
            start = 9 * ptr[n] + 3 * deg * i
            indptr[r + 1] = start + 3 * deg
            for k in range(deg):
                for j in range(3):
                    indices[start + 3 * k + j] = 3 * idx[ptr[n] + k] + j
    return indptr, indices


@njit
def _find(idx, lo, hi, value):
    while lo < hi:
        mid = (lo + hi) // 2
        if idx[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit
def add_blocks(ptr, idx, conn, blocks, data):
    """data += blocks summed into the block CSR pattern of (ptr, idx): blocks (ne, 3 nen, 3 nen)
    entry by entry, or scalar blocks (ne, nen, nen) (a mass) times the 3 x 3 identity."""
    ne, nen = conn.shape
    scalar = blocks.shape[1] == nen
    for e in range(ne):
        for a in range(nen):
            A = conn[e, a]
            deg = ptr[A + 1] - ptr[A]
            for b in range(nen):
                k = _find(idx, ptr[A], ptr[A + 1], conn[e, b]) - ptr[A]
                for i in range(3):
                    base = 9 * ptr[A] + 3 * deg * i + 3 * k
                    if scalar:
                        data[base + i] += blocks[e, a, b]
                    else:
                        for j in range(3):
                            data[base + j] += blocks[e, 3 * a + i, 3 * b + j]


@njit
def lumped_mass_hrz(conn, blocks, out):
    """Diagonal (HRZ) lumping: each cell's diagonal scaled to its total mass, summed per node."""
    ne, nen = conn.shape
    for e in range(ne):
        total = 0.0
        diag = 0.0
        for a in range(nen):
            diag += blocks[e, a, a]
            for b in range(nen):
                total += blocks[e, a, b]
        scale = total / diag
        for a in range(nen):
            out[conn[e, a]] += scale * blocks[e, a, a]
