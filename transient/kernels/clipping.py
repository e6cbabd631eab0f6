"""Intersection of convex polygons in the contact plane (Sutherland-Hodgman), pair by pair."""
import numpy as np

from ..jit import njit

MAX_VERTICES = 16   # a convex n-gon clipped by a convex m-gon has at most n + m vertices


@njit
def _clip_edge(poly, n, a, b, out):
    """Part of polygon poly[:n] on the left of the directed line a -> b, into out; returns count."""
    m = 0
    ex, ey = b[0] - a[0], b[1] - a[1]
    for i in range(n):
        p = poly[i]
        q = poly[(i + 1) % n]
        sp = ex * (p[1] - a[1]) - ey * (p[0] - a[0])
        sq = ex * (q[1] - a[1]) - ey * (q[0] - a[0])
        if sp >= 0.0:
            out[m, 0], out[m, 1] = p[0], p[1]
            m += 1
        if (sp >= 0.0) != (sq >= 0.0):
            t = sp / (sp - sq)
            out[m, 0] = p[0] + t * (q[0] - p[0])
            out[m, 1] = p[1] + t * (q[1] - p[1])
            m += 1
    return m


@njit
def clip_pairs(poly1, n1, poly2, n2, pairs):
    """Intersections of counterclockwise convex polygons, for each candidate pair (i, j).

    poly1 (N1, 4, 2), n1 (N1,) vertex counts; same for side 2; pairs (P, 2).
    Returns vertices (P, MAX_VERTICES, 2) and counts (P,) (0: no overlap).
    """
    P = pairs.shape[0]
    verts = np.zeros((P, MAX_VERTICES, 2))
    counts = np.zeros(P, np.int64)
    buf_a = np.empty((MAX_VERTICES, 2))
    buf_b = np.empty((MAX_VERTICES, 2))
    for k in range(P):
        i, j = pairs[k, 0], pairs[k, 1]
        m = n1[i]
        for v in range(m):
            buf_a[v, 0], buf_a[v, 1] = poly1[i, v, 0], poly1[i, v, 1]
        for e in range(n2[j]):
            if m == 0:
                break
            a = poly2[j, e]
            b = poly2[j, (e + 1) % n2[j]]
            m = _clip_edge(buf_a, m, a, b, buf_b)
            buf_a[:m] = buf_b[:m]
        counts[k] = m
        verts[k, :m] = buf_a[:m]
    return verts, counts
