"""One part of the components path reduced on its own: its interface fields, its factorization,
modes and static responses, formed into its basis.

A part's task (PartTask) holds its own matrices and interface loads; its key hashes them with
the settings and the source of the code that reduces it, so that a campaign that changes the
pad's lining reduces the pad again and reads the disc, the caliper and the bracket back, and
a reduction made by other code is never read as this one's (reduce.engine keeps them).
"""
import hashlib
import time
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..kernels.sparse import csr_dot
from ..model.dofs import shifted
from ..model.partcells import PartCells
from .. import blas, progress
from ..solve.linsolve import FactorizationError, factorize
from ..solve.lowrank import block_columns
from ..solve.modes import normal_modes, shift_sigma
from .basis import MODES_TOL, flexible_shapes
from .fields import field_map

# the modules whose arithmetic makes a part's reduction: their source is in its key
_SOURCES = ("reduce/parts.py", "reduce/basis.py", "reduce/fields.py", "solve/modes.py",
            "solve/lanczos.py", "solve/linsolve.py", "solve/lowrank.py", "model/dofs.py",
            "model/partcells.py", "model/assembly.py", "model/elasticity.py",
            "kernels/assembly.py", "mesh/elements.py")
ROW_BLOCK = 8192     # rows of the basis formed at a time in place


@dataclass(frozen=True)
class PartInterface:
    """The contact's loads on one part: E (n, k) sparse, the rows' gram G (k, k) in them
    (G = Cc^T diag(w k_t) Cc with C = Cc E^T the part's rows, w k_t the law's stiffness at
    each point); shape, block (k,): the compatible shape each column is the trace of (-1: kept
    whole) and the rows' direction it loads (reduce.fields.field_map); support (n, n) sparse
    and rigid (n, 6), the part's loaded interface and rigid motions (None: no field kept)."""
    E: object
    G: np.ndarray
    shape: np.ndarray
    block: np.ndarray
    support: object = None
    rigid: np.ndarray = None

    def arrays(self):
        """What the part's reduction reads of it, for its key."""
        out = [self.E.data, self.E.indices, self.E.indptr, np.array(self.E.shape), self.G,
               self.shape, self.block]
        if self.support is not None:
            S = self.support.tocsr()
            out += [S.data, S.indices, S.indptr, self.rigid]
        return out


@dataclass(frozen=True)
class PartBasis:
    """One part's reduction: T (n, r) on its free dofs, T^T M T = I, its first n_modes
    columns the part's normal modes; Kr = T^T K T."""
    name: str
    T: np.ndarray
    Kr: np.ndarray
    mode_hz: np.ndarray      # (n_modes,) [Hz]
    n_shapes: int            # interface shapes kept (contact_shapes at the tolerance)
    n_static: int            # static directions asked beyond the interface shapes
    seconds: dict            # factorization, modes, interface, statics, orthonormalization
    interface_mu: np.ndarray = None   # (f,) descending: the interface fields' flexibility
    #                                   against the law's (flexible_shapes' mu); the largest
    #                                   dropped is the fields' statics error
    interface_loads: int = 0          # the contact's loads on the part before the fields

    def statics_error(self, tol):
        """The largest flexibility of an interface direction dropped (below tol), relative to
        the contact law's: the error of the part's contact stiffness against the responses
        to every contact direction (0: none dropped)."""
        mu = self.interface_mu
        dropped = mu[mu < tol] if mu is not None else ()
        return float(dropped.max()) if len(dropped) else 0.0


