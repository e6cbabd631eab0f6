"""`transient sweep` follows `transient run`'s rules for its outputs: the folder is held by one
campaign at a time, nothing it did not write is replaced, what --resume makes of each stored
output follows the case it stores, campaign sizes are bounded before they are built, and bad
input is one line and exit 2 before any work (no cluster is started for it)."""
import json
import os
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

import transient.campaign.campaign as campaign
from transient.case.loading import load
from transient.cli import main
from transient.errors import CaseError
from transient.campaign.folder import LOCK, MARK, holding
from transient.campaign.outputs import plan
from transient.campaign.variants import make_variants, parse_parameter, variant_name

ROOT = Path(__file__).resolve().parent.parent
TWO = ROOT / "cases" / "two_bars.toml"
K = "contact.impact.k"
SHORT = ["solver.t_end=2e-5"]
NAME = variant_name({K: 1e14})


class Started(Exception):
    """What the cluster's start raises here: every check before it passed."""


@pytest.fixture
def no_cluster(monkeypatch):
    def start(*args):
        raise Started
    monkeypatch.setattr(campaign, "client_for", start)


def sweep_args(out, *more, kind="run"):
    return ["sweep", str(TWO), "--param", f"{K}=[1e14]", "--kind", kind, "--workers", "1",
            "--out", str(out), *[a for s in SHORT for a in ("--set", s)], *more]


def one_error(capsys):
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, err
    return err


def test_out_naming_a_file_or_nothing_is_refused(tmp_path, capsys, no_cluster):
    path = tmp_path / "notes.txt"
    path.write_text("mine")
    assert main(sweep_args(path)) == 2
    assert "is a file: expected a folder" in one_error(capsys)
    assert path.read_text() == "mine"
    assert main(sweep_args("")) == 2
    assert "--out: an empty name" in one_error(capsys)


def foreign_hdf5(path):
    with h5py.File(path, "w") as f:
        f["time"] = np.arange(3.0)


@pytest.mark.parametrize("name, make, kind", [
    ("sweep.csv", lambda p: p.write_text("a,b\n1,2\n"), "run"),
    ("sweep.json", lambda p: p.write_text("my notes"), "cea"),
    (f"{NAME}.h5", foreign_hdf5, "run"),
    (f"{NAME}.h5", lambda p: p.write_text("x,y\n"), "both"),
    (f"{NAME}.json", lambda p: p.write_text('{"modes": []}'), "cea"),
    (f"{NAME}.json", lambda p: p.mkdir(), "both"),
    (LOCK, lambda p: p.write_text("my lock notes"), "run"),
])
def test_a_file_this_package_did_not_write_is_never_replaced(tmp_path, capsys, no_cluster,
                                                             name, make, kind):
    out = tmp_path / "out"
    out.mkdir()
    make(out / name)
    before = sorted((p.name, p.is_dir() or p.read_bytes()) for p in out.iterdir())
    assert main(sweep_args(out, kind=kind)) == 2
    err = one_error(capsys)
    assert f"error: {out / name}: --out: " in err and "not" in err
    assert sorted((p.name, p.is_dir() or p.read_bytes()) for p in out.iterdir()) == before


def test_the_tables_of_an_earlier_campaign_are_its_own(tmp_path, no_cluster):
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.csv").write_text("variant,status,seconds,a\nv000,complete,1.5,2\n")
    (out / "sweep.json").write_text(json.dumps({"kind": "run", "parameters": ["a"],
                                                "rows": []}))
    (out / f"{NAME}.h5").write_bytes(b"")     # what a writer killed in its setup leaves
    with pytest.raises(Started):
        main(sweep_args(out))


def test_a_second_campaign_is_refused_naming_the_holder(tmp_path, capsys, no_cluster):
    out = tmp_path / "out"
    with holding(Path(out), "transient sweep first --out there"):
        assert main(sweep_args(out)) == 2
        err = one_error(capsys)
        assert f"error: {out}: --out: another campaign holds this folder (pid {os.getpid()}" \
            in err and "transient sweep first --out there" in err
    assert not (out / LOCK).exists()
    with pytest.raises(Started):
        main(sweep_args(out))
    assert not (out / LOCK).exists()


