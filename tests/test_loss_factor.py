"""A material's loss factor eta: in the cea the complex stiffness K + i eta K_m, whose modes
are lambda = i omega sqrt(1 + i eta) (real part -eta omega / 2 for a small eta) when the whole
model is of that material; in a run the viscous damping eta / omega_ref K_m, which decays a
mode of frequency omega at eta omega^2 / (2 omega_ref)."""
import numpy as np
import pytest
import scipy.sparse as sp

from test_materials import PAD as LINED_PAD
from transient.api import cea, load, prepare
from transient.cli import main
from transient.dynamics.system import reduced_loss
from transient.stages import choose_dt, simulate

ETA = 0.04

BLOCK = f"""
[materials.m]
E = 2.0e11
nu = 0.3
rho = 7800.0
loss_factor = {ETA}

[parts.block]
material = "m"
[parts.block.mesh]
kind = "box"
size = [0.1, 0.02, 0.03]
divisions = [5, 1, 2]
element = "hex20"

[constraints.root]
set = "block.xmin"

[sensors.tip]
part = "block"
point = [0.1, 0.01, 0.03]
direction = [0.0, 0.0, 1.0]

[solver]
scheme = "exponential"
t_end = 0.02

[solver.reduction]
enabled = true
fmax = 12000.0
"""


def _case(tmp_path, text=BLOCK, overrides=()):
    path = tmp_path / "block.toml"
    path.write_text(text)
    return load(path, list(overrides))


@pytest.mark.parametrize("reduced", [True, False], ids=["reduced", "full"])
def test_cea_of_one_lossy_material(tmp_path, reduced):
    sets = [] if reduced else ["solver.reduction.enabled=false", "solver.modes.fmax=12000.0"]
    lossy = cea(_case(tmp_path, overrides=sets)).modes
    plain = cea(_case(tmp_path, overrides=sets + ["materials.m.loss_factor=0.0"])).modes
    omega = plain.eigenvalues.imag
    assert len(omega) >= 3 and np.allclose(plain.eigenvalues.real, 0.0, atol=1e-9 * omega.max())
    # each undamped mode, its stiffness times 1 + i eta
    assert np.allclose(lossy.eigenvalues, 1j * omega * np.sqrt(1 + 1j * ETA),
                       rtol=1e-8 if reduced else 1e-6)
    assert np.allclose(lossy.real, -ETA * lossy.frequency_hz * np.pi, rtol=ETA ** 2)
    assert not lossy.unstable.any()


# test_materials' transversely isotropic lining on steel, the lining lossy, its cea reduced
PAD = (LINED_PAD[:LINED_PAD.index("[solver.modes]")].replace(
    "rho = 2500.0\n", "rho = 2500.0\nloss_factor = 0.1\n")
    + '[solver]\nmass = "consistent"\n\n[solver.modes]\nfmax = 15000.0\n\n'
    '[solver.reduction]\nenabled = true\nfmax = 15000.0\n')


@pytest.mark.slow
def test_a_lossy_lining_on_steel_reduced_against_full(tmp_path):
    """Only the lining's cells are lossy: each mode's damping is its share of strain energy
    in the lining (the reduced model's T^T K_lining T, not diagonal), against the full model's
    complex modes."""
    reduced = cea(_case(tmp_path, PAD)).modes
    full = cea(_case(tmp_path, PAD, ["solver.reduction.enabled=false"])).modes
    # the free pad's rigid motions, without stiffness, have no loss: none grows
    assert not reduced.unstable.any() and not full.unstable.any()
    rigid = reduced.frequency_hz < 1.0
    assert np.abs(reduced.real[rigid]).max() < 1e-9
    reduced = reduced.eigenvalues[~rigid]
    full = full.eigenvalues[full.frequency_hz >= 1.0]
    assert len(reduced) == len(full) == 4
    assert np.allclose(reduced.imag, full.imag, rtol=1e-3)
    assert np.allclose(reduced.real, full.real, rtol=3e-3)
    # the lining's share of each mode's strain differs: the ratio below its eta / 2
    ratio = -full.real / np.abs(full)
    assert (ratio < 0.05).all() and ratio.max() > 1.2 * ratio.min()


