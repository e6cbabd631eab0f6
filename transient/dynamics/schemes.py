"""One factory per time integration scheme: it binds a system and a step once and is the only
place that knows its kernel's argument order.

A Stepper advances a State by a chunk of steps into output Rows, in place, and returns
(status, steps done); status is one of kernels.codes OK, NOT_FINITE, NO_CONVERGENCE.
"""
import time
from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import CaseError
from ..jit import spinning
from ..kernels import exponential as exponential_kernels, newmark, stepping
from .state import Rows
from ..solve.linsolve import (FactorizationError, csr_triplet, factorize,
                              triangular_factors)

MAX_WOODBURY_BYTES = 2e9   # the implicit schemes keep S^-1 C^T (or D C^T) dense


@dataclass(frozen=True)
class Stepper:
    scheme: str
    dt: float
    advance: object              # (state, n_steps, every, rows, blocks) -> (status, done)
    blocks: np.ndarray = None    # row blocks of the reduced contact pass (summation order)
    stages: dict = field(default_factory=dict)   # setup it timed, name -> seconds
    meta: dict = field(default_factory=dict)
    threads: int = 0             # Numba threads running the blocks (0: as set); no arithmetic

    def __call__(self, state, n_steps, every, rows):
        """Advance state by n_steps, storing one row in `every` into rows."""
        if not self.threads:
            return self.advance(state, n_steps, every, rows, self.blocks)
        before = numba.get_num_threads()
        numba.set_num_threads(self.threads)
        try:
            if self.threads == 1:
                return self.advance(state, n_steps, every, rows, self.blocks)
            with spinning():
                return self.advance(state, n_steps, every, rows, self.blocks)
        finally:
            numba.set_num_threads(before)


def single_block(m):
    return np.array([0, m], np.int64)


def contact_group(system, C):
    """The kernels' contact group: the rows C (dense, or a CSR triplet on the full model), the
    points' initial gaps, weights and tangent, the laws' codes and parameters."""
    return (C, system.contacts.gap0, system.contacts.weights, system.tangent,
            system.contacts.code, system.contacts.params)


def signals_group(system, S):
    """The kernels' signals group: the loads' patterns, their signals' arrays and the sensors'
    rows S (dense, or a CSR triplet on the full model)."""
    return system.patterns, system.signals, S


def friction_arrays(system):
    """The friction's arrays for the reduced kernels (kernels.contact.contact_pass): Ct, Cc,
    V, law code, v_eps, table, and the tables; Ct with no rows when the system has none."""
    f = system.contacts.friction
    if f is None:
        n = system.n
        return (np.zeros((0, n)), np.zeros((0, n)), np.zeros(0), np.zeros(0, np.int64),
                np.zeros(0), np.zeros(0, np.int64), np.zeros((1, 1)), np.zeros((1, 1)),
                np.ones(1, np.int64))
    return (system.Ct, system.Cc, f.speed, f.code.astype(np.int64), f.v_eps,
            f.table.astype(np.int64), *f.tables)


def friction_arrays_sparse(system):
    """friction_arrays for the full model's kernels (kernels.friction.friction_pass_sparse):
    Ct and Cc as CSR triplets, Ct of no row when the system has no friction."""
    f = system.contacts.friction
    if f is None:
        rows = csr_triplet(sp.csr_matrix((0, system.K.shape[0])))
        return (rows, rows, np.zeros(0), np.zeros(0, np.int64), np.zeros(0),
                np.zeros(0, np.int64), np.zeros((1, 1)), np.zeros((1, 1)),
                np.ones(1, np.int64))
    return (csr_triplet(system.Ct), csr_triplet(system.Cc), f.speed, f.code.astype(np.int64),
            f.v_eps, f.table.astype(np.int64), *f.tables)


def explicit(system, dt, blocks=None):
    """Central differences (velocity Verlet); the state's gmin follows the smallest gaps."""
    if system.reduced:
        blocks = single_block(system.n_points) if blocks is None else blocks
        args = (system.omega2, system.damp, contact_group(system, system.C),
                friction_arrays(system), signals_group(system, system.sensors))

        def advance(state, n_steps, every, rows, blocks):
            return stepping.explicit_reduced(state.array, state.acc, n_steps, every, dt, *args,
                                             blocks, state.gmin, rows.arrays)
    else:
        args = (csr_triplet(system.K), system.mass, system.alpha, system.beta,
                contact_group(system, csr_triplet(system.C)), friction_arrays_sparse(system),
                signals_group(system, csr_triplet(system.sensors)))

        def advance(state, n_steps, every, rows, blocks):
            return stepping.explicit_full(state.array, state.acc, n_steps, every, dt, *args,
                                          state.gmin, rows.arrays)
    return Stepper("explicit", dt, advance, blocks)


