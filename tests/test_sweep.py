"""`transient sweep`: the variants of its parameters, a campaign on a LocalCluster of two
workers equal bit for bit to the same variants run one by one, resume, and refusals."""
import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import transient
from transient.cli import main
from transient.errors import CaseError
from transient.io.reading import summary
from transient.campaign.campaign import THREAD_ENV
from transient.campaign.variants import make_variants, parse_parameter, variant_name

from small_cases import PAD_DISC

ROOT = Path(__file__).resolve().parent.parent
PAD = ROOT / "cases" / "pad_disc.toml"
SMALL = PAD_DISC + ["motion.disc.omega=50.0", "solver.damping.residual=0.0", "solver.t_end=5e-3",
                    "output.every=2", "loads.tap.vector=[0.0,0.0,-0.02]"]


def test_parameters_and_their_variants():
    mu = parse_parameter("contact.pad_disc.friction.mu=0:0.6:4")
    assert mu.values == pytest.approx((0.0, 0.2, 0.4, 0.6))
    p = parse_parameter("loads.piston.value=[1e6, 2e6]")
    assert p.values == (1e6, 2e6)
    assert parse_parameter('solver.scheme="implicit"').values == ("implicit",)
    grid = make_variants([mu, p])
    assert len(grid) == 8 and grid[1].values == {mu.key: 0.0, p.key: 2e6}
    assert grid[5].overrides() == [
        "contact.pad_disc.friction.mu=0.4", "loads.piston.value=2000000.0"]
    # named by its values, not its place: the same name from another list, another order of
    # the parameters, or another spelling of a value
    assert grid[5].name == variant_name({mu.key: 0.4, p.key: 2e6})
    assert grid[5].name.startswith("v-") and len(grid[5].name) == 14
    again = make_variants([parse_parameter("loads.piston.value=[2.0e6]"),
                           parse_parameter("contact.pad_disc.friction.mu=[0.40, 0.5]")])
    assert again[0].name == grid[5].name and again[1].name not in {v.name for v in grid}
    assert len({v.name for v in grid}) == 8
    paired = make_variants([parse_parameter("a.b=[1, 2]"), parse_parameter("c.d=[3, 4]")],
                           "zip")
    assert [v.values for v in paired] == [{"a.b": 1, "c.d": 3}, {"a.b": 2, "c.d": 4}]


@pytest.mark.parametrize("params, mode, key", [
    (["mu"], "grid", "--param"), (["a.b=1:2:x"], "grid", "--param a.b"),
    (["a.b=[1,"], "grid", "--param a.b"), (["a.b=[]"], "grid", "--param a.b"),
    (["a.b=[1,2]", "c.d=[1]"], "zip", "--zip"), (["a.b=1", "a.b=2"], "grid", "--param"),
    ([], "grid", "--param")])
def test_bad_parameters_name_their_key(params, mode, key):
    with pytest.raises(CaseError) as exc:
        make_variants([parse_parameter(t) for t in params], mode)
    assert exc.value.key == key


def test_a_bad_variant_is_refused_before_anything_runs(tmp_path, capsys):
    args = ["sweep", str(PAD), "--param", "contact.pad_disc.friction.mu=[0.2,-0.4]",
            "--out", str(tmp_path / "out")]
    assert main(args) == 2
    err = capsys.readouterr().err
    name = variant_name({"contact.pad_disc.friction.mu": -0.4})
    assert err.count("\n") == 1 and f"variant {name} (contact.pad_disc.friction.mu=-0.4)" in err
    assert "contact.pad_disc.friction.mu" in err and not (tmp_path / "out").exists()


def _arrays(path):
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and not name.startswith(("checkpoint", "timings")):
                out[name] = obj[()]
        f.visititems(visit)
    return out


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """A mu sweep of three variants on two workers, and the same variants by `transient
    run`, each in a process with the workers' one-thread environment."""
    out = tmp_path_factory.mktemp("sweep")
    args = ["sweep", str(PAD), "--param", "contact.pad_disc.friction.mu=[0.0,0.2,0.4]",
            "--workers", "2", "--out", str(out / "campaign"), "--json"]
    for o in SMALL:
        args += ["--set", o]
    env = {**os.environ, **THREAD_ENV, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "transient"] + args, capture_output=True,
                          text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout.splitlines()[-1])["rows"]
    alone = []
    for mu in (0.0, 0.2, 0.4):
        path = out / f"alone_{mu}.h5"
        run = [sys.executable, "-m", "transient", "run", str(PAD), "-o", str(path), "--quiet",
               "--set", f"contact.pad_disc.friction.mu={mu}"]
        for o in SMALL:
            run += ["--set", o]
        assert subprocess.run(run, env=env, timeout=600).returncode == 0
        alone.append(path)
    return out / "campaign", rows, alone


