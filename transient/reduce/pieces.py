"""A part reduced in pieces (substructures), as AMLS does at its top level, so that no process
holds the whole part's factors, Lanczos vectors or dense basis.

The part's cells are cut by recursive coordinate bisection; the dofs of the nodes the pieces
share are the cut. Each piece is reduced with the cut held (Craig-Bampton, reduce.piece): its
fixed-cut modes, its static responses to its share of the interface fields and loads, and its
condensation on the cut. The cut is reduced to the traces of the modes of the pieces' fixed-cut
modes coupled to the whole cut, and to its relaxation under each static load, so that the
part's static responses lie in the span exactly; each piece extends those shapes into its
interior with their first dynamic correction. The part's own reduction (parts.part_basis) is
then made on that model, whose size the reach sets, and expanded piece by piece.

The interface fields (reduce.fields) are each piece's, with its cut held, gathered: the loaded
modes of the whole part would need its factorization, which is what the pieces avoid.
"""
import hashlib
import operator
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .. import blas
from ..cluster import submitted
from ..model.dofs import restrict
from ..solve.modes import shift_sigma
from .cut import coupled_traces
from .fields import FIELD_TOL
from .parts import PartBasis, PartInterface, PartTask, part_basis
from .piece import Piece
from .store import Store

CUT = -1             # piece_of's value on the cut's dofs
# the cut's shapes kept: directions whose norm in the cut's condensed mass, beyond those
# before them, is above this fraction of their own (the rest depend on them)
RELAXATION_TOL = 1e-10
# how far beyond the part's own reach its pieces' fixed-cut modes and the cut's modes go: the
# part's modes in the band to the part reduced whole as tests/test_pieces.py holds them
# (docs/performance.md, "A part in pieces", the reach's trade)
PIECE_REACH = 1.5


def cut_cells(centroids, weights, n):
    """(cells,) the piece of each cell, 0..n-1: recursive coordinate bisection of the cells'
    centroids (cells, 3), each cut across the longest extent at the weighted quantile that
    splits the pieces' count in proportion."""
    piece = np.zeros(len(centroids), dtype=np.int64)

    def split(idx, first, count):
        if count == 1:
            piece[idx] = first
            return
        c = centroids[idx]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        order = idx[np.argsort(c[:, axis], kind="stable")]
        left = count // 2
        cum = np.cumsum(weights[order])
        at = int(np.searchsorted(cum, cum[-1] * left / count))
        split(order[:at], first, left)
        split(order[at:], first + left, count - left)
    split(np.arange(len(centroids)), 0, n)
    return piece


