"""The reduced basis of a reference friction (contact.<pair>.friction.basis_mu,
reduce.reference): a basis made at one friction and rebased on another's preload and tangent
gives that friction's complex modes as its own basis does, and as the full model does; its
algebra (the update's Gram, the structural part) against direct products; basis_mu = mu is
the case's own basis, bit for bit."""
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.stability.stage import analyse
from transient.stages import prepare

from small_cases import PAD_DISC

PAD = Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml"
SMALL = PAD_DISC + ["motion.disc.omega=50.0", "solver.damping.residual=0.0"]
MU = "contact.pad_disc.friction.mu="
BASIS = "contact.pad_disc.friction.basis_mu="


def small(*more):
    return load(PAD, SMALL + list(more))


def _near(reference, modes):
    return np.array([np.argmin(np.abs(modes.eigenvalues - lam))
                     for lam in reference.eigenvalues])


@pytest.fixture(scope="module")
def analyses():
    """mu = 0.4: the full model's modes, the reduced model's on its own basis, and on the
    bases made at 0.3 and 0.6."""
    return {key: analyse(small(MU + "0.4", *more)) for key, more in (
        ("full", ["solver.reduction.enabled=false"]), ("own", []),
        ("0.3", [BASIS + "0.3"]), ("0.6", [BASIS + "0.6"]))}


@pytest.mark.parametrize("basis_mu", ["0.3", "0.6"])
@pytest.mark.slow
def test_a_rebased_basis_gives_the_complex_modes_of_its_own(analyses, basis_mu):
    """Every mode below fmax: against the own basis' within 3e-4 in frequency and 1% of the
    largest unstable real part (measured: 6e-5 and 0.13% from 0.3, 1.3e-4 and 0.29% from
    0.6); against the full model, the reduced analysis' own test (test_cea: 0.5% and 5%)."""
    full, own, rebased = analyses["full"], analyses["own"].modes, analyses[basis_mu].modes
    assert len(rebased.eigenvalues) == len(own.eigenvalues)
    near = _near(own, rebased)
    assert len(set(near)) == len(near)
    big = own.real[own.unstable].max()
    assert own.unstable.sum() >= 2
    np.testing.assert_allclose(rebased.frequency_hz[near], own.frequency_hz, rtol=3e-4)
    assert np.abs(rebased.real[near] - own.real).max() <= 0.01 * big
    assert np.array_equal(rebased.unstable[near], own.unstable)
    ref = full.modes.below(0.98 * 16000.0)
    near = _near(ref, rebased)
    np.testing.assert_allclose(rebased.frequency_hz[near], ref.frequency_hz, rtol=5e-3)
    assert np.abs(rebased.real[near] - ref.real).max() <= 0.05 * big


@pytest.mark.slow
def test_basis_mu_at_mu_is_the_own_basis_bit_for_bit(analyses):
    same = analyse(small(MU + "0.4", BASIS + "0.4")).modes
    own = analyses["own"].modes
    assert np.array_equal(same.eigenvalues, own.eigenvalues)


def test_the_rebased_model_holds_its_preload_and_one_more_direction():
    """The variant's preload joins the basis: held to round-off, one static direction more
    than the reference's basis; and the stage that made the basis is named."""
    own = prepare(small(MU + "0.4"))
    rebased = prepare(small(MU + "0.4", BASIS + "0.3"))
    assert rebased.meta["basis_projection_error"] < 1e-12
    assert own.meta["basis_projection_error"] < 1e-6      # its solve's accuracy (1.4e-8)
    assert rebased.meta["reduced_dofs"] == own.meta["reduced_dofs"] + 1
    assert "reference" in rebased.stages and "reference" not in own.stages
    assert rebased.meta["basis_mu"] == {"pad_disc": 0.3} and "basis_mu" not in own.meta
    from transient.cli.commands import _model_line
    assert "made at mu = 0.3 on pad_disc" in _model_line(rebased.meta)


