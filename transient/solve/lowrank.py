"""Solves with K - sigma M + C^T diag(d) C for any diagonal d, from one sparse factorization.

Contact couples the interface dofs densely (regularized rows span the whole interface), which
makes factorizing K + C^T D C slow and memory hungry. With m contact points, the Woodbury
identity needs only A0 = K - sigma M factorized once, Z = A0^-1 C^T (m solves) and G = C Z:

    (A0 + C^T D C)^-1 b = y - Z (I + D G)^-1 D C y,   y = A0^-1 b,

so a new tangent D costs an m x m factorization, and a solve one sparse solve plus O(n m).
"""
import time
from contextlib import closing
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..contact.regularize import factored_rows
from ..kernels.sparse import csr_dot, csr_dot_pair
from ..model.dofs import restrict, restricted, shifted
from .. import blas, progress
from .linsolve import factorize, release
from .rowspace import factored_row_space, row_space

MAX_BYTES = 1.5e9     # Z = A0^-1 C^T held dense up to this; G (rank^2) too, beyond it the
#                       dense form A0 + C^T D C is factorized
BLOCK = 128           # right-hand sides per solve when forming Z (bounds the solver's copies: three
#                       n x BLOCK arrays, 0.4 GB at 140k dofs; on pad_disc_long's interface loads
#                       as fast per column as 300 or all 599 at once)
BLOCK_BYTES = 2.56e8  # ... and fewer where n x BLOCK floats pass this: at 1M dofs a block of
#                       128 is 1 GB, three at once beside 9.8 GB of factors and the n x 819 basis


