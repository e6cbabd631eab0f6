"""The interface of a part reduced to fields whose count is set by the cutoff, not the mesh.

A part's contact loads are the traces of the (1-eps)-compatible shapes on its interface (the
columns of B, C = L B^T), as many as the interface's mesh resolves: their static responses, and
the dense algebra on them, grow with it. Below the cutoff, the coupled structure's interface
tractions are those of the part held by its counterpart: the part on springs of the contact's
stiffness over its interface (a loaded interface, Benfield and Hruda) has modes whose contact
forces span them, with the tractions of the part's rigid motions (uniform and linearly varying
pressures). Those forces, in the compatible shapes' coordinates, are the fields kept: each
applied along every direction its pair's rows take (normal, and along and across the sliding
with friction). Tied (bilateral) pairs keep every shape: their interface is a weld, whose
static flexibility no frequency bounds.
"""
import numpy as np
import scipy.sparse as sp

from ..model.dofs import rigid_motions, shifted
from ..solve.linsolve import factorize
from ..solve.modes import normal_modes, shift_sigma
from .basis import MODES_TOL

FIELD_TOL = 1e-8     # relative singular value below which a field depends on the others


def support_stiffness(pairs, ndof):
    """(ndof, ndof) sparse: springs of each sliding (not tied) pair's stiffness density k in
    every direction over its fine rule, on both sides' interface nodes: the loaded interface
    of each part, its counterpart held rigid."""
    K = sp.csr_matrix((ndof, ndof))
    for pair in pairs:
        if pair.spec.law.kind == "bilateral":
            continue
        fine = pair.interface.fine
        kw = sp.diags(pair.k * fine.weights)
        for side, C in ((pair.interface.side1, fine.C1), (pair.interface.side2, fine.C2)):
            C = sp.csr_matrix(C)
            for e in np.eye(3):
                R = (C @ side.direction_map(np.tile(e, (side.n, 1)), ndof)).tocsr()
                K = K + (R.T @ kw @ R).tocsr()
    return K


def part_rigid_motions(points, dofs):
    """(n, 6) the rigid motions of a part's dofs `dofs` about their nodes' centroid."""
    return rigid_motions(points, dofs, points[dofs // 3].mean(axis=0))


def field_map(K, M, support, E, G, shape, block, rigid, cutoff, shift_hz, backend):
    """P (k, f): the interface loads' combinations E P kept, f <= k. shape (k,): the
    compatible shape whose trace each load column is, -1 for a column kept whole (a tied
    pair's); block (k,): the direction of the rows it loads (0 normal, 1 along, 2 across
    the sliding). The loaded modes are those of (K + support, M) to the cutoff [Hz]; their
    factorization is freed on return."""
    whole = np.flatnonzero(shape < 0)
    kept = np.zeros((len(shape), len(whole)))
    kept[whole, np.arange(len(whole))] = 1.0
    columns = [kept]
    shaped = np.flatnonzero(shape >= 0)
    if len(shaped):
        Ks = K + support
        solve = factorize(shifted(Ks, M, shift_sigma(-shift_hz)), backend, definite=True)
        Psi = normal_modes(Ks, M, None, count=40, fmax=cutoff, shift=-shift_hz, solve=solve,
                           tol=MODES_TOL).shapes
        del solve
        forces = G[np.ix_(shaped, shaped)] @ (E[:, shaped].T @ np.hstack([Psi, rigid]))
        shapes, slot = np.unique(shape[shaped], return_inverse=True)
        blocks = [np.flatnonzero(block[shaped] == b) for b in np.unique(block[shaped])]
        # the fields are the shapes' coefficients of the forces in any block: a traction
        # field of the normal rows is one of the tangential rows too (friction drags it)
        F = []
        for b in blocks:
            Fb = np.zeros((len(shapes), forces.shape[1]))
            Fb[slot[b]] = forces[b]
            F.append(Fb)
        F = np.hstack(F)
        norms = np.linalg.norm(F, axis=0)
        F = F[:, norms > 0] / norms[norms > 0]
        U, s, _ = np.linalg.svd(F, full_matrices=False)
        Q = U[:, s > FIELD_TOL * s[0]] if len(s) else U[:, :0]
        for b in blocks:
            Pb = np.zeros((len(shape), Q.shape[1]))
            Pb[shaped[b]] = Q[slot[b]]
            columns.append(Pb)
    return np.hstack(columns)
