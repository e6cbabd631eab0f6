"""Real linear maps applied to complex columns at the cost of real products: the map takes
[Re Z, Im Z] in one call, and no complex copy of a real operator is made."""
import numpy as np


def real_times(R, Z):
    """R Z for a real R (dense or sparse) and a complex Z (n, k), as one real product with
    [Re Z, Im Z]: NumPy and SciPy make a complex copy of R otherwise (the size of the whole
    basis X), and two products read R twice."""
    return real_apply(R.__matmul__, Z)


def real_apply(f, Z):
    """f(Z) for a real linear map f (one array, or a tuple of them, out) and a complex Z
    (n, k), by one call on [Re Z, Im Z]: a contact set's dense factors would otherwise be
    copied complex, as real_times's R."""
    k = Z.shape[1]
    Y = f(np.hstack([Z.real, Z.imag]))
    if isinstance(Y, tuple):
        return tuple(y[:, :k] + 1j * y[:, k:] for y in Y)
    return Y[:, :k] + 1j * Y[:, k:]
