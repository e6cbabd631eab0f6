"""K and M against scikit-fem on distorted meshes; HRZ lumped mass; rigid-body modes of K.

scikit-fem is an independent implementation (its own shape functions, reference cells, node and
dof orderings), so agreement to rounding on distorted cells checks our kernels, quadrature and
summation. The two are compared entry by entry through a dof permutation, never by eigenvalues.

Correspondence with scikit-fem 12:

* reference cells: scikit-fem's hex is [0, 1]^3 (xi = 2 X - 1), its tet is the unit tet (xi = X),
  its wedge the unit triangle times [0, 1] (xi, eta = X, Y and zeta = 2 Z - 1);
* local nodes: our node at the reference point of scikit-fem's local dof s (``local_order``);
  for the hex corners that is VTK [6, 2, 5, 7, 1, 3, 4, 0], for tets and wedges the identity;
* global dofs: ElementVector's local dof 3 s + c is component c of scalar dof s, and
  basis.element_dofs gives its global number (``dof_permutation``);
* quadrature: intorder = our degree where scikit-fem's rule is the same point set (tensor Gauss
  with (degree + 2) // 2 points for the hex, tet degrees 1 and 2), otherwise our own rule is passed
  as quadrature= (tet degree 4), so the integrands are summed at identical points even on
  curved (non-polynomial) cells.

scikit-fem 12 has no quadratic wedge: wedge15 is checked against gmsh's own shape functions in
tests/test_wedges.py.
"""
import dataclasses

import numpy as np
import pytest

skfem = pytest.importorskip("skfem")
from skfem import (Basis, BilinearForm, ElementHex1, ElementHexS2, ElementTetP1,  # noqa: E402
                   ElementTetP2, ElementVector, ElementWedge1, Functional, MeshHex1, MeshHex2,
                   MeshTet1, MeshTet2, MeshWedge1)
from skfem.helpers import dot  # noqa: E402
from skfem.models.elasticity import lame_parameters, linear_elasticity  # noqa: E402
from skfem.quadrature import get_quadrature  # noqa: E402

from transient.model.assembly import CellBlock, assemble  # noqa: E402
from transient.mesh.elements import ELEMENTS, VOLUME_TYPES  # noqa: E402

from distorted import distorted_box  # noqa: E402

E, NU, RHO = 2.1e11, 0.3, 7850.0
TOL = 1e-10

# our type -> (scikit-fem scalar element, linear geometry mesh, quadratic geometry mesh)
SKFEM = {
    "hexahedron": (ElementHex1, MeshHex1, None),
    "hexahedron20": (ElementHexS2, MeshHex1, MeshHex2),
    "tetra": (ElementTetP1, MeshTet1, None),
    "tetra10": (ElementTetP2, MeshTet1, MeshTet2),
    "wedge": (ElementWedge1, MeshWedge1, None),
}


def to_ours(shape, X):
    """Our reference coordinates of scikit-fem reference points X (n, 3)."""
    if shape == "wedge":
        return np.column_stack([X[:, :2], 2.0 * X[:, 2] - 1.0])
    return 2.0 * X - 1.0 if shape == "hex" else X


def to_skfem(shape, xi, w):
    """Our rule (xi, w) in scikit-fem's reference cell and array layout."""
    if shape == "hex":
        return (0.5 * (xi + 1.0)).T, w / 8.0
    if shape == "wedge":
        return np.column_stack([xi[:, :2], 0.5 * (xi[:, 2] + 1.0)]).T, w / 2.0
    return xi.T, w


def local_order(cell_type, sk_element):
    """loc[s] = our local node at the reference point of scikit-fem's local dof s."""
    el = ELEMENTS[cell_type]
    xi = to_ours(el.shape, np.asarray(sk_element.doflocs, float))
    d = np.linalg.norm(xi[:, None, :] - el.nodes[None, :, :], axis=2)
    loc = d.argmin(axis=1)
    assert np.allclose(d.min(axis=1), 0.0) and len(set(loc)) == el.nen
    return loc


def skfem_mesh(cell_type, points, conn, curved):
    """scikit-fem mesh of the same cells; quadratic geometry when midside nodes are curved."""
    element, linear, quadratic = SKFEM[cell_type]
    el = ELEMENTS[cell_type]
    loc = local_order(cell_type, element())
    corners, compact = np.unique(conn[:, :el.n_corners], return_inverse=True)
    compact = compact.reshape(len(conn), el.n_corners)
    mesh = linear(points[corners].T.copy(), compact[:, loc[:el.n_corners]].T.copy())
    if not curved:
        return mesh
    # Our map interpolated at the quadratic geometry nodes: our serendipity / P2 space lies in
    # scikit-fem's Q2 / P2 geometry space, so the interpolant is our map exactly.
    mesh2 = quadratic.from_mesh(mesh)
    geo = quadratic.elem
    xi = to_ours(el.shape, np.asarray(geo.doflocs, float))
    x = np.einsum("ga,eak->egk", el.shape_functions(xi), points[conn])
    doflocs = np.full_like(mesh2.doflocs, np.nan)
    edofs = mesh2.dofs.element_dofs                     # (n geometry dofs, ne)
    doflocs[:, edofs.T.ravel()] = x.reshape(-1, 3).T
    # every shared geometry node must get one position from all its cells
    assert np.allclose(doflocs[:, edofs.T.ravel()], x.reshape(-1, 3).T, rtol=0, atol=1e-14)
    assert not np.isnan(doflocs).any()
    return dataclasses.replace(mesh2, doflocs=doflocs)