def implicit(system, dt, newton, linear_solver="auto", blocks=None):
    """Newmark average acceleration, Newton with the exact contact tangent (NewtonSpec).
    The reduced iteration operator is diagonal; the full one is factorized here."""
    if system.reduced:
        blocks = single_block(system.n_points) if blocks is None else blocks
        op = 1.0 + 0.5 * dt * system.damp + 0.25 * dt * dt * system.omega2
        GQ, GV = coupled_operators(system, 0.25 * dt * dt / op, 0.5 * dt / op, "scheme")
        head = (system.damp, system.omega2, contact_group(system, system.C),
                friction_arrays(system), signals_group(system, system.sensors))
        iteration = (GQ, GV, newton.tolerance, newton.max_iter)
        stages, meta = {}, {}

        def advance(state, n_steps, every, rows, blocks):
            return newmark.newmark_reduced(state.array, state.acc, n_steps, every, dt, *head,
                                           blocks, iteration, rows.arrays)
    else:
        t0 = time.perf_counter()
        factors, Z, G, GV, meta = _newmark_operator(system, dt, linear_solver)
        stages = {"iteration_operator": time.perf_counter() - t0}
        args = (csr_triplet(system.K), csr_triplet(system.M), system.alpha, system.beta,
                contact_group(system, csr_triplet(system.C)), friction_arrays_sparse(system),
                signals_group(system, csr_triplet(system.sensors)),
                (factors, Z, G, GV, newton.tolerance, newton.max_iter))

        def advance(state, n_steps, every, rows, blocks):
            return newmark.newmark_full(state.array, state.acc, n_steps, every, dt, *args,
                                        rows.arrays)
    return Stepper("implicit", dt, advance, blocks, stages, meta)


def coupled_operators(system, Dq, Dv, key):
    """GQ = C diag(Dq) Cs^T and GV = [Ct; Cc] diag(Dv) Cs^T, Cs = [C; Ct; Cc], of the implicit
    reduced kernels' exact corrections (kernels.woodbury.coupled_rows); without friction
    GQ = C diag(Dq) C^T and GV empty. Refused (solver.KEY) when too large to keep dense."""
    C = system.C
    m = system.n_points
    friction = system.contacts.friction is not None
    size = 8.0 * (15 * m * m if friction else m * m)
    if size > MAX_WOODBURY_BYTES:
        what = "C D [C; Ct; Cc]^T and [Ct; Cc] D [C; Ct; Cc]^T" if friction else "C D C^T"
        raise CaseError("", f"solver.{key}", f"the implicit {key} keeps {what} dense: {m} "
                        f"contact points is {1e-9 * size:.1f} GB; sample the points (contact "
                        f"rule \"sampled\") or use corrector \"evaluated\"")
    if not friction:
        return np.ascontiguousarray((C * Dq) @ C.T), np.zeros((0, 0))
    Cs = np.vstack([C, system.Ct, system.Cc])
    return (np.ascontiguousarray((C * Dq) @ Cs.T),
            np.ascontiguousarray((np.vstack([system.Ct, system.Cc]) * Dv) @ Cs.T))


def check_woodbury(n, m, path="", friction=False):
    """Refuse Newmark on a full model of n free dofs whose m contact rows make S^-1 C^T (with
    friction S^-1 [C; Ct; Cc]^T, three rows a point) too large to keep dense."""
    rows = 3 * m if friction else m
    if 8.0 * n * rows > MAX_WOODBURY_BYTES:
        what = "[C; Ct; Cc]^T" if friction else "C^T"
        raise CaseError(path, "solver.scheme", f"the implicit scheme on the full model keeps "
                        f"S^-1 {what} dense: {n} dofs x {rows} contact rows is "
                        f"{8e-9 * n * rows:.1f} GB; use a reduced model (solver.reduction)")


def _newmark_operator(system, dt, linear_solver):
    """Newmark's iteration operator S = (1 + dt/2 alpha) M + (dt/2 beta + dt^2/4) K_lin on the
    full model, factorized for the kernel, with Z = S^-1 C^T and G = C Z for the exact contact
    corrections (GV empty); with friction Z = S^-1 [C; Ct; Cc]^T, G = dt^2/4 C Z and
    GV = dt/2 [Ct; Cc] Z (kernels.newmark.newmark_full)."""
    n = system.K.shape[0]
    friction = system.contacts.friction is not None
    check_woodbury(n, system.n_points, friction=friction)
    h = 0.5 * dt
    op = ((1.0 + h * system.alpha) * system.M + (h * system.beta + h * h) * system.K).tocsr()
    try:
        p_in, L, U, p_out, backend = triangular_factors(op, linear_solver)
    except FactorizationError as exc:
        raise CaseError("", "solver", f"Newmark's iteration operator: {exc}") from None
    factors = (p_in, L, U, p_out)
    rows = sp.vstack([system.C, system.Ct, system.Cc]).tocsr() if friction else system.C
    Z = newmark.factor_columns(factors, csr_triplet(rows), n)
    # the kernel solves with explicit triangular factors, which PARDISO does not hand out
    how = ("cholmod (explicit L L^T for the kernel)" if backend == "cholmod" else
           "superlu (explicit L U for the kernel: PARDISO keeps its factors, CHOLMOD needs "
           "scikit-sparse)")
    meta = {"iteration_operator": {"backend": backend, "why": how,
                                   "factor_nonzeros": int(len(L[2]) + len(U[2]))}}
    if not friction:
        return factors, Z, np.ascontiguousarray(system.C @ Z), np.zeros((0, 0)), meta
    return (factors, Z, np.ascontiguousarray(0.25 * dt * dt * (system.C @ Z)),
            np.ascontiguousarray(0.5 * dt * (sp.vstack([system.Ct, system.Cc]) @ Z)), meta)