def part_basis(name, K, M, interface, loads, fmax, shift_hz, tol, backend="auto"):
    """The PartBasis of one part from its own matrices on its free dofs: K, M (n, n) sparse,
    interface the contact's loads on the part (a PartInterface; None: no contact on it): a
    task holds no array the size of the contact points, nor a dense one of the interface;
    loads (n, s) the static loads to respond to.

    The interface's loads are first reduced to the fields of its loaded modes to fmax
    (reduce.fields). Its own factorization of K - sigma M (the small shift keeps a floating
    part solvable) gives the modes and the responses beyond them; the fields' are kept by
    their flexibility against the contact law's (basis.flexible_shapes)."""
    seconds, t0 = {}, time.perf_counter()

    def lap(stage):
        nonlocal t0
        seconds[stage], t0 = time.perf_counter() - t0, time.perf_counter()
    n_loads = 0
    if interface is not None:
        E, G, n_loads = interface.E, interface.G, interface.E.shape[1]
        if interface.support is not None:
            try:
                P = field_map(K, M, interface.support, E, G, interface.shape, interface.block,
                              interface.rigid, fmax, shift_hz, backend)
            except FactorizationError as exc:
                raise PartError(name, str(exc)) from None
            E, G = sp.csc_matrix(E @ P), P.T @ G @ P
        lap("fields")
    sigma = shift_sigma(-shift_hz)
    try:
        solve = factorize(shifted(K, M, sigma), backend, definite=True)
    except FactorizationError as exc:
        raise PartError(name, str(exc)) from None
    lap("factorization")
    modes = normal_modes(K, M, None, count=40, fmax=fmax, shift=-shift_hz, solve=solve,
                         tol=MODES_TOL)
    lap("modes")
    # the basis' columns [Phi, interface shapes, statics] are formed in one column-major
    # array, each stage in place over the columns it turns into the next: a large part holds
    # one n x columns array, not the three copies its stages would make one from another
    m, f, s = modes.shapes.shape[1], E.shape[1] if interface is not None else 0, loads.shape[1]
    X = np.empty((K.shape[0], m + f + s), order="F")
    width = block_columns(len(X))   # columns solved, or multiplied by K or M, at a time
    X[:, :m] = modes.shapes
    Phi, frequencies, modes = X[:, :m], modes.frequencies, None
    MPhi = csr_dot(M, Phi)

    def beyond(b):
        """(K - sigma M)^-1 beyond the modes, P^T (K - sigma M)^-1 P with P = I - M Phi Phi^T,
        in place on b (n, k), a block of X's columns: the loads without their modal part, so
        that a floating part's rigid motion (1/sigma, orders of magnitude above its elastic
        response) never enters the responses only to be subtracted (its eigenvalue, round-off
        of the largest, is not known to that precision)."""
        _take_out(b, MPhi, Phi)
        with closing(progress.work(f"{name}: responses", b.shape[1], "load")) as bar:
            for start in range(0, b.shape[1], width):
                block = b[:, start:start + width]
                block[...] = solve(block)
                bar.advance(min(start + width, b.shape[1]))
        _take_out(b, Phi, MPhi)
    n_shapes, mu = 0, np.zeros(0)
    if interface is not None:
        KE = X[:, m:m + f]
        E.toarray(out=KE)
        beyond(KE)

        def shapes_in_place(Z):
            """KE Z written over KE's first columns (Z has no more columns than KE)."""
            for start in range(0, len(KE), ROW_BLOCK):
                rows = slice(start, start + ROW_BLOCK)
                KE[rows, :Z.shape[1]] = KE[rows] @ Z
            return KE[:, :Z.shape[1]]
        H = np.empty((f, f))
        for start in range(0, f, width):    # SciPy's sparse product copies KE C-ordered
            cols = slice(start, start + width)
            H[:, cols] = E.T @ KE[:, cols]
        shapes, mu = flexible_shapes(H, None, None, tol, shapes_in_place, gram=G)
        n_shapes = shapes.shape[1]
        del KE, shapes
    lap("interface")
    end = m + n_shapes + s
    if s:
        X[:, m + n_shapes:end] = loads
        beyond(X[:, m + n_shapes:end])
    lap("statics")
    # the factors past their last solve: given back before the basis is formed beside them
    getattr(solve, "free", lambda: None)()
    solve = beyond = None
    T = with_statics(X[:, :end], m, M)
    del X
    Kr = np.empty((T.shape[1], T.shape[1]))
    for start in range(0, T.shape[1], width):     # no n x r product of K beside T
        cols = slice(start, start + width)
        Kr[:, cols] = T.T @ csr_dot(K, T[:, cols])
    lap("orthonormalization")
    return PartBasis(name, T, 0.5 * (Kr + Kr.T), frequencies, n_shapes,
                     int(loads.shape[1]), seconds, mu, n_loads)


