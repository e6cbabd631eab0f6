"""Static equilibrium with unilateral linear penalty contact, p = k max(-g, 0).

Active set iteration: start with every contact point closed, solve the linear system, open the
points whose gap is positive and close those that penetrate, until the set no longer changes.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..contact.pair import contact_preload, contact_stiffness
from .linsolve import factorize


class StaticError(RuntimeError):
    pass


@dataclass(frozen=True)
class StaticSolution:
    u: np.ndarray            # (ndof,) displacement [m]
    gaps: list               # per pair: (P,) gap at the rule's points [m]
    pressures: list          # per pair: (P,) contact pressure [Pa]
    iterations: int


def solve_static(model, pairs, backend="auto", max_iter=50):
    """Displacement under the model's constant load with linear penalty contact."""
    ndof = model.ndof
    active = [np.ones(p.rule.n_points, bool) for p in pairs]
    obs = [p.observation(ndof) for p in pairs]
    T = _basis(model, pairs)
    for it in range(1, max_iter + 1):
        K = (model.K + contact_stiffness(pairs, ndof, active)).tocsr()
        f = model.load + contact_preload(pairs, ndof, active)
        Kr = (T.T @ K @ T).tocsr()
        u = T @ factorize(Kr, backend)(T.T @ f)
        gaps = [C @ u + p.rule.gap0 for C, p in zip(obs, pairs)]
        new = [g < 0 for g in gaps]
        if all(np.array_equal(a, b) for a, b in zip(active, new)):
            pressures = [p.k * np.maximum(-g, 0) for g, p in zip(gaps, pairs)]
            return StaticSolution(u, gaps, pressures, it)
        active = new
    raise StaticError(f"contact active set did not settle in {max_iter} iterations")


def _basis(model, pairs):
    """Free dofs, or T_eps for a pair in the primal formulation without its fixed dofs."""
    primal = [p.primal for p in pairs if p.primal is not None]
    if not primal:
        return sp.identity(model.ndof, format="csr")[:, model.free]
    if len(primal) > 1:
        raise StaticError("at most one contact pair can use the primal formulation")
    P = primal[0]
    # a column touching a fixed dof cannot keep it at zero: drop it (explicit zeros do not touch)
    F = sp.csr_matrix(P[model.fixed])
    F.eliminate_zeros()
    touching = np.unique(F.indices)
    return P[:, np.setdiff1d(np.arange(P.shape[1]), touching)].tocsr()
