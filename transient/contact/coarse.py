"""Coarse contact rule: greedy orthogonal selection of points, with non-negative weights.

The dual regularized observation g = C1 P1 q1 - C2 P2 q2 sees each side's displacement only
through its projection on the traces U1, U2 of the kept shapes: it acts on range(U1) + range(U2).
With orthonormal bases B1, B2 of those ranges, row i of [C1 B1, -C2 B2] is what candidate point i
sees of the kept subspace; the rows of the fine rule span a space of rank k (their SVD gives an
orthonormal basis V, and R = [C1 B1, -C2 B2] V are the candidates' rows in it).
The greedy selection (kernels/greedy.py) picks k rows that span it: the coarse points then
constrain the same kept displacements as the fine rule, so tied contact keeps its null space.
Weights w >= 0 make the coarse rule reproduce the fine rule's gap energy on that subspace,
E = R_fine^T diag(w_fine) R_fine, and the total contact area.
"""
import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla
from scipy.optimize import nnls
from scipy.spatial import cKDTree

from ..kernels.greedy import greedy_rows
from .regularize import range_basis


@dataclass(frozen=True)
class CoarseRule:
    rule: object              # the coarse Rule: regularized rows of the chosen points, weights
    chosen: np.ndarray        # indices of the chosen candidates
    residual: np.ndarray      # greedy residual at each pick (relative)
    rank: int                 # rank k of the fine rule's rows on the kept subspace
    weighting: str            # weights used: 'nearest', 'nnls' or 'exact'
    energy_error: float       # ||E_coarse - E_fine||_F / ||E_fine||_F on the kept shapes
    area_error: float         # relative error of the total weight against the fine rule's area
    errors: dict              # energy error of each weighting tried
    timings: dict


def side_bases(comp, eps):
    """Orthonormal bases B1, B2 of the ranges of the kept shapes' traces on each surface."""
    U1, U2 = comp.traces(eps)
    return range_basis(U1), range_basis(U2)


def subspace_rows(rule, B1, B2):
    """(P, r1 + r2): what each point of a rule sees of the kept displacements of both sides."""
    return np.hstack([np.asarray(rule.C1 @ B1), -np.asarray(rule.C2 @ B2)])


def row_basis(R_fine, tol=1e-10):
    """Orthonormal basis (r1 + r2, k) of the row space of the fine rule's rows."""
    _, s, vt = np.linalg.svd(R_fine, full_matrices=False)
    return vt[:int((s > tol * s[0]).sum())].T


def energy(R, w):
    return (R * w[:, None]).T @ R


def energy_error(R_coarse, w_coarse, E_fine):
    return float(np.linalg.norm(energy(R_coarse, w_coarse) - E_fine) / np.linalg.norm(E_fine))


def nnls_weights(R_sel, E_fine, area):
    """w >= 0 minimizing ||sum_s w_s R_s R_s^T - E||_F^2 / ||E||_F^2 + (sum w / area - 1)^2.

    In Gram form the problem is m x m: G_st = (R_s . R_t)^2, h_s = R_s^T E R_s.
    """
    scale = np.linalg.norm(E_fine) ** 2
    G = (R_sel @ R_sel.T) ** 2 / scale + 1.0 / area ** 2
    h = np.einsum("si,ij,sj->s", R_sel, E_fine, R_sel) / scale + 1.0 / area
    # NNLS on the Cholesky factor of G (ridge at round-off level: G is only semi-definite)
    L = sla.cholesky(G + 1e-12 * np.trace(G) / len(G) * np.eye(len(G)), lower=True)
    w, _ = nnls(L.T, sla.solve_triangular(L, h, lower=True), maxiter=50 * len(G))
    return w


EXACT_LIMIT = 5e7   # entries of the feature matrix of exact weights (400 MB)


