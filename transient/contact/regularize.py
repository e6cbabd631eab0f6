"""Regularized gap observation through the (1-eps)-compatible shapes (paper eq. 11-15).

Dual: the displacement of surface n is replaced by its projection on the traces U_n of the kept
shapes, g = C1 P1 q1 - C2 P2 q2 + g0 with P_n = U_n U_n^+; the pseudo-inverse is taken in the
identity norm (the paper's choice) or in the interface mass norm W_n = C_n^T diag(w) C_n.
Primal: the interface normal dofs are replaced by generalized coordinates, q = T_eps q_eps.
"""
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

RANK_TOL = 1e-10   # relative singular value below which a trace direction is dependent


def range_basis(U, tol=RANK_TOL):
    """Orthonormal basis of the range of U (identity norm)."""
    if U.shape[1] == 0:
        return U
    Q, s, _ = np.linalg.svd(U, full_matrices=False)
    return Q[:, s > tol * s[0]] if s.size and s[0] > 0 else Q[:, :0]


def projector_factors(U, W=None):
    """(Q, Y) with Q Y the projector on range(U): Q (N, r) an orthonormal basis of the range,
    Y = Q^T (identity norm) or (Q^T W Q)^-1 Q^T W (W-orthogonal)."""
    Q = range_basis(U)
    if W is None:
        return Q, Q.T
    G = Q.T @ W @ Q
    return Q, np.linalg.solve(G, Q.T @ W)


def projector(U, W=None):
    """Projector (N, N) on range(U): orthogonal in the identity norm, or W-orthogonal."""
    Q, Y = projector_factors(U, W)
    return Q @ Y


def interface_mass(rule):
    """W1, W2: the interface mass matrices C_n^T diag(w) C_n of each side (dense)."""
    w = sp.diags(rule.weights)
    return (rule.C1.T @ w @ rule.C1).toarray(), (rule.C2.T @ w @ rule.C2).toarray()


def dual_factors(comp, eps, fine, project="both", norm="mass"):
    """(Q1, Y1), (Q2, Y2): the factors of the dual regularization's projectors P_n = Q_n Y_n,
    None for a side not projected (its projector is the identity)."""
    U1, U2 = comp.traces(eps)
    W1, W2 = interface_mass(fine) if norm == "mass" else (None, None)
    F1 = projector_factors(U1, W1) if project in ("both", "surface1") else None
    F2 = projector_factors(U2, W2) if project in ("both", "surface2") else None
    return F1, F2


def factor_projectors(comp, F1, F2):
    """P1, P2 from dual_factors: Q_n Y_n, or the identity for a side not projected."""
    return (F1[0] @ F1[1] if F1 else np.eye(comp.n1)), (F2[0] @ F2[1] if F2 else np.eye(comp.n2))


def dual_projectors(comp, eps, fine, project="both", norm="mass"):
    """P1, P2 of the dual regularization; a side not projected keeps the identity."""
    return factor_projectors(comp, *dual_factors(comp, eps, fine, project, norm))


def row_factors(interface, rule, F1, F2, ndof):
    """(L, B) with the regularized rule's gap observation C1 P1 T1 - C2 P2 T2 = L B^T in model
    dofs (T_n the sides' dof maps): L = [C1 Q1, -C2 Q2] (P, r1 + r2) dense and
    B = [T1^T Y1^T, T2^T Y2^T] (ndof, r1 + r2) sparse, nonzero on the interface dofs only.
    The rows' space then comes from r1 + r2 columns, not from the dense P x N rows; None
    unless both sides are projected."""
    if F1 is None or F2 is None:
        return None
    (Q1, Y1), (Q2, Y2) = F1, F2
    L = np.hstack([rule.C1 @ Q1, -(rule.C2 @ Q2)])
    B = sp.hstack([interface.side1.dof_map(ndof).T @ sp.csr_matrix(Y1.T),
                   interface.side2.dof_map(ndof).T @ sp.csr_matrix(Y2.T)]).tocsr()
    return L, B


def factored_rows(L, B):
    """L B^T (P, ndof) as CSR, on the dofs B touches only (L (P, r) dense, B (ndof, r) CSR)."""
    B = sp.csr_matrix(B)
    cols = np.flatnonzero(np.diff(B.indptr))
    dense = L @ B[cols].toarray().T
    P = dense.shape[0]
    rows = sp.csr_matrix((dense.ravel(), np.tile(cols, P), np.arange(P + 1) * len(cols)),
                         shape=(P, B.shape[0]))
    rows.eliminate_zeros()
    return rows


def regularized_rule(rule, P1, P2):
    """The rule with its observation projected: C1 P1, C2 P2 (dense rows as CSR)."""
    return replace(rule, C1=sp.csr_matrix(rule.C1 @ P1), C2=sp.csr_matrix(rule.C2 @ P2))


def primal_basis(interface, comp, eps, ndof):
    """T_eps (ndof, ndof - N1 - N2 + r1 + r2): all dofs but the interface normal ones, plus the
    traces of the kept shapes on each side as generalized coordinates (paper eq. 11)."""
    U1, U2 = comp.traces(eps)
    blocks = []
    normal_dofs = []
    for side, U in ((interface.side1, U1), (interface.side2, U2)):
        D = side.dof_map(ndof)                    # (N, ndof): rows are unit node normals
        normal_dofs.append(D)
        blocks.append(D.T @ sp.csr_matrix(range_basis(U)))
    N = sp.vstack(normal_dofs).tocsr()
    # the complement: identity minus the normal directions of the interface nodes, spanned by
    # the model dofs of those nodes projected off the normal, plus all other dofs
    touched = np.unique(N.indices)
    other = np.setdiff1d(np.arange(ndof), touched)
    eye = sp.identity(ndof, format="csr")
    comp_cols = [eye[:, other]]
    for D in normal_dofs:
        nodes = D.indices.reshape(-1, 3)[:, 0] // 3
        normals = D.data.reshape(-1, 3)
        for d in range(2):
            t = _tangent(normals, d)
            rows = (3 * nodes)[:, None] + np.arange(3)
            cols = np.repeat(np.arange(len(nodes)), 3)
            comp_cols.append(sp.csr_matrix((t.ravel(), (rows.ravel(), cols)),
                                           shape=(ndof, len(nodes))))
    return sp.hstack(comp_cols + blocks).tocsr()


def _tangent(normals, which):
    """Unit tangents (n, 3) orthogonal to unit normals: the first or second of a frame."""
    ref = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(normals, ref)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1 if which == 0 else np.cross(normals, t1)
