"""The residual of the full model's equations at a reduced complex mode: how far the basis
carries it.

A reduced mode (lambda, z) expands to x = T z on the model's dofs. With K_lin the structure's
stiffness and the contact's tangent at the preload, K_f and D_f the friction's stiffness and
damping there (stability.linearize), the reduced damping's forces M T diag(d) z and the
materials' loss i H x (H = sum_m eta_m K_m), the residual
r = (K_lin + i H + K_f) x + lambda (M T diag(d) z + D_f x) + lambda^2 M x vanishes for a mode
of the full model; the Galerkin projection leaves it orthogonal to the basis. Its size relative
to the inertia forces, rho = |r|_{M^-1} / (|lambda|^2 |x|_M) (lumped mass norms on the free
dofs), is what the modes beyond the basis' cutoff and the directions it lacks leave out: it
falls as the cutoff grows (studies/study_cea_band.py measures it with the real parts' errors
against the full model).
"""
import numpy as np

from ..solve.lowrank import block_columns
from ..solve.realmaps import real_apply, real_times
from .linearize import preload_pressure


def mode_residuals(model, M, system, state, basis, modes, which):
    """rho (len(which),) of the reduced modes `which` (indices into ComplexModes `modes`) of a
    reduced system (dynamics.system.ReducedSystem at its preload `state`) on the basis
    (X, AW); M the reduced model's mass on the model's dofs."""
    # a block of modes at a time: each mode's residual is its own, and the modes' complex
    # fields side by side (x, its forces, its damping's) would be the model's size times
    # the modes, several times
    which = np.asarray(which, dtype=int)
    width = block_columns(model.ndof)
    return np.concatenate([np.zeros(0)] + [
        _residuals(model, M, system, state, basis, modes, which[start:start + width])
        for start in range(0, len(which), width)])


def _residuals(model, M, system, state, basis, modes, which):
    X, AW = basis
    contacts = system.contacts
    p, kt = preload_pressure(system, state)
    w = contacts.weights
    free = ~model.fixed
    mass = model.lumped_mass[free]
    held = mass > 0
    Z = modes.vectors[:, which]
    lam = modes.eigenvalues[which]
    U = real_times(X, AW @ Z)                        # x = T z, (ndof, k)
    Cx = real_apply(contacts.observe, U)
    force = real_times(model.K, U) + real_apply(contacts.normal_load, (w * kt)[:, None] * Cx)
    if system.loss is not None:
        force = force + 1j * real_times(model.loss, U)
    damp = system.damp if system.loss is None else system.base_damp
    damping = real_times(M, real_times(X, AW @ (damp[:, None] * Z)))
    if contacts.friction is not None:
        f = contacts.friction
        along, across = real_apply(contacts.observe_tangential, U)
        force += real_apply(contacts.tangential_load, (w * f.m * kt)[:, None] * Cx)
        damping += (real_apply(contacts.tangential_load, (w * p * f.dm)[:, None] * along)
                    + real_apply(contacts.across_load, (w * p * f.turn)[:, None] * across))
    r = (force + lam * damping + lam ** 2 * real_times(M, U))[free][held]
    x = U[free][held]
    top = np.sqrt(np.sum(np.abs(r) ** 2 / mass[held][:, None], axis=0))
    bottom = np.abs(lam) ** 2 * np.sqrt(np.sum(mass[held][:, None] * np.abs(x) ** 2, axis=0))
    return top / np.maximum(bottom, 1e-300)
