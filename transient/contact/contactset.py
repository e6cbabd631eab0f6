"""All contact points of a run stacked: observation rows, initial gaps, weights and laws."""
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..kernels.codes import EXPONENTIAL, FRICTIONLESS
from ..kernels.laws import evaluate
from .blocks import PairFactors
from .friction import CODES, steady, tangential_rows
from .laws import law_params
from .regularize import factored_rows


@dataclass(frozen=True)
class FrictionSet:
    """The friction of every point at steady sliding (contact.friction): the tangential
    observations and the law linearized there (zero on the points of pairs without friction)."""
    along: sp.csr_matrix     # (P, ndof) rows Ct along the sliding, or (ndof, r) Bt with
    across: sp.csr_matrix    # Ct = L Bt^T when the contact set is factored; Cc across
    speed: np.ndarray        # (P,) sliding speed V [m/s]
    m: np.ndarray            # (P,) traction per unit pressure mu(V) sgn_reg(V)
    dm: np.ndarray           # (P,) its slope in the sliding speed [s/m]
    turn: np.ndarray         # (P,) m / V: the damping across per unit pressure [s/m]
    code: np.ndarray         # (P,) the law for the kernels (kernels.friction): TANH, ATAN,
    #                          FRICTIONLESS (a pair without friction)
    v_eps: np.ndarray        # (P,) [m/s]
    table: np.ndarray        # (P,) the table of mu(|s|) in `tables`:
    tables: tuple            # (speeds (T, K), values (T, K), counts (T,))

    def subset(self, keep, factored):
        rows = (lambda R: R) if factored else (lambda R: R[keep])
        return FrictionSet(rows(self.along), rows(self.across), self.speed[keep],
                           self.m[keep], self.dm[keep], self.turn[keep], self.code[keep],
                           self.v_eps[keep], self.table[keep], self.tables)


@dataclass(frozen=True)
class ContactSet:
    rows: sp.csr_matrix      # (P, ndof) gap observation of every point, pairs one after another;
    #                          None when the factors hold them: C then builds them on demand
    gap0: np.ndarray         # (P,) initial gaps [m]
    weights: np.ndarray      # (P,) w J [m^2]
    code: np.ndarray         # (P,) law code of each point
    params: np.ndarray       # (P, 4) law parameters of each point
    slices: dict             # pair name -> slice of its points
    factors: tuple = None    # (L (P, r), B (ndof, r) sparse) with C = L B^T, when every pair's
    #                          rows are factored (regularized rules: contact.pair.row_factors);
    #                          L dense for one pair, a contact.blocks.PairFactors for several
    friction: FrictionSet = None   # None when no pair has friction

    @cached_property
    def C(self):
        """(P, ndof) CSR: the rows, or L B^T from the factors (formed on the first call: only
        the full system and the rows' fallbacks ask for them)."""
        return self.rows if self.rows is not None else factored_rows(*self.factors)

    @property
    def n_points(self):
        return len(self.gap0)

    def laws(self, g):
        """Pressure p, tangent k_t and potential Phi at gaps g (P,)."""
        p, kt, phi = np.empty_like(g), np.empty_like(g), np.empty_like(g)
        evaluate(self.code, self.params, np.ascontiguousarray(g), p, kt, phi)
        return p, kt, phi

    def subset(self, keep, weights):
        """The points keep (sorted indices) with new weights; pairs stay contiguous."""
        bounds = {name: np.searchsorted(keep, [s.start, s.stop]) for name, s in self.slices.items()}
        factors = None if self.factors is None else (self.factors[0][keep], self.factors[1])
        rows = self.rows[keep] if self.rows is not None else factored_rows(*factors)
        friction = (None if self.friction is None
                    else self.friction.subset(keep, factors is not None))
        return ContactSet(rows, self.gap0[keep], weights, self.code[keep],
                          self.params[keep], {name: slice(int(a), int(b))
                                              for name, (a, b) in bounds.items()}, factors,
                          friction)

    def shape_rows(self, T, W=None):
        """(B^T T W, Bt^T T W, Bc^T T W) (r, k), the right factors of the rows on T (the
        tangential ones with friction): C T W = L (B^T T W). None without factors."""
        if self.factors is None:
            return None
        f, B = self.friction, self.factors[1]
        return tuple(_times(R.T @ T, W) for R in [B] + ([f.along, f.across] if f else []))

    def observe(self, T, W=None):
        """C T (P, k) for T (ndof, k) dense or held by part (reduce.synthesis), C T W for W
        (k, n): from the factors when held, L (B^T T), which reads r x ndof sparse entries
        instead of the P dense rows, and W taken on the r factor rows before the P points'."""
        if self.factors is None:
            return _times(self.C @ T, W)
        L, B = self.factors
        return L @ _times(B.T @ T, W)

    def observe_tangential(self, T, W=None):
        """(Ct T, Cc T): the tangential observations along and across the sliding of a dense
        T (ndof, k); (Ct T W, Cc T W) for W (k, n), as in observe."""
        f = self.friction
        if self.factors is None:
            return _times(f.along @ T, W), _times(f.across @ T, W)
        L = self.factors[0]
        return (L @ _times(f.along.T @ T, W),
                L @ _times(f.across.T @ T, W))

    def tangential(self):
        """(Ct, Cc) as CSR rows (P, ndof) (formed from the factors when held)."""
        f = self.friction
        if self.factors is None:
            return f.along, f.across
        return factored_rows(self.factors[0], f.along), factored_rows(self.factors[0], f.across)

    def tangential_load(self, y):
        """Ct^T y (ndof, ...): the force on the dofs of tractions y (P, ...) along the sliding."""
        f = self.friction
        return f.along.T @ y if self.factors is None else f.along @ (self.factors[0].T @ y)

    def normal_load(self, y):
        """C^T y (ndof, ...): the force on the dofs of pressures times areas y (P, ...)."""
        return self.C.T @ y if self.factors is None else self.factors[1] @ (self.factors[0].T @ y)

    def across_load(self, y):
        """Cc^T y (ndof, ...): the force on the dofs of tractions y (P, ...) across it."""
        f = self.friction
        return f.across.T @ y if self.factors is None else f.across @ (self.factors[0].T @ y)

    def friction_force(self, p):
        """The force on the dofs of the friction tractions at steady sliding, Ct^T (w p m)."""
        return self.tangential_load(self.weights * p * self.friction.m)

    def force(self, u):
        """Contact force C^T (w p) [N] at displacement u, with gaps, pressures and tangents
        (through the factors when held: L (B^T u) and B (L^T w p))."""
        if self.factors is None:
            g = self.C @ u + self.gap0
        else:
            L, B = self.factors
            g = L @ (B.T @ u) + self.gap0
        p, kt, _ = self.laws(g)
        wp = self.weights * p
        f = self.C.T @ wp if self.factors is None else B @ (L.T @ wp)
        return f, g, p, kt


