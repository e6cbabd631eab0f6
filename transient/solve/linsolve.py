"""Sparse symmetric factorizations behind shift-invert and static solves.

Backends: CHOLMOD (scikit-sparse, when installed: fastest and leanest), PARDISO (MKL, through
the pypardiso wheel: what a plain pip install brings) and SuperLU (scipy, the fallback, far
slower and hungrier on 3D solids). `factorize(A)` returns a callable x = solve(b).
"""
import ctypes

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..blas import mkl_runtime
from ..errors import FactorizationError  # noqa: F401 (raised here, caught by callers)
from ..kernels.sparse import csr_upper


def available():
    """Names of the backends importable here, best first."""
    names = []
    try:
        import sksparse.cholmod  # noqa: F401
        names.append("cholmod")
    except ImportError:
        pass
    try:
        mkl_runtime()
        names.append("pardiso")
    except (ImportError, OSError):
        pass
    return names + ["superlu"]


def why(backend, asked):
    """Why a factorization ran on backend, for the run's output: asked by the case's
    solver.linear_solver, or the best one installed."""
    if asked != "auto":
        return f"{backend} (solver.linear_solver)"
    note = "" if backend == "cholmod" or "cholmod" in available() else (
        "; CHOLMOD needs scikit-sparse")
    return f"{backend} (the best installed{note})"


def factorize(A, backend="auto", definite=True):
    """Factorize a symmetric matrix A; returns solve(b) with b of shape (n,) or (n, k).

    definite: A is known positive definite (CHOLMOD and PARDISO use Cholesky then);
    otherwise PARDISO uses a symmetric indefinite LDL^T and CHOLMOD is skipped.
    """
    if backend == "auto":
        names = [n for n in available() if definite or n != "cholmod"]
        backend = names[0]
    if backend not in available():
        raise FactorizationError(f"linear solver '{backend}' is not installed "
                                 f"(available: {', '.join(available())})")
    A = sp.csr_matrix(A)
    if backend == "cholmod":
        return _cholmod(A)
    if backend == "pardiso":
        return _Pardiso(A, 2 if definite else -2)
    return _superlu(A)


def _cholmod(A):
    from sksparse.cholmod import CholmodNotPositiveDefiniteError, cholesky
    try:
        factor = cholesky(A.tocsc())
    except CholmodNotPositiveDefiniteError as exc:
        raise FactorizationError(f"matrix not positive definite: {exc}") from None

    def solve(b):
        return factor(b)
    solve.backend = "cholmod"
    return solve


def _superlu(A):
    try:
        lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A",
                       options=dict(SymmetricMode=True))
    except RuntimeError as exc:
        raise FactorizationError(f"SuperLU failed: {exc}") from None

    def solve(b):
        return lu.solve(b)
    solve.backend = "superlu"
    return solve


def factorize_complex(A):
    """Factorize a complex unsymmetric sparse matrix (the full model's K + s D + s^2 M of the
    complex modes' shifts); returns solve(b). PARDISO (complex unsymmetric, METIS ordering)
    when installed: SuperLU's complex LU of a 3D solid took several times longer."""
    if "pardiso" in available():
        return _Pardiso(A, COMPLEX_UNSYMMETRIC)
    lu = spla.splu(sp.csc_matrix(A, dtype=complex))

    def solve(b):
        return lu.solve(b)
    solve.backend = "superlu"
    return solve


COMPLEX_UNSYMMETRIC = 13     # PARDISO's mtypes
COMPLEX_SYMMETRIC = 6


def release(solve):
    """Free a factorization's memory for good where its backend can (PARDISO's: its factors
    and MKL's buffers); the others' is freed with the solver. A solve after it is an error."""
    free = getattr(solve, "free", None)
    if free is not None:
        free()


def schur_by_pardiso(backend):
    """Whether Schur complements are formed by PARDISO (schur_complement): where it is
    installed and the case did not ask for another backend."""
    return backend in ("auto", "pardiso") and "pardiso" in available()


def schur_complement(A, g):
    """S = A_GG - A_GI A_II^-1 A_IG (g, g), dense, of a symmetric (real, or complex and not
    Hermitian) sparse A on its last g rows and columns G, by PARDISO's partial factorization
    (iparm 36): the cost of a factorization, where forming it by solves would take one solve
    for each of G's dofs. The diagonal of A_GG must be stored (zeros explicit)."""
    if "pardiso" not in available():
        raise FactorizationError("a Schur complement needs PARDISO (pypardiso)")
    solver = _Pardiso(A, COMPLEX_SYMMETRIC if np.iscomplexobj(A.data) else -2, phase=11,
                      schur=g)
    del A      # the solver holds its own upper triangle: a caller's unnamed A goes here
    return solver.schur()