def test_a_rebased_run_takes_the_points_and_weights_sampled_at_the_reference():
    """The sampled rule's points and weights are the reference's (chosen once, on its basis
    and preload: physical points, whatever the coordinates), the reduced preload the case's."""
    at = prepare(small(MU + "0.3"))
    rebased = prepare(small(MU + "0.4", BASIS + "0.3"))
    a, b = at.system.contacts, rebased.system.contacts
    assert a.n_points == b.n_points > 0
    assert np.array_equal(a.weights, b.weights)
    assert rebased.meta["sampling"]["residual"] == at.meta["sampling"]["residual"]
    assert not np.array_equal(at.state.gmin, rebased.state.gmin)      # its own preload


def test_the_update_gram_and_the_structural_part_against_direct_products():
    """T^T U T (lowrank.TangentStiffness.update_gram) against T^T (K_lin T - K T), and the
    reference basis' K0r + T^T U T against T^T K_lin T = diag(omega^2)."""
    from transient.contact.contactset import first_tangent, stack
    from transient.contact.pair import build_contact
    from transient.dynamics.critical import critical_tangent
    from transient.model import constant_load
    from transient.reduce.basis import structural_gram
    from transient.reduce.stage import make_basis
    from transient.shared import build_shared
    from transient.solve.preload import solve_preload
    case = small(MU + "0.3")
    built = build_shared(case, "factorization")
    model, cs = built.model, built.solver
    pairs = build_contact(case, model, geometry=built.geometry)
    contacts = stack(pairs, model.ndof)
    preload = solve_preload(model.K, model.fixed, constant_load(case, model), contacts, cs,
                            start=first_tangent(pairs, contacts))
    tangent = cs.solver(contacts.weights * preload.tangent)
    basis = make_basis(case, model, model.M, contacts, preload,
                       [model.load_patterns[n] for n in case.loads], tangent,
                       critical_tangent(contacts, preload.tangent), cs.C, cs.M)
    K = tangent.stiffness
    T = basis.X[~model.fixed] @ basis.A
    KT = K @ T.copy()
    U = T.T @ (KT - K.K @ T)
    scale = basis.omega2.max()
    np.testing.assert_allclose(K.update_gram(lambda idx: T[idx], T.shape[1]), U,
                               atol=1e-11 * scale)
    np.testing.assert_allclose(T.T @ KT, np.diag(basis.omega2), atol=1e-9 * scale)
    K0r = structural_gram(basis, K, model.fixed)
    np.testing.assert_allclose(K0r, T.T @ (K.K @ T), atol=1e-9 * scale)


def test_the_update_gram_in_both_forms_against_dense_products():
    """X^T C^T diag(d) C X from the rows (C, d) and from the rows' space (cols, V, core), given
    X by its rows, against the dense product and the operator's own."""
    import scipy.sparse as sp
    from transient.solve.lowrank import TangentStiffness
    rng = np.random.default_rng(0)
    n, p, s = 40, 12, 5
    K = sp.random(n, n, density=0.2, random_state=1, format="csr")
    K = (K + K.T).tocsr()
    C = sp.random(p, n, density=0.1, random_state=2, format="csr")
    d = rng.random(p)
    X = rng.standard_normal((n, s))
    ref = (C @ X).T @ (d[:, None] * (C @ X))
    cols = np.unique(C.indices)
    assert len(cols) < n                       # the rows touch some dofs only
    Q, R = np.linalg.qr(C[:, cols].toarray().T)
    forms = [TangentStiffness(K, C=C, d=d),
             TangentStiffness(K, cols=cols, V=Q, core=R @ (d[:, None] * R.T))]
    for form in forms:
        np.testing.assert_allclose(form.update_gram(lambda idx: X[idx], s), ref, rtol=1e-10)
        np.testing.assert_allclose(X.T @ (form @ X.copy() - K @ X), ref, rtol=1e-10,
                                   atol=1e-12)
