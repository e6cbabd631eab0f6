"""The frozen systems the schemes integrate: a reduced one (modal coordinates, M = I) or the
free dofs of the full model, with the contact points, loads, observations and critical step.

Both integrate M a + c v + K_lin q = F(t) + C^T [w (p(g) + k_t* (g - g0))], g = C q + g0, with
K_lin the stiffness linearized at the preload (k_t*: the contact tangent there), so the contact
rows carry only the nonlinear remainder; F(t) = sum_j patterns_j s_j(t).
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from . import critical
from ..kernels.sparse import csr_dot
from ..model.dofs import free_block, restrict
from .. import blas


# vectors whose stiffness is below this fraction of the largest are rigid motions, their
# eigenvalue round-off (reduce.basis clips theirs at 0): the loss they would carry, at most
# max(eta) (omega2_i omega2_j)^1/2, is 1e-6 max(eta) of the largest there
STILL_RTOL = 1e-12


@dataclass(frozen=True)
class System:
    contacts: object         # ContactSet of the points integrated (weights, laws, slices)
    tangent: np.ndarray      # (m,) k_t* at the preload [Pa/m]
    patterns: np.ndarray     # (J, n) load patterns on the system's coordinates
    signals: tuple           # their time signals, packed (case.signals.compile_signals)
    sensors: object          # (s, n) observation of q: the sensors, then q itself if stored
    sensor_names: tuple
    n_field: int             # rows of `sensors` after the named ones (the state q itself)
    critical: object         # CriticalStep (dynamics.critical); None for a system only
    #                          linearized (the cea's)

    @property
    def n(self):
        return self.patterns.shape[1]

    @property
    def n_points(self):
        return self.contacts.n_points


@dataclass(frozen=True)
class ReducedSystem(System):
    """q = T q_r with T^T M T = I and T^T K_lin T = diag(omega2)."""
    omega2: np.ndarray = None    # (n,) [rad^2/s^2]
    damp: np.ndarray = None      # (n,) modal damping coefficients 2 zeta omega + Rayleigh [1/s]
    C: np.ndarray = None         # (m, n) contact rows C T, dense
    T: np.ndarray = None         # (ndof, n) the basis, zero on fixed dofs (field output only)
    Ct: np.ndarray = None        # (m, n) tangential rows along the sliding (friction only)
    Cc: np.ndarray = None        # (m, n) and across it
    loss: np.ndarray = None      # (n, n) T^T H T, H = sum_m eta_m K_m the materials' loss:
    #                              the cea's i T^T H T; damp holds its diagonal / omega_ref
    base_damp: np.ndarray = None  # (n,) damp without the loss's share (the cea's D)
    shape_rows: tuple = None     # (r, n) each: C = L Y[0], Ct = L Y[1], Cc = L Y[2] with L the
    #                              contact set's left factor, when its rows are factored
    reduced = True


@dataclass(frozen=True)
class FullSystem(System):
    """The free dofs of the model: K_lin, the lumped mass, Rayleigh damping alpha M + beta K."""
    K: sp.csr_matrix = None      # (n, n) K_lin on the free dofs
    mass: np.ndarray = None      # (n,) lumped mass [kg]
    M: sp.csr_matrix = None      # the mass of the implicit scheme (consistent or lumped)
    alpha: float = 0.0
    beta: float = 0.0
    C: sp.csr_matrix = None      # (m, n) contact rows on the free dofs
    free: np.ndarray = None      # the free dofs q lives on
    Ct: sp.csr_matrix = None     # (m, n) tangential rows along the sliding (friction only)
    Cc: sp.csr_matrix = None     # (m, n) and across it
    loss: sp.csr_matrix = None   # (n, n) H on the free dofs: the cea's i H (no run takes it)
    reduced = False


def _observation(sensors, n, field, dense):
    rows = sensors
    if field:
        rows = np.vstack([rows, np.eye(n)]) if dense else sp.vstack([rows, sp.eye(n)]).tocsr()
    return np.ascontiguousarray(rows) if dense else sp.csr_matrix(rows)


def patterns_matrix(vectors, n):
    """Load patterns as rows (J, n) for the kernels."""
    return np.ascontiguousarray(np.array(vectors, dtype=float).reshape(len(vectors), n))


def reduced_system(X, AW, omega2, fmax, damping, contacts, tangent, patterns, signals,
                   sensors, sensor_names, field, pressure=None, critical_step=True,
                   loss=None, loss_hz=0.0):
    """The reduced system on the basis T = X AW (X (ndof, m), AW (m, n)) with eigenvalues
    omega2. T itself (ndof x n, the setup's largest product at scale: 4x pad_disc's 198 GFLOP)
    is formed only for field output; the contact rows, sensors and loads come from X.

    damping: DampingSpec; vectors above fmax [Hz] (the basis' cutoff: its statics) take the
    residual ratio on top of the modal.
    patterns: load vectors on the model's dofs; sensors (s, ndof) their observation.
    pressure: the preload's at the points, for the friction's explicit step bounds.
    critical_step: False for a system that is only linearized (no CriticalStep).
    loss: the model's H = sum_m eta_m K_m (None: no material has a loss factor). The run
    takes the viscous damping H / omega_ref, omega_ref = 2 pi loss_hz, as each vector's own
    share, the diagonal of T^T H T / omega_ref: the kernels' damping is diagonal, and the
    coupling the off-diagonal terms carry (between vectors that strain the lossy materials
    unlike their stiffness, a multi-material model's) is left to the cea, which takes the
    whole T^T H T.
    """
    omega = np.sqrt(omega2)
    above = omega > 2 * np.pi * fmax
    ratio = damping.modal + damping.residual * above
    damp = 2 * ratio * omega + damping.alpha + damping.beta * omega2
    base, Hr = damp, None
    with blas.every_core():      # products of a few hundred columns, no solve
        if loss is not None:
            Hr = reduced_loss(loss, X, AW, omega2)
            damp = base + np.diag(Hr) / (2 * np.pi * loss_hz)
        Y = contacts.shape_rows(X, AW)
        Cr = np.ascontiguousarray(contacts.observe(X, AW) if Y is None
                                  else contacts.factors[0] @ Y[0])
        n = len(omega2)
        S = _observation((sensors @ X) @ AW, n, field, dense=True)
        Ct = Cc = None
        if contacts.friction is not None:
            Ct, Cc = (np.ascontiguousarray(R) for R in (
                contacts.observe_tangential(X, AW) if Y is None
                else (contacts.factors[0] @ Y[1], contacts.factors[0] @ Y[2])))
    return ReducedSystem(contacts, tangent,
                         patterns_matrix([AW.T @ (X.T @ p) for p in patterns], n),
                         signals, S, sensor_names, n if field else 0,
                         critical.reduced(omega2, Cr, contacts, tangent, Ct, Cc, pressure)
                         if critical_step else None,
                         omega2=omega2,
                         damp=damp, C=Cr, T=X @ AW if field else None, Ct=Ct, Cc=Cc,
                         loss=Hr, base_damp=base if Hr is not None else None, shape_rows=Y)


def reduced_loss(H, X, AW, omega2):
    """(n, n) T^T H T, T = X AW, of the loss H on a basis X dense, or held by part (the
    components path's reduce.synthesis.Synthesis, which forms X^T H X a part at a time), with
    eigenvalues omega2 of K_lin. A vector without stiffness (a free part's rigid motion) has no
    loss, H <= max(eta) K_lin in energy: its round-off, square-rooted by the cea, would grow."""
    if hasattr(X, "congruence"):
        G = X.congruence(H)
    else:
        # on both cores (SciPy's product is single-threaded), the same sums on any
        G = X.T @ csr_dot(H, X)
    Hr = AW.T @ (0.5 * (G + G.T)) @ AW
    Hr = 0.5 * (Hr + Hr.T)
    still = omega2 <= STILL_RTOL * omega2.max()
    Hr[still] = 0.0
    Hr[:, still] = 0.0
    return Hr


def full_system(K_lin, lumped, M, damping, contacts, tangent, free, patterns, signals, sensors,
                sensor_names, field, critical_step=True, loss=None):
    """The full system on the free dofs. M: the mass the implicit scheme uses, None for the
    lumped one; critical_step as in reduced_system; loss: the model's H, for the cea only
    (case.checks refuses a full model's run with a loss factor)."""
    Kf = free_block(K_lin, free)
    mass = lumped[free]
    Cf = restrict(contacts.C, cols=free)
    S = _observation(sensors[:, free], len(free), field, dense=False)
    Ct = Cc = None
    if contacts.friction is not None:
        Ct, Cc = (restrict(R, cols=free) for R in contacts.tangential())
    return FullSystem(contacts, tangent, patterns_matrix([p[free] for p in patterns], len(free)),
                      signals, S, sensor_names, len(free) if field else 0,
                      critical.full(Kf, mass, Cf, contacts, tangent) if critical_step
                      else None, K=Kf, mass=mass,
                      M=sp.diags(mass).tocsr() if M is None else free_block(M, free),
                      alpha=damping.alpha, beta=damping.beta, C=Cf, free=free, Ct=Ct, Cc=Cc,
                      loss=None if loss is None else free_block(loss, free))
