"""The public API on a run's results and on studies (transient.history, summary, export, bench,
compare_modes, compat_pairs): each returns or writes what its command prints or writes for the
same input, and the commands reach their numbers through it."""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

import transient
import transient.api
from transient.cli import main
from transient.errors import CaseError

ROOT = Path(__file__).resolve().parent.parent
BAR, CUBE = ROOT / "cases" / "bar_impact.toml", ROOT / "cases" / "drilled_cube.toml"
SHORT = ["solver.t_end=2e-5", "output.field=true"]
# the bench's timings differ run to run (and so may its target): the rest must not
TIMED = {"setup_s", "kernel_s", "total_s", "steps_per_s"}


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    return transient.run(transient.load(BAR, SHORT),
                         tmp_path_factory.mktemp("results") / "bar.h5").path


def printed(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr().out
    assert code == 0
    return out


def test_summary_is_what_info_prints(bar, capsys):
    found = transient.summary(bar)
    assert found == json.loads(printed(capsys, "info", bar, "--json"))
    with h5py.File(bar, "r") as f:
        assert found["steps"] == len(f["time"]) > 100 and found["t_end"] == f["time"][-1]
    assert found["status"] == "complete" and "sensors/tip" in found["series"]
    from transient.cli.report import format_summary
    assert printed(capsys, "info", bar) == format_summary(found) + "\n"
    with pytest.raises(CaseError) as exc:
        transient.summary(Path(bar).with_name("none.h5"))
    assert exc.value.message == "file not found"


def test_history_reads_what_the_file_holds(bar):
    h = transient.history(bar)
    found = transient.summary(bar)
    assert h.path == Path(bar) and h.rows == found["steps"] and h.meta["status"] == "complete"
    assert {k: list(v) for k, v in h.series.items()} == found["series"]
    with h5py.File(bar, "r") as f:
        time, tip = f["time"][()], f["sensors/tip"][()]
    assert np.array_equal(h.time(), time) and np.array_equal(h.read("sensors/tip"), tip)
    case = h.case()
    assert case.text == BAR.read_text() and list(case.overrides) == SHORT
    with pytest.raises(CaseError) as exc:
        transient.history(BAR)          # a case file is no history
    assert exc.value.path == str(BAR)


def test_plots_of_a_history_open_it_through_the_api(bar, tmp_path, capsys, monkeypatch):
    opened = []
    real = transient.api.history

    def spy(path):
        opened.append(str(path))
        return real(path)
    monkeypatch.setattr(transient.api, "history", spy)
    png = tmp_path / "tip.png"
    assert printed(capsys, "plot", "history", bar, "-o", png) == f"{png}\n"
    assert opened == [bar] and png.stat().st_size > 0


def _files(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_export_writes_the_files_the_command_writes(bar, tmp_path, capsys):
    mine = transient.export(bar, tmp_path / "api", format="vtu", every=50)
    out = printed(capsys, "export", bar, "--out", tmp_path / "cli", "--format", "vtu",
                  "--every", "50")
    assert [p.relative_to(tmp_path / "api") for p in mine] == [
        Path(p).relative_to(tmp_path / "cli") for p in out.split()]
    assert [p.name for p in mine] == ["contact_wall.pvd", "field.pvd"]
    written, rows = _files(tmp_path / "api"), transient.history(bar).rows
    # a .vtu a series a row kept (one in 50, and the last), a .pvd naming them
    assert len(written) == 2 + 2 * len(np.union1d(np.arange(0, rows, 50), [rows - 1]))
    assert written == _files(tmp_path / "cli")
    # by default next to the history
    assert transient.export(bar) == [Path(bar).with_name("bar_export") / f"{s}.xdmf"
                                     for s in ("contact_wall", "field")]
    for options, key in (({"every": 0}, "--every"), ({"format": "vtk"}, "--format"),
                         ({"out": "/proc/transient_export"}, "--out")):
        with pytest.raises(CaseError) as exc:
            transient.export(bar, **options)
        assert exc.value.key == key


def _untimed(rows):
    return json.dumps([{k: v for k, v in r.items() if k not in TIMED} for r in rows])


@pytest.mark.slow
def test_bench_returns_the_rows_the_command_prints(tmp_path, capsys):
    """A rigid wall has no second mesh: the fine rule's row, then the others refused."""
    options = {"eps": [1e-3], "points": [0], "tolerances": [1e-2], "t_end": 2e-5}
    found = transient.bench(transient.load(BAR), out=tmp_path / "api", **options)
    out = json.loads(printed(capsys, "bench", BAR, "--eps", "1e-3", "--points", "0",
                             "--tolerances", "1e-2", "--t-end", "2e-5", "--out",
                             tmp_path / "cli", "--json"))
    assert _untimed(found.rows) == _untimed(out["rows"]) and len(found.rows) == 6
    assert found.rows[0]["status"] == "complete" and found.target is out["target"] is None
    assert found.summary() == {"rows": found.rows, "target": None}
    assert [f.name for f in found.files] == ["bench.csv", "bench.json", "bench.png"]
    assert all(f.parent == tmp_path / "api" and f.stat().st_size > 0 for f in found.files)
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(
        f.name for f in found.files)


def test_bench_and_compare_modes_refuse_bad_input_before_the_model(monkeypatch):
    import transient.stages
    import transient.studies.modal

    def no_model(*args, **kwargs):
        raise AssertionError("the model was built before the input was refused")
    monkeypatch.setattr(transient.stages, "build_model", no_model)
    monkeypatch.setattr(transient.studies.modal, "build_model", no_model)
    case = transient.load(BAR)
    for options, key in (({"pair": "nowhere"}, "contact"), ({"reference": "coarse"},
                                                           "--reference"),
                         ({"cycle_from": 1.0}, "--cycle-from"),
                         ({"out": "/proc/transient_bench"}, "--out")):
        with pytest.raises(CaseError) as exc:
            transient.bench(case, **options)
        assert exc.value.key == key
    for args, key in ((("nowhere", "tip"), "--input"), (("tip", "nowhere"), "--output")):
        with pytest.raises(CaseError) as exc:
            transient.compare_modes(case, case, *args)
        assert exc.value.key == key
    with pytest.raises(CaseError, match="--damping"):
        transient.compare_modes(case, case, "tip", "tip", damping=1.0)


@pytest.mark.slow
def test_compat_pairs_are_compat_of_each_pair(capsys):
    case = transient.load(CUBE)
    (found,) = transient.compat_pairs(case)
    alone = transient.compat(case)
    grid = np.logspace(-16, 0, 65)
    untimed = ("setup_s", "timings", "coarse")
    assert found.pair.name == alone.pair.name == "interface"
    assert {k: v for k, v in found.summary(grid).items() if k not in untimed} == {
        k: v for k, v in alone.summary(grid).items() if k not in untimed}
    assert transient.compat_pairs(case, []) == []
    with pytest.raises(CaseError) as exc:
        transient.compat_pairs(case, ["interface", "nowhere"])
    assert exc.value.key == "contact" and "no pair 'nowhere'" in exc.value.message