def test_a_killed_campaign_leaves_no_lock(tmp_path, no_cluster):
    out = tmp_path / "out"
    code = ("import sys, time; from pathlib import Path; from transient.campaign.folder import "
            "holding\nwith holding(Path(sys.argv[1]), 'killed'):\n print('held', flush=True)\n"
            " time.sleep(600)")
    child = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE,
                             text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert child.stdout.readline().strip() == "held"
    assert json.loads((out / LOCK).read_text())["command"] == "killed"
    child.send_signal(signal.SIGKILL)
    child.wait()
    with pytest.raises(Started):
        main(sweep_args(out))


@pytest.mark.parametrize("params, mode, words", [
    (["a.b=0:1:1000000000"], "--grid", "count 1000000000: more than 10000"),
    ([f"k{i}.x=0:1:16" for i in range(16)], "--grid", f"{16 ** 16} variants (more than"),
    (["a.b=0:1:101", "c.d=0:1:101"], "--grid", "10201 variants (more than"),
    (["a.b=[" + ",".join(map(str, range(20_000))) + "]", "c.d=0:1:20000"], "--zip",
     "20000 values (more than"),
    (["a.b=0:1:5", "c.d=[1,2]"], "--zip", "as long as each other"),
    (["a.b=0:inf:3"], "--grid", "start and stop must be finite"),
    (["a.b=nan:1:3"], "--grid", "start and stop must be finite"),
    (["a.b=[0.5, 0.50]"], "--grid", "a.b=0.5 is given twice"),
    (["a.b=0:0:3"], "--grid", "a.b=0.0 is given twice"),
    (["a.b={x = 1}"], "--grid", "a table value"),
])
def test_campaign_sizes_are_bounded_before_any_list_is_built(monkeypatch, capsys, tmp_path,
                                                             no_cluster, params, mode, words):
    """The count comes from the parameters' lengths (no linspace, no list of a billion), in
    Python integers (16**16 is not 0), for grid and zip; no warning on the way."""
    import transient.campaign.variants as variants
    made = []
    real = variants.np.linspace
    monkeypatch.setattr(variants.np, "linspace", lambda a, b, n: made.append(n) or real(a, b, n))
    argv = ["sweep", str(TWO), mode, "--out", str(tmp_path / "out")]
    for p in params:
        argv += ["--param", p]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(argv) == 2
    err = one_error(capsys)
    assert err.startswith("error: command line: --") and words in err, err
    assert all(n <= variants.MAX_VARIANTS for n in made)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("address", ["not an address", "", "tcp://host:port", "foo://bar:1",
                                     "tcp://h:99999"])
def test_a_scheduler_that_is_no_address_is_one_line(tmp_path, capsys, no_cluster, address):
    assert main(sweep_args(tmp_path / "out", "--scheduler", address)) == 2
    assert "error: command line: --scheduler: expected an address" in one_error(capsys)
    assert not (tmp_path / "out").exists()


def _stored(out, more=()):
    """A history of the variant k = 1e14 of two_bars, as the campaign names it."""
    v = make_variants([parse_parameter(f"{K}=[1e14]")])[0]
    path = out / f"{v.name}.h5"
    sets = SHORT + list(more) + v.overrides()
    assert main(["run", str(TWO), "-o", str(path), "--quiet", *[a for s in sets
                                                              for a in ("--set", s)]]) == 0
    return v, path


def _what(out, v, sets, kind="run", resume=True):
    p = plan(out, [v], {v.name: load(TWO, sets + v.overrides())}, kind, resume)
    return "done" if v.name in p.done else p.todo[v.name]


