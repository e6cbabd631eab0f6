"""A run whose step fails (energy balance past its tolerance, a state not finite, Newton not
converged) goes back to the last row before the failure and goes on at half the step, down to
dt / 2^solver.subdivision: the rows keep their times, the history says when, to what and why,
the same run comes out whatever chunks it was cut into and when stopped and resumed, and below
the floor it aborts with the steps it tried."""
import os
import signal

import h5py
import numpy as np
import pytest
import scipy.linalg as sla

from test_cea import small
from test_resume import assert_same, series
from test_validation import BAR
from transient.case.loading import load
from transient.stability.linearize import linearized
from transient.cli import main
from transient.io.reading import summary
from transient.integration import run
from transient.stages import prepare

# bar_impact at a step forced above its critical one (1.76e-7 s): it diverges at 4e-7 s, its
# balance drifting by 0.80 within 6 us, and at 2e-7 s; it holds at 1e-7 s
FORCED = ["solver.dt=4e-7", "solver.force_dt=true", "solver.t_end=1.2e-4"]


def sets(*overrides):
    return [a for o in overrides for a in ("--set", o)]


def test_a_failing_step_is_halved_until_it_holds(tmp_path, capsys):
    path = tmp_path / "bar.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"] + sets(*FORCED)) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if line.startswith("note: ")]
    assert len(notes) == 2 and "4e-07 -> 2e-07 s (energy balance drifted" in notes[0]
    assert "subdivided to 1e-07 s" in captured.out
    d = summary(path)
    assert d["status"] == "complete" and d["energy_drift"] < 0.05
    steps = d["meta"]["subdivisions"]
    assert [s["dt"] for s in steps] == [2e-7, 1e-7] and d["meta"]["dt_end"] == 1e-7
    assert steps[0]["t"] <= steps[1]["t"] < 1e-5 and "drifted" in steps[0]["why"]
    with h5py.File(path, "r") as f:
        t = f["time"][()]
        assert f.attrs["dt"] == 4e-7                  # the run's first step
    # the rows at one sample step throughout (every doubled as the step halved), to t_end
    np.testing.assert_allclose(np.diff(t), 4e-7, rtol=1e-9)
    assert t[-1] == pytest.approx(1.2e-4, rel=1e-12)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"subdivided at t = {steps[0]['t']:.6g} s to 2e-07 s: energy balance" in out


@pytest.mark.slow
def test_where_the_step_is_halved_does_not_depend_on_the_chunks(tmp_path):
    runs = []
    for chunk in (0, 10, 50):
        path = tmp_path / f"bar{chunk}.h5"
        assert main(["run", BAR, "-o", str(path), "--quiet"] + sets(
            *FORCED, f"solver.chunk={chunk}")) == 0
        runs.append(series(path))
    assert_same(runs[0], runs[1])
    assert_same(runs[0], runs[2])


@pytest.mark.slow
def test_a_subdivided_run_stopped_and_resumed_is_the_fresh_run(tmp_path):
    case = load(BAR, FORCED + ["solver.chunk=20"])
    fresh = run(case, tmp_path / "fresh.h5")
    assert fresh.status == "complete" and len(fresh.subdivisions) == 2

    def stop(line):
        # a SIGTERM when the step is first halved: the run stops after the chunk in hand
        os.kill(os.getpid(), signal.SIGTERM)
    part = tmp_path / "part.h5"
    stopped = run(case, part, note=stop)
    assert stopped.status == "aborted: terminated (SIGTERM)"
    resumed = run(case, part, resume=True)
    assert resumed.status == "complete" and resumed.steps == fresh.steps
    assert_same(series(tmp_path / "fresh.h5"), series(part))
    assert summary(part)["meta"]["subdivisions"] == summary(tmp_path / "fresh.h5")["meta"][
        "subdivisions"]


def test_no_step_down_to_the_floor_holds_and_the_run_stops(tmp_path, capsys):
    path = tmp_path / "bar.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"] + sets(
        *FORCED, "solver.subdivision=1")) == 3
    err = capsys.readouterr().err
    assert "note: step subdivided" in err
    line = err.splitlines()[-1]
    assert line.startswith("error: run aborted: energy balance drifted")
    assert "no step down to the floor dt / 2 held (steps tried: 4e-07, 2e-07 s" in line
    d = summary(path)
    assert d["status"].startswith("aborted: ") and d["meta"]["dt_end"] == 2e-7