def exact_weights(R, E_fine, area):
    """NNLS over all candidates on the explicit energy features (ECSW): an exact rule.

    Each candidate contributes R_i R_i^T to the energy; by Caratheodory's theorem a non-negative
    combination of them equal to E (the fine rule is one) needs at most k (k + 1) / 2 + 1 points,
    and NNLS returns such a sparse one. Returns the weights of all candidates (mostly zero).
    """
    n, k = R.shape
    iu = np.triu_indices(k)
    scale = np.where(iu[0] == iu[1], 1.0, np.sqrt(2.0))     # Frobenius norm of symmetric parts
    Z = np.empty((len(iu[0]) + 1, n))
    Z[:-1] = (R[:, iu[0]] * R[:, iu[1]] * scale).T / np.linalg.norm(E_fine)
    Z[-1] = 1.0 / area
    b = np.r_[E_fine[iu] * scale / np.linalg.norm(E_fine), 1.0]
    w, _ = nnls(Z, b, maxiter=50 * n)
    return w


def nearest_weights(points_sel, fine):
    """Each fine point's weight given to the nearest chosen point (in space)."""
    _, owner = cKDTree(points_sel).query(fine.points)
    return np.bincount(owner, weights=fine.weights, minlength=len(points_sel))


def select(candidates, fine, B1, B2, m=0, tol=1e-8, weighting="nearest"):
    """Coarse rule of up to m candidate points (m = 0: the rank k of the fine rule's rows).

    weighting: nearest (each fine weight to its nearest chosen point: exact area and smooth
    fields, the best tied frequencies measured), nnls (energy on the whole kept subspace and
    area), best (the lower energy error of the two), or exact (no greedy selection: NNLS over
    all candidates reproduces the energy exactly, with as many points as it needs).

    candidates: a Rule with the regularized observation (the fine rule or a centre rule);
    fine: the regularized fine rule, which gives the reference energy and area; B1, B2:
    orthonormal bases of the kept traces on each side (side_bases).
    """
    t0 = time.perf_counter()
    R_fine = subspace_rows(fine, B1, B2)
    V = row_basis(R_fine)
    R_fine = R_fine @ V
    R = np.ascontiguousarray(R_fine if candidates is fine
                             else subspace_rows(candidates, B1, B2) @ V)
    E_fine = energy(R_fine, fine.weights)
    k = V.shape[1]
    target = m if m > 0 else k
    if weighting == "exact":
        k_features = k * (k + 1) // 2
        if k_features * len(R) > EXACT_LIMIT:
            raise ValueError(f"exact weights need {k_features} x {len(R)} energy features, "
                             f"over {EXACT_LIMIT:.0e}: use weights = nearest or nnls")
        w_all = exact_weights(R, E_fine, fine.area)
        chosen = np.flatnonzero(w_all > 0)
        residual = np.zeros(len(chosen))
        t_select = time.perf_counter() - t0
        options = {"exact": w_all[chosen]}
    else:
        chosen, residual = greedy_rows(R, target, tol, target > k)
        t_select = time.perf_counter() - t0
        makers = {"nnls": lambda: nnls_weights(R[chosen], E_fine, fine.area),
                  "nearest": lambda: nearest_weights(candidates.points[chosen], fine)}
        names = list(makers) if weighting == "best" else [weighting]
        options = {name: makers[name]() for name in names}
    R_sel = R[chosen]
    errors = {name: energy_error(R_sel, w, E_fine) for name, w in options.items()}
    best = min(errors, key=errors.get)
    w = options[best]
    rule = subset_rule(candidates, chosen, w)
    timings = {"selection": t_select, "weights": time.perf_counter() - t0 - t_select}
    return CoarseRule(rule, chosen, residual, k, best, errors[best],
                      float(w.sum() / fine.area - 1), errors, timings)


def subset_rule(rule, idx, weights):
    """The rule on its points idx with new weights (rows None stay None: held as factors)."""
    return replace(rule, points=rule.points[idx], weights=weights, normals=rule.normals[idx],
                   gap0=rule.gap0[idx], face1=rule.face1[idx], face2=rule.face2[idx],
                   C1=None if rule.C1 is None else rule.C1[idx],
                   C2=None if rule.C2 is None else rule.C2[idx])
