"""The setup-time estimate of `--dry-run` (issue 47): learned from the setups this machine has
timed (transient.setuptimes), never from figures measured on another."""
import json
import math
import platform
from pathlib import Path

import pytest

import transient
from transient import setuptimes
from transient.case.loading import load

from small_cases import PAD_DISC

PAD = str(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml")


@pytest.fixture
def log(tmp_path, monkeypatch):
    path = tmp_path / "setups.jsonl"
    monkeypatch.setenv("TRANSIENT_SETUP_LOG", str(path))
    return path


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
    (line,) = [json.loads(x) for x in log.read_text().splitlines()]
    assert line["path"] == "assembled/cea" and line["host"] == platform.node()
    assert line["entries"] > 0 and line["fine_points"] > 0 and line["seconds"] > 0
    dry = transient.dry_run(case, "cea")["setup_seconds"]
    # one size: its own time at both exponents, the same size
    assert dry["setups"] == 1
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
    (line,) = [json.loads(x) for x in log.read_text().splitlines()]
    assert line["path"] == "modes" and line["seconds"] > 0
    assert transient.dry_run(case, "modes")["setup_seconds"]["setups"] == 1
