"""The first stages of a case that a campaign's variants share (transient sweep): the model's
structure, the contact pairs' geometry, the factorization with the contact's low-rank update
and the reduced basis at a reference friction. Each declares the spec fields it reads
(READS); variants equal on them share its result (stage_key), built once by build_shared and
handed to stages.prepare as a Built.
"""
from dataclasses import dataclass

import numpy as np

from .contact.contactset import stack
from .contact.pair import GEOMETRY, build_contact, build_geometry
from .model import build_model
from .reduce.reference import reference_basis, reference_case
from .reduce.stage import reduction_mass
from . import blas
from .solve.lowrank import contact_solver
from .timings import Stages


# The spec fields each shareable stage reads, with those of the stages before it
# (tests/test_sweep.py records each stage's reads and holds it to these): variants equal on
# them share the stage's result. A path through a table of named specs ("contact.k") reads
# that field of every one of them. The loads and sensors are each variant's own, applied to
# the shared model's structure (model.build_model): a pressure sweep shares the model, the
# contact and the factorization.
_MODEL = ("parts", "materials", "constraints", "solver.quadrature", "limits")
_CONTACT = _MODEL + tuple(f"contact.{name}" for name in GEOMETRY)
_FACTORIZATION = _CONTACT + ("solver.shift_hz", "solver.linear_solver")
# the basis: of the case at its reference friction (reduce.reference.reference_case, whose
# key a friction sweep's variants share when they give one basis_mu); its preload reads the
# loads, the laws, the friction and the sliding, and a sampled rule's points its tolerance
_BASIS = _FACTORIZATION + ("loads", "motion", "contact.law", "contact.friction",
                           "contact.sampling_tolerance", "solver.newton", "solver.mass",
                           "solver.reduction.enabled", "solver.reduction.method",
                           "solver.reduction.fmax", "solver.reduction.cutoff",
                           "solver.reduction.statics",
                           "solver.reduction.statics_tolerance")
READS = {"model": _MODEL, "contact": _CONTACT, "factorization": _FACTORIZATION,
         "basis": _BASIS}
SHARED = tuple(READS)       # the stages in order


def stage_key(case, stage):
    """What a stage's result depends on: the case's directory (its mesh files) and the reprs
    of the fields it reads (frozen specs: equal reprs, equal inputs)."""
    def field(x, names):
        if isinstance(x, dict):
            return tuple((k, field(v, names)) for k, v in x.items())
        return field(getattr(x, names[0]), names[1:]) if names else repr(x)
    if stage == "basis":
        case = reference_case(case)
    return (str(case.directory),) + tuple(field(case, path.split("."))
                                          for path in READS[stage])


@dataclass(frozen=True)
class Built:
    """What the first stages built once give each of the variants that share them (a
    campaign's: stage_key): the Model, the contact pairs' geometry, the factorization of
    K - sigma M with the contact's low-rank update and the basis at a reference friction, as
    far as they go."""
    model: object
    geometry: list = None        # contact.pair.build_geometry of each pair
    solver: object = None        # solve.lowrank.ContactSolver
    seconds: dict = None         # stage -> seconds it took to build
    basis: object = None         # reduce.reference.SharedBasis


def build_shared(case, depth, built=None):
    """The Built of a case's first stages to `depth` (one of SHARED), going on from `built`
    (a Built of a shallower depth, for cases equal on its stages' READS)."""
    stages = Stages()
    with blas.one_thread():
        model = built.model if built is not None else stages.timed("model", build_model, case)
        geometry = built.geometry if built is not None else None
        if depth != "model" and case.contact and geometry is None:
            geometry = stages.timed("contact", lambda: [build_geometry(case, model, name)
                                                        for name in case.contact])
        solver = built.solver if built is not None else None
        components = case.solver.reduction.method == "components"
        if (depth in ("factorization", "basis") and case.contact and solver is None
                and not components):
            solver = stages.timed("factorization", factorization, case, model,
                                  stack(geometry, model.ndof))
        basis = (stages.timed("basis", shared_basis, case, model, geometry, solver)
                 if depth == "basis" and solver is not None and case.solver.reduction.enabled
                 else None)
    seconds = {**(built.seconds if built is not None else {}), **stages}
    return Built(model, geometry, solver, seconds, basis)


def shared_basis(case, model, geometry, cs):
    """The reduce.reference.SharedBasis of a case at its reference friction, for the variants
    that share it (on the model's structure with the case's loads)."""
    model = build_model(case, model)
    M, Mf = reduction_mass(case, model, cs)
    return reference_basis(case, model, M, build_contact(case, model, geometry=geometry), cs,
                           [model.load_patterns[name] for name in case.loads], Mf)


def factorization(case, model, contacts):
    """K - sigma M factorized on the model's free dofs, with the contacts' low-rank update."""
    return contact_solver(model, contacts, -(2 * np.pi * case.solver.shift_hz) ** 2,
                          case.solver.linear_solver)
