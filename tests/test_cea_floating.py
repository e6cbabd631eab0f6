"""The cea of models with floating parts: the full model's shift-invert Arnoldi with their rigid
modes deflated, against a closed form (free bars: rigid modes at 0, axial modes at n c / 2 L)
and against the dense eigenvalues of the same M, D, K; its bounds end in one line."""
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from transient.case.loading import load
from transient.stability.linearize import linearized
from transient.stability.reference import MAX_NEAR, Unresolved, full_complex_modes
from transient.stability.stage import analysed_case, analysis_of
from transient.cli import main
from transient.stages import prepare

CASES = Path(__file__).resolve().parent.parent / "cases"
TWO = str(CASES / "two_bars.toml")
# two free steel bars of 20 cells: 504 dofs, the axial modes above 16 kHz within fmax
COARSE = ["parts.left.mesh.divisions=[20,1,1]", "parts.right.mesh.divisions=[20,1,1]",
          "solver.modes.fmax=30000"]
C_BAR = np.sqrt(2.1e11 / 7800.0)      # m/s, nu = 0: one-dimensional waves
L_BAR = 0.1


def _analysed(*overrides):
    case = load(TWO, COARSE + list(overrides))
    setup = prepare(analysed_case(case), analysis=True)
    return analysis_of(case, setup), linearized(setup.system, setup.state)


def _dense(M, D, K, alpha, fmax):
    """The eigenvalues of M a + alpha M v + K q = 0 up to fmax from the symmetric (K, M): the
    rigid ones (|f| < 1 Hz) at 0 and -alpha, the others -alpha / 2 + i sqrt(w^2 - alpha^2 / 4)."""
    assert abs(D - alpha * M).max() <= 1e-12 * abs(M).max()
    w2 = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    rigid = np.abs(w2) < (2 * np.pi) ** 2
    lam = [0.0] * int(rigid.sum()) + ([-alpha] * int(rigid.sum()) if alpha else [])
    lam = np.concatenate([lam, -alpha / 2 + 1j * np.sqrt(w2[~rigid] - alpha ** 2 / 4)])
    return _by_frequency(lam[lam.imag <= 2 * np.pi * fmax])


def _by_frequency(lam):
    return lam[np.lexsort((lam.real, lam.imag))]


@pytest.mark.parametrize("alpha", [0.0, 40.0])
def test_free_bars_rigid_modes_at_zero_and_axial_modes_at_n_c_over_2l(alpha):
    result, (M, D, K) = _analysed(f"solver.damping.alpha={alpha}")
    lam = result.modes.eigenvalues
    # twelve rigid modes (six per bar) exactly at 0, and with a mass-proportional damping
    # twelve more at -alpha: no defective cluster left to ARPACK
    assert np.count_nonzero(lam == 0) == 12
    if alpha:
        assert np.count_nonzero(np.abs(lam + alpha) < 1e-9 * alpha) == 12
    # each bar's first axial mode, twice (identical bars), at c / 2 L within the mesh's error
    axial = C_BAR / (2 * L_BAR)
    near = np.flatnonzero(np.abs(result.modes.frequency_hz - axial) < 0.01 * axial)
    assert len(near) == 2
    np.testing.assert_allclose(result.modes.frequency_hz[near], axial, rtol=3e-3)
    # every mode to fmax, repeated ones as often as they are repeated (four bending modes of
    # each frequency: two bars, two directions), against the dense eigenvalues
    expected = _dense(M, D, K, alpha, 30000.0)
    found = _by_frequency(lam)
    assert len(found) == len(expected)
    np.testing.assert_allclose(found, expected, atol=1e-9 * np.abs(expected).max())


@pytest.mark.slow
def test_bars_tied_by_a_closed_contact_float_as_one():
    # a linear contact closed at zero gap ties the bars' ends along x: the assembly's rigid
    # motions and each bar's own ones that the contact does not see are deflated together
    result, (M, D, K) = _analysed("parts.right.mesh.origin=[0.1,0.0,0.0]",
                                  'contact.impact.law.kind="linear"')
    expected = _dense(M, D, K, 0.0, 30000.0)
    assert np.count_nonzero(expected == 0) == 11
    found = _by_frequency(result.modes.eigenvalues)
    assert len(found) == len(expected) and not result.modes.unstable.any()
    np.testing.assert_allclose(found, expected, atol=1e-9 * np.abs(expected).max())


def test_the_reduced_cea_of_free_bars_has_the_consistent_mass_modes():
    """The reduced model (consistent mass) on the same bars: its elastic modes are the dense
    ones of (K, M) to fmax, its rigid ones at round-off of 0."""
    case = load(TWO, COARSE + ["solver.reduction.enabled=true", "solver.reduction.fmax=30000"])
    result = analysis_of(case, prepare(analysed_case(case), analysis=True))
    model = result.model
    free = model.free
    w2 = sla.eigh(model.K[free][:, free].toarray(), model.M[free][:, free].toarray(),
                  eigvals_only=True)
    f = np.sqrt(w2[w2 > (2 * np.pi) ** 2]) / (2 * np.pi)
    f = f[f <= 30000.0]
    lam = result.modes.eigenvalues
    elastic = np.abs(lam) > 2 * np.pi
    np.testing.assert_allclose(np.sort(lam[elastic].imag) / (2 * np.pi), f, rtol=1e-8)
    assert np.abs(lam[~elastic]).max() < 1e-3 * 2 * np.pi * 30000.0
    assert 12 <= np.count_nonzero(~elastic) <= 24


@pytest.mark.slow
def test_a_cluster_beyond_the_bound_is_unresolved_not_a_hang():
    # 200 modes within one shift's disc: k doubles to MAX_NEAR, then the bound says so
    n = 200
    w = 2 * np.pi * np.linspace(400.0, 600.0, n)
    M, D, K = sp.identity(n), sp.csr_matrix((n, n)), sp.diags(w ** 2)
    assert n > MAX_NEAR
    with pytest.raises(Unresolved, match=f"more than {MAX_NEAR} eigenvalues"):
        full_complex_modes(M, D, K, 1000.0, shifts=1)


def test_arpack_not_converging_is_one_line_naming_what_to_change(monkeypatch, capsys):
    calls = []

    def stalls(*args, **kwargs):
        calls.append(kwargs["maxiter"])
        raise spla.ArpackNoConvergence("no convergence", np.zeros(0), np.zeros((0, 0)))
    monkeypatch.setattr(spla, "eigs", stalls)
    assert main(["cea", TWO] + [a for o in COARSE for a in ("--set", o)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert ": solver.reduction.enabled: " in err and "did not converge" in err
    assert "solver.modes.fmax" in err
    # a bounded count of bounded calls: k doubled from 12 to MAX_NEAR, then the error
    assert calls and all(c == calls[0] for c in calls) and len(calls) == 4