@pytest.mark.slow
def test_a_friction_run_failing_at_the_default_step_completes_subdivided(tmp_path):
    """The small pad and disc of test_cea at mu = 0.6, at the default step: the evaluated
    corrector fails as the vibration saturates (its balance at 0.14 by 6.4 ms: the run stops
    without subdivision, as pad_disc's did at 1.5 ms). Subdivided it completes at a quarter
    of the step or less, its balance within the run's drift tolerance, its rows at one sample
    step; its fastest unstable mode (11.8 kHz, the CEA's 2825 1/s) grew before at the default
    step's rate of it (2810 1/s fitted over 1-3 ms), the mode's amplitude from the stored field
    as tests/test_squeal.py takes it. Where the saturated vibration ends up follows the setup's
    round-off: with SuperLU the run completes at an eighth of the step at 0.7%, with PARDISO
    at a sixteenth at 4.0% (MKL 2026.2.1; 1.0% at an eighth with an earlier MKL), one thread
    or two alike."""
    sets = ["contact.pad_disc.friction.mu=0.6", "loads.tap.vector=[0.0,0.0,-0.02]",
            "solver.t_end=8e-3", "output.field=true", "output.every=1"]
    held = run(small(*sets, "solver.subdivision=0"), tmp_path / "held.h5")
    assert held.status.startswith("aborted: energy balance drifted")
    case = small(*sets)
    notes = []
    out = run(case, tmp_path / "run.h5", note=notes.append)
    assert out.status == "complete" and out.energy_drift < case.solver.drift_tolerance
    assert len(notes) == len(out.subdivisions) >= 1 and out.dt <= 3.125e-6 / 4
    assert out.subdivisions[0]["t"] > held.t_end - 1e-3
    setup = prepare(case)
    _, D, K = linearized(setup.system, setup.state)
    n = setup.system.n
    lam, left = sla.eig(np.block([[np.zeros((n, n)), np.eye(n)], [-K, -D]]), left=True,
                        right=False)
    grow = np.argmax(np.where(lam.imag > 0, lam.real, -np.inf))
    with h5py.File(tmp_path / "run.h5", "r") as f:
        t, q = f["time"][()], f["field/q"][()]
    np.testing.assert_allclose(np.diff(t), 3.125e-6, rtol=1e-9)
    z = np.hstack([q - setup.state.q, np.gradient(q, t, axis=0)])
    amplitude = np.abs(z @ left[:, grow].conj())
    linear = (t > 1e-3) & (t < 3e-3)
    rate = np.polyfit(t[linear], np.log(amplitude[linear]), 1)[0]
    assert lam[grow].real > 2500
    assert rate == pytest.approx(lam[grow].real, rel=0.06)


@pytest.mark.parametrize("overrides, reason", [
    (["solver.t_end=2e-5"], "the contact's penalty at omega_c dt = 0.7 (contact.*.k)"),
    (["solver.t_end=2e-5", "solver.dt=5e-8"], "solver.dt"),
    (["solver.t_end=2e-5", 'solver.scheme="exponential"', "solver.reduction.enabled=true"],
     "0.9 of the evaluated corrector's bound on the contact remainder (contact.*.k)"),
    (["solver.t_end=2e-5", 'solver.scheme="exponential"', "solver.reduction.enabled=true",
      'solver.corrector="implicit"', "solver.reduction.fmax=2e5"],
     "20 steps a period at solver.reduction.fmax")])
def test_a_run_says_and_stores_what_set_its_step(tmp_path, capsys, overrides, reason):
    """Central differences at the bar's contact penalty bound, the case's own dt, the
    exponential scheme at its evaluated corrector's bound and at its accuracy step: the run's
    line names what set the step, and the history keeps it (`transient info`)."""
    path = tmp_path / "bar.h5"
    assert main(["run", BAR, "-o", str(path)] + sets(*overrides)) == 0
    line = [x for x in capsys.readouterr().out.splitlines() if " steps of " in x][0]
    assert f" ({reason}) to t = " in line
    assert summary(path)["meta"]["dt_reason"] == reason
    assert main(["info", str(path)]) == 0
    assert f"s: {reason}" in capsys.readouterr().out
