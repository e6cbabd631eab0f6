"""Sparse kernels on CSR triplets (indptr, indices, data): products and triangular solves."""
from ..jit import njit_fast


@njit_fast
def csr_matvec(indptr, indices, data, x, out):
    for i in range(out.shape[0]):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        out[i] = s


@njit_fast
def csr_abs_matvec(indptr, indices, data, x, out):
    """|A| |x|: the scale of the round-off in A x."""
    for i in range(out.shape[0]):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += abs(data[k] * x[indices[k]])
        out[i] = s


@njit_fast
def factor_solve(p_in, L, U, p_out, b, x, work):
    """x = A^-1 b from linsolve.triangular_factors: L z = b[p_in], U w = z, x = w[p_out].
    work (n,) is scratch; b and x may be the same array."""
    Lp, Li, Ld = L
    Up, Ui, Ud = U
    n = b.shape[0]
    for i in range(n):
        work[i] = b[p_in[i]]
    for i in range(n):                      # forward: the diagonal is the row's last entry
        s = work[i]
        end = Lp[i + 1] - 1
        for k in range(Lp[i], end):
            s -= Ld[k] * work[Li[k]]
        work[i] = s / Ld[end]
    for i in range(n - 1, -1, -1):          # backward: the diagonal is the row's first entry
        s = work[i]
        start = Up[i]
        for k in range(start + 1, Up[i + 1]):
            s -= Ud[k] * work[Ui[k]]
        work[i] = s / Ud[start]
    for i in range(n):
        x[i] = work[p_out[i]]
