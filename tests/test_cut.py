"""The cut's coupled modes (reduce/cut.py, reduce.pieces.cut_basis) against the coupled model
formed dense, on a lattice held at its cut: a ring of springs and masses on an annulus, its
inner ring grounded, cut into sectors along radial lines. Uniform, it has cyclic symmetry and
its modes come in equal pairs (a disc's, as the brake's); spread at random, it has none."""
import numpy as np
import pytest
import scipy.linalg as sla

import transient.reduce.cut as cut
from bench_cut import outside
from transient.reduce.cut import modes_below
from transient.reduce.pieces import _orthonormal, cut_basis
from transient.solve.lanczos import NotConverged
from transient.solve.modes import shift_sigma

SHIFT_HZ = 0.01
SIGMA = shift_sigma(-SHIFT_HZ)


def lattice(spread=0.0, split=0.0, rings=10, around=64, sectors=8, seed=0):
    """(K, M, piece of each node, -1 on the cut) of the annulus lattice, one dof a node: unit
    springs and masses, or log-normal of that spread; split changes one spring by that much
    (the pairs' symmetry broken by so little)."""
    node = np.arange(rings * around).reshape(rings, around)
    edges = np.array([(node[i, j], node[i, (j + 1) % around]) for i in range(rings)
                      for j in range(around)]
                     + [(node[i, j], node[i + 1, j]) for i in range(rings - 1)
                        for j in range(around)])
    n = rings * around
    rng = np.random.default_rng(seed)
    k = np.exp(spread * rng.standard_normal(len(edges)))
    k[0] *= 1 + split
    K = np.zeros((n, n))
    np.add.at(K, (edges[:, 0], edges[:, 0]), k)
    np.add.at(K, (edges[:, 1], edges[:, 1]), k)
    np.add.at(K, (edges[:, 0], edges[:, 1]), -k)
    np.add.at(K, (edges[:, 1], edges[:, 0]), -k)
    K[node[0], node[0]] += 4.0
    M = np.diag(np.exp(spread * rng.standard_normal(n)))
    column = np.arange(n) % around
    piece = column // (around // sectors)
    piece[column % (around // sectors) == 0] = -1
    return K, M, piece


def held_at_the_cut(K, M, piece, reach):
    """(S, Mh, couplings) as reduce.piece.Piece.condensed makes them: each piece held at the
    cut, its condensation summed with the cut's own, its fixed-cut modes to reach (rad/s)^2
    and their mass coupling with the cut's dofs it touches."""
    cut_dofs = np.flatnonzero(piece < 0)
    Ks = K - SIGMA * M
    S, Mh = Ks[np.ix_(cut_dofs, cut_dofs)], M[np.ix_(cut_dofs, cut_dofs)]
    couplings = []
    for p in range(piece.max() + 1):
        I = np.flatnonzero(piece == p)
        G = np.flatnonzero(np.abs(Ks[np.ix_(I, cut_dofs)]).sum(axis=0))
        KG, MG, MI = Ks[np.ix_(I, cut_dofs[G])], M[np.ix_(I, cut_dofs[G])], M[np.ix_(I, I)]
        Psi = -np.linalg.solve(Ks[np.ix_(I, I)], KG)
        S[np.ix_(G, G)] += KG.T @ Psi
        Mh[np.ix_(G, G)] += MG.T @ Psi + Psi.T @ MG + Psi.T @ MI @ Psi
        omega2, Phi = sla.eigh(K[np.ix_(I, I)], MI)
        kept = omega2 <= reach
        couplings.append((G, omega2[kept], Phi[:, kept].T @ (MI @ Psi + MG)))
    return 0.5 * (S + S.T), 0.5 * (Mh + Mh.T), couplings


def dense_coupled(S, Mh, couplings):
    """(lambda, modes) of the coupled model formed whole: K_cb = diag(omega2 - sigma, S),
    M_cb = [[I, C], [C^T, Mh]] (cut_basis's eigenproblem before reduce.cut)."""
    m, g = sum(len(w) for _, w, _ in couplings), len(S)
    Kcb, Mcb = np.zeros((m + g, m + g)), np.eye(m + g)
    Kcb[m:, m:], Mcb[m:, m:] = S, Mh
    at = 0
    for G, omega2, C in couplings:
        rows = np.arange(at, at + len(omega2))
        Kcb[rows, rows] = omega2 - SIGMA
        Mcb[np.ix_(rows, m + G)], Mcb[np.ix_(m + G, rows)] = C, C.T
        at += len(omega2)
    return sla.eigh(Kcb, Mcb)


def fmax_at(top):
    return np.sqrt(top + SIGMA) / (2 * np.pi)


def moving(lam, modes, S):
    """The traces of the modes (Mcb-normalized) that move the cut: those whose trace holds
    over cut.STILL squared of their strain energy (x_G^T S x_G against x^T K_cb x = lam)."""
    U = modes[len(modes) - len(S):]
    return U[:, np.sqrt(np.einsum("ij,ij->j", U, S @ U) / lam) > cut.STILL]


@pytest.mark.parametrize("spread", [0.0, 0.3])
def test_the_modes_below_top_are_counted_by_their_inertia(spread):
    """Sylvester's count of the coupled model's eigenvalues below top equals the dense
    eigensolver's, for tops from below the first to above the last, below and above the
    pieces' own modes (D - top of either sign in the Schur complement), and just past each of
    the first modes (the uniform lattice's pairs among them)."""
    S, Mh, couplings = held_at_the_cut(*lattice(spread), reach=6.0)
    lam = dense_coupled(S, Mh, couplings)[0]
    shifted = [(G, w - SIGMA, C) for G, w, C in couplings]
    d = np.concatenate([w - SIGMA for _, w, _ in couplings])
    tops = np.concatenate([np.geomspace(0.5 * lam[0], 1.5 * lam[-1], 40),
                           0.5 * (d[1:] + d[:-1])[::37], lam[1:60] * (1 + 1e-6)])
    for top in tops:
        assert modes_below(S, Mh, shifted, top) == np.count_nonzero(lam < top), top


def test_the_inertia_is_read_from_every_pivot_of_the_ldlt():
    """The negative eigenvalues of symmetric indefinite matrices, those whose zero diagonal
    makes dsytrf take 2x2 pivots among them, counted from its factors as by eigvalsh."""
    rng = np.random.default_rng(2)
    for n, zero in ((40, 0), (60, 30), (101, 101)):
        A = rng.standard_normal((n, n))
        A = A + A.T + np.diag(rng.uniform(-2, 2, n))
        A[np.arange(zero), np.arange(zero)] = 0.0
        count = modes_below(A, np.zeros_like(A), [], 0.0)
        assert count == np.count_nonzero(np.linalg.eigvalsh(A) < 0)


def cases():
    """(name, lattice, top as the dense eigenvalue it lies just above, or between)."""
    yield "generic", dict(spread=0.3), lambda lam: 0.5 * (lam[40] + lam[41])
    # the second of a pair of equal modes 1e-6 below top, the next pair 6% above it
    yield "pairs", dict(), lambda lam: lam[42] * (1 + 1e-6)
    # the same pairs split by some 1e-9 of their eigenvalue
    yield "split pairs", dict(split=1e-4), lambda lam: lam[42] * (1 + 1e-6)
    # nine tenths of the model's modes: far more than any first guess or block
    yield "most modes", dict(spread=0.3), lambda lam: 0.5 * (lam[-50] + lam[-49])


@pytest.mark.parametrize("name, shape, top_of", list(cases()), ids=[c[0] for c in cases()])
def test_the_cut_spans_the_traces_of_the_coupled_models_modes(name, shape, top_of):
    """cut_basis against the coupled model formed dense: as many shapes; each trace of a
    mode below top in the shapes' span as in the dense one's (the traces of every pair whole,
    whichever vectors of its plane each eigensolver returns), and each relaxation; the two
    bases' spans equal; the shapes Mh-orthonormal as the dense one's. The modes that hold the
    cut still (the uniform lattice's with nodal lines on the cut) leave no shape in either."""
    S, Mh, couplings = held_at_the_cut(*lattice(**shape), reach=6.0)
    lam, modes = dense_coupled(S, Mh, couplings)
    top = top_of(lam)
    below = np.count_nonzero(lam <= top)
    if name != "generic":
        assert np.min(np.abs(lam - top)) > 1e-8 * top     # top itself lies in a gap
    B = np.random.default_rng(1).standard_normal((len(S), 3))
    U = moving(lam[:below], modes[:, :below], S)
    traces = _orthonormal(U, Mh, None)
    dense = np.hstack([traces, _orthonormal(np.linalg.solve(S, B), Mh, traces)])
    V = cut_basis(S, Mh, B, couplings, fmax_at(top), SHIFT_HZ)
    assert V.shape == dense.shape
    assert outside(V, U, Mh) <= outside(dense, U, Mh) + 1e-9
    assert outside(V, np.linalg.solve(S, B), Mh) < 1e-10
    assert outside(V, dense, Mh) < 1e-8 and outside(dense, V, Mh) < 1e-8
    gram = V.T @ Mh @ V - np.eye(V.shape[1])
    assert np.abs(gram).max() <= max(1e-10, 10 * np.abs(dense.T @ Mh @ dense
                                                        - np.eye(V.shape[1])).max())


def test_a_mode_the_lanczos_misses_is_searched_again(monkeypatch):
    """A Lanczos that skips a mode below top returns the counted number of modes with the
    last above top: the search is made again (then found whole), and where it keeps
    missing, it is said, not returned short."""
    S, Mh, couplings = held_at_the_cut(*lattice(0.3), reach=6.0)
    lam = dense_coupled(S, Mh, couplings)[0]
    top = 0.5 * (lam[30] + lam[31])
    B = np.zeros((len(S), 0))
    found = cut_basis(S, Mh, B, couplings, fmax_at(top), SHIFT_HZ)
    searches = []

    def skipping(apply, n, count, block, seed, tol):
        """The Lanczos asked one mode more, its first left out; every time, or once."""
        searches.append(block)
        if len(searches) > 1 and not always:
            return largest_pairs(apply, n, count, block, seed, tol)
        mu, Y = largest_pairs(apply, n, count + 1, block, seed, tol)
        return mu[1:], Y[:, 1:]

    largest_pairs = cut.largest_pairs
    monkeypatch.setattr(cut, "largest_pairs", skipping)
    always = False
    again = cut_basis(S, Mh, B, couplings, fmax_at(top), SHIFT_HZ)
    assert searches == [cut.BLOCK, 2 * cut.BLOCK]
    assert again.shape == found.shape and outside(again, found, Mh) < 1e-8
    always = True
    with pytest.raises(NotConverged, match="31 below top"):
        cut_basis(S, Mh, B, couplings, fmax_at(top), SHIFT_HZ)
    assert len(searches) == 2 + cut.ATTEMPTS