def test_what_resume_makes_of_a_stored_history(tmp_path, capsys):
    """Complete and the variant's: read back; stopped short of the new t_end (by the end of
    its run, or from outside): continued; aborted on its own or not resuming: made again; a
    longer run, or one of another case: refused, naming the variant and what differs."""
    out = tmp_path / "out"
    out.mkdir()
    v, path = _stored(out)
    capsys.readouterr()
    assert _what(out, v, SHORT) == "done"
    assert _what(out, v, SHORT + ["solver.chunk=7", "title='x'"]) == "done"
    assert _what(out, v, ["solver.t_end=4e-5"]) == "continue"
    assert _what(out, v, SHORT, resume=False) == "fresh"
    for sets, words in ((["solver.t_end=1e-5"], "holds a longer run"),
                        (SHORT + ["solver.dt=1e-8"], "(solver.dt differs)"),
                        (SHORT + ["materials.steel.rho=7000.0"],
                         "(materials.steel.rho differs)")):
        with pytest.raises(CaseError) as exc:
            _what(out, v, sets)
        assert exc.value.path == str(path) and exc.value.key == "--resume"
        assert f"variant {v.name} ({K}=100000000000000.0): " in exc.value.message
        assert words in exc.value.message and "not replaced" in exc.value.message
        # made again when not resuming: the campaign's own output, as run replaces it
        assert _what(out, v, sets, resume=False) == "fresh"
    for status, what in (("running", "continue"), ("aborted: interrupted", "continue"),
                         ("aborted: terminated (SIGTERM)", "continue"),
                         ("aborted: energy balance drifted by 1", "fresh")):
        with h5py.File(path, "a") as f:
            f.attrs["status"] = status
        assert _what(out, v, SHORT) == what, status
    # a history its writer still holds is refused, resuming or not
    import fcntl
    with open(path, "ab") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        for resume in (True, False):
            with pytest.raises(CaseError, match="another run is writing this history"):
                _what(out, v, SHORT, resume=resume)
    # kind both: its complex modes missing, the history is made again with them
    assert _what(out, v, SHORT, "both") == "fresh"
    # complete, but its rows cannot be read back: made again
    with h5py.File(path, "a") as f:
        f.attrs["status"] = "complete"
    assert _what(out, v, SHORT) == "done"
    with h5py.File(path, "a") as f:
        del f["time"]
    assert _what(out, v, SHORT) == "fresh"


def test_what_resume_makes_of_stored_complex_modes(tmp_path):
    """Complex modes carry the case that made them: the same check as a history's."""
    out = tmp_path / "out"
    out.mkdir()
    v = make_variants([parse_parameter(f"{K}=[1e14]")])[0]
    path = out / f"{v.name}.json"
    case = load(TWO, SHORT + ["solver.dt=1e-8"] + v.overrides())
    path.write_text(json.dumps({"written_by": MARK, "status": "complete", "modes": [],
                                "case": case.text, "case_path": str(TWO),
                                "overrides": list(case.overrides)}))
    assert _what(out, v, SHORT + ["solver.dt=1e-8", "solver.t_end=1.0"], "cea") == "done"
    stored = json.loads(path.read_text())
    path.write_text(json.dumps({**stored, "modes": [{"real": 1.0}]}))
    assert _what(out, v, SHORT + ["solver.dt=1e-8"], "cea") == "fresh"     # unreadable
    path.write_text(json.dumps({**stored, "overrides": [1], "case": ["x"]}))
    with pytest.raises(CaseError, match="its stored case does not load"):
        _what(out, v, SHORT + ["solver.dt=1e-8"], "cea")
    path.write_text(json.dumps(stored))
    with pytest.raises(CaseError, match=f"variant {v.name} .*solver.dt differs"):
        _what(out, v, SHORT, "cea")
    assert _what(out, v, SHORT, "cea", resume=False) == "fresh"
    # with its history complete and the variant's, a 'both' variant is read back
    _stored(out, ["solver.dt=1e-8"])
    assert _what(out, v, SHORT + ["solver.dt=1e-8"], "both") == "done"
    assert _what(out, v, ["solver.dt=1e-8", "solver.t_end=4e-5"], "both") == "continue"


@pytest.mark.slow
def test_the_exit_code_follows_the_rows(tmp_path, capsys):
    """A variant refused at its setup (a step above the critical one) makes the campaign exit
    2, the others complete or aborted; with none refused, an aborted run makes it exit 3;
    each said in one line naming the first such variant."""
    out = tmp_path / "out"
    argv = ["sweep", str(TWO), "--param", "solver.force_dt=[false,true]", "--workers", "1",
            "--out", str(out), "--set", "solver.t_end=2e-5", "--set", "solver.dt=1e-6",
            "--set", "solver.subdivision=0", "--json"]
    assert main(argv) == 2
    captured = capsys.readouterr()
    rows = json.loads(captured.out.splitlines()[-1])["rows"]
    assert rows[0]["status"].startswith("refused: solver.dt: 1.000e-06 s is above")
    assert rows[1]["status"].startswith("aborted: energy balance drifted")
    err = captured.err
    assert len(err.strip().splitlines()) == 1 and err.startswith(
        f"error: {TWO}: solver.dt: variant {rows[0]['variant']} (solver.force_dt=false): "
        "1.000e-06 s is above") and "1 of 2 variants refused" in err
    argv[3] = "solver.force_dt=[true]"
    assert main(argv + ["--resume"]) == 3
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith(
        f"error: 1 of 1 variants did not complete (variant {rows[1]['variant']} "
        "(solver.force_dt=true): aborted: energy balance drifted")