class _Pardiso:
    """MKL PARDISO on the upper triangle of a symmetric matrix (or the whole of a complex
    unsymmetric one, mtype 13), factorized once.

    pypardiso only locates the MKL runtime; its solver works on the unsymmetric form and
    hashes the matrix at every solve, so the calls are made here directly.
    """
    backend = "pardiso"

    def __init__(self, A, mtype, phase=12, schur=0):
        self._lib, self.perm, self.data = mkl_runtime(), None, None
        fn = self._lib.pardiso
        i32 = ctypes.POINTER(ctypes.c_int32)
        fn.argtypes = [ctypes.POINTER(ctypes.c_int64), i32, i32, i32, i32, i32, ctypes.c_void_p,
                       i32, i32, i32, i32, i32, i32, ctypes.c_void_p, ctypes.c_void_p, i32]
        fn.restype = None
        self._fn = fn
        A = sp.csr_matrix(A)
        if not A.has_canonical_format:       # sorted, without duplicates (summed)
            A = A.copy()
            A.sum_duplicates()
        self.n = A.shape[0]
        self.dtype = (np.complex128 if mtype in (COMPLEX_UNSYMMETRIC, COMPLEX_SYMMETRIC)
                      else np.float64)
        if mtype == COMPLEX_SYMMETRIC:
            # its upper triangle, real and imaginary parts through one pattern
            A = A.astype(self.dtype, copy=False)
            self.indptr, self.indices, real = csr_upper(A.indptr, A.indices,
                                                        np.ascontiguousarray(A.data.real))
            imag = csr_upper(A.indptr, A.indices, np.ascontiguousarray(A.data.imag))[2]
            self.data = real + 1j * imag
        elif mtype == COMPLEX_UNSYMMETRIC:
            A.sort_indices()
            self.indptr, self.indices = (A.indptr.astype(np.int32), A.indices.astype(np.int32))
            self.data = A.data.astype(self.dtype)
        else:
            self.indptr, self.indices, self.data = csr_upper(
                A.indptr, A.indices, A.data.astype(np.float64, copy=False))
        self.mtype = mtype
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1      # user-set parameters
        self.iparm[1] = 2      # METIS nested dissection ordering
        self.iparm[9] = 8 if mtype == 2 else 13   # pivot perturbation 1e-8 / 1e-13
        if mtype == COMPLEX_UNSYMMETRIC:
            self.iparm[10] = self.iparm[12] = 1   # scaling and weighted matching (unsymmetric)
        self.iparm[34] = 1     # zero-based indices
        # conditional numerical reproducibility on MKL's threads: the same factors and solves
        # run after run, whatever the load (a preload or a basis must not move in its last
        # bits from one run to the next)
        self.iparm[33] = max(1, int(self._lib.mkl_get_max_threads()))
        if phase == 11:
            self.iparm[17] = self.iparm[18] = -1     # report the factors' nonzeros and MFLOP
        # the Schur complement's dofs marked in perm (not a user ordering: iparm 5 stays 0)
        if schur:
            self.perm = np.zeros(self.n, dtype=np.int32)
            self.perm[self.n - schur:] = 1
            self.iparm[35], self._schur = 1, schur
        self._call(phase, np.zeros(self.n, self.dtype), np.zeros(self.n, self.dtype))

    def schur(self):
        """The Schur complement on the dofs marked at the analysis, by the numerical
        factorization (phase 22), which returns it dense in x; the factors then freed."""
        g = self._schur
        x = np.zeros(g * g, self.dtype)
        try:
            self._call(22, np.zeros(self.n, self.dtype), x)
        finally:
            self.free()
        return x.reshape(g, g)

    def _call(self, phase, b, x):
        err = ctypes.c_int32(0)
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        i32 = ctypes.POINTER(ctypes.c_int32)
        one = ctypes.c_int32(1)
        self._fn(self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(one),
                 ctypes.byref(one), ctypes.byref(ctypes.c_int32(self.mtype)),
                 ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self.n)),
                 self.data.ctypes.data, self.indptr.ctypes.data_as(i32),
                 self.indices.ctypes.data_as(i32),
                 None if self.perm is None else self.perm.ctypes.data_as(i32),
                 ctypes.byref(ctypes.c_int32(nrhs)),
                 self.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(0)),
                 b.ctypes.data, x.ctypes.data, ctypes.byref(err))
        if err.value != 0:
            what = {-4: "zero pivot", -2: "not enough memory",
                    -3: "reordering problem"}.get(err.value, "error")
            raise FactorizationError(f"PARDISO {what} (code {err.value})")

    def __call__(self, b, out=None):
        # column-major both ways, as PARDISO reads and writes them: a row-major copy of x
        # cost 1.2 s of pad_disc_long's setup (a transpose of every block of responses).
        # out: a column-major array of b's shape to write x into (a block of a larger one)
        if self.data is None:
            raise RuntimeError("PARDISO's factors were released (a solve after the last one)")
        b = np.asfortranarray(b, dtype=self.dtype)
        x = out if out is not None and out.flags.f_contiguous else np.empty_like(b, order="F")
        self._call(33, b, x)
        if out is not None and x is not out:
            out[...] = x
        return x if out is None else out

    def free(self):
        """Release the factors (PARDISO's memory and MKL's cached buffers: 10.3 GB at 1M
        dofs) for a setup past its last solve; a solve after it is an error."""
        self._release()
        self._lib.mkl_free_buffers()

    def _release(self):
        if self.data is not None:
            self._call(-1, np.zeros(1, self.dtype), np.zeros(1, self.dtype))
            self.data = self.indptr = self.indices = None

    def __del__(self):
        # the factors only: MKL keeps its buffers for the next factorization (a preload's
        # Newton may factorize at every iteration), which free() alone gives back
        try:
            self._release()
        except Exception:
            pass


