"""The reduce stage: the reduced basis of the preloaded structure and, for a sampled rule, the
points sampled on its dynamics. It returns the contact set and the preload the reduced model
integrates (the sampled points' and the preload they hold) instead of editing the pipeline's.
"""
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..contact.coarse import subset_rule
from ..errors import CaseError
from .. import blas
from ..solve.lowrank import block_columns
from ..solve.preload import Preload
from .basis import reduced_basis
from .sampling import ReducedPreloadError, sample_contact


@dataclass(frozen=True)
class ReducedModel:
    X: np.ndarray            # (ndof, m) and
    AW: np.ndarray           # (m, n): the basis T = X AW, T^T M T = I (T formed only if needed;
    #                          mass-scaled statics: I is the mass with theirs added, mass_scaled)
    omega2: np.ndarray       # (n,) eigenvalues of T^T K_lin T (contact at the preload included)
    q0: np.ndarray           # (n,) the preload in reduced coordinates
    v0: np.ndarray           # (n,) the initial velocity there
    contacts: object         # ContactSet integrated (the points kept, with their weights)
    pairs: list              # ContactPairs with the rules of the points kept
    preload: Preload         # the preload those points hold
    meta: dict               # basis sizes and timings, sampling figures
    unsampled: object = None  # a sampled rule's: the ReducedModel of its candidates, before
    #                           the sampling (what the cea analyses)


def candidates(case, pairs, contacts):
    """Mask of the points a sampled rule picks from (None when no pair is sampled)."""
    sampled = [p for p in pairs if p.spec.rule == "sampled"]
    if not sampled:
        return None
    mask = np.zeros(contacts.n_points, bool)
    for p in sampled:
        mask[contacts.slices[p.name]] = True
    return mask


def reduce(case, model, M, pairs, contacts, preload, patterns, v0, solve, kt_crit, stages,
           rows=None, Mf=None, solved=None, basis=None, sample=None):
    """The reduced model of a case (solver.reduction) on its linearized stiffness K_lin, the
    tangent solve's (solve: lowrank.TangentSolve; solve.stiffness is K_lin on the free dofs).
    rows: the contact rows on the free dofs, when the factorization stage has them; without
    them, a solve that holds the rows' space (solve.row_space) stands for them. Mf: M on the
    free dofs when the caller has it. solved: called once the basis has made its last solve
    (reduced_basis). basis: the case's Basis made already (reduce.reference: of a reference
    friction, rebased on this K_lin), or None to make it here; sample: a sampled rule's points
    and weights (sampling.Sample) chosen already (at that reference), or None to choose them."""
    from time import perf_counter
    reduction = case.solver.reduction
    t0 = perf_counter()
    if basis is None:
        basis = make_basis(case, model, M, contacts, preload, patterns, solve, kt_crit, rows,
                           Mf, solved)
    stages["reduction"] = stages.get("reduction", 0.0) + perf_counter() - t0
    # T^T (M u): two sparse products with vectors, not one with the n x r basis
    q0, v = basis.coordinates(M @ preload.u), basis.coordinates(M @ v0)
    meta = {"reduced_dofs": len(basis.omega2), "normal_modes": basis.n_modes,
            "reduction_method": reduction.method,
            **({"reduction_auto": case.reduction_auto} if case.reduction_auto else {}),
            "modes_fmax_hz": reduction.modes_fmax,
            "modes_hz": [float(f) for f in basis.mode_hz],
            "contact_shapes": basis.n_contact_shapes,
            # the static directions asked (contact shapes, load patterns, the preload) and kept
            # beyond the modes: those dropped lie in the span of the rest
            "static_shapes": [basis.n_contact_shapes + basis.n_static, basis.n_static_kept],
            "basis_timings": basis.timings, "basis_peak_rss_gb": basis.peaks,
            "basis_projection_error": float(np.linalg.norm(basis.expand(q0) - preload.u)
                                            / max(np.linalg.norm(preload.u), 1e-300)),
            "band_residual": band_residual(model, M, contacts, preload, basis,
                                           reduction.fmax),
            "free_dofs": int((~model.fixed).sum())}
    mask = candidates(case, pairs, contacts)
    cap = reduction.mass_scaling_hz
    unsampled = mass_scaled(ReducedModel(basis.X, basis.A, basis.omega2, q0, v, contacts,
                                         pairs, preload, dict(meta)), cap)
    if mask is None:
        return unsampled
    stages.check()
    t0 = perf_counter()
    sampled = sample_on(case, contacts, mask, basis, q0, preload, sample)
    with blas.every_core():
        AW = basis.A @ sampled.W
    stages["sampling"] = perf_counter() - t0
    held = Preload(basis.X @ (AW @ sampled.q), sampled.gap, sampled.pressure, sampled.tangent,
                   preload.iterations + sampled.iterations, sampled.residual, preload.seconds)
    meta["sampling"] = {"candidates": int(mask.sum()), "points": int(len(sampled.sample.chosen)),
                        "residual": sampled.sample.residual,
                        "band_modes": sampled.sample.band,
                        "preload_iterations": sampled.iterations}
    return mass_scaled(ReducedModel(basis.X, AW, sampled.omega2, sampled.q, sampled.W.T @ v,
                                    sampled.contacts,
                                    _sampled_pairs(pairs, contacts, sampled.keep,
                                                   sampled.contacts), held, meta, unsampled),
                       cap)