@pytest.mark.slow
def test_a_sweep_equals_its_variants_run_one_by_one(campaign):
    out, rows, alone = campaign
    assert [r["variant"] for r in rows] == [variant_name({"contact.pad_disc.friction.mu": mu})
                                            for mu in (0.0, 0.2, 0.4)]
    assert [r["contact.pad_disc.friction.mu"] for r in rows] == [0.0, 0.2, 0.4]
    for row, path in zip(rows, alone):
        assert row["status"] == "complete" and row["seconds"] > 0
        got, ref = _arrays(out / row["output"]), _arrays(path)
        assert set(got) == set(ref) and len(got) > 5
        for name in ref:
            assert np.array_equal(got[name], ref[name]), name
    # the summaries: growth at mu = 0.4 only (the small pad and disc flutter above 0.3; a
    # fit over 5 ms of beating modes, the sign its point: over 3 ms the growing mode's 8x
    # did not yet stand out of the tap's response of the modes to 2 fmax)
    assert rows[2]["growth_rate"] > 500
    assert rows[0]["growth_rate"] is None or rows[0]["growth_rate"] < 100
    assert 11e3 < rows[2]["cycle_frequency"] < 12.5e3
    saved = json.loads((out / "sweep.json").read_text())
    assert saved["rows"] == rows
    # the model, the contact's geometry and the factorization built once for the three
    # (shared.stage_key), by tasks of their own: no variant ran them, each its own loads
    # (the basis follows mu: each variant makes its own, but test_a_friction_sweep_at_one_...)
    assert saved["shared"] == {"model": 1, "contact": 1, "factorization": 1, "basis": 0}
    for r in rows:
        assert "loads" in r["stages"] and "preload" in r["stages"]
        assert not {"model", "contact", "factorization"} & set(r["stages"])
    lines = (out / "sweep.csv").read_text().splitlines()
    assert len(lines) == 4 and lines[0].startswith("variant,status,seconds,")


@pytest.mark.slow
def test_resume_runs_only_the_missing_variants(campaign, capsys):
    out, rows, _ = campaign
    (out / rows[1]["output"]).unlink()
    with h5py.File(out / rows[2]["output"], "a") as f:
        f.attrs["status"] = "aborted: interrupted"           # as a sweep cut off leaves it
    before = (out / rows[0]["output"]).stat().st_mtime_ns
    args = ["sweep", str(PAD), "--param", "contact.pad_disc.friction.mu=[0.0,0.2,0.4]",
            "--workers", "1", "--out", str(out), "--resume", "--json"]
    for o in SMALL:
        args += ["--set", o]
    assert main(args) == 0
    again = json.loads(capsys.readouterr().out.splitlines()[-1])["rows"]
    assert [r["resumed"] for r in again] == [True, False, False]
    # the interrupted history goes on from its checkpoint (here its last step: no step again)
    assert [r["continued"] for r in again] == [False, False, True]
    assert (out / rows[0]["output"]).stat().st_mtime_ns == before
    assert all(r["status"] == "complete" for r in again)
    # rows read back from a complete history, and rerun ones, say the same
    assert [r["growth_rate"] for r in again] == [r["growth_rate"] for r in rows]


def _holders(path, own):
    """The processes (other than own) with the file at path open."""
    pids = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit() or int(proc.name) == own:
            continue
        try:
            if any(os.readlink(fd) == str(path) for fd in (proc / "fd").iterdir()):
                pids.append(int(proc.name))
        except OSError:
            continue
    return pids


