"""One piece of a part reduced in pieces (reduce.pieces): its stages, each run where the piece
is (a Dask worker, or this process), each with its own factorization of the piece held at the
cut: a worker keeps nothing between stages but their results.

The piece's interior dofs I are its own; the cut's dofs G it touches are shared with the other
pieces. Held at the cut it is a Craig-Bampton component: its fixed-cut modes Phi, its
constraint modes Psi = -(K_II - sigma M_II)^-1 (K_IG - sigma M_IG), and its static responses.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..kernels.sparse import csr_dot
from ..model.dofs import shifted
from ..solve.linsolve import (FactorizationError, factorize, release, schur_by_pardiso,
                              schur_complement)
from ..solve.lowrank import block_columns
from ..solve.modes import normal_modes, shift_sigma
from .basis import MODES_TOL
from .fields import field_map
from .parts import ROW_BLOCK, PartError, with_statics


# the complex step of the condensation, relative to the piece's largest ratio of stiffness to
# mass: far below round-off of every eigenvalue, far above underflow
STEP = 1e-30


@dataclass(frozen=True)
class Piece:
    """A piece's operators, sliced from its part's on the free dofs: K, M (I, I), KG, MG
    (I, G) sparse; G (g,) the cut's dofs it touches (indices into the cut); loads (I, s)
    sparse its rows of the part's static loads (set once the fields are known); support (I,
    I), E (I, k) sparse and rigid (I, 6) its share of the part's interface (None: no contact
    loads on it)."""
    name: str
    K: object
    M: object
    KG: object
    MG: object
    G: np.ndarray
    shift_hz: float
    backend: str
    support: object = None
    E: object = None
    rigid: np.ndarray = None

    def solver(self):
        """(K_II - sigma M_II)^-1, the piece held at the cut (a piece is never free: its cut
        is a surface), and sigma."""
        sigma = shift_sigma(-self.shift_hz)
        try:
            return factorize(shifted(self.K, self.M, sigma), self.backend, definite=True), sigma
        except FactorizationError as exc:
            raise PartError(self.name, str(exc)) from None

    def fields(self, G, shape, block, cutoff):
        """P (k, f) the interface fields of the piece's loaded interface, held at the cut
        (reduce.fields.field_map); None where no contact load reaches the piece."""
        if self.E is None or not self.E.nnz:
            return None
        try:
            return field_map(self.K, self.M, self.support, sp.csc_matrix(self.E), G, shape,
                             block, self.rigid, cutoff, self.shift_hz, self.backend)
        except FactorizationError as exc:
            raise PartError(self.name, str(exc)) from None

    def condensed(self, loads, fmax):
        """(A, (S, Mh, B, omega2, C)): A (I, a) the fixed-cut modes to fmax and the static
        responses to loads (I, s) sparse beyond them, M-orthonormal; the piece's condensation
        on the cut's dofs it touches, S = K_GI Psi (g, g) and Mh = M_GI Psi + Psi^T M_IG +
        Psi^T M_II Psi (K shifted), B (g, s) the loads carried to the cut, -K_GI K_II^-1
        loads; the modes' squared frequencies omega2 (m,) and mass coupling with the cut,
        C = Phi^T (M_II Psi + M_IG) (m, g)."""
        solve, sigma = self.solver()
        modes = normal_modes(self.K, self.M, None, count=40, fmax=fmax, shift=-self.shift_hz,
                             solve=solve, tol=MODES_TOL)
        Phi, g, by_schur = modes.shapes, self.KG.shape[1], schur_by_pardiso(self.backend)
        KG = (self.KG - sigma * self.MG).tocsc()
        if by_schur:
            # C^T = M_GI Phi + Psi^T M_II Phi = M_GI Phi - K_GI K_II^-1 M_II Phi: a solve a
            # mode, the condensation itself from a factorization of its own (condensation)
            C = (self.MG.T @ Phi - KG.T @ solve(csr_dot(self.M, Phi))).T
        else:
            S, Mh, C = self._condensation_by_solves(solve, KG, Phi)
        # only the loads that reach the piece: one away from the contact has no field's rows,
        # and its responses to them, and their relaxations on the cut, are zero
        loads = sp.csc_matrix(loads)
        loaded = np.flatnonzero(np.diff(loads.indptr))
        m, width = Phi.shape[1], block_columns(self.K.shape[0])
        X = np.empty((self.K.shape[0], m + len(loaded)), order="F")
        X[:, :m] = Phi
        for start in range(0, len(loaded), width):
            cols = loaded[start:start + width]
            X[:, m + start:m + start + len(cols)] = solve(loads[:, cols].toarray())
        B = np.zeros((g, loads.shape[1]))
        B[:, loaded] = -(KG.T @ X[:, m:])
        omega2 = np.sign(modes.frequencies) * (2 * np.pi * modes.frequencies) ** 2
        A = with_statics(X, m, self.M)
        if by_schur:
            # its factors, and MKL's buffers that held them, let go before the
            # condensation's complex ones (a piece's stage peaks there)
            release(solve)
            solve = X = None
            S, Mh = self.condensation(sigma)
        return A, (S, Mh, B, omega2, C)

    def condensation(self, sigma):
        """(S, Mh) (g, g) of condensed(), by one complex symmetric factorization with the cut
        last: the Schur complement of K - z M on the cut at z = sigma + i h is S(z) = -K_GI
        K_II^-1 K_IG there, and dS/dz = -Mh, so that its real part is S and its imaginary
        part -h Mh, both to round-off for h below round-off of the spectrum (the complex
        step: no difference taken, nothing cancels). PARDISO forms it within the
        factorization (iparm 36), where Psi by solves costs two solves for each cut dof."""
        h = STEP * abs(self.K.diagonal()).max() / abs(self.M.diagonal()).max()
        # K - z M made here and handed over unnamed: the solver's copy of its upper triangle
        # is all that stays beside the factors
        X = schur_complement(self._with_cut(complex(sigma, h)), self.KG.shape[1])
        S = np.ascontiguousarray(X.real)
        Mh = X.imag * (-1.0 / h)
        X = None
        return 0.5 * (S + S.T), 0.5 * (Mh + Mh.T)

    def _with_cut(self, z):
        """K - z M on the piece's dofs and the cut's it touches, the cut last, its own block
        empty but for explicit zeros on its diagonal (what PARDISO asks of a symmetric
        matrix): the piece's share of the cut's stiffness is the caller's."""
        g = self.KG.shape[1]
        zero = sp.csr_matrix((np.zeros(g), (np.arange(g), np.arange(g))), shape=(g, g))
        Z = sp.bmat([[self.K - z * self.M, self.KG - z * self.MG], [None, zero]], format="csr")
        Z.sort_indices()
        return Z

    def _condensation_by_solves(self, solve, KG, Phi):
        """(S, Mh, C) of condensed() by Psi's solves, a block of cut dofs at a time: where
        PARDISO is not (another backend asked), and the reference condensation() is tested
        against."""
        KGt, MGt = KG.T.tocsr(), self.MG.T.tocsr()
        g = KG.shape[1]
        S, Mh, C = np.empty((g, g)), np.empty((g, g)), np.empty((Phi.shape[1], g))
        width = block_columns(self.K.shape[0])
        for start in range(0, g, width):
            cols = slice(start, start + width)
            Psi = -solve(KG[:, cols].toarray())
            S[:, cols] = KGt @ Psi
            # Psi^T x = -K_GI K_II^-1 x: Psi^T M_IG + Psi^T M_II Psi in one solve
            Y = self.MG[:, cols].toarray() + csr_dot(self.M, Psi)
            C[:, cols] = Phi.T @ Y
            Mh[:, cols] = MGt @ Psi - KGt @ solve(Y)
        return 0.5 * (S + S.T), 0.5 * (Mh + Mh.T), C

    def extended(self, A, V, loads, empty=None):
        """((A2, ext), blocks): the cut's shapes V (g, c) extended into the interior, ext =
        Psi V (I, c), and A (I, a) with the interior's first dynamic correction to that
        motion beyond it, (K_II - sigma M_II)^-1 (M_II ext + M_IG V): the leading term of the
        fixed-cut modes it truncates (the interior's response at omega is ext + omega^2 times
        it + O(omega^4)). blocks: the piece's share of the part's K, M and loads on its
        columns [A2, W], W = [ext; V] (piece_blocks). empty(shape, order) makes the two
        (I, .) arrays (a reduce.store.Store's files: they are the stage's working set)."""
        empty = empty or (lambda shape, order: np.empty(shape, order=order))
        solve, sigma = self.solver()
        KG = (self.KG - sigma * self.MG).tocsr()
        n, a, c = self.K.shape[0], A.shape[1], V.shape[1]
        X = empty((n, a + c), "F")
        X[:, :a] = A
        ext = empty((n, c), "F")
        width = block_columns(n)
        for start in range(0, c, width):
            cols = slice(start, start + width)
            ext[:, cols] = -solve(KG @ V[:, cols])
            X[:, a + start:a + start + width] = solve(csr_dot(self.M, ext[:, cols])
                                                      + self.MG @ V[:, cols])
        solve = None
        A2 = with_statics(X, a, self.M)
        return (A2, ext), self.blocks(A2, ext, V, loads)

    def blocks(self, A, ext, V, loads):
        """For X in (K, M): (A^T X A, A^T X W, the piece's share of W^T X W) with W = [ext;
        V]; then the loads' (A^T F, ext^T F) (the cut's own rows are the caller's). A block of
        columns at a time: X A and X W are the piece's dofs times all its columns, the
        stage's largest arrays were they made whole."""
        a, c = A.shape[1], ext.shape[1]
        width = block_columns(len(A))
        out = []
        for X, XG in ((self.K, self.KG), (self.M, self.MG)):
            AXA, AXW, WXW = np.empty((a, a)), np.empty((a, c)), np.empty((c, c))
            for start in range(0, a, width):
                cols = slice(start, start + width)
                AXA[:, cols] = A.T @ csr_dot(X, A[:, cols])
            for start in range(0, c, width):
                cols = slice(start, start + width)
                XW = csr_dot(X, ext[:, cols]) + XG @ V[:, cols]
                AXW[:, cols] = A.T @ XW
                WXW[:, cols] = ext.T @ XW + V.T @ (XG.T @ ext[:, cols])
            out.append((AXA, AXW, WXW))
        Ft = loads.T.tocsr()
        out.append(((Ft @ A).T, (Ft @ ext).T))
        return out

    @staticmethod
    def expanded(held, Ta, Tw, into=None, rows=None):
        """The part's basis on the piece's rows, A2 Ta + ext Tw (held = (A2, ext)), made a
        block of rows at a time into into[rows] (a new array without into): no piece's dofs
        times the part's columns made whole beside it, and the same arithmetic either way."""
        A2, ext = held
        if into is None:
            into, rows = np.empty((len(A2), Ta.shape[1])), np.arange(len(A2))
        for start in range(0, len(A2), ROW_BLOCK):
            block = slice(start, start + ROW_BLOCK)
            into[rows[block]] = A2[block] @ Ta + ext[block] @ Tw
        return into