def band_residual(model, M, contacts, preload, basis, fmax):
    """The largest residual in the whole model of the basis' modes below fmax, the reduced
    eigenpairs (omega^2, x = T a) of K_lin at the preload: ||K_lin x - omega^2 M x|| over
    ||K_lin x|| in M^-1's norm. Zero for the whole model's own modes; what a basis misses of the band's
    (its truncation, a part's interface the components path did not span) shows here."""
    band = np.flatnonzero(basis.omega2 <= (2 * np.pi * fmax) ** 2)
    if not len(band):
        return 0.0
    # in the norm of M^-1 (the lumped mass): the energy's, where a force on a light dof
    # counts as its motion does, not the Euclidean's, which the stiff dofs dominate
    free = ~model.fixed
    scale = 1.0 / np.sqrt(model.lumped_mass[free])[:, None]
    # a block of modes at a time: each mode's residual is its own, and the whole band's
    # fields side by side (x, K x, M x) would be the model's size times the band, three times
    width = block_columns(model.ndof)
    worst = 0.0
    for start in range(0, len(band), width):
        cols = band[start:start + width]
        W = np.zeros((len(basis.omega2), len(cols)))
        W[cols, np.arange(len(cols))] = 1.0
        with blas.every_core():
            x = basis.expand(W)
            Kx = model.K @ x
            if contacts.n_points:
                Kx += contacts.normal_load((contacts.weights * preload.tangent)[:, None]
                                           * contacts.observe(x))
            r = Kx - (M @ x) * basis.omega2[cols]
        del x
        worst = max(worst, float(np.max(np.linalg.norm(r[free] * scale, axis=0)
                                        / np.maximum(np.linalg.norm(Kx[free] * scale, axis=0),
                                                     1e-300))))
    return worst


def reduction_mass(case, model, cs):
    """(M, its free block or None): the reduced model's mass (solver.mass: the lumped diagonal
    or the consistent M), with the free block the factorization cs holds of the consistent
    one."""
    M = sp.diags(model.lumped_mass).tocsr() if case.solver.mass == "lumped" else model.M
    return M, (cs.M if cs is not None and M is model.M else None)


def make_basis(case, model, M, contacts, preload, patterns, solve, kt_crit, rows=None,
               Mf=None, solved=None):
    """The Basis of the case's preloaded structure on the tangent solve's K_lin (reduce's
    arguments): its modes, the contact shapes, the friction's coupling loads' and the load
    patterns' responses, and the preload itself."""
    reduction = case.solver.reduction
    loads = [np.stack(patterns, axis=1)] if patterns and reduction.statics else []
    K_lin, free = solve.stiffness, ~model.fixed
    Ku = np.zeros((model.ndof, 1))
    Ku[free] = K_lin @ preload.u[free][:, None]     # its response is the preload itself
    loads.append(Ku)
    known = getattr(solve, "row_space", None)
    if rows is None and not (known is not None and len(known.Rm) == contacts.n_points
                             and reduction.statics_tolerance > 0):
        rows = contacts.C        # the contact shapes need the rows themselves
    contact = ((rows, contacts.weights * kt_crit)
               if reduction.statics and contacts.n_points else None)
    coupling = (FrictionLoads(contacts, preload, free, reduction.fmax)
                if contacts.friction is not None and reduction.statics else None)
    return reduced_basis(K_lin, M, model.fixed, reduction.modes_fmax, np.hstack(loads), solve,
                         case.solver.shift_hz, contact, reduction.statics_tolerance, coupling,
                         Mf, solved)


def mass_scaled(red, cap_hz):
    """red with its vectors above cap_hz given the mass that brings them to it
    (solver.reduction.mass_scaling_hz; red itself when 0).

    A vector of eigenvalue omega^2 > omega_c^2 gets the mass alpha = omega^2 / omega_c^2: the
    coordinates q' = alpha^1/2 q keep M = I, with the eigenvalue omega^2 / alpha = omega_c^2 and
    the basis column T / alpha^1/2, so the stiffness, the static response to any load and the
    state's displacement T q are unchanged, and the kernels integrate the scaled system as
    any other. Only the vectors' inertia changes: those above the cutoff are the statics (contact
    and loads), whose dynamics the basis does not resolve anyway; in the band of the modes
    their response lags by (f / f_c)^2, the error the complex modes of the scaled model
    measure against the unscaled one's."""
    if not cap_hz:
        return red
    alpha = np.maximum(red.omega2 / (2 * np.pi * cap_hz) ** 2, 1.0)
    root = np.sqrt(alpha)
    meta = dict(red.meta, mass_scaling={"vectors": int(np.sum(alpha > 1.0)),
                                        "largest": float(alpha.max())})
    # (a sampled model's unsampled one is scaled where it is made, on its own eigenvalues)
    return replace(red, AW=red.AW / root, omega2=red.omega2 / alpha, q0=red.q0 * root,
                   v0=red.v0 * root, meta=meta)


