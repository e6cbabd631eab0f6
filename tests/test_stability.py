"""studies/study_stability.py: its classification of a run's outcome, and the outcomes of its
--quick subset pinned (every scenario stable, refused or aborted, never FAILED)."""
from pathlib import Path

import numpy as np
import pytest

from transient.io.history import History

import study_stability as study  # benchmarks/, studies/, tools/: pytest's pythonpath (setup.cfg)

# what the --quick scenarios do today; a set where either outcome is acceptable (an abort on
# the energy balance or the critical step that a better integrator may turn into a stable run)
EXPECTED = {
    "dt/auto": {"stable"},
    "dt/0.5x": {"stable"},
    "dt/0.9x": {"refused"},
    "dt/0.9x forced": {"stable"},
    "dt/1.2x": {"refused"},
    "dt/1.2x forced": {"aborted", "stable"},
    "lambda/bar lambda=1e4": {"stable"},
    "lambda/bar lambda=1e8": {"aborted", "stable"},
    "lambda/pad lambda=1e8": {"stable"},
    "p0/bar p0=1e6": {"stable"},
    "p0/pad p0=1e3": {"stable"},
    "penetration/exponential 100/lambda": {"aborted", "stable"},
    "penetration/linear 1e-4 m": {"aborted", "stable"},
    "speed/linear 50 m/s": {"stable"},
    "open/bar linear": {"stable"},
    "no contact/bar explicit": {"stable"},
    "eps/fine eps=1e-12": {"stable"},
    "eps/greedy eps=1e-12": {"stable"},
    "eps/sampled eps=1e-12": {"stable"},
    "sampling/sampled tol=1e0": {"stable"},
    "tap/pad 8 kN tap, implicit": {"aborted", "stable"},
    "m/greedy m=1": {"stable"},
    f"m/greedy m=1000 (> {study.PAD_FINE_POINTS} fine points)": {"refused"},
    "implicit/bar dt=5x": {"stable"},
    "implicit/pad": {"stable"},
    "scheme/exponential on the full bar": {"refused"},
}


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    """The --quick subset, run once (about 20 child runs of a second each)."""
    out = study.study(quick=True, directory=tmp_path_factory.mktemp("stability"))
    return {row["id"]: row for row in out}


def test_quick_subset_covers_every_axis():
    all_axes = {s.axis for s in study.scenarios()}
    quick = [s for s in study.scenarios() if s.quick]
    assert {s.axis for s in quick} == all_axes
    assert {s.id for s in quick} == set(EXPECTED)
    ids = [s.id for s in study.scenarios()]
    assert len(ids) == len(set(ids))


@pytest.mark.slow
def test_no_outcome_failed(rows):
    failed = {k: (r["command"], r["evidence"]) for k, r in rows.items()
              if r["outcome"] == "FAILED"}
    assert not failed


@pytest.mark.slow
def test_outcomes_are_those_pinned(rows):
    assert set(rows) == set(EXPECTED)
    wrong = {k: (r["outcome"], study.note(r)) for k, r in rows.items()
             if r["outcome"] not in EXPECTED[k]}
    assert not wrong


@pytest.mark.slow
def test_dt_above_the_critical_step_is_refused_by_name(rows):
    row = rows["dt/1.2x"]
    assert row["outcome"] == "refused" and row["exit_code"] == 2
    assert "solver.dt" in row["reason"] and "critical step" in row["reason"]
    assert "force_dt" in row["reason"]


@pytest.mark.slow
def test_dt_above_the_contacts_step_is_refused_by_name(rows):
    # stable, but the penalty runs at omega_c dt = 1.13 where impacts need not keep their
    # energy (dynamics.critical.CONTACT_OMEGA_DT)
    row = rows["dt/0.9x"]
    assert row["outcome"] == "refused" and row["exit_code"] == 2
    assert "solver.dt" in row["reason"] and "contact.wall.k" in row["reason"]
    assert "omega_c dt = 1.13" in row["reason"] and "force_dt" in row["reason"]


@pytest.mark.slow
def test_dt_below_the_critical_step_is_stable(rows):
    for key in ("dt/auto", "dt/0.5x", "dt/0.9x forced"):
        row = rows[key]
        assert row["outcome"] == "stable" and row["status"] == "complete"
        assert 0.0 <= row["energy_drift"] < 0.01 and row["steps"] > 500
    for f in (0.5, 0.9):
        forced = " forced" if f == 0.9 else ""
        assert rows[f"dt/{f}x{forced}"]["dt"] == pytest.approx(f * rows["dt/auto"]["dt_critical"])
    # the automatic step: the contact's, 0.56 x critical on the shipped bar
    assert rows["dt/auto"]["dt"] == pytest.approx(0.556 * rows["dt/auto"]["dt_critical"], rel=0.01)


