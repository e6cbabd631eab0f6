"""The setup-time estimate of `--dry-run` and of a setup's start (issue 47): learned from the
setups this machine has timed (transient.setuptimes), never from figures measured on another;
before any, from this machine's calibration (transient.calibration). The calibration's seconds
are injected but in the tests that say so, so that every check holds whatever the machine's
speed."""
import json
import math
import platform
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import transient
from transient import calibration, progress, setuptimes
from transient.case.loading import load
from transient.case.sizes import entries, generated_cells
from transient.cli import main

from small_cases import PAD_DISC

PAD = str(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml")
MEASURE = setuptimes.measure          # the real one: a child process timing the calibration
KINDS = ["assembled/cea", "assembled/run", "components/cea", "components/run", "full/cea",
         "full/run", "modes"]


@pytest.fixture
def log(tmp_path, monkeypatch):
    """A log of the test's own, whose calibration fails: the estimate is the log's alone."""
    path = tmp_path / "setups.jsonl"
    monkeypatch.setenv("TRANSIENT_SETUP_LOG", str(path))
    monkeypatch.setattr(setuptimes, "measure", lambda path_kind: None)
    return path


@pytest.fixture
def measured(log, monkeypatch):
    """The log's calibration 2 s at 1 M entries, its measures counted."""
    calls = []

    def measure(path_kind):
        calls.append(path_kind)
        return {"entries": 1e6, "seconds": 2.0}
    monkeypatch.setattr(setuptimes, "measure", measure)
    return calls


def test_a_power_law_over_two_sizes_is_fitted_and_one_size_gives_a_range(log):
    assert setuptimes.estimate("assembled/cea", 1e6) is None
    setuptimes.record("assembled/cea", 1e6, 100, 2.0)
    one = setuptimes.estimate("assembled/cea", 8e6)
    low, high = (2.0 * 8.0 ** p for p in setuptimes.EXPONENTS)
    assert one["setups"] == 1
    assert one["low"] == pytest.approx(low, rel=1e-12)
    assert one["high"] == pytest.approx(high, rel=1e-12)
    setuptimes.record("assembled/cea", 4e6, 100, 2.0 * 4.0 ** 1.5)
    two = setuptimes.estimate("assembled/cea", 8e6)
    assert two["setups"] == 2
    assert two["low"] == pytest.approx(2.0 * 8.0 ** 1.5, rel=1e-9)
    assert two["high"] == pytest.approx(2.0 * 8.0 ** 1.5, rel=1e-9)


def test_other_hosts_other_kinds_and_damaged_lines_are_not_read(log):
    setuptimes.record("components/cea", 1e6, 100, 50.0)
    with open(log, "a") as f:
        f.write(json.dumps({"host": platform.node() + "-other", "path": "assembled/cea",
                            "entries": 1e6, "fine_points": 1, "seconds": 1.0}) + "\n")
        f.write('{"host": "cut sh\n')
    assert setuptimes.estimate("assembled/cea", 1e6) is None
    assert setuptimes.estimate("components/cea", 1e6)["setups"] == 1


def test_a_cea_records_its_setup_and_the_dry_run_estimates_from_it(log):
    case = load(PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.4"])
    assert transient.dry_run(case, "cea")["setup_seconds"] is None
    transient.cea(case)
    (line,) = setups(log)
    assert line["path"] == "assembled/cea" and line["host"] == platform.node()
    assert line["entries"] > 0 and line["fine_points"] > 0 and line["seconds"] > 0
    dry = transient.dry_run(case, "cea")["setup_seconds"]
    # one size: its own time at both exponents, the same size
    assert dry["setups"] == 1 and dry["source"] == "setups"
    assert math.isclose(dry["low"], line["seconds"]) and math.isclose(dry["high"],
                                                                     line["seconds"])
    assert transient.dry_run(case, "run")["setup_seconds"] is None     # a run's is its own


def test_off_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("TRANSIENT_SETUP_LOG", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    setuptimes.record("assembled/run", 1e6, 1, 1.0)
    assert list(tmp_path.iterdir()) == []


def test_the_modes_command_records_its_time_and_its_dry_run_reads_it(log):
    case = load(PAD, PAD_DISC)
    assert transient.dry_run(case, "modes")["setup_seconds"] is None
    transient.modes(case)
    (line,) = setups(log)
    assert line["path"] == "modes" and line["seconds"] > 0
    assert transient.dry_run(case, "modes")["setup_seconds"]["setups"] == 1


def setups(log):
    """The log's setups (its calibrations' lines, a failed one too, left out)."""
    return [json.loads(x) for x in log.read_text().splitlines() if "calibration" not in x]


def calibrations(log):
    return [json.loads(x) for x in log.read_text().splitlines() if "calibration" in x]


def test_the_calibration_is_made_once_kept_in_the_log_and_scaled_at_both_exponents(log,
                                                                                    measured):
    said = []
    found = setuptimes.estimate("assembled/cea", 8e6, announce=said.append)
    low, high = (2.0 * 8.0 ** p for p in setuptimes.GROWTH)
    assert found["source"] == "calibration" and found["setups"] == 0
    assert found["low"] == pytest.approx(low, rel=1e-12)
    assert found["high"] == pytest.approx(high, rel=1e-12) and high > low
    assert measured == ["assembled/cea"] and len(said) == 1 and "calibrating" in said[0]
    (line,) = [json.loads(x) for x in log.read_text().splitlines()]
    assert line["calibration"] == "assembled/cea" and "path" not in line   # no setup's line
    assert line["version"] == transient.__version__ and line["host"] == platform.node()
    # read back: the next estimate (another size) measures nothing and says nothing
    again = setuptimes.estimate("assembled/cea", 64e6, announce=said.append)
    assert again["low"] == pytest.approx(2.0 * 64.0 ** min(setuptimes.GROWTH))
    assert again["high"] == pytest.approx(2.0 * 64.0 ** max(setuptimes.GROWTH))
    assert again["high"] / found["high"] > again["low"] / found["low"] > 1
    assert measured == ["assembled/cea"] and len(said) == 1
    # smaller than the calibration: at most its seconds, at least scaled at the steepest
    small = setuptimes.estimate("assembled/cea", 0.25e6)
    assert small["high"] == pytest.approx(2.0)
    assert small["low"] == pytest.approx(2.0 * 0.25 ** max(setuptimes.GROWTH))
    # each path its own
    setuptimes.estimate("components/cea", 1e6)
    assert measured == ["assembled/cea", "components/cea"] and len(calibrations(log)) == 2


def test_a_new_version_or_an_old_calibration_is_measured_again(log, measured, monkeypatch):
    setuptimes.estimate("modes", 1e6)
    monkeypatch.setattr(transient, "__version__", transient.__version__ + ".post1")
    setuptimes.estimate("modes", 1e6)
    setuptimes.estimate("modes", 1e6)
    assert measured == ["modes", "modes"]
    versions = [r["version"] for r in calibrations(log)]
    assert versions[1] == transient.__version__ != versions[0]
    late = time.time() + setuptimes.MAX_AGE + 1.0
    assert setuptimes.calibrated(setuptimes._records(), "modes", transient.__version__,
                                 now=late) is None


def test_setups_timed_here_come_before_the_calibration(log, measured):
    setuptimes.estimate("assembled/run", 4e6)
    setuptimes.record("assembled/run", 4e6, 100, 10.0)
    found = setuptimes.estimate("assembled/run", 4e6)
    assert found["source"] == "setups" and found["setups"] == 1
    assert found["low"] == pytest.approx(10.0) and found["high"] == pytest.approx(10.0)
    assert measured == ["assembled/run"]


def test_off_estimates_nothing_and_never_calibrates(tmp_path, monkeypatch, measured):
    monkeypatch.setenv("TRANSIENT_SETUP_LOG", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert setuptimes.estimate("assembled/cea", 8e6) is None
    assert measured == [] and list(tmp_path.iterdir()) == []


def test_a_failed_calibration_gives_no_estimate_and_no_error(log, monkeypatch, capsys):
    # the child process killed at its timeout, as one that hangs or takes too long
    monkeypatch.setattr(setuptimes, "measure", MEASURE)
    monkeypatch.setattr(setuptimes, "TIMEOUT", 0.01)
    assert setuptimes.estimate("assembled/cea", 8e6) is None
    # kept as failed: not tried again (each try may take TIMEOUT) within MAX_AGE
    assert json.loads(log.read_text().splitlines()[-1])["failed"]
    tries = []
    monkeypatch.setattr(setuptimes, "measure", lambda path_kind: tries.append(path_kind))
    assert setuptimes.estimate("assembled/cea", 8e6) is None and not tries
    assert setuptimes.estimate("assembled/cea", 8e6, calibrate=False) is None
    args = ["cea", PAD, "--dry-run"] + [a for s in PAD_DISC for a in ("--set", s)]
    assert main(args) == 0
    assert "setup: no estimate" in capsys.readouterr().out


def test_a_damaged_or_foreign_line_is_not_read(log, measured):
    log.write_bytes(b"\xff\xfe not text\n")
    with open(log, "a") as f:
        f.write('{"host": "cut sh\n' + json.dumps(
            {"host": platform.node() + "-other", "calibration": "assembled/cea",
             "version": transient.__version__, "entries": 1, "seconds": 1.0,
             "time": time.time()}) + "\nnot json\n[1, 2]\n" + json.dumps(
            {"host": platform.node(), "calibration": "assembled/cea"}) + "\n")
    setuptimes.estimate("assembled/cea", 2e6)
    assert measured == ["assembled/cea"]
    assert setuptimes.estimate("assembled/cea", 1e6)["low"] == pytest.approx(2.0)


@pytest.mark.parametrize("path_kind", KINDS)
def test_the_calibration_is_pad_disc_coarser_on_the_path_asked(path_kind):
    case = calibration.case_of(path_kind)
    shipped = load(PAD)
    for name, part in case.parts.items():
        mine = {k: v for k, v in part.mesh.params.items() if k != "divisions"}
        theirs = {k: v for k, v in shipped.parts[name].mesh.params.items() if k != "divisions"}
        assert mine == theirs
    reduction = case.solver.reduction
    method = path_kind.split("/")[0]
    assert reduction.enabled == (method != "full")
    assert method not in ("assembled", "components") or reduction.method == method
    assert case.contact["pad_disc"].friction.mu > 0          # a cea's linearization has work
    # pad_disc's divisions quartered: 1/64 of its dofs
    for name in ("disc", "pad"):
        theirs = shipped.parts[name].mesh.params["divisions"]
        assert list(case.parts[name].mesh.params["divisions"]) == [
            max(1, int(d / 4 + 0.5)) for d in theirs]


def test_the_dry_run_on_a_fresh_log_says_its_estimate_is_the_calibration_s(log, measured,
                                                                           capsys):
    args = ["cea", PAD, "--dry-run"] + [a for s in PAD_DISC for a in ("--set", s)]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "(from this machine's calibration)" in captured.out
    assert "calibrating this machine's assembled/cea setup" in captured.err
    assert main(args) == 0                              # kept: not made again, not said
    captured = capsys.readouterr()
    assert "calibrating" not in captured.err and measured == ["assembled/cea"]
    assert main(args + ["--json"]) == 0
    d = json.loads(capsys.readouterr().out)["setup_seconds"]
    assert d["source"] == "calibration" and d["low"] < d["high"]


def model_of(size):
    """A stand-in for a Model of `size` element-matrix entries (hex20 cells), as
    setuptimes.announce reads it."""
    cells = np.zeros((math.ceil(size / 3600), 20))
    return SimpleNamespace(parts={"block": SimpleNamespace(mesh=SimpleNamespace(
        cells={"hex20": cells}))})


def said(seconds):
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def test_a_long_setup_says_its_estimate_as_it_starts(log, measured, capsys):
    short, long = model_of(setuptimes.LONG / 2), model_of(setuptimes.LONG)
    setuptimes.announce("assembled/run", long)         # not on a terminal: nothing
    assert capsys.readouterr().err == "" and measured == []
    with progress.shown():
        setuptimes.announce("assembled/run", short)    # short: no calibration made for it
        assert capsys.readouterr().err == "" and measured == []
        setuptimes.announce("assembled/run", long)     # long: calibrated, said, estimated
        err = capsys.readouterr().err.splitlines()
        assert measured == ["assembled/run"] and len(err) == 2 and "calibrating" in err[0]
        size = entries([(len(long.parts["block"].mesh.cells["hex20"]), 20)])
        low, high = (said(2.0 * (size / 1e6) ** p) for p in setuptimes.GROWTH)
        assert err[1] == (f"setup: about {low} to {high} (from this machine's calibration)"
                          " ...")
        setuptimes.announce("assembled/run", short)    # known now: said, not made again
        assert "setup: about" in capsys.readouterr().err and measured == ["assembled/run"]


def test_a_setup_on_a_terminal_says_its_estimate_before_its_stages(log, measured, capsys):
    case = load(PAD, PAD_DISC)
    setuptimes.estimate("assembled/run", 1e6)           # the calibration, kept
    with progress.shown():
        transient.prepare(case)
    err = capsys.readouterr().err.splitlines()
    said = [i for i, line in enumerate(err) if line.startswith("setup: about")]
    contact = err.index("stage contact ...")
    assert len(said) == 1 and said[0] < contact
    assert "from this machine's calibration" in err[said[0]]


def test_a_calibration_the_modes_make_is_no_time_of_theirs(log, measured, monkeypatch):
    # every calibration takes 1000 s on the clock the modes are timed by: none of it recorded
    from transient.solve import tied
    offset = [0.0]
    clock = SimpleNamespace(perf_counter=lambda: time.perf_counter() + offset[0])
    monkeypatch.setattr(tied, "time", clock)
    counted = setuptimes.measure

    def slow(path_kind):
        offset[0] += 1000.0
        return counted(path_kind)
    monkeypatch.setattr(setuptimes, "measure", slow)
    monkeypatch.setattr(setuptimes, "LONG", 0)          # calibrated before any setup
    with progress.shown():
        transient.modes(load(PAD, PAD_DISC))
    (line,) = [json.loads(x) for x in log.read_text().splitlines() if "path" in x]
    assert measured == ["modes"] and offset[0] == 1000.0
    assert line["path"] == "modes" and 0 < line["seconds"] < 1000.0


@pytest.mark.slow
def test_a_real_calibration_times_the_package_s_setup_and_changes_no_result(log, monkeypatch,
                                                                            capsys):
    monkeypatch.setattr(setuptimes, "measure", MEASURE)
    monkeypatch.setattr(setuptimes, "LONG", 0)          # calibrated as the setup starts
    case = load(PAD, PAD_DISC)
    with progress.shown():
        calibrated = transient.prepare(case)
    assert "(from this machine's calibration) ..." in capsys.readouterr().err
    (made,) = calibrations(log)
    coarse = calibration.case_of("assembled/run")
    assert made["entries"] == entries([generated_cells(p.mesh) for p in coarse.parts.values()])
    assert made["seconds"] > 0 and made["calibration"] == "assembled/run"
    # the child's setups recorded nothing, this process's its one
    assert [json.loads(x).get("path") for x in log.read_text().splitlines()] == [
        None, "assembled/run"]
    # bit for bit with a setup that made none: the calibration ran in a process of its own
    monkeypatch.setenv("TRANSIENT_SETUP_LOG", "off")
    with progress.shown():
        plain = transient.prepare(case)
    a, b = calibrated.system, plain.system
    for name in ("omega2", "damp", "C", "T", "Ct", "tangent", "patterns"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.array_equal(calibrated.state.array, plain.state.array)