@pytest.mark.slow
def test_a_worker_killed_mid_variant_leaves_the_sweep_complete(campaign, tmp_path):
    """The worker running a variant is killed (SIGKILL) once it holds that variant's history
    open: the scheduler reruns the task on the other worker, and every history comes out
    complete and equal to the variant run alone."""
    import signal
    import time
    _, _, alone = campaign
    out = tmp_path / "campaign"
    args = [sys.executable, "-m", "transient", "sweep", str(PAD), "--param",
            "contact.pad_disc.friction.mu=[0.0,0.2,0.4]", "--workers", "2", "--out", str(out),
            "--json"]
    for o in SMALL:
        args += ["--set", o]
    env = {**os.environ, **THREAD_ENV, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=env)
    killed = None
    deadline = time.monotonic() + 300
    # the event: a worker process holding a variant's history (its run under way)
    while killed is None and child.poll() is None and time.monotonic() < deadline:
        for path in sorted(out.glob("v*.h5")) if out.exists() else []:
            holders = _holders(path.resolve(), child.pid)
            if holders:
                os.kill(holders[0], signal.SIGKILL)
                killed = path.name
                break
        time.sleep(0.01)
    stdout, stderr = child.communicate(timeout=600)
    assert killed is not None, "no variant was seen running"
    assert child.returncode == 0, stderr
    rows = json.loads(stdout.splitlines()[-1])["rows"]
    assert all(r["status"] == "complete" for r in rows)
    for row, path in zip(rows, alone):
        got, ref = _arrays(out / row["output"]), _arrays(path)
        for name in ref:
            assert np.array_equal(got[name], ref[name]), (killed, row["variant"], name)


@pytest.mark.slow
def test_the_run_sweeps_pictures(campaign, capsys):
    out, _, _ = campaign
    assert main(["plot", "sweep", str(out)]) == 0
    picture = Path(capsys.readouterr().out.split()[-1])
    assert picture == out / "sweep_run.png" and picture.stat().st_size > 10_000
    assert main(["plot", "sweep", str(out), "--x", "solver.dt"]) == 2
    assert "--x" in capsys.readouterr().err


def _mu_args(out, kind, values="[0.0,0.4]", *more):
    args = ["sweep", str(PAD), "--param", f"contact.pad_disc.friction.mu={values}", "--kind",
            kind, "--workers", "1", "--out", str(out), "--json"]
    for o in SMALL:
        args += ["--set", o]
    return args + list(more)        # after SMALL: its overrides win


def _mu_sweep(out, kind, capsys, values="[0.0,0.4]", *more):
    assert main(_mu_args(out, kind, values, *more)) == 0
    return json.loads(capsys.readouterr().out.splitlines()[-1])["rows"]


@pytest.fixture(scope="module")
def cea_campaign(tmp_path_factory):
    """A cea sweep of mu 0, 0.2 and 0.4 on one worker: its folder and rows."""
    out = tmp_path_factory.mktemp("cea") / "cea"
    assert main(_mu_args(out, "cea", "[0.0,0.2,0.4]")) == 0
    return out, json.loads((out / "sweep.json").read_text())["rows"]


def _modes(path):
    return [(m["frequency_hz"], m["real"]) for m in json.loads(path.read_text())["modes"]]


@pytest.mark.slow
def test_a_cea_sweep_and_its_stability_map(campaign, cea_campaign, tmp_path, capsys):
    """mu 0 and 0.4 on the small pad and disc: no unstable mode, then its flutter pair's
    growing member (11-12.5 kHz); the map of every mode against mu."""
    out, rows = cea_campaign
    assert [r["contact.pad_disc.friction.mu"] for r in rows] == [0.0, 0.2, 0.4]
    rows = [rows[0], rows[2]]                           # mu 0 and 0.4
    assert [r["unstable"] for r in rows][0] == 0 and rows[1]["unstable"] >= 1
    assert 11e3 < rows[1]["frequency_hz"] < 12.5e3 and rows[1]["max_real"] > 500
    stored = json.loads((out / rows[1]["output"]).read_text())
    modes = stored["modes"]
    assert len(modes) > 10 and sum(m["unstable"] for m in modes) == rows[1]["unstable"]
    # the shapes the map links the variants by: a few hundred nodes' three dofs
    assert stored["shapes"]["shape"] == [len(stored["shapes"]["dofs"]), len(modes)]
    assert main(["plot", "sweep", str(out), "-o", str(tmp_path / "map.png")]) == 0
    assert (tmp_path / "map.png").stat().st_size > 10_000
    key = "contact.pad_disc.friction.mu"
    with open(tmp_path / "map_unstable.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert [float(r[key]) for r in table] == [r[key] for r in cea_campaign[1]
                                              for _ in range(r["unstable"])]
    (found,) = transient.sweep_branches(out).values()
    assert found.linked_by == "shapes" and list(found.values) == [0.0, 0.2, 0.4]
    # both kinds from one setup: the complex modes of the run's stages before its sampling
    # are the cea's, and the history the run's alone, bit for bit
    both = _mu_sweep(tmp_path / "both", "both", capsys)
    alone = campaign[2][0], campaign[2][2]              # mu 0 and 0.4 by transient run
    for row, cea_row, path in zip(both, rows, alone):
        got, ref = _arrays(tmp_path / "both" / row["output"]), _arrays(path)
        assert set(got) == set(ref) and all(np.array_equal(got[k], ref[k]) for k in ref)
        assert row["status"] == "complete" and row["output"].endswith(".h5")
        got = json.loads((tmp_path / "both" / row["modes_output"]).read_text())
        assert got == json.loads((out / cea_row["output"]).read_text())
        assert row["max_real"] == cea_row["max_real"] and "growth_rate" in row
        assert "sampling" in row["stages"]
    assert both[1]["growth_rate"] > 500          # the flutter pair's growth at mu = 0.4
    picture = tmp_path / "both.png"
    assert main(["plot", "sweep", str(tmp_path / "both"), "-o", str(picture)]) == 0
    assert all((tmp_path / f"both_{k}.png").stat().st_size > 10_000 for k in ("cea", "run"))


