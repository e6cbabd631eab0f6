"""The transpose of an operator held by blocks (reduce.synthesis, contact.blocks): A.T @ y
is A.transpose_times(y), with no transposed copy of the blocks."""


class Transposed:
    """A^T of an operator A with transpose_times and a shape."""

    __array_ufunc__ = None     # ndarray @ A^T defers to it, never an object array

    def __init__(self, A):
        self.A = A
        self.shape = A.shape[::-1]

    @property
    def T(self):
        return self.A

    def __matmul__(self, y):
        return self.A.transpose_times(y)