def stack(pairs, ndof):
    """The contact set of a run's pairs (empty when there are none)."""
    if not pairs:
        return ContactSet(sp.csr_matrix((0, ndof)), np.zeros(0), np.zeros(0),
                          np.zeros(0, np.int64), np.zeros((0, 4)), {})
    rows, gap0, w, code, params, slices = [], [], [], [], [], {}
    start = 0
    factored = all(pair.factors is not None for pair in pairs)
    for pair in pairs:
        n = pair.rule.n_points
        c, prm = law_params(pair.spec.law, pair.k)
        if not factored:
            rows.append(sp.csr_matrix(pair.observation(ndof)))
        gap0.append(pair.rule.gap0)
        w.append(pair.rule.weights)
        code.append(np.full(n, c, np.int64))
        params.append(np.tile(prm, (n, 1)))
        slices[pair.name] = slice(start, start + n)
        start += n
    C, factors = None, None
    if factored:
        # the rows are held as factors only: dense points x interface dofs otherwise
        # one pair's held as they are: a copy of L would be among the setup's largest arrays;
        # several pairs' a pair at a time (contact.blocks), never block-diagonal dense
        factors = ((pairs[0].factors[0], sp.csr_matrix(pairs[0].factors[1])) if len(pairs) == 1
                   else (PairFactors([pair.factors[0] for pair in pairs]),
                         sp.hstack([pair.factors[1] for pair in pairs]).tocsr()))
    else:
        C = sp.vstack(rows).tocsr()
        C.eliminate_zeros()
    friction = _friction(pairs, ndof, factored)
    return ContactSet(C, np.concatenate(gap0), np.concatenate(w), np.concatenate(code),
                      np.vstack(params), slices, factors, friction)


def first_tangent(pairs, contacts):
    """(P,) the tangent a preload's first Newton step takes at least (solve_preload's start):
    the pair's stiffness density k on the points of exponential laws (the tangent of its
    operating pressure, as the case states it), 0 on the others, whose tangent at the initial
    gaps is their own (a penalty law's k, or 0 where open)."""
    out = np.zeros(contacts.n_points)
    for pair in pairs:
        s = contacts.slices[pair.name]
        out[s] = np.where(contacts.code[s] == EXPONENTIAL, pair.k, 0.0)
    return out


def _friction(pairs, ndof, factored):
    """The FrictionSet of the pairs, None when none has friction."""
    if all(pair.sliding is None for pair in pairs):
        return None
    along, across, speed, m, dm, turn, code, v_eps, table, tables = ([] for _ in range(10))
    for pair in pairs:
        n = pair.rule.n_points
        spec = pair.spec.friction
        if pair.sliding is None:
            width = pair.factors[1].shape[1] if factored else ndof
            zero = sp.csr_matrix((ndof, width) if factored else (n, width))
            along.append(zero)
            across.append(zero)
            for x in (speed, m, dm, turn):
                x.append(np.zeros(n))
            code.append(np.full(n, FRICTIONLESS))
            v_eps.append(np.ones(n))
            table.append(np.zeros(n, np.int64))
            continue
        t, c = tangential_rows(pair, pair.sliding, ndof)
        along.append(t)
        across.append(c)
        law = steady(spec, pair.sliding.speed)
        speed.append(pair.sliding.speed)
        m.append(law.m)
        dm.append(law.dm)
        turn.append(law.turn)
        code.append(np.full(n, CODES[spec.regularization]))
        v_eps.append(np.full(n, spec.v_eps))
        table.append(np.full(n, len(tables), np.int64))
        tables.append((spec.speeds, spec.values) if spec.speeds else ((0.0,), (spec.mu,)))
    join = sp.hstack if factored else sp.vstack
    width = max((len(v) for v, _ in tables), default=1)
    tab_v, tab_mu = np.zeros((max(len(tables), 1), width)), np.zeros((max(len(tables), 1), width))
    counts = np.ones(max(len(tables), 1), np.int64)
    for k, (v, mu) in enumerate(tables):
        tab_v[k, :len(v)], tab_mu[k, :len(v)], counts[k] = v, mu, len(v)
    return FrictionSet(join(along).tocsr(), join(across).tocsr(),
                       *map(np.concatenate, (speed, m, dm, turn, code, v_eps, table)),
                       (tab_v, tab_mu, counts))


def _times(Y, W):
    return Y if W is None else Y @ W
