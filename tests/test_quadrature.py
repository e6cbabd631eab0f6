"""The simplex rules: exact to their degree, and the tetrahedron's symmetric under every
permutation of its vertices to degree 5 (a mirrored tet10 integrated at the same points)."""
import itertools
from math import factorial

import numpy as np
import pytest

from transient.mesh.quadrature import tetrahedron


@pytest.mark.parametrize("degree", range(1, 9))
def test_the_tetrahedron_rule_integrates_every_monomial_of_its_degree(degree):
    points, weights = tetrahedron(degree)
    assert np.all(weights > 0)
    for total in range(degree + 1):
        for a in range(total + 1):
            for b in range(total + 1 - a):
                c = total - a - b
                exact = factorial(a) * factorial(b) * factorial(c) / factorial(total + 3)
                got = weights @ (points[:, 0] ** a * points[:, 1] ** b * points[:, 2] ** c)
                assert abs(got - exact) <= 1e-14 * exact, (a, b, c)


@pytest.mark.parametrize("degree", range(1, 6))
def test_the_tetrahedron_rule_is_the_same_under_any_order_of_the_vertices(degree):
    points, weights = tetrahedron(degree)
    bary = np.column_stack([points, 1.0 - points.sum(axis=1)])
    key = lambda b, w: sorted(map(tuple, np.round(np.column_stack([b, w]), 14)))
    for order in itertools.permutations(range(4)):
        assert key(bary[:, order], weights) == key(bary, weights), order
