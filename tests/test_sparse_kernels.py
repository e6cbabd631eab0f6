"""Sparse kernels against scipy: triangular solves from each factorization backend."""
import numpy as np
import pytest
import scipy.sparse as sp

from transient.kernels.newmark import factor_columns
from transient.kernels.sparse import (csr_abs_matvec, csr_dot, csr_matvec, csr_upper,
                                      factor_solve)
from transient.solve.linsolve import available, triangular_factors


def spd(n=60, seed=0):
    A = sp.random(n, n, density=0.08, random_state=seed)
    return (A + A.T + n * sp.eye(n)).tocsr()


@pytest.mark.parametrize("backend", ["superlu", "cholmod"])
def test_factor_solve_inverts_the_matrix(backend):
    if backend not in available():
        pytest.skip(f"{backend} not installed")
    A = spd()
    p_in, L, U, p_out, name = triangular_factors(A, backend)
    assert name == backend
    b = np.random.default_rng(1).standard_normal(A.shape[0])
    x = np.empty_like(b)
    factor_solve(p_in, L, U, p_out, b, x, np.empty_like(b))
    assert np.abs(A @ x - b).max() < 1e-12 * np.abs(b).max()
    C = sp.random(5, A.shape[0], density=0.1, random_state=2).tocsr()
    trip = (C.indptr.astype(np.int64), C.indices.astype(np.int64), C.data)
    Z = factor_columns((p_in, L, U, p_out), trip, A.shape[0])
    assert np.allclose(A @ Z, C.T.toarray(), atol=1e-12)


def test_matvecs():
    A = spd()
    A.data -= 0.5 * A.data.max()          # signs of both kinds
    x = np.random.default_rng(3).standard_normal(A.shape[0])
    out = np.empty_like(x)
    csr_matvec(A.indptr, A.indices, A.data, x, out)
    assert np.allclose(out, A @ x)
    csr_abs_matvec(A.indptr, A.indices, A.data, x, out)
    assert np.allclose(out, abs(A) @ np.abs(x))


def test_csr_dot_is_the_same_on_every_thread_count_and_scipys_to_round_off():
    import numba
    A = sp.random(300, 200, density=0.05, random_state=3).tocsr()
    A.data -= 0.5                          # signs of both kinds, so that sums cancel
    X = np.random.default_rng(4).standard_normal((200, 37))
    before = numba.get_num_threads()
    try:
        out = {}
        for threads in (1, 2):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            out[threads] = (csr_dot(A, X), csr_dot(A, np.asfortranarray(X)),
                            csr_dot(A, X[:, 0]))
    finally:
        numba.set_num_threads(before)
    for a, b in zip(out[1], out[2]):
        assert np.array_equal(a, b)
    # two orders of summing a row's k products differ by at most 2 k eps of their magnitudes
    counts = np.diff(A.indptr)
    bound = 2 * counts.max() * np.finfo(float).eps * (abs(A) @ np.abs(X))
    assert np.all(np.abs(out[1][0] - A @ X) <= bound)
    assert np.array_equal(out[1][1], out[1][0])
    assert np.all(np.abs(out[1][2] - A @ X[:, 0]) <= bound[:, 0])
    # every remainder after the groups of four
    assert {int(c) % 4 for c in counts} == {0, 1, 2, 3}


def test_a_pair_of_one_pattern_is_two_csr_dots_bit_for_bit():
    from transient.kernels.sparse import csr_dot_pair, shares_pattern
    A = sp.random(300, 300, density=0.05, random_state=5).tocsr()
    A.data -= 0.5
    B = A.copy()
    B.data = np.random.default_rng(6).standard_normal(B.nnz)
    X = np.random.default_rng(7).standard_normal((300, 19))
    assert shares_pattern(A, B) and {int(c) % 4 for c in np.diff(A.indptr)} == {0, 1, 2, 3}
    for shared in (None, True):
        AX, BX = csr_dot_pair(A, B, np.asfortranarray(X), shared)
        assert np.array_equal(AX, csr_dot(A, X)) and np.array_equal(BX, csr_dot(B, X))
    # another pattern: the two products apart, the same numbers
    C = sp.random(300, 300, density=0.04, random_state=8).tocsr()
    assert not shares_pattern(A, C) and not shares_pattern(A, A.tocsc())
    AX, CX = csr_dot_pair(A, C, X)
    assert np.array_equal(AX, csr_dot(A, X)) and np.array_equal(CX, csr_dot(C, X))


def test_the_upper_triangle_is_scipys_triu_entry_for_entry():
    """What PARDISO is given: SciPy's triu (sorted), explicit zeros and all, as int32."""
    for seed in range(3):
        A = spd(80, seed)
        A.data[::7] = 0.0                  # explicit zeros are kept, as triu keeps them
        U = sp.triu(A, format="csr")
        U.sort_indices()
        indptr, indices, data = csr_upper(A.indptr, A.indices, A.data)
        assert indptr.dtype == indices.dtype == np.int32
        assert np.array_equal(indptr, U.indptr) and np.array_equal(indices, U.indices)
        assert np.array_equal(data, U.data)