def dof_permutation(basis, conn, loc):
    """perm[our dof] = scikit-fem dof, checked to be one-to-one and consistent over cells."""
    ne, nen = conn.shape
    ours = 3 * conn[:, loc][:, :, None] + np.arange(3)          # (ne, nen, 3)
    sk = basis.element_dofs.T.reshape(ne, nen, 3)               # local dof 3 s + c
    perm = np.full(3 * conn.max() + 3, -1)
    perm[ours.ravel()] = sk.ravel()
    assert np.array_equal(perm[ours.ravel()], sk.ravel())        # consistent over cells
    assert np.array_equal(np.sort(perm), np.arange(basis.N))     # one-to-one and onto
    return perm


def skfem_rule(cell_type, degree):
    """Basis keyword giving scikit-fem the same quadrature points as our rule of this degree."""
    el = ELEMENTS[cell_type]
    X, W = to_skfem(el.shape, *el.rule(degree))
    Xs, Ws = get_quadrature(SKFEM[cell_type][0](), degree)
    if Xs.shape == X.shape:
        a, b = np.lexsort(X), np.lexsort(Xs)
        if np.allclose(X[:, a], Xs[:, b], atol=1e-14) and np.allclose(W[a], Ws[b], atol=1e-15):
            return {"intorder": degree}
    return {"quadrature": (X, W)}


@BilinearForm
def mass_form(u, v, w):
    return RHO * dot(u, v)


@Functional
def volume_form(w):
    return 1.0 + 0.0 * w.x[0]


def ours(points, conn, cell_type):
    ne = len(conn)
    block = CellBlock(cell_type, conn, np.full(ne, E), np.full(ne, NU), np.full(ne, RHO))
    return assemble(points, [block])


def relative(A, B):
    return abs(A - B).max() / abs(B).max()


CASES = [(t, False) for t in SKFEM] + [("hexahedron20", True), ("tetra10", True)]


@pytest.mark.parametrize("cell_type, curved", CASES,
                         ids=[t + ("-curved" if c else "") for t, c in CASES])
def test_matches_skfem(cell_type, curved):
    points, conn = distorted_box(cell_type, curved)
    el = ELEMENTS[cell_type]
    ops = ours(points, conn, cell_type)
    assert min(d.min() for d in ops.min_det) > 0
    element = SKFEM[cell_type][0]()
    mesh = skfem_mesh(cell_type, points, conn, curved)
    vector = ElementVector(element)
    kb = Basis(mesh, vector, **skfem_rule(cell_type, el.stiffness_degree))
    mb = Basis(mesh, vector, **skfem_rule(cell_type, el.mass_degree))
    perm = dof_permutation(kb, conn, local_order(cell_type, element))
    K = linear_elasticity(*lame_parameters(E, NU)).assemble(kb).tocsr()[perm][:, perm]
    M = mass_form.assemble(mb).tocsr()[perm][:, perm]
    assert relative(ops.K, K) < TOL
    assert relative(ops.M, M) < TOL
    # HRZ lumping keeps every cell's mass and gives positive nodal masses
    mass = RHO * volume_form.assemble(mb)
    assert ops.lumped_mass.min() > 0
    assert abs(ops.lumped_mass[::3].sum() - mass) < 1e-12 * mass


def rigid_modes(points):
    """(3 nn, 6) translations and infinitesimal rotations, dof = 3 node + component."""
    n = len(points)
    R = np.zeros((n, 3, 6))
    x = points - points.mean(axis=0)
    for i in range(3):
        R[:, i, i] = 1.0
    for k, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        R[:, i, 3 + k] = -x[:, j]
        R[:, j, 3 + k] = x[:, i]
    return R.reshape(3 * n, 6)


@pytest.mark.parametrize("cell_type", VOLUME_TYPES)
def test_rigid_body_modes(cell_type):
    # 2x2x2 keeps the dense eigenvalue count cheap
    points, conn = distorted_box(cell_type, cell_type == "hexahedron20", 1, (2, 2, 2))
    K = ours(points, conn, cell_type).K
    R = rigid_modes(points)
    scale = abs(K).max() * abs(R).max()
    assert abs(K @ R).max() < 1e-11 * scale
    # exactly six: the seventh smallest eigenvalue is well away from zero
    lam = np.linalg.eigvalsh(K.toarray())
    assert abs(lam[:6]).max() < 1e-11 * lam[-1]
    assert lam[6] > 1e-6 * lam[-1]