def _fds(pid, path):
    """How many of the process's file descriptors are open on the file at path."""
    try:
        return sum(os.readlink(fd) == str(path) for fd in Path(f"/proc/{pid}/fd").iterdir())
    except OSError:
        return 0


def _status(path):
    """(status, rows of its checkpoint or None) of a history no one is writing."""
    with h5py.File(path, "r", locking=False) as f:
        return f.attrs["status"], (int(f["checkpoint"].attrs["rows"]) if "checkpoint" in f
                                   else None)


def _kill_once_a_variant_is_half_way(child, out, timeout=300.0):
    """SIGKILL the sweep in child and its workers (its process group) once one variant's
    history is complete and another's is running before 400 of its 481 rows: that worker is
    stopped (SIGSTOP) between two writes to its history (its only descriptor on the file is
    the lock's, not HDF5's), so the kill leaves that history as a killed run leaves it,
    whatever the machine's speed. Returns the stopped history's path."""
    import signal
    import time
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert child.poll() is None, "the sweep ended before it was killed"
        histories = sorted(p.resolve() for p in out.glob("v-*.h5")) if out.exists() else []
        for pid in _group(child.pid) - {child.pid}:
            for path in [p for p in histories if _fds(pid, p)]:
                os.kill(pid, signal.SIGSTOP)
                try:
                    if _fds(pid, path) == 1 and path.stat().st_size:
                        status, rows = _status(path)
                        others = [_status(p)[0] for p in histories if p != path]
                        if (status == "running" and rows is not None and 0 < rows < 400
                                and "complete" in others):
                            os.killpg(child.pid, signal.SIGKILL)
                            return path
                except (OSError, KeyError):
                    pass
                os.kill(pid, signal.SIGCONT)
        time.sleep(0.002)
    raise AssertionError("no variant seen half way")