def _take_out(b, A, B):
    """b -= A (B^T b) in place, a block of b's rows at a time: no n x k temporary."""
    coefficients = B.T @ b
    for start in range(0, len(b), ROW_BLOCK):
        rows = slice(start, start + ROW_BLOCK)
        b[rows] -= A[rows] @ coefficients


class PartError(RuntimeError):
    def __init__(self, part, message):
        super().__init__(message)
        self.part = part

    def __reduce__(self):        # raised on a Dask worker, it travels back whole
        return PartError, (self.part, str(self))


def with_statics(X, m, M):
    """The basis [Phi, S W] in place of X = [Phi, S] (its first m columns the modes, the
    rest S the static responses), returned as X's first columns: S without what the modes
    hold (twice, for round-off: on a floating part they are dominated by its rigid motion),
    its dependent directions dropped, M-orthonormal."""
    Phi, S = X[:, :m], X[:, m:]
    if not S.shape[1]:
        return Phi
    MPhi = csr_dot(M, Phi)
    for _ in range(2):
        _take_out(S, Phi, MPhi)
    G = np.empty((S.shape[1], S.shape[1]))
    width = block_columns(len(S))
    for start in range(0, S.shape[1], width):      # no n x k product of M beside S
        cols = slice(start, start + width)
        G[:, cols] = S.T @ csr_dot(M, S[:, cols])
    norms = np.sqrt(np.maximum(np.diag(G), 0.0))
    big = norms > 1e-12 * norms.max()
    if not big.any():          # no load on the part and no interface direction kept
        return Phi
    if big.all():
        S /= norms
    else:
        for j in np.flatnonzero(big):
            S[:, j] /= norms[j]
    G = G[np.ix_(big, big)] / np.outer(norms[big], norms[big])
    lam, V = np.linalg.eigh(0.5 * (G + G.T))
    keep = lam > 1e-12 * max(lam.max(), 1.0)
    W = np.zeros((S.shape[1], int(keep.sum())))
    W[big] = V[:, keep] / np.sqrt(lam[keep])
    # S W over S's first columns a block of rows at a time (W has no more columns than S)
    for start in range(0, len(S), ROW_BLOCK):
        rows = slice(start, start + ROW_BLOCK)
        S[rows, :W.shape[1]] = S[rows] @ W
    return X[:, :m + W.shape[1]]


@dataclass(frozen=True)
class PartTask:
    """One part's reduction to make: part_basis' arguments, the part's K and M as its cells
    (model.partcells.PartCells), assembled by the process that runs it."""
    name: str
    cells: PartCells
    interface: PartInterface  # or None
    loads: np.ndarray        # (n, s)
    fmax: float              # the cutoff its modes reach [Hz]
    shift_hz: float
    tol: float
    backend: str

    @property
    def n(self):
        """The part's free dofs."""
        return len(self.cells.free)

    def run(self):
        with blas.one_thread():
            K, M = self.cells.matrices()
            return part_basis(self.name, K, M, self.interface, self.loads, self.fmax,
                              self.shift_hz, self.tol, self.backend)

    def key(self):
        """The hex digest of what the reduction is made from (not the part's name: two equal
        parts share it), hashed once a task: the cells and arrays of a large part take a
        while, and the cache, its file names and the cluster's task names each ask."""
        if "_key" not in self.__dict__:
            # frozen: the digest is no field, set past the dataclass' guard
            object.__setattr__(self, "_key", self._digest())
        return self.__dict__["_key"]

    def _digest(self):
        h = hashlib.sha256()
        for text in _source_texts():
            h.update(text)
        h.update(repr((self.fmax, self.shift_hz, self.tol, self.backend)).encode())
        self.cells.digest(h)
        arrays = [self.loads]
        if self.interface is not None:
            arrays += self.interface.arrays()
        for a in arrays:
            a = np.ascontiguousarray(a)
            h.update(repr((a.dtype.str, a.shape)).encode())
            h.update(a.data)
        return h.hexdigest()


_TEXTS = []


def _source_texts():
    if not _TEXTS:
        root = Path(__file__).resolve().parent.parent
        _TEXTS.extend((root / name).read_bytes() for name in _SOURCES)
    return _TEXTS
