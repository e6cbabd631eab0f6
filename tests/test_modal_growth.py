"""The transient read on the complex modes (stability.growth): a run's motion projected on the
left complex eigenvectors of its system linearized at its preload.

On the two-dof mode-coupling model (tests/test_cea_mode_coupling.py) above its flutter
threshold the growing mode and its decaying partner share one frequency: no band filter or
envelope tells them apart. Started on both, a motion of the linearized system gives each its
own exponential, at its initial amplitude (the normalization) and its real part; the
package's scheme run on it gives the real parts within its accuracy. Below the threshold the
two modes are apart in frequency but not orthogonal (friction makes K non-symmetric): with
the band cut between them, only the left eigenvectors keep the mode above out of the one
below.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.dynamics.chunks import buffer
from transient.dynamics.schemes import initial_acceleration, stepper
from transient.stability.growth import first_order_modes, modal_growth
from transient.stability.linearize import linearized

from small_cases import PAD_DISC
from test_cea_mode_coupling import mu_c_undamped
from test_cea import PAD
from test_squeal_two_dof import two_dof

ROWS = 40             # rows per period
PERIODS = 12          # the motion's length
STEPS = 400           # the scheme's steps per period (test_squeal_two_dof's)
MU = 1.05             # of the flutter threshold: the pair grows and decays at 0.07 omega
# the initial amplitudes of the growing and the decaying mode [sqrt(kg) m]: over PERIODS the
# growing one rises e^5.5 to 2.5 mm, the contact spring far from opening (the preload's gap
# is 67 mm), the decaying one falls as much, far above the round-off of the preload
START = {"growing": 1e-5, "decaying": 1e-4}


def flutter():
    """(system, preload state, the two modes of positive frequency: their eigenvalues and
    right eigenvectors, growing first) of the two-dof model at MU mu_c, undamped."""
    system, state, *_ = two_dof(MU * mu_c_undamped())
    lam, right = modes_at(system, state)
    order = np.argsort(-lam.real)
    return system, state, lam[order], right[:, order]


def modes_at(system, state):
    """(eigenvalues, right eigenvectors) of the modes of positive frequency, by frequency."""
    lam, _, right = first_order_modes(*linearized(system, state))
    upper = np.flatnonzero(lam.imag > 0)
    upper = upper[np.argsort(lam[upper].imag)]
    return lam[upper], right[:, upper]


def linear_motion(system, state, lam, right, c, t):
    """The rows q(t) = q0 + 2 Re sum_k c_k phi_k exp(lambda_k t) (t (r,)): (r, n)."""
    n = system.n
    return state.q + 2 * np.real((right[:n] * c) @ np.exp(np.outer(lam, t))).T


def field(system):
    """The system observing its state q (output.field)."""
    n = system.n
    return replace(system, sensors=np.eye(n), sensor_names=(), n_field=n)


def projected_linear_motion():
    """(ModalGrowth, eigenvalues, initial amplitudes) of the flutter pair's linear motion
    z(t) = 2 Re sum_k c_k x_k exp(lambda_k t) over PERIODS."""
    system, state, lam, right = flutter()
    c = np.array([START["growing"], START["decaying"]])
    period = 2 * np.pi / lam[0].imag
    t = np.arange(PERIODS * ROWS + 1) * period / ROWS
    q = linear_motion(system, state, lam, right, c, t)
    result = modal_growth(system, state.q, t, lambda i, j: q[i:j], 2 * lam.imag.max() / np.pi,
                          0.0)
    return result, lam, c


def test_the_projection_of_a_linear_motion_gives_each_mode_its_own_exponential():
    """z(t) = 2 Re sum_k c_k x_k exp(lambda_k t) over the two modes: the amplitudes are
    |c_k| exp(Re lambda_k t) to round-off and the fits their real parts; right eigenvectors
    in place of the left ones mix the pair (they are not orthogonal), a dropped normalization
    scales them."""
    result, lam, c = projected_linear_motion()
    order = [int(np.argmin(np.abs(result.eigenvalues - x))) for x in lam]
    expected = c[:, None] * np.exp(np.outer(lam.real, result.time))
    assert result.amplitudes[order] == pytest.approx(expected, rel=1e-8)
    assert result.excited[order].all()
    assert result.growth[order] == pytest.approx(lam.real, rel=1e-8)


def test_the_table_and_the_picture_of_a_projection(tmp_path):
    """The flutter pair's projection as CSV (a row per mode, its fitted growth, the CEA's
    cells empty without a CEA) and as a picture with both modes drawn."""
    import csv
    from matplotlib.image import imread
    from transient.plots.growth import growth_figure, shown_modes, write_growth_csv
    result, lam, _ = projected_linear_motion()
    table, png = tmp_path / "growth.csv", tmp_path / "growth.png"
    write_growth_csv(result, table)
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(result.eigenvalues)
    growth = sorted(float(r["growth"]) for r in rows)
    assert growth == pytest.approx(sorted(lam.real), rel=1e-8)
    assert all(r["cea_real"] == "" and r["excited"] == "True" for r in rows)
    assert len(shown_modes(result)) == 2
    growth_figure(result, png, "flutter pair")
    rgb = imread(png)[..., :3]
    assert rgb.shape[1] >= 500 and (rgb.min(axis=2) < 0.9).mean() > 0.01


@pytest.mark.parametrize("scheme, corrector", [("exponential", "propagated"),
                                               ("implicit", "evaluated")])
def test_a_run_on_the_flutter_pair_grows_and_decays_at_their_real_parts(scheme, corrector):
    """The package's scheme from the preload perturbed along both modes: each projected
    growth within 1e-2 of its real part (test_squeal_two_dof's bound for the scheme at
    STEPS a period, measured there within 1.2e-3)."""
    system, state, lam, right = flutter()
    n = system.n
    rest = state.q.copy()
    z = 2 * np.real(right @ np.array([START["growing"], START["decaying"]]))
    state.q[:] += z[:n]
    state.v[:] += z[n:]
    system = field(system)
    initial_acceleration(system, state, False)
    period = 2 * np.pi / lam[0].imag
    dt = period / STEPS
    every = STEPS // ROWS
    steps = PERIODS * STEPS
    solver = replace(load(PAD).solver, scheme=scheme, corrector=corrector, corrections=1)
    rows = buffer(system, steps // every, False)
    status, done = stepper(system, solver, dt)(state, steps, every, rows)
    assert status == 0 and done == steps
    t = np.concatenate([[0.0], rows.time])
    q = np.vstack([rest + z[:n], rows.sensors])
    result = modal_growth(system, rest, t, lambda i, j: q[i:j], 2 * lam.imag.max() / np.pi,
                          0.0)
    order = [int(np.argmin(np.abs(result.eigenvalues - x))) for x in lam]
    assert result.excited[order].all()
    assert result.growth[order] == pytest.approx(lam.real, rel=1e-2)


def test_the_left_eigenvectors_keep_a_mode_outside_the_band_out_of_the_one_inside():
    """0.8 mu_c with modal damping 4 1/s (test_squeal_two_dof's): the two modes decay at -2
    1/s, 16% apart in frequency. A motion of both, equal, projected with the band cut between
    them: the lower mode's amplitude is its own exponential to round-off (with equal damping
    the upper one leaks nothing through the central differences), where the right
    eigenvectors in place of the left ones would read 82% of the upper one into it."""
    system, state, *_ = two_dof(0.8 * mu_c_undamped(), 4.0)
    lam, right = modes_at(system, state)
    c = np.array([START["decaying"], START["decaying"]])
    period = 2 * np.pi / lam[1].imag
    t = np.arange(2 * PERIODS * ROWS + 1) * period / ROWS
    q = linear_motion(system, state, lam, right, c, t)
    result = modal_growth(system, state.q, t, lambda i, j: q[i:j], lam.imag.mean() / (2 * np.pi),
                          0.0)
    assert len(result.eigenvalues) == 1
    expected = c[0] * np.exp(lam[0].real * result.time)
    assert result.amplitudes[0] == pytest.approx(expected, rel=1e-8)
    assert result.growth[0] == pytest.approx(lam[0].real, rel=1e-8)


SQUEAL = Path(__file__).resolve().parent.parent / "cases" / "pad_disc_squeal.toml"

# pad_disc_squeal's run resolved finely enough that it is the linear system the CEA analyses
# (docs/performance.md has the figures at the case's own settings): a quarter of the case's
# step (the exponential scheme's error on each mode is second order in it, on the growth and on
# the eigenvectors, which mixes a mode into its neighbours a few tens of Hz away), its points
# sampled to 1e-3 (at the case's 3e-2 the sampled rule's linearization, which the run
# integrates, is not the fine rule's that the CEA analyses to 5% on every stable mode), over
# 20 ms of the 2 mN tap's linear phase, a row every 16 steps (six a period of the band's top).
LINEAR_PHASE = ["solver.t_end=0.02", "solver.dt=7.8125e-7", "output.every=16",
                "output.field=true", "contact.pad_disc.sampling_tolerance=1e-3"]


@pytest.mark.slow
def test_pad_disc_squeal_read_mode_by_mode_agrees_with_its_cea():
    """Every unstable mode's projected growth within 5% of the CEA's real part, and every
    stable one whose rate its window resolves within 5% (issue 48's criterion): the tap
    excites every mode above the floor, and only the near-neutral ones, whose change over
    20 ms the fit's own deviation buries, are left out as unresolved."""
    from transient.stability.stage import analysis_of, fmax_of
    from transient.stages import prepare, stepper as case_stepper
    from transient.stability.growth import loads_end
    case = load(SQUEAL, LINEAR_PHASE)
    setup = prepare(case, unsampled=True)
    modes = analysis_of(case, setup.unsampled).modes
    system, dt, every = setup.system, case.solver.dt, case.output.every
    steps = int(round(case.solver.t_end / dt))
    state = setup.state.copy()
    out = buffer(system, steps // every, False)
    status, done = case_stepper(case, system, dt)(state, steps, every, out)
    assert status == 0 and done == steps
    named = len(system.sensor_names)
    t = np.concatenate([setup.rows0.time[:1], out.time])
    q = np.vstack([setup.rows0.sensors[:1], out.sensors])[:, named:]
    free_from, _ = loads_end(case, dt, t[-1])
    result = modal_growth(system, setup.state.q, t, lambda i, j: q[i:j], fmax_of(case),
                          free_from, modes)
    assert result.excited.all()
    unstable = result.cea_unstable
    assert unstable.sum() == modes.unstable.sum() > 0
    assert np.all(np.abs(result.difference[unstable]) <= 0.05)
    checked = result.resolved & ~unstable & np.isfinite(result.difference)
    assert np.all(np.abs(result.difference[checked]) <= 0.05)


# the coarsest pad_disc_squeal that squeals (one unstable mode at mu = 0.4): a quick run
SMALL_SQUEAL = PAD_DISC + ["contact.pad_disc.friction.mu=0.4", "output.field=true"]


def small_run(path, more=()):
    """A history of SMALL_SQUEAL (with overrides more) at path."""
    from transient.integration import run
    run(load(SQUEAL, SMALL_SQUEAL + list(more)), path)
    return path


@pytest.mark.slow
def test_plot_modal_growth_writes_the_table_and_the_picture_of_a_squealing_run(tmp_path,
                                                                              capsys):
    """The command on 12 ms of the small squeal (its linear phase): the CSV holds a row per
    mode of the band, the unstable one's growth within 5% of the CEA's real part, the PNG
    draws it; the API gives the same table."""
    import csv
    from matplotlib.image import imread
    from transient.api import modal_growth as api_growth
    from transient.cli import main
    history = small_run(tmp_path / "small.h5", ["solver.t_end=0.012"])
    png, table = tmp_path / "growth.png", tmp_path / "growth.csv"
    assert main(["plot", "modal-growth", str(history), "-o", str(png), "--csv", str(table)]) == 0
    printed = capsys.readouterr().out
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    result = api_growth(history)
    assert len(rows) == len(result.eigenvalues) and "not excited" in printed
    unstable = [r for r in rows if r["cea_unstable"] == "True"]
    assert len(unstable) == 1 and unstable[0]["excited"] == "True"
    assert abs(float(unstable[0]["difference"])) <= 0.05
    rgb = imread(png)[..., :3]
    assert rgb.shape[1] >= 500 and (rgb.min(axis=2) < 0.9).mean() > 0.01


@pytest.mark.parametrize("more, key", [(["output.field=false"], "output.field"),
                                       (["output.every=8"], "output.every")])
def test_a_history_the_projection_cannot_read_is_refused_naming_the_key(tmp_path, more, key):
    """Without the state stored, or rows sparser than four a period of the band's top (a row
    every 25 us against 16 kHz), one line naming the key, before any CEA."""
    from transient.api import modal_growth as api_growth
    from transient.errors import CaseError
    history = small_run(tmp_path / "small.h5", ["solver.t_end=4e-4"] + more)
    with pytest.raises(CaseError, match=key):
        api_growth(history)