def block_columns(n, most=None):
    """Columns of a block of n-row arrays: `most` (BLOCK), fewer where they would pass
    BLOCK_BYTES (32 at 1M dofs, 128 up to 250k)."""
    most = BLOCK if most is None else most
    return max(8, min(most, int(BLOCK_BYTES // (8 * max(n, 1)))))


@dataclass(frozen=True)
class RowSpace:
    """What a tangent solve on a rich rule's row space already holds: the dofs the rows touch
    (cols), an orthonormal basis V of the rows' space there, the rows in it (Rm, C E = Rm V^T),
    G = V^T E^T A0^-1 E V, responses(Y) = A0^-1 E V Y (from Z when it is held, else solved),
    and R() such that the tangent's responses to the loads E V are A0^-1 E V R. held: Z is
    held, so responses are products, not solves."""
    cols: np.ndarray
    V: np.ndarray
    Rm: np.ndarray
    G: np.ndarray
    responses: object
    R: object
    held: bool = False


@dataclass(frozen=True)
class TangentStiffness:
    """K + C^T diag(d) C on the free dofs, applied to a block: K X plus the update in the
    solver's own form of the rows, E V core V^T E^T X (on the rows' space: core = Rm^T D Rm,
    the tangent solve's) or C^T (d C X). For regularized rows the update is dense over the
    interface dofs (pad_disc_long: 7.1M entries, 0.75 s to add to K and 0.5 s more to take the
    free block of the sum), so it is formed only for a dense eigensolver (tocsr)."""
    K: sp.csr_matrix
    cols: np.ndarray = None
    V: np.ndarray = None
    core: np.ndarray = None
    C: sp.csr_matrix = None
    d: np.ndarray = None

    @property
    def shape(self):
        return self.K.shape

    def __matmul__(self, X):
        return self._updated(X, csr_dot(self.K, X) if X.ndim == 2 else self.K @ X)

    def with_mass(self, M, X, shared=None):
        """(M X, self @ X) for a block X (n, s): M and K of one assembly share their pattern,
        and both products then read it and X once (csr_dot_pair; shared as there)."""
        MX, KX = csr_dot_pair(M, self.K, X, shared)
        return MX, self._updated(X, KX)

    def update_gram(self, rows, s):
        """X^T U X for the update U = C^T diag(d) C of K and a block X (n, s) on the free dofs
        given by its rows: rows(idx) is X[idx] (only the dofs the update touches are asked:
        a basis' X A is never formed whole). From the rows' space, or the rows' products."""
        if self.V is not None:
            B = self.V.T @ rows(self.cols)
            return B.T @ (self.core @ B)
        if self.C is not None:
            cols = np.unique(self.C.indices)
            CX = self.C[:, cols] @ rows(cols)
            return CX.T @ (self.d[:, None] * CX)
        return np.zeros((s, s))

    def _updated(self, X, out):
        """out = K X plus the update times X."""
        if self.V is not None:
            out[self.cols] += self.V @ (self.core @ (self.V.T @ X[self.cols]))
        if self.C is not None:
            CX = self.C @ X
            out += self.C.T @ (self.d[:, None] * CX if CX.ndim == 2 else self.d * CX)
        return out

    def tocsr(self):
        K = self.K
        if self.V is not None:
            n, k = K.shape[0], len(self.cols)
            E = sp.csr_matrix((np.ones(k), (self.cols, np.arange(k))), shape=(n, k))
            B = E @ sp.csr_matrix(self.V)
            K = K + B @ sp.csr_matrix(self.core) @ B.T
        if self.C is not None:
            K = K + self.C.T @ sp.diags(self.d) @ self.C
        return sp.csr_matrix(K)

    def toarray(self):
        return self.tocsr().toarray()


@dataclass(frozen=True)
class TangentSolve:
    """x = (A0 + C^T diag(d) C)^-1 b for b (n,) or (n, k), by calling it; stiffness: the
    tangent K + C^T diag(d) C itself (TangentStiffness)."""
    solve: object
    backend: str
    row_space: RowSpace = None     # set when Woodbury ran on the rows' space
    stiffness: TangentStiffness = None

    def __call__(self, b):
        return self.solve(b)


class ContactSolver:
    """Factorization of A0 = K - sigma M on the free dofs, updated by contact tangents.
    C: the contact rows on the free dofs (P, n), or None when factors hold them.

    The update C^T D C has rank at most min(m, rank C). With more points than the k dofs the
    rows touch (a fine rule: 7734 points on the pad_disc interface), C is written Rm B^T with
    B = E V: E selects those dofs and V (k x rho) is an orthonormal basis of the row space of
    C E. Woodbury then runs on the rho columns of B instead of the m rows of C: rho = k for the
    fine rule, and only r1 + r2 (the kept shapes' traces) for a regularized one, whose dense
    rows touch every interface dof (pad_disc: 2668 dofs, rank 599).

    factors (L, B), C = L B^T with r columns (regularized rows: contact.pair.row_factors),
    give the row space from r x r algebra instead of the k x k Gram of the dense rows.
    """

    def __init__(self, K, M, C, sigma, backend="auto", factors=None):
        self.K, self.M = K.tocsr(), M.tocsr()     # (M: the reduced basis' mass too)
        self.n = K.shape[0]
        self.sigma = sigma
        self.backend = backend
        if C is None:
            # the rows as factors only: their dofs are those B touches
            L, B = factors[0], sp.csr_matrix(factors[1])
            m, self.cols, self.C = L.shape[0], np.flatnonzero(np.diff(B.indptr)), None
        else:
            self.C = C.tocsr()
            m, self.cols = C.shape[0], np.unique(self.C.indices)
        n, k = K.shape[0], len(self.cols)
        self.m = m
        self.by_columns = k < m and 8.0 * k * k <= MAX_BYTES
        if C is None and not self.by_columns:
            self.C = factored_rows(*factors)
        # what the stage's seconds go to: at 1M dofs 112 s of factors, then 187 s for the 780
        # responses G takes (Z not held; in 25 blocks of 32, 130 s in 7 of 128 at 1 GB each)
        t0 = time.perf_counter()
        self.solve0 = factorize(self.A0, backend, definite=sigma <= 0)   # A0 not held
        self.timings = {"factors": time.perf_counter() - t0}
        t0 = time.perf_counter()
        if m and self.by_columns:
            # the gate is on what Z holds, rho columns: regularized rows span far fewer
            # directions than the k dofs they touch (pad_disc: 599 of 2668)
            self.Rm, self.V = (row_space(self.C[:, self.cols].toarray()) if factors is None
                               else factored_row_space(*factors, self.cols))
        rank = self.Rm.shape[1] if m and self.by_columns else min(m, k)
        self.timings["row_space"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        # Woodbury needs G (rank x rank); Z = A0^-1 B (n x rank) is held when it fits, and
        # otherwise solved for at each use (two solves per solve instead of one and Z times a
        # block): memory n x BLOCK instead of n x rank (n rank grows as n^5/3 with the mesh)
        self.lowrank = m > 0 and 8.0 * rank * rank <= MAX_BYTES
        if not self.lowrank:
            if self.C is None:
                self.C = factored_rows(*factors)      # A0 + C^T D C is formed
            return
        self.CT = None if self.by_columns else self.C.T.tocsc()
        self.Z = np.empty((n, rank), order="F") if 8.0 * n * rank <= MAX_BYTES else None
        G = None if self.Z is not None else np.empty((rank, rank))
        loads, width = None, block_columns(n)
        into = np.empty((n, min(width, rank)), order="F") if self.Z is None else None
        with closing(progress.work("responses", rank, "load")) as bar:
            for start in range(0, rank, width):
                block = slice(start, min(start + width, rank))
                # one array of loads for every block, and the responses solved into Z's
                # columns, or without Z into one block: n x BLOCK of fresh memory a block
                # otherwise, twice (0.1 s on pad_disc; 25 blocks of 252 MB at 1M dofs)
                loads = self._loads(block, loads)
                if self.Z is not None:
                    self._solve_into(loads, self.Z[:, block])
                else:
                    G[:, block] = self._rows_of(
                        self._solve_into(loads, into[:, :loads.shape[1]]))
                bar.advance(block.stop)
        # with Z held, G in one product (as before Z could be left out: the same sums)
        self.G = self._rows_of(self.Z) if self.Z is not None else G
        self.timings["responses"] = time.perf_counter() - t0
        if self.by_columns:
            # the rows are Rm V^T on cols from here on: the dense copy (points x interface dofs,
            # the largest array of a regularized fine rule at scale) is not held
            self.C = None

    @property
    def A0(self):
        """K - sigma M, formed when asked: the factors hold it, and a copy is a sparse matrix
        more through the setup (held, it was 0.40 GB of 4x pad_disc's 7.23 GB peak)."""
        return shifted(self.K, self.M, self.sigma)

    def release(self):
        """Free the factors for good, once the setup that owns this solver is past its last
        solve (reduce: the basis' orthonormalization and the sampling solve nothing): at 1M
        dofs they were 10.3 GB of the 24 the Grams ran out of. A shared solver (a campaign's)
        is not released. Only PARDISO's factors can be freed in place (the solves hold them)."""
        release(self.solve0)

    def __getstate__(self):
        # a factorization does not travel between processes (PARDISO's handle is its own):
        # the receiver factorizes A0 again, the same factors in the same thread setting
        # (PARDISO's conditional numerical reproducibility), and keeps the rest (Z, G, V)
        state = dict(self.__dict__)
        del state["solve0"]
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.solve0 = factorize(self.A0, self.backend, definite=self.sigma <= 0)

    def _solve_into(self, loads, out):
        """out = A0^-1 loads (n, k), returned: PARDISO writes a column-major out itself, other
        backends' solutions are copied in."""
        if getattr(self.solve0, "backend", "") == "pardiso":
            return self.solve0(loads, out=out)
        out[...] = np.atleast_2d(self.solve0(loads).T).T
        return out

    def _loads(self, Y, buffer=None):
        """B Y (n, k), F-ordered: B = E V by columns, C^T otherwise; Y (rank, k), or a slice
        of B's columns (taken, not multiplied). buffer: an earlier call's result, reused by
        columns when it has enough of them."""
        if isinstance(Y, slice):
            part = self.V[:, Y] if self.by_columns else self.CT[:, Y].toarray()
        else:
            part = self.V @ Y if self.by_columns else self.CT @ Y
        if not self.by_columns:
            return np.asfortranarray(part)
        k = part.shape[1]
        if buffer is not None and buffer.shape[1] >= k:
            b = buffer[:, :k]          # (its nonzero rows are cols, all overwritten)
        else:
            b = np.zeros((self.n, k), order="F")
        b[self.cols] = part
        return b

    def _rows_of(self, Zb):
        """B^T Zb in the update's coordinates: V^T E^T Zb by columns, C Zb otherwise."""
        return self.V.T @ Zb[self.cols] if self.by_columns else np.asarray(self.C @ Zb)

    def responses(self, Y, out=None):
        """Z Y = A0^-1 B Y for Y (rank,) or (rank, k): from Z when held, else one solve.
        out: an (n, k) array to write them into (a view of the reduced basis), for a 2-D Y."""
        # Z Y as (Y^T Z^T)^T, Z^T row-major, on every core (no solve runs meanwhile): OpenBLAS
        # packs the tall Z of Z Y whole for a few columns. pad_disc's 66554 x 599 times 16
        # columns (a Lanczos step's Woodbury term) 74 -> 45 ms on one thread, 22 on two; times
        # one column 24 -> 13 ms on two
        if self.Z is not None and (Y.ndim == 1 or out is None):
            with blas.every_core():
                return self.Z @ Y if Y.ndim == 1 else (Y.T @ self.Z.T).T
        Y2 = Y[:, None] if Y.ndim == 1 else Y
        # BLOCK columns at a time: no n x k product beside out (the basis' own columns), and
        # without Z the loads and the solver's own copies are n x BLOCK, not n x k (the kept
        # contact shapes: 515 at 500k dofs, 2 GB each, three at once)
        x = np.empty((self.n, Y2.shape[1])) if out is None else out
        loads, width = None, block_columns(self.n)
        into = (np.empty((self.n, min(width, Y2.shape[1])), order="F") if self.Z is None
                else None)
        for start in range(0, Y2.shape[1], width):
            block = slice(start, min(start + width, Y2.shape[1]))
            if self.Z is not None:
                with blas.every_core():
                    x[:, block] = (Y2[:, block].T @ self.Z.T).T
                continue
            loads = self._loads(Y2[:, block], loads)
            x[:, block] = self._solve_into(loads, into[:, :loads.shape[1]])
        return x[:, 0] if Y.ndim == 1 else x

    def solver(self, d):
        """solve(b) for (A0 + C^T diag(d) C) x = b; b (n,) or (n, k)."""
        d = np.asarray(d, float)
        if self.m == 0 or not np.any(d):
            return TangentSolve(self.solve0, getattr(self.solve0, "backend", "?"),
                                stiffness=TangentStiffness(self.K))
        if not self.lowrank:
            A = (self.A0 + self.C.T @ sp.diags(d) @ self.C).tocsr()
            solve = factorize(A, self.backend, definite=False)
            return TangentSolve(solve, getattr(solve, "backend", "?"),
                                stiffness=TangentStiffness(self.K, C=self.C, d=d))
        Z, solve0 = self.responses, self.solve0
        if self.by_columns:
            with blas.every_core():
                # Rm^T D Rm as X^T X, X = D^1/2 Rm, when no d is negative: NumPy hands a
                # product of an array with its own transpose to syrk (half the flops)
                X = np.sqrt(d)[:, None] * self.Rm if np.all(d >= 0) else None
                core = X.T @ X if X is not None else self.Rm.T @ (d[:, None] * self.Rm)
            # the rank x rank LU on one thread: on two, 3-4x slower (pad_disc_long, 599^2)
            lu = sla.lu_factor(np.eye(len(core)) + core @ self.G)
            cols, V = self.cols, self.V

            def solve(b):
                y = solve0(b)
                return y - Z(sla.lu_solve(lu, core @ (V.T @ y[cols])))
            # the responses to the loads B = E V without solving again:
            # (A0 + B core B^T)^-1 B = Z R, R = I - (I + core G)^-1 core G; with the solver's
            # rows in that basis, C = Rm B^T
            known = RowSpace(cols, V, self.Rm, self.G, Z,
                             lambda: np.eye(len(core)) - sla.lu_solve(lu, core @ self.G),
                             self.Z is not None)
            stiffness = TangentStiffness(self.K, cols, V, core)
        else:
            lu = sla.lu_factor(np.eye(len(d)) + d[:, None] * self.G)
            C = self.C

            def solve(b):
                y = solve0(b)
                Cy = C @ y
                return y - Z(sla.lu_solve(lu, d[:, None] * Cy if Cy.ndim == 2 else d * Cy))
            known, stiffness = None, TangentStiffness(self.K, C=C, d=d)
        return TangentSolve(solve, getattr(self.solve0, "backend", "?") + "+woodbury", known,
                            stiffness)

    def tied(self):
        """(TangentSolve, rank): solve(b) for the limit of solver(d) as every d grows without bound,
        the problem with the rows' gap held at zero, and the number of directions it holds.

        (A0 + B D B^T)^-1 b = y - Z (D^-1 + G)^-1 B^T y tends to y - Z G^-1 B^T y (y = A0^-1
        b): x with B^T x = 0, the constraint's multipliers G^-1 B^T y. B = E V, V an
        orthonormal basis of the rows' space on the dofs they touch: the rows' singular values
        above 1e-6 of the largest (rowspace.ROW_SPACE_TOL on their Gram), so a rich rule's
        round-off directions stay free. The difference cancels what A0^-1 gives a part that only the
        contact holds (10^7 times the rest with a 1 Hz shift, the pad on the disc): through an
        orthonormal V the solve stays symmetric to 3e-9 there, through the rows themselves
        (their singular values spread over 1e6) to 1e-5, where the Lanczos stalls."""
        backend = getattr(self.solve0, "backend", "?")
        if self.m == 0:
            return TangentSolve(self.solve0, backend), 0
        if not self.lowrank:
            raise ValueError(f"the {self.m} contact rows span too many directions for the "
                             "low-rank update the exact tie needs")
        solve0, cols = self.solve0, self.cols
        if self.by_columns:
            V, G, Z = self.V, self.G, self.responses
        else:
            # fewer points than dofs: the responses to the rows' orthonormal basis, solved
            _, V = row_space(self.C[:, cols].toarray())
            n, rank = self.n, V.shape[1]
            if 8.0 * n * rank > MAX_BYTES:
                raise ValueError(f"the responses to the {rank} directions of the contact "
                                 f"rows on {n} dofs exceed {MAX_BYTES / 1e9:g} GB")
            ZV, width = np.empty((n, rank), order="F"), block_columns(n)
            for start in range(0, rank, width):
                block = slice(start, min(start + width, rank))
                b = np.zeros((n, block.stop - start), order="F")
                b[cols] = V[:, block]
                self._solve_into(b, ZV[:, block])
            G, Z = V.T @ ZV[cols], ZV.__matmul__
        cho = sla.cho_factor(G)

        def solve(b):
            y = solve0(b)
            return y - Z(sla.cho_solve(cho, V.T @ y[cols]))
        return TangentSolve(solve, backend + "+tied"), V.shape[1]


def contact_solver(model, contacts, sigma, backend="auto"):
    """The ContactSolver of a model's free dofs under a contact set's rows (the explicit
    rows, or their factors)."""
    free = model.free
    factors = (None if contacts.factors is None
               else (contacts.factors[0], contacts.factors[1][free]))
    return ContactSolver(*restricted((model.K, model.M), free, free),
                         None if contacts.rows is None else restrict(contacts.C, cols=free),
                         sigma, backend, factors)
