"""Isoparametric maps of faces: forward, inverse (in a projection plane) and unit normals."""
import numpy as np

from ..mesh.elements import ELEMENTS


def forward(X, xi, ftype):
    """Points x (n, 3) of faces with node coordinates X (n, nfn, 3) at reference points xi (n, 2)."""
    N = ELEMENTS[ftype].shape_functions(xi)
    return np.einsum("na,nak->nk", N, X)


def tangents(X, xi, ftype):
    """dx/dxi and dx/deta (n, 3) each."""
    dN = ELEMENTS[ftype].shape_derivatives(xi)
    return np.einsum("na,nak->nk", dN[:, :, 0], X), np.einsum("na,nak->nk", dN[:, :, 1], X)


def unit_normals(X, xi, ftype):
    """Unit normals (n, 3) of faces oriented by their node order (outward for boundary faces)."""
    t1, t2 = tangents(X, xi, ftype)
    n = np.cross(t1, t2)
    return n / np.linalg.norm(n, axis=1)[:, None]


def reference_centre(ftype):
    return np.array([0.0, 0.0]) if ELEMENTS[ftype].shape == "quad" else np.array([1 / 3, 1 / 3])


def inverse(X2d, p, ftype, tol=1e-15, max_iter=30):
    """Reference coordinates (n, 2) of points p (n, 2) in faces given by their projected nodes.

    Newton on P(x(xi)) = p, from the face's reference centre. X2d (n, nfn, 2) are the node
    coordinates in the projection plane. Points may lie slightly outside the face (curved edges
    approximated by chords); the map is then extrapolated, which is smooth.
    Returns xi and a bool array of points whose Newton iteration converged.
    """
    el = ELEMENTS[ftype]
    n = len(p)
    xi = np.tile(reference_centre(ftype), (n, 1))
    done = np.zeros(n, bool)
    # round-off of the residual scales with the coordinates' magnitude, not the face's size
    scale = np.abs(X2d).max(axis=(1, 2)) + 1e-300
    for _ in range(max_iter):
        N = el.shape_functions(xi)
        dN = el.shape_derivatives(xi)
        r = np.einsum("na,nak->nk", N, X2d) - p
        J = np.einsum("nad,nak->nkd", dN, X2d)           # (n, 2, 2): dP_k / dxi_d
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        step = np.empty_like(xi)
        step[:, 0] = (J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1]) / det
        step[:, 1] = (-J[:, 1, 0] * r[:, 0] + J[:, 0, 0] * r[:, 1]) / det
        xi -= step
        done = (np.abs(r).max(axis=1) <= tol * scale) | (np.abs(step).max(axis=1) <= 1e-13)
        if done.all():
            break
    return xi, done
