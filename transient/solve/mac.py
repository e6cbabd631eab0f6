"""The modal assurance criterion (MAC): how alike two shapes are, 1 for one shape up to a
factor, 0 for shapes orthogonal in the chosen weighting; real or complex shapes alike."""
import numpy as np

from .realmaps import real_times


def mac(X, Y, M=None):
    """(n, m) MAC |x_i^H M y_j|^2 / ((x_i^H M x_i) (y_j^H M y_j)) of the columns of X (p, n) and
    Y (p, m), real or complex, in the weighting M (p, p), real, dense or sparse: a mass, or the
    identity when None; 0 where a column's norm is 0."""
    if M is None:
        MX, MY, cross = X, Y, np.abs(X.conj().T @ Y) ** 2
    else:
        MX, MY = _times(M, X), _times(M, Y)
        cross = np.abs(_times(X.conj().T, MY)) ** 2
    nx = np.real(np.einsum("ij,ij->j", X.conj(), MX))
    ny = np.real(np.einsum("ij,ij->j", Y.conj(), MY))
    norms = np.outer(nx, ny)
    return np.where(norms > 0, cross / np.where(norms > 0, norms, 1.0), 0.0)


def _times(A, B):
    """A B, by real products where A is real and B complex (realmaps.real_times)."""
    if np.iscomplexobj(B) and not np.iscomplexobj(A):
        return real_times(A, B)
    return A @ B