def _decay(series, t, period):
    """Decay rate [1/s] of a signal's amplitude from its peaks (each the largest |value|
    of a period) over the second half of the run."""
    late = t >= t[-1] / 2
    edges = np.arange(t[late][0], t[-1] - period, period)
    peaks = [np.abs(series[(t >= a) & (t < a + period)]).max() for a in edges]
    slope = np.polyfit(edges, np.log(peaks), 1)[0]
    return -slope


@pytest.mark.parametrize("at_mode", [False, True], ids=["at-fmax", "at-first-mode"])
def test_a_run_decays_a_mode_at_the_viscous_rate(tmp_path, at_mode):
    """A tap (initial velocity) on a cantilever: its first bending mode, the one left once
    the higher ones (damped as omega^2) have decayed, decays at eta omega^2 / (2 omega_ref),
    omega_ref the band's top by default, the mode's own when loss_frequency says so (the
    cea's -eta omega / 2 there)."""
    case = _case(tmp_path)
    setup = prepare(case)
    omega1 = np.sqrt(setup.system.omega2[0])
    if at_mode:
        case = _case(tmp_path, overrides=[f"solver.damping.loss_frequency="
                                          f"{float(omega1 / (2 * np.pi))!r}"])
        setup = prepare(case)
    omega_ref = omega1 if at_mode else 2 * np.pi * case.solver.reduction.fmax
    expected = ETA * setup.system.omega2 / omega_ref
    assert np.allclose(setup.system.damp, expected, rtol=1e-9)
    setup.state.v[:] = 0.0
    setup.state.v[0] = 1.0                    # the first mode alone, then all of them
    dt = choose_dt(case, setup)
    series, status, _ = simulate(case, setup, dt, int(round(case.solver.t_end / dt)))
    assert status == "complete"
    rate = _decay(series["sensors/tip"], series["time"], 2 * np.pi / omega1)
    assert rate == pytest.approx(0.5 * ETA * omega1 ** 2 / omega_ref, rel=0.02)


def test_a_full_models_run_with_a_loss_factor_is_refused(tmp_path, capsys):
    path = tmp_path / "block.toml"
    path.write_text(BLOCK)
    assert main(["run", str(path), "--set", "solver.reduction.enabled=false", "--set",
                 'solver.scheme="explicit"', "-o", str(tmp_path / "out.h5")]) == 2
    err = capsys.readouterr().err
    assert ": materials.m.loss_factor: a run takes the materials' loss on the reduced" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out.h5").exists()


def test_no_loss_factor_adds_nothing(tmp_path):
    """Without a loss factor the model has no loss matrix and the system's damping is the
    other keys' alone: the shipped cases' histories do not move."""
    setup = prepare(_case(tmp_path, overrides=["materials.m.loss_factor=0.0"]))
    assert setup.model.loss is None and setup.system.loss is None
    assert setup.system.base_damp is None and not setup.system.damp.any()


def test_the_loss_on_a_basis_held_by_part_is_the_dense_ones():
    """The components path holds its basis by part (reduce.synthesis.Synthesis, the parts'
    bases side by side, two dofs in none): T^T H T on it is the dense basis', with H coupling
    the parts too, and a vector without stiffness takes no loss."""
    from transient.reduce.synthesis import Synthesis
    rng = np.random.default_rng(0)
    B = sp.random(30, 30, density=0.2, random_state=1)
    H = (B @ B.T).tocsr()
    dofs = [np.arange(12), np.arange(14, 30)]
    X = Synthesis(30, dofs, [rng.standard_normal((12, 2)), rng.standard_normal((16, 4))])
    AW = rng.standard_normal((6, 4))
    omega2 = np.array([0.0, 1e3, 2e3, 3e3])
    dense = reduced_loss(H, X.toarray(), AW, omega2)
    assert np.allclose(reduced_loss(H, X, AW, omega2), dense, rtol=1e-13,
                       atol=1e-13 * np.abs(dense).max())
    X = X.toarray()
    T = X @ AW
    exact = T.T @ (H @ T)
    assert not dense[0].any() and not dense[:, 0].any()
    assert np.allclose(dense[1:, 1:], exact[1:, 1:], rtol=1e-12)
