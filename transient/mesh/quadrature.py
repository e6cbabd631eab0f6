"""Quadrature rules on the reference cells.

Reference cells: the segment [-1, 1], the square [-1, 1]^2, the cube [-1, 1]^3, the unit triangle
{x, y >= 0, x + y <= 1}, the unit tetrahedron {x, y, z >= 0, x + y + z <= 1} and the wedge, that
triangle times [-1, 1] in z.
Every rule is returned as (points (n, dim), weights (n,)); a rule of degree p integrates every
polynomial of total degree <= p exactly (on the square, cube and wedge: of degree <= p in each
direction, the wedge's triangle counting as one).
"""
from functools import lru_cache

import numpy as np
from scipy.special import roots_jacobi, roots_legendre


@lru_cache(maxsize=None)
def gauss_line(n):
    """n-point Gauss-Legendre rule on [-1, 1] (degree 2n - 1)."""
    x, w = roots_legendre(n)
    return x, w


def gauss_tensor(n, dim):
    """Tensor Gauss-Legendre rule with n points per direction on [-1, 1]^dim."""
    x, w = gauss_line(n)
    grids = np.meshgrid(*([x] * dim), indexing="ij")
    wgrids = np.meshgrid(*([w] * dim), indexing="ij")
    points = np.stack([g.ravel() for g in grids], axis=1)
    weights = np.prod(np.stack([g.ravel() for g in wgrids], axis=1), axis=1)
    return points, weights


def _collapsed(degree, dim):
    """Conical product (Duffy-collapsed Gauss-Jacobi) rule on the unit simplex, positive weights.

    The simplex is the image of the unit cube under x1 = t1, x2 = (1 - t1) t2, ...; the Jacobian
    (1 - t1)^(dim-1) (1 - t2)^(dim-2) ... is absorbed by Gauss-Jacobi weights.
    """
    n = degree // 2 + 1
    factors = []
    for k in range(dim):
        alpha = dim - 1 - k
        t, w = roots_jacobi(n, alpha, 0.0)
        factors.append(((t + 1.0) / 2.0, w / 2.0 ** (alpha + 1)))
    grids = np.meshgrid(*[f[0] for f in factors], indexing="ij")
    wgrids = np.meshgrid(*[f[1] for f in factors], indexing="ij")
    t = np.stack([g.ravel() for g in grids], axis=1)
    weights = np.prod(np.stack([g.ravel() for g in wgrids], axis=1), axis=1)
    points = np.empty_like(t)
    remaining = np.ones(len(t))
    for k in range(dim):
        points[:, k] = remaining * t[:, k]
        remaining = remaining * (1.0 - t[:, k])
    return points, weights


# Symmetric rules with positive weights and fewer points than the conical product.
_A2 = (5.0 - np.sqrt(5.0)) / 20.0
_TET = {
    1: (np.array([[0.25, 0.25, 0.25]]), np.array([1.0 / 6.0])),
    2: (np.array([[_A2, _A2, _A2], [1 - 3 * _A2, _A2, _A2], [_A2, 1 - 3 * _A2, _A2],
                  [_A2, _A2, 1 - 3 * _A2]]), np.full(4, 1.0 / 24.0)),
}
_TRI = {
    1: (np.array([[1 / 3, 1 / 3]]), np.array([0.5])),
    2: (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1.0 / 6.0)),
}


def _dunavant4():
    a1, w1 = 0.445948490915965, 0.223381589678011
    a2, w2 = 0.091576213509771, 0.109951743655322
    pts, wts = [], []
    for a, w in ((a1, w1), (a2, w2)):
        b = 1.0 - 2.0 * a
        pts += [[a, a], [b, a], [a, b]]
        wts += [w, w, w]
    return np.array(pts), 0.5 * np.array(wts)


def _dunavant5():
    a1, w1 = 0.470142064105115, 0.132394152788506
    a2, w2 = 0.101286507323456, 0.125939180544827
    pts, wts = [[1 / 3, 1 / 3]], [0.225]
    for a, w in ((a1, w1), (a2, w2)):
        b = 1.0 - 2.0 * a
        pts += [[a, a], [b, a], [a, b]]
        wts += [w, w, w]
    return np.array(pts), 0.5 * np.array(wts)


@lru_cache(maxsize=None)
def triangle(degree):
    """Rule of the given degree on the unit triangle (weights sum to 1/2)."""
    if degree < 1:
        degree = 1
    if degree in _TRI:
        return _TRI[degree]
    if degree <= 4:
        return _refine_weights(*_dunavant4(), 2)
    if degree == 5:
        return _refine_weights(*_dunavant5(), 2)
    return _collapsed(degree, 2)


def _walkington14():
    """The 14-point rule of degree 5 on the tetrahedron (Walkington; Keast's family), symmetric
    under every permutation of the vertices with positive weights: two orbits of 4 points
    (a, a, a, 1 - 3a) and one of 6 (b, b, 1/2 - b, 1/2 - b) in barycentric coordinates. A
    conical product is not symmetric: a mirrored curved tet10 was integrated at other points
    than its original, and its mass differed by the rule's own error."""
    bary = []
    for a in (0.0927352503108912, 0.3108859192633006):
        bary += [[a, a, a, 1 - 3 * a][i:] + [a, a, a, 1 - 3 * a][:i] for i in range(4)]
    b, c = 0.0455037041256496, 0.5 - 0.0455037041256496
    bary += [[b, b, c, c], [b, c, b, c], [b, c, c, b], [c, b, b, c], [c, b, c, b], [c, c, b, b]]
    weights = [0.01224884051939366] * 4 + [0.01878132095300264] * 4 + [0.007091003462846911] * 6
    return _refine_weights(np.array(bary)[:, :3], np.array(weights), 3)


@lru_cache(maxsize=None)
def tetrahedron(degree):
    """Rule of the given degree on the unit tetrahedron (weights sum to 1/6), symmetric to
    degree 5 (a tet10's mass is degree 4)."""
    if degree < 1:
        degree = 1
    if degree in _TET:
        return _TET[degree]
    if degree <= 5:
        return _walkington14()
    return _collapsed(degree, 3)


def _refine_weights(points, weights, dim):
    """Tabulated rules carry 15 digits; rescale so the weights sum exactly to the cell measure."""
    measure = 0.5 if dim == 2 else 1.0 / 6.0
    return points, weights * (measure / weights.sum())


def wedge(degree):
    """The triangle's rule of the given degree times Gauss-Legendre along z, exact to the same
    degree (weights sum to 1). The triangle rules to degree 5 are symmetric in x and y, so a
    wedge turned inside out by a mirror (which swaps x and y) is integrated at the same points."""
    tp, tw = triangle(degree)
    zp, zw = gauss_line(max(1, (degree + 2) // 2))
    points = np.column_stack([np.repeat(tp, len(zp), axis=0), np.tile(zp, len(tp))])
    return points, np.repeat(tw, len(zp)) * np.tile(zw, len(tp))


def rule(shape, degree):
    """Rule of at least the given degree on a reference shape ('hex', 'quad', 'tet', 'tri',
    'wedge')."""
    if shape == "wedge":
        return wedge(degree)
    if shape == "hex":
        return gauss_tensor(max(1, (degree + 2) // 2), 3)
    if shape == "quad":
        return gauss_tensor(max(1, (degree + 2) // 2), 2)
    if shape == "tet":
        return tetrahedron(degree)
    if shape == "tri":
        return triangle(degree)
    raise ValueError(f"unknown reference shape {shape!r}")