@pytest.mark.slow
def test_forced_dt_above_critical_never_leaves_a_nan_in_a_complete_file(rows):
    row = rows["dt/1.2x forced"]
    assert row["outcome"] in ("aborted", "stable")
    if row["outcome"] == "aborted":
        assert row["status"].startswith("aborted:") and row["rows"] > 1


@pytest.mark.slow
def test_scenes_without_contact_are_stable_with_a_tiny_drift(rows):
    for key in ("open/bar linear", "no contact/bar explicit"):
        row = rows[key]
        assert row["outcome"] == "stable"
        assert row["energy_drift"] < 1e-9


@pytest.mark.slow
def test_greedy_m_above_the_fine_points_is_refused_by_name(rows):
    row = rows[f"m/greedy m=1000 (> {study.PAD_FINE_POINTS} fine points)"]
    assert row["outcome"] == "refused"
    assert "contact.pad_disc.points" in row["reason"] and "1000" in row["reason"]
    assert rows["m/greedy m=1"]["points"] == 1


@pytest.mark.slow
def test_aborts_keep_their_rows_and_say_why(rows):
    for key, row in rows.items():
        if row["outcome"] == "aborted":
            assert row["exit_code"] == 3 and row["rows"] > 0 and row["reason"], key


@pytest.mark.slow
def test_table_shows_every_row(rows):
    lines = [study.format_row(r, 120) for r in rows.values()]
    assert all(r["id"] in line and r["outcome"] in line for r, line in zip(rows.values(), lines))


# the classification itself, on made-up results

def _history(path, status, values):
    with History.create(path, {"dt": 1e-6}, {"time": (), "energy/kinetic": ()}) as h:
        h.append({"time": np.arange(len(values), dtype=float), "energy/kinetic": values})
        h.finish(status)
    return path


def _result(code, path, stdout="", stderr=""):
    return study.Result(code, stdout, stderr, Path(path))


def test_classify_stable_refused_aborted(tmp_path):
    ok = _history(tmp_path / "ok.h5", "complete", [1.0, 1.0, 1.0])
    outcome, d = study.classify(_result(0, ok, '{"status": "complete", "steps": 2}'))
    assert outcome == "stable" and d["energy_drift"] == 0.0 and d["rows"] == 3
    outcome, d = study.classify(_result(2, tmp_path / "none.h5",
                                        stderr="error: case.toml: solver.dt: too large\n"))
    assert outcome == "refused" and d["reason"] == "case.toml: solver.dt: too large"
    stopped = _history(tmp_path / "stopped.h5", "aborted: state not finite", [1.0, 1.0])
    outcome, d = study.classify(_result(3, stopped, stderr="error: run aborted: state not "
                                        "finite\n"))
    assert outcome == "aborted" and d["reason"] == "state not finite"


def test_classify_fails_what_is_neither(tmp_path):
    nan = _history(tmp_path / "nan.h5", "complete", [1.0, np.nan, 1.0])
    outcome, d = study.classify(_result(0, nan, '{"status": "complete"}'))
    assert outcome == "FAILED" and "non-finite" in d["evidence"][0]
    outcome, d = study.classify(_result(2, tmp_path / "none.h5",
                                        stderr="error: one\nerror: two\n"))
    assert outcome == "FAILED" and "2 lines" in d["evidence"][0]
    outcome, d = study.classify(_result(1, tmp_path / "none.h5", stderr="Traceback (most "
                                        "recent call last):\n  File ...\nValueError: x\n"))
    assert outcome == "FAILED" and "traceback" in d["evidence"][0]
    outcome, d = study.classify(_result(-11, tmp_path / "none.h5"))
    assert outcome == "FAILED" and "SIGSEGV" in d["evidence"][0]
    drifted = _history(tmp_path / "drift.h5", "complete", [1.0, 2.0])
    outcome, d = study.classify(_result(0, drifted, '{"status": "complete"}'))
    assert outcome == "FAILED" and "drift" in d["evidence"][0]
    kept_nan = _history(tmp_path / "kept_nan.h5", "aborted: drift", [1.0, np.inf])
    outcome, d = study.classify(_result(3, kept_nan, stderr="error: run aborted: drift\n"))
    assert outcome == "FAILED" and "aborted file" in d["evidence"][0]
    outcome, d = study.classify(_result(2, drifted, stderr="error: refused after all\n"))
    assert outcome == "FAILED" and "rows" in d["evidence"][0]
