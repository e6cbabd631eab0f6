"""Free blocks by remapped column indices against SciPy's fancy indexing."""
import numpy as np
import scipy.sparse as sp

from transient.model.dofs import free_block, restrict


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