def piece_of_dofs(points, cells, dofs, n, coupling=None):
    """((len(dofs),), (cells,)): the piece of each of a part's free dofs dofs (global dof ids
    of nodes dofs // 3, points their coordinates by global node), CUT on the nodes the pieces
    share, and the piece of each cell. cells: connectivity arrays in global node ids.
    coupling (len(dofs),)^2 sparse or None: an operator the pieces are reduced with beyond
    their cells' (the interface's springs); a dof it couples to another piece's interior is
    put in the cut too, so that no piece's interior meets another's."""
    centroids = np.vstack([points[c].mean(axis=1) for c in cells])
    weights = np.concatenate([np.full(len(c), float(c.shape[1]) ** 2) for c in cells])
    piece = cut_cells(centroids, weights, n)
    nodes = np.concatenate([c.ravel() for c in cells])
    of_cell = np.concatenate([np.repeat(piece[start:start + len(c)], c.shape[1])
                              for start, c in zip(np.cumsum([0] + [len(c) for c in cells]),
                                                  cells)])
    low = np.full(len(points), n, dtype=np.int64)
    high = np.full(len(points), -1, dtype=np.int64)
    np.minimum.at(low, nodes, of_cell)
    np.maximum.at(high, nodes, of_cell)
    node_piece = np.where(low == high, low, CUT)
    out = node_piece[dofs // 3]
    if coupling is not None:
        A = sp.coo_matrix(coupling)
        across = (out[A.row] >= 0) & (out[A.col] >= 0) & (out[A.row] != out[A.col])
        if across.any():
            cut_nodes = np.unique(dofs[A.col[across]] // 3)
            out[np.isin(dofs // 3, cut_nodes)] = CUT
    return out, piece


def cut_basis(S, Mh, B, couplings, fmax, shift_hz, overwrite=False):
    """V (g, c): the cut's shapes, Mh-orthonormal: the traces on the cut of the modes to fmax
    of the pieces' fixed-cut modes coupled to the whole cut (Craig-Bampton's model with every
    constraint mode: the characteristic constraint modes of the condensation alone miss the
    interior's inertia, and converge slowly), then the relaxations S^-1 B beyond them. S, Mh
    (g, g): the pieces' condensation summed with the cut's own; B (g, s) the loads carried to
    the cut; couplings: (G, omega2 (m,), C (m, len(G))) of each piece, its modes' squared
    frequencies and their mass coupling Phi^T (M_II Psi + M_IG) with the cut's dofs G. The
    coupled model is applied by blocks, never formed (reduce.cut); overwrite: S's memory
    taken for its Cholesky factor."""
    sigma = shift_sigma(-shift_hz)
    top = (2 * np.pi * fmax) ** 2 - sigma
    traces, R = coupled_traces(S, Mh, [(G, omega2 - sigma, C) for G, omega2, C in couplings],
                               top, overwrite)
    traces = _orthonormal(traces, Mh, None)
    return np.hstack([traces, _orthonormal(sla.cho_solve((R, False), B), Mh, traces)])


def _orthonormal(R, Mh, Phi):
    """R's directions beyond Phi's (Mh-orthonormal; None: none), Mh-orthonormal, those of a
    norm below RELAXATION_TOL of their column's dropped."""
    norms = np.sqrt(np.einsum("ij,ij->j", R, Mh @ R))
    R = R[:, norms > 0] / norms[norms > 0]
    if Phi is not None:
        MPhi = Mh @ Phi
        for _ in range(2):
            R -= Phi @ (MPhi.T @ R)
    G = R.T @ Mh @ R
    lam, W = np.linalg.eigh(0.5 * (G + G.T))
    keep = lam > RELAXATION_TOL
    return R @ (W[:, keep] / np.sqrt(lam[keep]))



class Here:
    """The pieces' stages in this process, a piece after the other: each stage's arguments
    taken as it comes to them, so that what a piece's stage lets go is freed before the
    next piece's."""
    def split(self, fn, arguments, one_by_one=False):
        """([fn(*a)[0]], [fn(*a)[1]]) for a in arguments: the large results held, the small
        ones gathered (one_by_one: given one at a time, each let go once the caller has
        taken it)."""
        held, small = [], []
        for args in arguments:
            h, m = fn(*args)
            held.append(h)
            small.append(m)
        return held, _drained(small) if one_by_one else small

    def each(self, fn, arguments):
        """fn(*a) for a in arguments, one at a time."""
        for args in arguments:
            yield fn(*args)


class OnCluster:
    """The pieces' stages on a Dask client's workers: each stage's large result (the piece's
    columns) stays where it was made, its small ones are gathered; a task whose worker dies
    is run again from its inputs (none is scattered)."""
    def __init__(self, client):
        self.client = client

    def _call(self, fn, args):
        return submitted(self.client, _on_worker, fn, *args, pure=False)

    def split(self, fn, arguments, one_by_one=False):
        futures = [self._call(fn, args) for args in arguments]
        held = [self.client.submit(operator.getitem, f, 0, pure=False) for f in futures]
        small = [self.client.submit(operator.getitem, f, 1, pure=False) for f in futures]
        if one_by_one:
            return held, (f.result() for f in _drained(small))
        return held, self.client.gather(small)

    def each(self, fn, arguments):
        """fn(*a) for a in arguments, all submitted, gathered one at a time and let go."""
        for future in _drained([self._call(fn, args) for args in arguments]):
            yield future.result()


def _drained(items):
    """The list's items in order, each out of the list as it is given: the caller's is then
    the only reference."""
    while items:
        yield items.pop(0)


def _on_worker(fn, *args):
    from ..settings import configure
    configure()
    with blas.one_thread():
        return fn(*args)


def pieces_basis(task, where=None, store=None):
    """The PartBasis of a part reduced in pieces (a PiecesTask), its pieces' stages run where
    says (Here: in this process, OnCluster: on a Dask client's workers), the cut's and the
    part's own reduction on that model in this process, its basis filled in store's file (a
    reduce.store.Store; None: in memory) a piece's rows at a time."""
    where, store = where or Here(), store or Store()
    seconds, t0 = {}, time.perf_counter()

    def lap(stage):
        nonlocal t0
        seconds[stage], t0 = time.perf_counter() - t0, time.perf_counter()
    interface, piece_of = task.interface, task.piece_of
    n = int(piece_of.max()) + 1
    cut = np.flatnonzero(piece_of == CUT)
    interior = [np.flatnonzero(piece_of == i) for i in range(n)]
    fields = interface is not None and interface.support is not None
    # each piece assembled from its own cells where it is reduced
    pieces, Gs = where.split(_piece, ((task.name, task.cells.subset(task.cell_piece == i), I,
                                       cut, _share(interface, I, fields), task.shift_hz,
                                       task.backend) for i, I in enumerate(interior)))
    E, G = (interface.E, interface.G) if interface is not None else (None, None)
    if fields:
        Ps = [P for P in where.each(Piece.fields, ((p, G, interface.shape,
                                                    interface.block, task.fmax)
                                                   for p in pieces))
              if P is not None]
        P = np.zeros((E.shape[1], 0))
        if Ps:
            U, s, _ = np.linalg.svd(np.hstack(Ps), full_matrices=False)
            P = U[:, s > FIELD_TOL * s[0]]
        E, G = sp.csc_matrix(E @ P), P.T @ G @ P
    lap("fields")
    F = sp.csr_matrix(task.loads) if E is None else sp.hstack(
        [E, sp.csr_matrix(task.loads)]).tocsr()
    loads = [F[I] for I in interior]
    # each piece held at the cut, then the cut condensed, reduced and extended
    A, small = where.split(_condensed, ((p, f, PIECE_REACH * task.fmax, store)
                                        for p, f in zip(pieces, loads)), one_by_one=True)
    Kc, Mc = task.Kc, task.Mc
    S = (Kc - shift_sigma(-task.shift_hz) * Mc).toarray()
    Mh, B = Mc.toarray(), F[cut].toarray()
    # each piece's condensation let go once summed (the pieces' together are about the cut's
    # size twice over), its modes' couplings kept for the cut's modes
    couplings = []
    for g, (Sp, Mp, Bp, omega2, C) in zip(Gs, small):
        S[np.ix_(g, g)] += Sp
        Mh[np.ix_(g, g)] += Mp
        B[g] += Bp
        couplings.append((g, omega2, C))
        del Sp, Mp
    lap("pieces")
    # S is overwritten by its Cholesky factor: the cut's stage holds two of its size, not three
    V = cut_basis(S, Mh, B, couplings, PIECE_REACH * task.fmax, task.shift_hz,
                  overwrite=True)
    del S, Mh, B, couplings
    lap("cut")
    # each piece's first columns are in its extended ones: taken from the list as its
    # extension starts, they go once it has run
    held, blocks = where.split(_extended, ((p, A.pop(0), V[g], f, store)
                                           for p, g, f in zip(pieces, Gs, loads)))
    lap("extension")
    Kcb, Mcb, Fcb, at = _model(blocks, V, Kc, Mc, F[cut])
    f = 0 if E is None else E.shape[1]
    cb_interface = None if E is None else PartInterface(
        sp.csc_matrix(Fcb[:, :f]), G, np.full(f, -1), np.zeros(f, dtype=np.int64))
    lap("model")
    # the part's own reduction on that model: its modes, interface shapes and statics
    red = part_basis(task.name, sp.csr_matrix(Kcb), sp.csr_matrix(Mcb), cb_interface,
                     Fcb[:, f:], task.fmax, task.shift_hz, task.tol, task.backend)
    lap("part")
    T = store.empty(task.name, (len(piece_of), red.T.shape[1]))
    Tw = red.T[at[-2]:]
    T[cut] = V @ Tw
    # each piece writes its rows into T's file where its columns are; T in memory (a store
    # without files) takes them back a piece at a time, each let go once in T
    target = T.filename if isinstance(T, np.memmap) else None
    rows = where.each(_expanded, ((held.pop(0), red.T[at[i]:at[i + 1]], Tw, interior[i],
                                   target) for i in range(n)))
    for I, r in zip(interior, rows):
        if r is not None:
            T[I] = r
    lap("expansion")
    return PartBasis(task.name, T, red.Kr, red.mode_hz, red.n_shapes, red.n_static, seconds,
                     red.interface_mu, interface.E.shape[1] if interface is not None else 0)


def _condensed(piece, loads, fmax, store):
    """Piece.condensed, its columns A kept in store's file (mapped where they were made) until
    the extension takes them: a worker's memory then holds one stage's work, not the columns
    of every piece it has made."""
    A, small = piece.condensed(loads, fmax)
    return store.kept(piece.name, A), small


def _extended(piece, A, V, loads, store):
    """Piece.extended, its columns (A2, ext) made and kept in store's files until the
    expansion: a piece's extended columns (its dofs times the cut's shapes, twice) are a
    worker's peak."""
    (A2, ext), blocks = piece.extended(
        A, V, loads, lambda shape, order: store.empty(piece.name, shape, order))
    return (store.kept(piece.name, A2), store.kept(piece.name, ext)), blocks


def _expanded(held, Ta, Tw, I, target):
    """Piece.expanded: the piece's rows I of the part's basis written into the file target
    (the store's, mapped again where the piece's columns are: each piece its own rows) and
    None returned, or the rows returned (target None)."""
    if target is None:
        return Piece.expanded(held, Ta, Tw)
    T = np.load(target, mmap_mode="r+")
    Piece.expanded(held, Ta, Tw, T, I)
    T.flush()


def _piece(name, cells, I, cut, share, shift_hz, backend):
    """(Piece, G) of a part's piece on its interior dofs I (positions among the part's free
    dofs) from its cells alone (model.partcells.PartCells: their K and M are the part's on
    the interior's rows, no other piece's cell touching them), with G the cut's dofs (positions
    in cut) it couples to. share: its part of the interface (_share)."""
    (K, M), (KG, MG) = cells.on([(I, I), (I, cut)])
    G = np.flatnonzero(np.diff(sp.csc_matrix(abs(KG) + abs(MG)).indptr))
    KG, MG = KG[:, G].tocsr(), MG[:, G].tocsr()
    return Piece(name, K, M, KG, MG, G, shift_hz, backend, **share), G


def _share(interface, I, fields):
    """The interface's loads (and with fields its springs and rigid motions) on the dofs I."""
    if interface is None:
        return {}
    share = dict(E=sp.csr_matrix(interface.E)[I])
    if fields:
        share.update(support=restrict(interface.support, I, I), rigid=interface.rigid[I])
    return share


def _model(blocks, V, Kc, Mc, Fc):
    """(Kcb, Mcb, Fcb, at): the part's K, M and loads on the columns [A2_1 .. A2_n, W] from
    the pieces' blocks (Piece.blocks) and the cut's own rows; at: the columns' offsets."""
    sizes = [b[0][0].shape[0] for b in blocks] + [V.shape[1]]
    at = np.concatenate([[0], np.cumsum(sizes)])
    r, w = at[-1], slice(at[-2], at[-1])
    Kcb, Mcb, Fcb = np.zeros((r, r)), np.zeros((r, r)), np.zeros((r, Fc.shape[1]))
    Kcb[w, w], Mcb[w, w], Fcb[w] = V.T @ (Kc @ V), V.T @ (Mc @ V), (Fc.T @ V).T
    for i, b in enumerate(blocks):
        a = slice(at[i], at[i + 1])
        for Xcb, (AA, AW, WW) in zip((Kcb, Mcb), b[:2]):
            Xcb[a, a], Xcb[a, w], Xcb[w, a] = AA, AW, AW.T
            Xcb[w, w] += WW
        Fcb[a], Fcb[w] = b[2][0], Fcb[w] + b[2][1]
    return 0.5 * (Kcb + Kcb.T), 0.5 * (Mcb + Mcb.T), Fcb, at


@dataclass(frozen=True)
class PiecesTask(PartTask):
    """A part's reduction in pieces: PartTask's, and piece_of (n,) the piece of each free dof
    (CUT on the cut), cell_piece the piece of each of its cells (cells' order), Kc and Mc its
    K and M on the cut (the pieces' cells' sum there)."""
    piece_of: np.ndarray = None
    cell_piece: np.ndarray = None
    Kc: object = None
    Mc: object = None

    def run(self, where=None, store=None):
        with blas.one_thread():
            return pieces_basis(self, where, store)

    def _digest(self):
        h = hashlib.sha256(super()._digest().encode())
        for text in _texts():
            h.update(text)
        for a in (self.piece_of, self.cell_piece):
            h.update(np.ascontiguousarray(a, dtype=np.int64).data)
        return h.hexdigest()


_TEXTS = []


def _texts():
    if not _TEXTS:
        here = Path(__file__).resolve().parent
        _TEXTS.extend((here / name).read_bytes() for name in ("pieces.py", "piece.py", "cut.py"))
    return _TEXTS
