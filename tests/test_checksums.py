"""Every array of a history carries HDF5's checksum (fletcher32): bytes changed inside a
dataset's data after the run are refused by every reader in one line naming the file and the
dataset as damaged (exit 2), while a history written before the checksums still reads."""
import shutil

import h5py
import pytest

import transient.io.checksums
import transient.io.history
from test_validation import BAR, one_error
from transient.cli import main

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
