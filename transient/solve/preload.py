"""Preload: static equilibrium under the constant loads with the nonlinear contact laws.

Newton with a backtracking line search on the residual r(u) = f + C^T w p(C u + g0) - K u over
the free dofs (plus, with friction, the tractions of steady sliding Ct^T w p m: the preload is
then the steady sliding state). The tangent K + C^T diag(w k_t) C is applied through a
ContactSolver (one sparse factorization of K - sigma M, low-rank updates for the contact): the
tiny shift -sigma M keeps floating parts solvable and only slows the quadratic convergence by a
factor of order sigma over the lowest eigenvalue.
"""
import time
from dataclasses import dataclass

import numpy as np

from .linsolve import FactorizationError


STALE = 1e-2      # change of the laws' tangents (of their largest) a friction preload's
#                   Newton tangent is kept through


class PreloadError(RuntimeError):
    pass


@dataclass(frozen=True)
class Preload:
    u: np.ndarray            # (ndof,) displacement at equilibrium [m]
    gap: np.ndarray          # (P,) gaps there [m]
    pressure: np.ndarray     # (P,) [Pa]
    tangent: np.ndarray      # (P,) k_t [Pa/m]
    iterations: int
    residual: float          # final residual relative to the load (or the contact force)
    seconds: float


def solve_preload(K, fixed, load, contacts, solver, tol=1e-10, max_iter=50, start=None):
    """Equilibrium u with K u = load + contact force, clamped dofs at zero.

    solver: a ContactSolver on the free dofs (lowrank.py).
    start: (P,) the tangent the first Newton step takes at least (contact.contactset.
    first_tangent: the pair's k on the exponential laws' points), or None. From the undeformed
    state an exponential law is far softer than where the load takes it (pad_disc: 100 times,
    5e9 against 5e11 Pa/m at 1 MPa), so its first step overshot deep into the stiff branch and
    the line search cut it to 1/64, then 1/16 and 1/4: three iterations and 13 residuals for a
    fifth of the residual.
    """
    t0 = time.perf_counter()
    ndof = K.shape[0]
    free = np.flatnonzero(~fixed)
    u = np.zeros(ndof)
    fc, g, p, kt = contacts.force(u)
    if not np.any(load):
        # no constant load, no preload: the undeformed state, whatever its contact forces
        return Preload(u, g, p, kt, 0, 0.0, time.perf_counter() - t0)

    def residual(u):
        fc, g, p, kt = contacts.force(u)
        if contacts.friction is not None:
            # steady sliding: the friction tractions mu p along the constant sliding
            # directions. The tangent below leaves out their non-symmetric stiffness, so the
            # iterations converge linearly, at a rate of order mu times the coupling of the
            # tangential loads into the pressures (small where supports take them): pad_disc
            # at mu = 0.4, 0.13 an iteration, 14 in all against 7 (Anderson's mixing of the
            # last 3 steps saved 2: the error spans the interface's many directions)
            fc = fc + contacts.friction_force(p)
        return (load + fc - K @ u)[free], g, p, kt

    r, g, p, kt = residual(u)
    held = None           # the laws' tangents the Newton tangent kept was made of (friction)
    scale = max(np.linalg.norm(load[free]), np.linalg.norm(fc[free]), 1e-300)
    norm = np.linalg.norm(r)
    for it in range(1, max_iter + 1):
        d = kt if it > 1 or start is None else np.maximum(kt, start)
        try:
            # with friction the iterations converge linearly (residual above) at a rate far
            # above what a tangent 1% off adds: it is kept while the laws' tangents move less
            # (the core of its low-rank update: 0.055 s of each of pad_disc_squeal's 14)
            if held is None or np.max(np.abs(d - held)) > STALE * np.max(held):
                tangent = solver.solver(contacts.weights * d)
                held = d if contacts.friction is not None else None
            du = tangent(r)
        except FactorizationError as exc:
            raise PreloadError(f"preload tangent is singular ({exc}): is every part held by "
                               "constraints or closed contact?") from None
        step = 1.0
        while True:
            trial = u.copy()
            trial[free] += step * du
            r_new, g_new, p_new, kt_new = residual(trial)
            if np.linalg.norm(r_new) < norm or step < 1e-6:
                break
            step *= 0.5
        u, r, g, p, kt = trial, r_new, g_new, p_new, kt_new
        norm = np.linalg.norm(r)
        if norm <= tol * scale:
            return Preload(u, g, p, kt, it, norm / scale, time.perf_counter() - t0)
    raise PreloadError(f"preload Newton did not converge in {max_iter} iterations "
                       f"(residual {norm / scale:.2e}): a part that only contact holds must "
                       "touch under the constant loads, and a part free to move under them "
                       "has no static equilibrium (check constraints and the contact pairs)")