def exponential(system, dt, corrections, corrector, newton, blocks=None):
    """The exponential integrator of a reduced system: each mode's linear part propagated
    exactly, the contact remainder corrected `corrections` times ("evaluated" or
    "propagated"), or solved for by Newton ("implicit")."""
    if not system.reduced:
        raise CaseError("", "solver.scheme", "the exponential scheme propagates the modes of a "
                        "reduced model: set solver.reduction.enabled = true")
    blocks = single_block(system.n_points) if blocks is None else blocks
    coef = exponential_coefficients(system.omega2, system.damp, dt)
    head = ((coef, system.damp, system.omega2), contact_group(system, system.C),
            friction_arrays(system), signals_group(system, system.sensors))
    if corrector == "implicit":
        # the end state moves by G1x (and its velocity by G1v) per unit end force
        correction = (*coupled_operators(system, coef[:, 6], coef[:, 7], "corrector"),
                      newton.max_iter)
        kernel = exponential_kernels.exponential_implicit
    else:
        correction = (corrections, corrector == "propagated")
        kernel = exponential_kernels.exponential_reduced

    def advance(state, n_steps, every, rows, blocks):
        return kernel(state.array, state.acc, n_steps, every, dt, *head, blocks, correction,
                      (state.forces, state.start), rows.arrays)
    return Stepper("exponential", dt, advance, blocks)


def stepper(system, solver, dt, blocks=None):
    """The Stepper of a solver spec's scheme (one of SCHEMES) at step dt."""
    if solver.scheme == "explicit":
        return explicit(system, dt, blocks)
    if solver.scheme == "implicit":
        return implicit(system, dt, solver.newton, solver.linear_solver, blocks)
    return exponential(system, dt, solver.corrections, solver.corrector, solver.newton, blocks)


def exponential_coefficients(omega2, damp, dt):
    """Per mode of x'' + c x' + omega^2 x = F(t), F linear over a step of length dt:
    (n, 8) = [E11, E12, E21, E22, G0x, G0v, G1x, G1v] with
    (x, v)(dt) = E (x, v)(0) + G0 F(0) + G1 (F(dt) - F(0)), from the exponential of the
    augmented matrix [[A, B, 0], [0, 0, 1/dt], [0, 0, 0]] (Van Loan), exact for every omega."""
    out = np.empty((len(omega2), 8))
    aug = np.zeros((4, 4))
    aug[0, 1] = 1.0
    aug[1, 2] = 1.0
    aug[2, 3] = 1.0 / dt
    for k, (w2, c) in enumerate(zip(omega2, damp)):
        aug[1, 0], aug[1, 1] = -w2, -c
        X = sla.expm(aug * dt)
        out[k] = X[0, 0], X[0, 1], X[1, 0], X[1, 1], X[0, 2], X[1, 2], X[0, 3], X[1, 3]
    return out


def initial_acceleration(system, state, store_contact, M=None):
    """a(0), the forces at t = 0 and the initial row (energies included, contact if stored),
    from the forces at the initial state: an explicit step of length 0. M: a consistent mass
    of the full model to redo a(0) with (the explicit step divides by the lumped one)."""
    trial = state.copy()
    rows = Rows.of(system, 1, store_contact)
    explicit(system, 0.0)(trial, 1, 1, rows)
    state.a[:] = trial.a
    state.acc[2] = trial.acc[2]          # explicit_full's damping power at t = 0
    state.acc[3] = trial.acc[3]          # the sliding's input power at t = 0
    state.array[6] = trial.array[6]      # and the friction force
    if system.reduced:
        # the forces at t = 0: the first extrapolation then takes them constant
        state.forces[:] = trial.a + system.omega2 * trial.q + system.damp * trial.v
        state.start[:] = state.forces
    elif M is not None:
        force = system.mass * (state.a + system.alpha * state.v)
        state.a[:] = factorize(M)(force) - system.alpha * state.v
    return rows


SCHEMES = {"explicit": explicit, "implicit": implicit, "exponential": exponential}
