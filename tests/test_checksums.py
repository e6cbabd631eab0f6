"""Every array of a history carries HDF5's checksum (fletcher32): bytes changed inside a
dataset's data after the run are refused by every reader in one line naming the file and the
dataset as damaged (exit 2), while a history written before the checksums still reads."""
import fcntl
import shutil

import h5py
import numpy as np
import pytest

import transient.io.checksums
import transient.io.history
from test_validation import BAR, one_error
from transient.cli import main
from transient.errors import DamagedHistory
from transient.io.history import History
from transient.io.reading import load_checkpoint, summary

SHORT = ["--set", "solver.t_end=6e-5", "--set", "output.field=true",
         "--set", "output.contact=true"]


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    path = tmp_path_factory.mktemp("checksums") / "bar.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"] + SHORT) == 0
    return path


def arrays(f):
    found = {}
    f.visititems(lambda name, obj: found.update({name: obj})
                 if isinstance(obj, h5py.Dataset) else None)
    return found


def test_every_array_of_a_history_is_checksummed(base):
    with h5py.File(base, "r") as f:
        found = arrays(f)
        assert {"time", "geometry/contact/wall/points", "system/C/data",
                "checkpoints/0/state"} <= set(found)
        unchecked = [name for name, ds in found.items() if ds.ndim and not ds.fletcher32]
        assert unchecked == []


def flip(path, name, count=200):
    """Change `count` bytes inside the stored data of dataset `name` (its first chunk). Not
    by inverting them: fletcher32 sums 16-bit words in ones' complement, where 0x0000 and
    0xFFFF are one value, so zeros inverted (a pressure where the contact is open) pass."""
    with h5py.File(path, "r") as f:
        info = f[name].id.get_chunk_info(0)
    count = min(count, info.size - 8)
    with open(path, "r+b") as raw:
        raw.seek(info.byte_offset + 4)
        data = raw.read(count)
        raw.seek(info.byte_offset + 4)
        raw.write(bytes(b ^ 0x5A for b in data))


def command(kind, path, tmp_path):
    return {"info": ["info", str(path)],
            "info --json": ["info", str(path), "--json"],
            "plot history": ["plot", "history", str(path), "-o", str(tmp_path / "p.png")],
            "plot spectrum": ["plot", "spectrum", str(path), "-o", str(tmp_path / "p.png")],
            "plot pressure": ["plot", "pressure", str(path), "-o", str(tmp_path / "p.png")],
            "export": ["export", str(path), "--out", str(tmp_path / "export")],
            "run --resume": ["run", BAR, "-o", str(path), "--resume", "--quiet",
                             "--set", "solver.t_end=1.2e-4"] + SHORT[2:]}[kind]


@pytest.mark.parametrize("name, kind", [
    ("sensors/tip", "info"),
    ("energy/kinetic", "info --json"),
    ("sensors/tip", "plot history"),
    ("time", "plot spectrum"),
    ("contact/wall/pressure", "plot pressure"),
    ("field/q", "export"),
    ("geometry/contact/wall/points", "export"),
    ("sensors/tip", "run --resume"),
    ("system/C/data", "run --resume"),
    ("checkpoint/state", "run --resume"),
])
def test_flipped_bytes_inside_a_dataset_are_refused_in_one_line(base, tmp_path, capsys, name,
                                                                 kind):
    path = tmp_path / "bar.h5"
    shutil.copy(base, path)
    flip(path, name)
    before = path.read_bytes()
    err = one_error(capsys, command(kind, path, tmp_path))
    assert f"error: {path}: " in err and "damaged" in err and "checksum" in err
    # the checkpoint named by the slot its link points to
    assert f": {name}: " in err or (name.startswith("checkpoint/")
                                    and ": checkpoints/" in err)
    assert path.read_bytes() == before          # nothing written over the damaged file


@pytest.mark.slow
def test_a_history_written_before_the_checksums_still_reads(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(transient.io.checksums, "FILTER", {})
    monkeypatch.setattr(transient.io.history, "FILTER", {})
    path = tmp_path / "old.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"] + SHORT) == 0
    with h5py.File(path, "r") as f:
        assert not any(ds.fletcher32 for ds in arrays(f).values())
    monkeypatch.undo()
    for kind in ("info", "plot history", "export", "run --resume"):
        assert main(command(kind, path, tmp_path)) == 0, kind
    capsys.readouterr()


