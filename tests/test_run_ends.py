"""A run ends on solver.t_end: its last step shortened when dt does not divide t_end (the
exponential scheme's with propagators of its own), its end stored as a row of its own when off
the rows' grid (`output.every` larger than the run included), that row left out of spectra and
dropped by a resume, which goes on as a fresh run to the longer t_end, bit for bit; and a
resumed history keeps the case it was resumed with."""
import h5py
import numpy as np
import pytest

from test_cea import small
from test_resume import assert_same, series
from test_validation import BAR
from transient.cli import main
from transient.dynamics.plan import Plan
from transient.io.reading import summary
from transient.io.stored import open_history
from transient.integration import run

DT_BAR = 9.774968030638217e-08        # bar_impact's automatic step: 6e-5 is 613.8 of them


def bar(tmp_path, name, *sets, resume=False):
    path = tmp_path / name
    args = ["run", BAR, "-o", str(path), "--quiet"] + [a for s in sets for a in ("--set", s)]
    assert main(args + (["--resume"] if resume else [])) == 0
    return path


def test_plan_is_whole_steps_and_a_shortened_last_one():
    assert Plan.of(0.01, 3.125e-6, 4) == Plan(0.01, 3.125e-6, 4, 3200, False)
    plan = Plan.of(6e-5, DT_BAR, 7)
    assert (plan.steps, plan.partial, plan.grid, plan.end_row) == (613, True, 609, True)
    half = plan.halved()
    assert (half.steps, half.every, half.grid) == (1227, 14, 1218)


@pytest.mark.slow
def test_a_run_ends_on_t_end_with_its_end_a_row_of_its_own(tmp_path):
    path = bar(tmp_path, "bar.h5", "solver.t_end=6e-5", "output.every=7")
    with h5py.File(path, "r") as f:
        t = f["time"][()]
        assert f.attrs["end_row"]
    assert t[-1] == 6e-5                                   # exactly
    assert len(t) == 1 + 613 // 7 + 1
    np.testing.assert_allclose(np.diff(t[:-1]), 7 * DT_BAR, rtol=1e-9)
    assert 0 < t[-1] - t[-2] < 7 * DT_BAR
    assert summary(path)["t_end"] == 6e-5
    # spectra take the rows on the grid: one sample step
    stored = open_history(path)
    assert stored.uniform().rows == stored.rows - 1
    assert main(["plot", "spectrum", str(path), "-o", str(tmp_path / "s.png")]) == 0


def test_every_larger_than_the_run_stores_its_end(tmp_path, capsys):
    path = bar(tmp_path, "bar.h5", "solver.t_end=2e-5", "output.every=1000000")
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "t_end         2e-05 s" in out and "rows          2\n" in out
    d = summary(path)
    assert d["t_end"] == 2e-5 and d["steps"] == 2


@pytest.mark.slow
def test_resumed_past_an_end_row_is_the_fresh_run(tmp_path):
    sets = ["output.every=7", "solver.chunk=70"]
    whole = bar(tmp_path, "whole.h5", "solver.t_end=1.2e-4", *sets)
    part = bar(tmp_path, "part.h5", "solver.t_end=6e-5", *sets)
    bar(tmp_path, "part.h5", "solver.t_end=1.2e-4", *sets, resume=True)
    assert_same(series(whole), series(part))
    with h5py.File(part, "r") as f:
        assert f.attrs["end_row"] and f["time"][-1] == 1.2e-4


@pytest.mark.slow
def test_a_resumed_history_keeps_the_case_it_was_resumed_with(tmp_path):
    path = bar(tmp_path, "bar.h5", "solver.t_end=6e-5")
    bar(tmp_path, "bar.h5", "solver.t_end=1.2e-4", "solver.drift_tolerance=0.1", resume=True)
    stored = open_history(path)
    assert stored.meta["overrides"] == ["solver.t_end=1.2e-4", "solver.drift_tolerance=0.1"]
    case = stored.case()
    assert case.solver.t_end == 1.2e-4 and case.solver.drift_tolerance == 0.1
    # and a later resume checks against it: the same longer run again is no change
    bar(tmp_path, "bar.h5", "solver.t_end=1.2e-4", "solver.drift_tolerance=0.1", resume=True)
    assert summary(path)["t_end"] == 1.2e-4


@pytest.mark.slow
def test_the_exponential_schemes_shortened_step_lands_on_t_end(tmp_path):
    """The small pad and disc tapped, ended half way through a step: its last step, with
    propagators of its own, lands where a run at an eighth of the step is at t_end within the
    error of its whole steps (1.05 and 0.99 times the last one's measured; the whole step's
    propagators there were 8.6 times it off, a quarter of what half a step moves the rim)."""
    dt = 3.125e-6
    t_end = 200.5 * dt
    base = ["loads.tap.vector=[0.0,0.0,-0.02]", "output.every=1"]
    coarse = run(small(*base, f"solver.t_end={t_end!r}"), tmp_path / "coarse.h5")
    fine = run(small(*base, f"solver.t_end={t_end!r}", f"solver.dt={dt / 8!r}"),
               tmp_path / "fine.h5")
    assert coarse.status == fine.status == "complete" and coarse.dt == dt
    with h5py.File(tmp_path / "coarse.h5", "r") as a, h5py.File(tmp_path / "fine.h5") as b:
        assert a["time"][-1] == t_end and b["time"][-1] == pytest.approx(t_end, rel=1e-12)
        for name in a["sensors"]:
            x, y = a["sensors"][name][()], b["sensors"][name][()]
            # the coarse run's error at its last two whole steps, then at t_end
            whole = max(abs(x[-2] - y[-5]), abs(x[-3] - y[-13]))
            assert abs(x[-1] - y[-1]) < 2 * whole, name
