"""Free blocks by remapped column indices against SciPy's fancy indexing; K - sigma M by the
data of a shared pattern against SciPy's sum."""
import numpy as np
import scipy.sparse as sp

from transient.model.dofs import free_block, restrict, restricted, shifted


def test_restrict_is_scipys_indexing():
    rng = np.random.default_rng(0)
    A = sp.random(60, 50, density=0.2, random_state=1, format="csr")
    A = (sp.diags(np.r_[np.ones(7), 0.0, np.ones(52)]) @ A).tocsr()     # an empty row
    A.eliminate_zeros()
    rows = np.sort(rng.choice(60, 40, replace=False))
    cols = np.sort(rng.choice(50, 31, replace=False))
    for r, c in ((rows, cols), (None, cols), (rows, None), (None, np.arange(50))):
        ref = A[r if r is not None else slice(None)][:, c if c is not None else slice(None)]
        got = restrict(A, r, c)
        assert got.shape == ref.shape and (got != ref).nnz == 0
        got.check_format()
    K = (A[:50] + A[:50].T).tocsr()
    assert (free_block(K, cols) != K[cols][:, cols]).nnz == 0


def test_matrices_of_one_pattern_are_restricted_together_and_others_apart():
    """restricted gives each matrix's own block, its entries in SciPy's order, whether the
    matrices share their pattern (one pass, B a copy of A with other values) or not (C)."""
    rng = np.random.default_rng(2)
    A = sp.random(80, 80, density=0.15, random_state=3, format="csr")
    B = sp.csr_matrix((rng.normal(size=A.nnz), A.indices, A.indptr), shape=A.shape)
    C = sp.random(80, 80, density=0.1, random_state=4, format="csr")
    rows = np.sort(rng.choice(80, 50, replace=False))
    cols = np.sort(rng.choice(80, 61, replace=False))
    for mats in ((A, B), (A, C), (A, B, C)):
        for r, c in ((rows, cols), (None, cols), (rows, None)):
            got = restricted(mats, r, c)
            for X, Y in zip(mats, got):
                ref = X[r if r is not None else slice(None)][:, c if c is not None
                                                               else slice(None)]
                assert Y.shape == ref.shape and np.array_equal(Y.indptr, ref.indptr)
                assert np.array_equal(Y.indices, ref.indices)
                assert np.array_equal(Y.data, ref.data)


def test_shifted_is_scipys_sum_on_a_shared_pattern_and_otherwise():
    rng = np.random.default_rng(2)
    pattern = sp.random(40, 40, density=0.2, random_state=3, format="csr")
    pattern = (pattern + pattern.T + sp.eye(40)).tocsr()
    pattern.sort_indices()
    K, M = pattern.copy(), pattern.copy()
    K.data = rng.standard_normal(K.nnz)
    M.data = rng.standard_normal(M.nnz)
    sigma = -3.0
    # entries that cancel: SciPy's sum leaves them out, and so must the shared-pattern path
    K.data[:5] = sigma * M.data[:5]
    M.data[5:9] = K.data[5:9] = 0.0
    for k, m in ((K, M), (K, sp.csr_matrix(M.toarray()))):     # shared, and not
        ref = (k - sigma * m).tocsr()
        got = shifted(k, m, sigma)
        got.check_format()
        assert np.array_equal(got.indptr, ref.indptr)
        assert np.array_equal(got.indices, ref.indices)
        assert np.array_equal(got.data, ref.data)
    assert (shifted(K, M, 0.0) != K).nnz == 0