def _group(group):
    """The live (not zombie) processes of a process group."""
    pids = set()
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and os.getpgid(int(proc.name)) == group and (
                    (proc / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"):
                pids.add(int(proc.name))
        except (OSError, IndexError):
            continue
    return pids


@pytest.mark.slow
def test_a_killed_sweep_resumes_to_the_fresh_outputs(campaign, cea_campaign, tmp_path, capsys):
    """A sweep of both kinds killed (SIGKILL, its workers with it) with one variant complete
    and the other's run half way, then resumed: the complete one read back, the other's
    history continued from its checkpoint; every history bit for bit the run alone, every
    complex mode the cea sweep's. Resumed again with another list of values: the value kept
    is read back, the new one computed, equal to fresh ones; the value left out keeps its
    files untouched."""
    import time
    out = tmp_path / "killed"
    env = {**os.environ, **THREAD_ENV, "PYTHONPATH": str(ROOT)}
    # two steps a chunk (a chunk changes where the run is cut, never its numbers): the run
    # stored at many points, one of which the kill finds
    child = subprocess.Popen([sys.executable, "-m", "transient"]
                             + _mu_args(out, "both", "[0.0,0.4]", "--set", "solver.chunk=2"),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                             start_new_session=True)
    stopped = _kill_once_a_variant_is_half_way(child, out)
    child.communicate(timeout=60)
    deadline = time.monotonic() + 60
    while _group(child.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _group(child.pid)
    assert _status(stopped)[0] == "running"          # as a killed run leaves it
    fresh = {0.0: (campaign[2][0], cea_campaign[1][0]), 0.2: (campaign[2][1],
                                                              cea_campaign[1][1]),
             0.4: (campaign[2][2], cea_campaign[1][2])}

    def check(rows):
        for row in rows:
            alone, cea_row = fresh[row["contact.pad_disc.friction.mu"]]
            assert row["status"] == "complete"
            got, ref = _arrays(out / row["output"]), _arrays(alone)
            assert set(got) == set(ref) and len(got) > 5
            for name in ref:
                assert np.array_equal(got[name], ref[name]), (row["variant"], name)
            assert _modes(out / row["modes_output"]) == _modes(cea_campaign[0]
                                                               / cea_row["output"])
    rows = _mu_sweep(out, "both", capsys, "[0.0,0.4]", "--resume")
    check(rows)
    assert {r["output"]: (r["resumed"], r["continued"]) for r in rows}[stopped.name] == (
        False, True)
    assert sorted(r["resumed"] for r in rows) == [False, True]
    kept = {p.name: p.read_bytes() for p in out.iterdir() if p.name.startswith("v-")}
    again = _mu_sweep(out, "both", capsys, "[0.2,0.4]", "--resume")
    check(again)
    assert [(r["resumed"], r["continued"]) for r in again] == [(False, False), (True, False)]
    assert [r["variant"] for r in again][1] == rows[1]["variant"]
    for name, data in kept.items():                  # mu 0 and 0.4: untouched
        assert (out / name).read_bytes() == data, name
    saved = json.loads((out / "sweep.json").read_text())["rows"]
    assert [r["contact.pad_disc.friction.mu"] for r in saved] == [0.2, 0.4]


@pytest.mark.slow
def test_a_sweep_resumed_to_a_longer_t_end_continues_its_histories(campaign, tmp_path,
                                                                   capsys):
    """Stopped at half the time, then resumed to the whole: each history continues from its
    checkpoint, bit for bit the run alone to the whole; to a shorter time than stored, the
    campaign is refused (the longer run would be lost)."""
    out = tmp_path / "half"
    half = ["--set", "solver.t_end=2.5e-3"]
    rows = _mu_sweep(out, "run", capsys, "[0.0,0.4]", *half)
    assert all(r["steps"] == 800 for r in rows)
    rows = _mu_sweep(out, "run", capsys, "[0.0,0.4]", "--resume")
    assert [(r["resumed"], r["continued"]) for r in rows] == [(False, True)] * 2
    for row, alone in zip(rows, (campaign[2][0], campaign[2][2])):
        got, ref = _arrays(out / row["output"]), _arrays(alone)
        assert set(got) == set(ref)
        for name in ref:
            assert np.array_equal(got[name], ref[name]), (row["variant"], name)
    assert rows[1]["growth_rate"] == campaign[1][2]["growth_rate"]
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(_mu_args(out, "run", "[0.0,0.4]", "--resume", *half)) == 2
    err = capsys.readouterr().err
    assert "holds a longer run" in err and f"variant {rows[0]['variant']}" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_plot_sweep_needs_a_sweep(tmp_path, capsys):
    assert main(["plot", "sweep", str(tmp_path)]) == 2
    assert "sweep.json" in capsys.readouterr().err


class _Recorder:
    """A case (or any of its specs) that records the dotted paths read through it."""

    def __init__(self, obj, path, reads):
        self._obj, self._path, self._reads = obj, path, reads

    def _wrap(self, value, path):
        import dataclasses
        if dataclasses.is_dataclass(value) or isinstance(value, dict):
            return _Recorder(value, path, self._reads)
        self._reads.add(path)
        return value

    def __getattr__(self, name):
        derived = getattr(type(self._obj), name, None)
        if isinstance(derived, property):
            # a spec's property reads its fields: record those
            return derived.fget(self)
        return self._wrap(getattr(self._obj, name), f"{self._path}.{name}".lstrip("."))

    def __getitem__(self, key):
        self._reads.add(self._path)
        return self._wrap(self._obj[key], self._path)

    def __iter__(self):
        self._reads.add(self._path)
        return iter(self._obj)

    def __len__(self):
        self._reads.add(self._path)
        return len(self._obj)

    def __contains__(self, key):
        self._reads.add(self._path)
        return key in self._obj

    def items(self):
        self._reads.add(self._path)
        return [(k, self._wrap(v, self._path)) for k, v in self._obj.items()]

    def values(self):
        return [v for _, v in self.items()]

    def keys(self):
        self._reads.add(self._path)
        return self._obj.keys()

    def get(self, key, default=None):
        return self[key] if key in self._obj else default


def _outside(reads, stage):
    from transient.shared import READS
    allowed = READS[stage] + ("path", "directory")
    # a table's own path is its names looked up (what a field of each of them reads too)
    return sorted(r for r in reads if not any(r == a or r.startswith(a + ".")
                                              or a.startswith(r + ".") for a in allowed))


CASES = [(PAD, SMALL), (ROOT / "cases" / "drilled_cube.toml", [])]


@pytest.mark.parametrize("case, more", CASES)
def test_the_model_reads_only_what_its_key_holds(case, more):
    """build_model through a case that records its reads: every field its structure reads is
    under shared.READS['model'] (or names the case's file), so variants equal there may share
    it; the loads and sensors it reads are applied to a shared structure again."""
    from transient.case.loading import load
    from transient.model import build_model
    reads = set()
    model = build_model(_Recorder(load(case, more), "", reads))
    assert {r.split(".")[0] for r in _outside(reads, "model")} == {"loads", "sensors"}
    assert any(r.startswith("parts") for r in reads)
    # the structure shared: only the loads and sensors read again, the same arrays made
    reads.clear()
    again = build_model(_Recorder(load(case, more), "", reads), model)
    assert not any(r.startswith(("materials", "constraints", "solver")) for r in reads)
    for name in model.load_patterns:
        assert np.array_equal(again.load_patterns[name], model.load_patterns[name])
    assert (again.sensors != model.sensors).nnz == 0 and again.K is model.K


@pytest.mark.parametrize("case, more", CASES)
def test_the_contact_and_the_factorization_read_only_what_their_keys_hold(case, more):
    """The pairs' geometry and the factorization through a recording case read only the fields
    of shared.READS['contact'] and ['factorization'] (the law and the friction are each
    variant's own)."""
    from transient.case.loading import load
    from transient.contact.contactset import stack
    from transient.contact.pair import build_geometry
    from transient.model import build_model
    from transient.shared import factorization
    loaded = load(case, more + ["contact.{}.friction.mu=0.3".format(
        next(iter(load(case, more).contact)))] if case == PAD else more)
    model = build_model(loaded)
    reads = set()
    for name in loaded.contact:
        build_geometry(_Recorder(loaded, "", reads), model, name)
    assert not _outside(reads, "contact") and any(r.startswith("contact.") for r in reads)
    contacts = stack([build_geometry(loaded, model, name) for name in loaded.contact],
                     model.ndof)
    reads.clear()
    factorization(_Recorder(loaded, "", reads), model, contacts)
    assert not _outside(reads, "factorization") and "solver.linear_solver" in reads


@pytest.mark.slow
def test_a_friction_sweep_at_one_basis_mu_shares_the_basis(tmp_path):
    """With contact.<pair>.friction.basis_mu, the variants of a friction sweep share the basis
    made at that friction (one build, counted) and each rebases it on its own preload; their
    histories and complex modes are bit for bit those of `transient run` and `transient cea`
    of the same variant, which make that basis themselves (mu = 0.2: the basis is its own, made
    by the shared stage as by the variant alone)."""
    out = tmp_path / "basis"
    more = [f"--set={o}" for o in SMALL + ["contact.pad_disc.friction.basis_mu=0.2"]]
    env = {**os.environ, **THREAD_ENV, "PYTHONPATH": str(ROOT)}

    def transient(*args):
        done = subprocess.run([sys.executable, "-m", "transient", *args, *more],
                              capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr
        return done.stdout
    def swept(kind, where):
        return json.loads(transient("sweep", str(PAD), "--param",
                                    "contact.pad_disc.friction.mu=[0.0,0.2,0.4]", "--kind",
                                    kind, "--workers", "2", "--out", str(where),
                                    "--json").splitlines()[-1])["rows"]
    rows = swept("both", out)
    # a cea campaign's basis is built as `transient cea` builds it (no points sampled)
    ceas = swept("cea", tmp_path / "cea")
    saved = json.loads((out / "sweep.json").read_text())
    assert saved["shared"] == {"model": 1, "contact": 1, "factorization": 1, "basis": 1}
    for row, mu in zip(rows, (0.0, 0.2, 0.4)):
        assert row["status"] == "complete"
        assert not {"factorization", "reference"} & set(row["stages"])
        assert "basis" in row["shared_s"]           # all three from the one build
        alone = tmp_path / f"alone_{mu}.h5"
        transient("run", str(PAD), "-o", str(alone), "--quiet",
                  f"--set=contact.pad_disc.friction.mu={mu}")
        got, ref = _arrays(out / row["output"]), _arrays(alone)
        assert set(got) == set(ref) and len(got) > 5
        for name in ref:
            assert np.array_equal(got[name], ref[name]), (mu, name)
        cea = json.loads(transient("cea", str(PAD), "--json",
                                   f"--set=contact.pad_disc.friction.mu={mu}"))
        for modes in (json.loads((out / row["modes_output"]).read_text())["modes"],
                      json.loads((tmp_path / "cea" / ceas[rows.index(row)]["output"])
                                 .read_text())["modes"]):
            assert [(m["frequency_hz"], m["real"]) for m in modes] == [
                (m["frequency_hz"], m["real"]) for m in cea["modes"]]
        # one by one, the variant makes the basis at 0.2 itself (its own at 0.2)
        assert ("reference" in summary(alone)["meta"]["stages"]) == (mu != 0.2)
    assert rows[2]["growth_rate"] > 500 and rows[2]["unstable"] >= 1


@pytest.mark.slow
def test_the_shared_basis_reads_only_what_its_key_holds():
    """The basis at a reference friction through a recording case reads only the fields of
    shared.READS['basis'] (and the sensors that the model's loads place with them)."""
    from transient.case.loading import load
    from transient.shared import build_shared, shared_basis
    loaded = load(PAD, SMALL + ["contact.pad_disc.friction.mu=0.3"])
    built = build_shared(loaded, "factorization")
    reads = set()
    shared = shared_basis(_Recorder(loaded, "", reads), built.model, built.geometry,
                          built.solver)
    assert shared.basis.X.shape[1] > shared.basis.n_modes > 0
    outside = _outside(reads, "basis")
    assert {r.split(".")[0] for r in outside} <= {"sensors"}, outside
    assert any(r.startswith("contact.") and "friction" in r for r in reads)


@pytest.mark.slow
def test_a_pressure_sweep_shares_every_first_stage(tmp_path, capsys):
    """The piston's pressure is a load: two pressures share the model's structure, the
    contact's geometry and the factorization; each variant's preload is its own (the contact
    force follows the pressure)."""
    out = tmp_path / "p"
    args = ["sweep", str(PAD), "--param", "loads.piston.value=[5e5,1e6]", "--kind", "cea",
            "--workers", "1", "--out", str(out), "--json"]
    for o in SMALL:
        args += ["--set", o]
    assert main(args) == 0
    capsys.readouterr()
    saved = json.loads((out / "sweep.json").read_text())
    assert saved["shared"] == {"model": 1, "contact": 1, "factorization": 1, "basis": 0}
    assert all(r["status"] == "complete" for r in saved["rows"])


@pytest.mark.slow
def test_progress_counts_the_variants_done_and_the_failed(tmp_path):
    """The campaign's bar is told each variant done, and how many failed so far: a step above
    the explicit scheme's critical one is refused at the variant's setup, a row with its
    reason, and the campaign goes on."""
    from transient.campaign.campaign import sweep
    calls = []
    rows = sweep(PAD, make_variants([parse_parameter("solver.dt=[0.0,1e-3]")], "grid"),
                 tmp_path / "out", "run", SMALL + ['solver.scheme="explicit"'], workers=1,
                 progress=lambda *a: calls.append(a), announce=None)
    assert calls[0] == (0, 2, 0) and calls[-1] == (2, 2, 1)
    assert sorted(c[0] for c in calls) == [0, 1, 2]
    assert rows[0]["status"] == "complete"
    assert rows[1]["status"].startswith("refused: solver.dt: 1.000e-03 s is above")
