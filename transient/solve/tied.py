"""The modes of a case with its contact pairs tied (`transient modes`): how a pair's contact
enters them is `solver.modes.tie`.

- penalty: springs of density k on the pair's rule, C^T diag(k w) C (bilateral: the gap is
  neither opened nor closed for free), whatever the pair's law;
- preload: the laws' tangents at the preload under the constant loads, K + C^T diag(w k_t) C:
  the linearization the reduced model starts from;
- exact: the gap held at zero on the rule's rows, the limit k -> infinity of the penalty (the
  paper's "perfect bilateral contact", section 4.2). Over incompatible meshes a rich rule then
  leaves the interface only its exactly compatible shapes (a handful: the paper's locking),
  where any finite k leaves the nearly compatible ones soft.

The preload and exact ties go through one factorization of K - sigma M and the contact's
low-rank update (lowrank.ContactSolver), the penalty through the factorization of K + C^T D C.
"""
import time
from dataclasses import dataclass

from .. import setuptimes
from ..contact.contactset import first_tangent, stack
from ..contact.pair import build_contact, contact_stiffness
from ..errors import CaseError
from ..model import constant_load
from ..model.band import check_modes_band
from ..model.model import build_model
from .lowrank import contact_solver
from .modes import normal_modes, shift_sigma
from .preload import PreloadError, solve_preload

# The tied solve is a difference of two solves (y - Z G^-1 B^T y), exact to some 1e-10 of its
# norm: a residual of 1e-12 stalls the Lanczos (tet10 pad and disc: 43 of 55 pairs), 1e-9 (the
# reduced basis' own tolerance, reduce.basis.MODES_TOL) converges.
TIED_TOL = 1e-9


@dataclass(frozen=True)
class Tie:
    kind: str                # solver.modes.tie: penalty, preload or exact
    timings: dict            # the contact solver's factorization and the preload [s]
    held: int = 0            # exact: directions of the rows held at zero
    dofs: int = 0            # exact: the dofs the rows touch
    preload: object = None   # preload: the Preload the tangents come from


def case_modes(case):
    """(model, pairs, Modes, Tie): the work of `transient modes` on a case, its seconds logged
    as the setup of kind `modes` (setuptimes), what a dry run of `modes` is estimated from."""
    t0 = time.perf_counter()
    model = build_model(case)
    check_modes_band(case, model)
    t1 = time.perf_counter()
    setuptimes.announce("modes", model)
    t0 += time.perf_counter() - t1      # a calibration it makes is no time of these modes
    pairs = build_contact(case, model)
    found, tie = contact_modes(case, model, pairs)
    setuptimes.record_setup("modes", model, pairs, time.perf_counter() - t0)
    return model, pairs, found, tie


def contact_modes(case, model, pairs):
    """(Modes, Tie) of the case's model with its pairs tied as solver.modes.tie says."""
    settings = case.solver.modes
    kind = settings.tie if pairs else "penalty"
    args = (model.M, model.fixed, settings.count, settings.fmax, settings.shift,
            case.solver.linear_solver)
    if kind == "penalty":
        # K with the springs not held here: normal_modes keeps only its free block (at 1M
        # dofs a regularized rule's springs make it 1.3 GB, beside the factors and the Lanczos)
        return normal_modes(model.K + contact_stiffness(pairs, model.ndof) if pairs else model.K,
                            *args), Tie(kind, {})
    t0 = time.perf_counter()
    contacts = stack(pairs, model.ndof)
    # the shift of normal_modes (negative: -(2 pi shift)^2), so that its Lanczos and the
    # contact solver's factorization are of the same K - sigma M
    cs = contact_solver(model, contacts, shift_sigma(settings.shift), case.solver.linear_solver)
    timings = {"contact_factorization": time.perf_counter() - t0}
    if kind == "exact":
        try:
            solve, held = cs.tied()
        except ValueError as exc:
            raise CaseError(case.path, "solver.modes.tie", f"exact: {exc}") from None
        modes = normal_modes(None, *args, solve=solve, tol=TIED_TOL)
        return modes, Tie(kind, timings, held, len(cs.cols))
    t0 = time.perf_counter()
    try:
        preload = solve_preload(model.K, model.fixed, constant_load(case, model), contacts, cs,
                                case.solver.newton.tolerance, case.solver.newton.max_iter,
                                first_tangent(pairs, contacts))
    except PreloadError as exc:
        raise CaseError(case.path, "loads", str(exc)) from None
    tangent = cs.solver(contacts.weights * preload.tangent)
    timings["preload"] = time.perf_counter() - t0
    return (normal_modes(tangent.stiffness, *args, solve=tangent),
            Tie(kind, timings, preload=preload))