def cut(path, name, row, count=200):
    """What a kill inside an append leaves (io.history): the chunk of series `name` holding
    `row` rewritten in place from that row on, its checksum not yet, so that it fails; the
    rows before `row` keep their bytes (HDF5 writes them back unchanged)."""
    with h5py.File(path, "r") as f:
        ds = f[name]
        start = row - row % ds.chunks[0]
        info = ds.id.get_chunk_info_by_coord((start,) + (0,) * (ds.ndim - 1))
        at = (row - start) * ds.dtype.itemsize * int(np.prod(ds.chunks[1:]))
    count = min(count, info.size - 4 - at)      # within the chunk's data
    assert count > 0
    with open(path, "r+b") as raw:
        raw.seek(info.byte_offset + at)
        data = raw.read(count)
        raw.seek(info.byte_offset + at)
        raw.write(bytes(b ^ 0x5A for b in data))


def killed_history(path, rows=(10, 10), checkpoints=2):
    """A history as a killed run leaves it: chunks appended and checkpointed, no finish."""
    h = History.create(path, {}, {"time": (), "x": (3,)})
    done = 0
    for k, n in enumerate(rows):
        t = done + np.arange(n, dtype=float)
        h.append({"time": t, "x": np.outer(t, [1.0, -2.0, 3.0])})
        done += n
        if k < checkpoints:
            h.checkpoint({"q": np.full(4, float(done))})
    return done


def test_a_kill_inside_an_append_is_repaired_by_the_first_reader(tmp_path):
    path = tmp_path / "run.h5"
    killed_history(path)
    with h5py.File(path, "r") as f:
        before = {name: f[name][()] for name in ("time", "x")}
    for name in ("time", "x"):
        cut(path, name, 20)
    with h5py.File(path, "r") as f, pytest.raises(OSError, match="filter returned failure"):
        f["x"][()]
    d = summary(path)
    assert d["status"] == "running" and d["steps"] == 20 and d["t_end"] == 19.0
    with h5py.File(path, "r") as f:     # whole again for every reader
        for name, value in before.items():
            np.testing.assert_array_equal(f[name][()], value)
            assert f[name].id.get_num_chunks() == 1


def test_a_cut_after_the_checkpoint_drops_the_rows_it_took(tmp_path):
    # killed in the append after an append that had no checkpoint yet: the history reads
    # as its checkpoint's rows, which a resume continues from
    path = tmp_path / "run.h5"
    assert killed_history(path, rows=(10, 10, 5), checkpoints=2) == 25
    cut(path, "time", 25)
    cut(path, "x", 22)
    d = summary(path)
    assert d["steps"] == 20 and d["t_end"] == 19.0
    assert np.array_equal(load_checkpoint(path)["q"], np.full(4, 20.0))


@pytest.mark.parametrize("case", ["committed rows", "finished", "no checkpoint", "locked"])
def test_a_cut_history_is_not_repaired_unless_its_checkpoint_vouches_for_it(tmp_path, case):
    path = tmp_path / "run.h5"
    killed_history(path, checkpoints=0 if case == "no checkpoint" else 2)
    cut(path, "x", 13 if case == "committed rows" else 20)    # a disk's damage, not a kill's
    if case == "finished":
        with h5py.File(path, "r+") as f:
            f.attrs["status"] = "complete"
    before = path.read_bytes()
    with open(path, "rb") as held:
        if case == "locked":            # the run still writes it
            fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(DamagedHistory) as exc:
            summary(path)
    assert ("being written" in str(exc.value)) == (case == "locked")
    assert case == "locked" or exc.value.key == "x"
    assert path.read_bytes() == before


def test_a_run_killed_inside_an_append_resumes_to_the_uninterrupted_run(base, tmp_path):
    # the kill emulated in the run's last append: the rows from its checkpoint on rewritten,
    # their chunk's checksum not; the resume repairs and recomputes them
    path, whole = tmp_path / "bar.h5", tmp_path / "whole.h5"
    shutil.copy(base, path)
    with h5py.File(path, "r+") as f:
        f.attrs["status"] = "running"
        rows = int(f["checkpoint"].attrs["rows"])
        names = [n for n, ds in arrays(f).items() if n.split("/")[0] in
                 ("time", "sensors", "energy", "contact") and len(ds) > rows]
    for name in names:
        cut(path, name, rows)
    assert main(command("run --resume", path, tmp_path)) == 0
    assert main(["run", BAR, "-o", str(whole), "--quiet", "--set", "solver.t_end=1.2e-4"]
                + SHORT[2:]) == 0
    with h5py.File(path, "r") as a, h5py.File(whole, "r") as b:
        assert a.attrs["status"] == "complete" and names
        for name in names:
            np.testing.assert_array_equal(a[name][()], b[name][()], err_msg=name)
