"""tests/fuzz_cases.py: its TOML writer and its outcome classes, then a fixed seed of mutants
through the command line, each of which must exit 0, 2 or 3 and none end in a FAILURE (a
traceback, a warning, an error message that is not one line 'error: ...', a crash, the memory
bound, a timeout). No outcome depends on the machine's speed: the Ctrl-C mutations (where
SIGINT lands is a matter of timing) are left out, and the timeout only guards against a hung
mutant (the slowest take a few seconds)."""
import math
import tomllib

import pytest

import fuzz_cases as fuzz  # a sibling in tests/

SEED = 2026
MUTANTS = 400


@pytest.mark.parametrize("base", sorted(fuzz.BASES))
def test_base_cases_round_trip_through_the_toml_writer(base):
    data = fuzz.base_case(base)
    assert tomllib.loads(fuzz.dumps(data)) == data


def test_control_characters_reach_the_package_as_themselves():
    data = {"title": "a\nb\x00\x1b\u2028\x7f\x85", "t": {"x\ny": [1.5, 2 ** 70, True, {}],
                                                       "": {"k": -math.inf}}, "e": {}}
    text = fuzz.dumps(data)
    assert text.isascii()
    assert tomllib.loads(text) == data


def test_outcomes_of_the_contract_and_failures_beside_them():
    ok = {"code": 2, "stderr": "error: /c.toml: solver.t_end: expected a number\n"}
    assert fuzz.classify(ok) == (2, [])
    assert fuzz.classify({"code": 0, "stderr": ""}) == (0, [])
    assert fuzz.classify({"code": 130, "stderr": "interrupted\n"}) == (130, [])
    cases = [({"code": 1, "stderr": ""}, "exit code 1"),
             ({"code": 2, "stderr": "error: /c.toml: x\nmore\n"}, "error message of several"),
             ({"code": 2, "stderr": "c.toml: x\n"}, "error message not starting"),
             ({"code": 2, "stderr": "error: no file named\n"}, "error message naming no file"),
             ({"code": 0, "stderr": "", "warnings": ["RuntimeWarning: overflow (a.py:1)"]},
              "warning: RuntimeWarning"),
             ({"code": None, "exception": "ValueError: x"}, "uncaught exception: ValueError"),
             ({"code": None, "exception": "MemoryError: "}, "memory bound"),
             ({"code": 0, "stderr": "Traceback (most recent call last):\n"}, "traceback"),
             ({"timeout": 60.0}, "timeout"), ({"crash": -11}, "crash"),
             ({"code": 0, "stderr": "", "unraisable": ["ValueError in <f>"]}, "unraisable")]
    for result, failure in cases:
        outcome, failures = fuzz.classify(result)
        assert outcome == "FAILURE" and any(f.startswith(failure) for f in failures), result
    # Ctrl-C landing in a finalizer is Python's (ignored and printed), not the package's
    interrupted = {"code": 0, "stderr": "", "interrupted": True,
                   "unraisable": ["KeyboardInterrupt in <function remove>"]}
    assert fuzz.classify(interrupted) == (0, [])
    # and so is Ctrl-C while main parses its arguments, before the command's own handling
    early = {"code": None, "exception": "KeyboardInterrupt: ", "interrupted": True,
             "before_command": True}
    assert fuzz.classify(early) == (130, [])
    assert fuzz.classify(dict(early, before_command=False))[0] == "FAILURE"


def test_a_mutant_is_the_same_whatever_ran_before_it(tmp_path):
    # two_bars makes no base history, so every mutant of it is a case mutant
    made = [fuzz.make_mutant(SEED, i, ["two_bars"], tmp_path / f"{run}{i}", None)
            for run in ("a", "b") for i in (3, 7)]
    for first, again in zip(made[:2], made[2:]):
        assert first.notes == again.notes

        def text(m):
            # paths the mutations write into the case name the mutant's own directory
            return (m.directory / "case.toml").read_bytes().replace(bytes(m.directory), b"")
        assert text(first) == text(again)


