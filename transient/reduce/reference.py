"""The reduced basis of a reference friction (contact.<pair>.friction.basis_mu): built once at
the steady sliding of that coefficient, it serves every friction coefficient near it. A
friction sweep's variants then share the basis (shared.READS['basis']) and each rebases it on
its own preload and tangent (reduce.basis.rebase: its preload joins the basis, and the whole
is diagonalized on its own K_lin), instead of making its own modes and statics. A sampled
rule's points and weights are chosen once too, on the reference's basis and preload, and each
case solves its own reduced preload on them.

Why it holds: K_lin = K + C^T D C differs between two coefficients by the contact tangent D
only (the pressures the friction shifts). The contact shapes span the responses to every
normal contact load whatever D, and a mode of one D is a mode of the other plus such a
response and an inertia term the low modes hold; the friction's coupling statics span the
same loads for any coefficient up to its scale. pad_disc at mu = 0.4 on the basis of 0.3: the
unstable complex modes within 1.3e-5 in frequency and 1 1/s of 1991 in real part (a basis
without friction, mu = 0, is 40% off: it lacks those statics, hence basis_mu > 0). The squeal
case (cases/pad_disc_squeal.toml, mu = 0.4, 20 ms) on the basis and points of 0.3 and 0.5: its
growth rate within 0.08% of its own basis' and points' (1981 1/s), the limit cycle's RMS
within 0.9% and its frequency within 6e-4.
"""
from dataclasses import dataclass, replace

import numpy as np

from ..contact.contactset import first_tangent, stack
from ..contact.pair import attach
from ..dynamics.critical import critical_tangent
from ..errors import CaseError
from ..model import constant_load
from ..solve.preload import PreloadError, solve_preload
from .basis import structural_gram
from .stage import candidates, make_basis, sample_on


@dataclass(frozen=True)
class SharedBasis:
    """The basis of a reference case (reference_case) and what rebasing it needs."""
    basis: object            # reduce.basis.Basis on the reference's tangent
    K0r: np.ndarray          # (n, n) T^T K T without the contact's update (rebase)
    sample: object = None    # a sampled rule's points and weights chosen on that basis and
    #                          preload (sampling.Sample), or None


def reference_case(case):
    """The case whose preload the basis is built at: each pair's friction at its basis_mu
    (its own mu where 0), the basis_mu keys then cleared (variants at one basis_mu share this
    case's basis, shared.stage_key); the case itself when no pair gives a basis_mu."""
    if not any(c.friction.basis_mu for c in case.contact.values()):
        return case
    contact = {name: replace(c, friction=replace(
        c.friction, mu=c.friction.basis_mu or c.friction.mu, basis_mu=0.0))
        for name, c in case.contact.items()}
    return replace(case, contact=contact)


def reference_basis(case, model, M, pairs, cs, patterns, Mf=None):
    """The SharedBasis of reference_case(case) on the model, its pairs (any friction: their
    geometry is taken) and the factorization cs (lowrank.ContactSolver)."""
    ref = reference_case(case)
    pairs = [attach(ref, p) for p in pairs]
    contacts = stack(pairs, model.ndof)
    solver = case.solver
    try:
        preload = solve_preload(model.K, model.fixed, constant_load(ref, model), contacts, cs,
                                solver.newton.tolerance, solver.newton.max_iter,
                                first_tangent(pairs, contacts))
    except PreloadError as exc:
        name = next(n for n, c in case.contact.items() if c.friction.basis_mu)
        raise CaseError(case.path, f"contact.{name}.friction.basis_mu",
                        f"the preload at this friction: {exc}") from None
    tangent = cs.solver(contacts.weights * preload.tangent)
    basis = make_basis(ref, model, M, contacts, preload, patterns, tangent,
                       critical_tangent(contacts, preload.tangent), cs.C, Mf)
    K0r = structural_gram(basis, tangent.stiffness, model.fixed)
    mask, sample = candidates(ref, pairs, contacts), None
    if mask is not None:
        # the points and weights as reduce chooses them on this basis and preload
        sample = sample_on(ref, contacts, mask, basis, basis.coordinates(M @ preload.u),
                           preload).sample
    return SharedBasis(basis, K0r, sample)