def pardiso_analysis(A, definite=True):
    """PARDISO's symbolic analysis of A alone (phase 11, the ordering the factorization uses):
    what factorizing it would take, without allocating the factors. Returns factor_nnz,
    factor_gb (held through the solves), peak_gb (analysis, factorization and solve) and
    gflop (the factorization's)."""
    solver = _Pardiso(sp.csr_matrix(A), 2 if definite else -2, phase=11)
    ip = solver.iparm
    # 1-based iparm(15) analysis peak, (16) permanent, (17) factorization and solve, in KiB;
    # (18) the factors' nonzeros, (19) MFLOP
    kib = 1024 / 1e9
    return {"factor_nnz": int(ip[17]), "factor_gb": kib * int(ip[16]),
            "peak_gb": kib * max(int(ip[14]), int(ip[15]) + int(ip[16])),
            "gflop": int(ip[18]) / 1e3}


def triangular_factors(A, backend="auto"):
    """Triangular factors of a symmetric positive definite A for solves inside Numba kernels:
    A x = b is x = w[p_out] with L z = b[p_in], U w = z. L, U as CSR triplets
    (indptr, indices, data) with the diagonal stored; returns (p_in, L, U, p_out, name).

    CHOLMOD gives L L^T when scikit-sparse is installed; otherwise SuperLU with a symmetric
    ordering and no pivoting (PARDISO does not hand out its factors).
    """
    A = sp.csr_matrix(A)
    if (backend in ("auto", "cholmod")) and "cholmod" in available():
        from sksparse.cholmod import CholmodNotPositiveDefiniteError, cholesky
        try:
            factor = cholesky(A.tocsc())
        except CholmodNotPositiveDefiniteError as exc:
            raise FactorizationError(f"matrix not positive definite: {exc}") from None
        L = factor.L().tocsr()
        P = factor.P()
        return (P.astype(np.int64), csr_triplet(L), csr_triplet(L.T),
                np.argsort(P).astype(np.int64),
                "cholmod")
    try:
        lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options=dict(SymmetricMode=True))
    except RuntimeError as exc:
        raise FactorizationError(f"SuperLU failed: {exc}") from None
    return (np.argsort(lu.perm_r).astype(np.int64), csr_triplet(lu.L), csr_triplet(lu.U),
            lu.perm_c.astype(np.int64), "superlu")


def csr_triplet(A):
    """(indptr, indices, data) of A in CSR with sorted indices: what the kernels take."""
    A = sp.csr_matrix(A)
    if not A.has_sorted_indices:
        A = A.sorted_indices()
    return A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data.astype(np.float64)