@pytest.mark.slow
def test_fixed_seed_has_no_failure(tmp_path):
    report = fuzz.fuzz(MUTANTS, SEED, keep=tmp_path, timeout=fuzz.TIMEOUT_S, interrupts=False)
    assert sum(report["outcomes"].values()) == MUTANTS
    # a seed that ran nothing to its end would test nothing but the validation
    assert report["outcomes"].get("0", 0) > MUTANTS // 20
    assert not report["failures"], fuzz.format_report(report)
    assert set(report["outcomes"]) <= {"0", "2", "3"}


SWEEP_MUTANTS = 20


def test_sweep_mutants_leave_the_other_mutants_as_they_were(tmp_path):
    # a share of sweep mutants is drawn apart: every other mutant of the seed is unchanged
    for i in range(12):
        if fuzz.random.Random(f"{SEED}:{i}:sweep").random() < 0.5:
            continue
        old = fuzz.make_mutant(SEED, i, ["two_bars"], tmp_path / f"a{i}", None)
        new = fuzz.make_mutant(SEED, i, ["two_bars"], tmp_path / f"b{i}", None, sweeps=0.5)
        assert new.notes == old.notes and new.argv[0] == old.argv[0] and new.folder is None


def test_what_a_sweep_must_not_do_is_a_failure(tmp_path):
    import json
    assert fuzz.classify({"code": 2, "stderr": "error: /o: --out: x\n", "replaced": ["/o/a"]}
                         )[0] == "FAILURE"
    assert fuzz.classify({"code": 0, "stderr": "", "mislabelled": ["v-1: v-1.json"]}
                         )[0] == "FAILURE"
    # a row whose output was made with other values is found
    (tmp_path / "v-1.json").write_text(json.dumps({"overrides": ["a.b=5e13", "c=1"]}))
    (tmp_path / "v-2.json").write_text(json.dumps({"overrides": ["c=1", "a.b=1.0"]}))
    (tmp_path / "sweep.json").write_text(json.dumps({"parameters": ["a.b"], "rows": [
        {"variant": "v-1", "status": "complete", "a.b": 1.0, "output": "v-1.json"},
        {"variant": "v-2", "status": "complete", "a.b": 1.0, "output": "v-2.json"}]}))
    assert fuzz.mislabelled(tmp_path) == ["v-1: v-1.json"]


@pytest.mark.slow
def test_sweep_mutants_have_no_failure(tmp_path):
    """A fixed seed of sweep mutants (a campaign's command line mutated, files of the user in
    its folder, a second campaign, a resume after a changed --param list or a killed sweep):
    each ends in exit 0 or 2 with no FAILURE, leaves the files it did not write as they were,
    and names each row's own output."""
    report = fuzz.fuzz(SWEEP_MUTANTS, SEED, keep=tmp_path, timeout=fuzz.TIMEOUT_S,
                       interrupts=False, sweeps=1.0)
    assert not report["failures"], fuzz.format_report(report)
    assert set(report["outcomes"]) <= {"0", "2", "3"}
    assert report["outcomes"].get("0", 0) >= 3 and report["outcomes"].get("2", 0) >= 3


def test_a_wait_for_the_compile_lock_is_not_the_mutants():
    # another process compiling the same kernels makes a command say so on stderr (jit)
    wait = "waiting for the Numba compile lock /tmp/numba/.compile.lock, held by pid 1\n"
    assert fuzz.classify({"code": 0, "stderr": wait}) == (0, [])
    error = "error: /c.toml: x: expected y\n"
    assert fuzz.classify({"code": 2, "stderr": wait + error}) == (2, [])
    assert fuzz.classify({"code": 0, "stderr": wait + "more\n"})[0] == "FAILURE"


def test_analyses_are_among_the_mutants(tmp_path):
    """cea and plot cea (--mu ranges bad, huge or infinite) come with the case mutants."""
    # (two_bars makes no base history: every mutant of it is a case mutant)
    made = [fuzz.make_mutant(SEED, i, ["two_bars"], tmp_path / f"m{i}", None)
            for i in range(200)]
    cea = [m for m in made if m.argv[0] == "cea"]
    plots = [m for m in made if m.argv[:2] == ["plot", "cea"]]
    assert len(cea) > 10 and len(plots) > 5
    assert all("--out" in m.argv for m in plots)
    assert any(a.startswith("--mu=") for m in plots for a in m.argv)
