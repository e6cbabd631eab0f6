"""The reduced CEA across its band on a brake nobody tuned the package to (a slotted,
chamfered two-material tet10 pad on a disc, slow sliding), against the full model's complex
modes mode by mode; and the residual of the full model's equations each reduced mode reports."""
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.stability.compare import pair_modes
from transient.stability.linearize import linearized
from transient.stability.stage import analyse, analysed_case
from transient.stages import prepare

from small_cases import PAD_DISC

ROOT = Path(__file__).resolve().parent.parent
SLOTTED = ROOT / "cases" / "slotted_pad.toml"
SMALL_SLOTTED = ['parts.disc.mesh.path="../tests/data/slotted_pad/disc.msh"',
                 'parts.pad.mesh.path="../tests/data/slotted_pad/pad.msh"',
                 "contact.pad_disc.friction.mu=0.5"]
PAD = ROOT / "cases" / "pad_disc.toml"
SMALL = PAD_DISC + ["solver.damping.residual=0.0", "contact.pad_disc.friction.mu=0.5"]


@pytest.mark.slow
def test_slotted_two_material_pad_matches_the_full_model():
    """Every mode unstable in either analysis below fmax: frequency within 0.1%, real part
    within 5% of its own (or 5 1/s), the same stability. The disc turns at 5 rad/s, where the
    friction's damping across the sliding (m / V) is stiff: its coupling statics, with the
    modes to 2 fmax, carry the band (the modes cut at fmax do not)."""
    full = analyse(load(SLOTTED, SMALL_SLOTTED + ["solver.reduction.enabled=false"]))
    reduced = analyse(load(SLOTTED, SMALL_SLOTTED))
    fmax = reduced.fmax
    pairs = pair_modes(full.modes, reduced.modes, fmax)
    assert sum(p.unstable and p.real > 100 for p in pairs) >= 2
    assert [p for p in pairs if not p.within()] == []
    cut = analyse(load(SLOTTED, SMALL_SLOTTED + [f"solver.reduction.cutoff={fmax}"]))
    assert [p for p in pair_modes(full.modes, cut.modes, fmax) if not p.within()] != []


@pytest.fixture(scope="module")
def full_matrices():
    setup = prepare(analysed_case(load(PAD, SMALL + ["solver.reduction.enabled=false"])),
                    analysis=True)
    return setup.system.free, linearized(setup.system, setup.state), setup.model.lumped_mass


@pytest.mark.parametrize("cutoff", [16000.0, 32000.0])
def test_mode_residual_is_that_of_the_full_models_equations(full_matrices, cutoff):
    """The residual each unstable mode reports equals |(K + lam D + lam^2 M) x|_{M^-1} /
    (|lam|^2 |x|_M) formed on the full model's own linearized matrices (stability.linearize of the
    full system), x = T z."""
    free, (M, D, K), lumped = full_matrices
    result = analyse(load(PAD, SMALL + [f"solver.reduction.cutoff={cutoff}"]))
    X, A = result.basis
    which = np.flatnonzero(result.modes.unstable)
    assert len(which) >= 2
    mass = lumped[free]
    for row, j in zip(result.shapes, which):
        lam = result.modes.eigenvalues[j]
        x = (X @ (A @ result.modes.vectors[:, j]))[free]
        r = K @ x + lam * (D @ x) + lam ** 2 * (M @ x)
        rho = (np.sqrt(np.sum(np.abs(r) ** 2 / mass))
               / (abs(lam) ** 2 * np.sqrt(np.sum(mass * np.abs(x) ** 2))))
        assert row["residual"] == pytest.approx(rho, rel=1e-6)


def test_mode_residuals_fall_as_the_basis_reaches_higher():
    rho = {}
    for cutoff in (16000.0, 32000.0):
        result = analyse(load(PAD, SMALL + [f"solver.reduction.cutoff={cutoff}"]))
        rho[cutoff] = {round(r["frequency_hz"], -1): r["residual"] for r in result.shapes}
    common = set(rho[16000.0]) & set(rho[32000.0])
    assert len(common) >= 2
    assert all(rho[32000.0][f] < 0.5 * rho[16000.0][f] for f in common)
