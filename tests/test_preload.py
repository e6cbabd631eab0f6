"""The preload's Newton on a small pad and disc: its first step on the pair's stiffness, and a
friction preload's tangent kept while the laws' tangents barely move, reach the equilibrium
the plain Newton reaches, in fewer iterations and fewer tangents."""
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.contact.contactset import first_tangent, stack
from transient.contact.pair import build_contact
from transient.model import build_model, constant_load
from transient.solve import preload as preload_module
from transient.solve.lowrank import contact_solver
from transient.solve.preload import solve_preload

from small_cases import PAD_DISC

PAD = Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml"


class Counted:
    """A ContactSolver whose tangents (solver(d) calls) are counted."""

    def __init__(self, cs):
        self.cs, self.tangents = cs, 0

    def solver(self, d):
        self.tangents += 1
        return self.cs.solver(d)


def _preload(mu, start, stale):
    case = load(PAD, PAD_DISC + [f"contact.pad_disc.friction.mu={mu}"])
    model = build_model(case)
    pairs = build_contact(case, model)
    contacts = stack(pairs, model.ndof)
    cs = Counted(contact_solver(model, contacts, -(2 * np.pi * case.solver.shift_hz) ** 2))
    old = preload_module.STALE
    preload_module.STALE = stale
    try:
        pre = solve_preload(model.K, model.fixed, constant_load(case, model), contacts, cs,
                            1e-10, 50, first_tangent(pairs, contacts) if start else None)
    finally:
        preload_module.STALE = old
    return pre, cs.tangents, first_tangent(pairs, contacts)


@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_first_step_on_the_pairs_stiffness_and_kept_tangents_reach_the_same_preload(mu):
    plain, plain_tangents, _ = _preload(mu, start=False, stale=0.0)
    fast, tangents, start = _preload(mu, start=True, stale=preload_module.STALE)
    # the exponential law's points start on k (pad_disc: 5e11 Pa/m, 100 times its tangent at
    # the initial gaps)
    assert np.all(start == 5.0e11)
    assert plain_tangents == plain.iterations          # a tangent an iteration
    assert fast.iterations < plain.iterations
    if mu:
        # linear convergence (the friction is not in the tangent): tangents kept at its end
        assert tangents < fast.iterations
    else:
        assert tangents == fast.iterations
    assert fast.residual < 1e-10 and plain.residual < 1e-10
    scale = np.abs(plain.u).max()
    assert np.abs(fast.u - plain.u).max() < 1e-8 * scale
    np.testing.assert_allclose(fast.pressure, plain.pressure, rtol=1e-6,
                               atol=1e-8 * plain.pressure.max())