class FrictionLoads:
    """The friction forces the modes drive at steady sliding, whose static responses give the
    basis what the coupling of the modes through friction moves, which the modes and the
    normal contact shapes need not hold:
    - of every mode phi, Ct^T diag(w m k_t) C phi: the pressure its normal motion changes,
      dragged along the sliding (the friction stiffness's columns on the modes);
    - of the band's modes (below band_hz), Ct^T diag(w p m') Ct phi + Cc^T diag(w p m / V) Cc
      phi: the traction its velocity turns across the sliding and changes along it (the
      friction damping's columns). At a slow sliding m / V is a stiff damper across it, and
      the interface's motion across the sliding that it drives is a direction no mode or
      normal contact shape holds (studies/study_cea_band.py --spans)."""

    def __init__(self, contacts, preload, free, band_hz):
        f = contacts.friction
        self.contacts, self.free, self.band = contacts, free, (2 * np.pi * band_hz) ** 2
        self.stiffness = contacts.weights * f.m * preload.tangent
        self.along = contacts.weights * preload.pressure * f.dm
        self.across = contacts.weights * preload.pressure * f.turn

    def width(self, omega2):
        """Columns of the loads of modes of eigenvalues omega2."""
        return len(omega2) + int(np.sum(omega2 <= self.band))

    def __call__(self, Phi, omega2):
        """(nfree, width(omega2)): the stiffness loads of every mode, then the damping loads
        of the band's."""
        c, free = self.contacts, self.free
        X = np.zeros((len(free), Phi.shape[1]))
        X[free] = Phi
        stiffness = c.tangential_load(self.stiffness[:, None] * c.observe(X))[free]
        X = X[:, omega2 <= self.band]
        along, across = c.observe_tangential(X)
        damping = (c.tangential_load(self.along[:, None] * along)
                   + c.across_load(self.across[:, None] * across))[free]
        return np.hstack([stiffness, damping])


def sample_on(case, contacts, candidate, basis, q0, preload, sample=None):
    """The sampled rule's points on a Basis and the reduced preload they hold (_sample), with
    the rows observed on the basis' coordinates."""
    with blas.every_core():      # dense algebra on the reduced coordinates, no solve
        Cr = contacts.observe(basis.X, basis.A)
        tangential = (None if contacts.friction is None else
                      contacts.observe_tangential(basis.X, basis.A))
        return _sample(case, contacts, candidate, basis.omega2, Cr, q0, preload, tangential,
                       sample)


def _sample(case, contacts, candidate, omega2, Cr, q0, preload, tangential=None, sample=None):
    """The sampled rule's points (sampling.py), with the reduced preload they hold. The points
    of every sampled pair are chosen together, to the first one's tolerance and cap (or
    given: sample)."""
    solver = case.solver
    name = next(n for n, s in contacts.slices.items() if candidate[s].any())
    spec = case.contact[name]
    band = int(np.sum(omega2 <= (2 * np.pi * solver.reduction.modes_fmax) ** 2))
    try:
        return sample_contact(contacts, candidate, omega2, Cr, q0, preload.gap,
                              preload.pressure, preload.tangent, band,
                              spec.sampling_tolerance, spec.points,
                              solver.newton.tolerance, solver.newton.max_iter, tangential,
                              sample)
    except ReducedPreloadError as exc:
        raise CaseError(case.path, f"contact.{name}.sampling_tolerance", str(exc)) from None


def _sampled_pairs(pairs, rich, keep, contacts):
    """The pairs with the rules of the points kept (sampled pairs: chosen points and weights)."""
    out = []
    for p in pairs:
        s, new = rich.slices[p.name], contacts.slices[p.name]
        local = keep[new] - s.start
        if len(local) == s.stop - s.start:
            out.append(p)
            continue
        factors = None if p.factors is None else (p.factors[0][local], p.factors[1])
        sliding = (None if p.sliding is None
                   else replace(p.sliding, speed=p.sliding.speed[local]))
        out.append(replace(p, rule=subset_rule(p.rule, local, contacts.weights[new]),
                           candidates=s.stop - s.start, factors=factors, sliding=sliding))
    return out
