"""Damaged histories found by fuzzing (tests/fuzz_cases.py), each refused by the reader that
owns the file layout: one line naming the file and the dataset or attribute (exit 2, no
traceback, no warning), in info, plot, export and run --resume alike."""
import shutil

import h5py
import numpy as np
import pytest

from test_validation import BAR, one_error
from transient.cli import main

SHORT = ["--set", "solver.t_end=6e-5", "--set", "output.field=true"]     # 380 rows


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    path = tmp_path_factory.mktemp("damaged") / "bar.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"] + SHORT) == 0
    return path


def replace(name, value):
    def damage(f):
        del f[name]
        f[name] = value
    return damage


def attribute(name, value, group="/"):
    def damage(f):
        f[group].attrs[name] = value
    return damage


def delete_attribute(name):
    def damage(f):
        del f.attrs[name]
    return damage


def extra(f):
    f["extra"] = np.zeros(1000)          # not chunked: cannot grow with the run


NESTED = "[" * 100000 + "]" * 100000


@pytest.mark.parametrize("damage, command, key", [
    (attribute("pairs", NESTED), "info", "attribute pairs"),
    (attribute("overrides", NESTED), "run --resume", "attribute overrides"),
    (attribute("sensor_names", NESTED, "system"), "run --resume",
     "system attribute sensor_names"),
    (replace("sensors/tip", np.float64(1.0)), "info", "sensors/tip"),
    (replace("time", np.float64(1.0)), "plot history", "time"),
    (attribute("version", np.void(b"\xff\xfe")), "info --json", "attribute version"),
    (attribute("version", b"\xff\xfe"), "info", "attribute version"),
    (attribute("timings", "null"), "info", "attribute timings"),
    (attribute("pairs", "null"), "plot pressure", "attribute pairs"),
    (replace("contact/wall/gap", np.array([b"x"] * 380)), "export", "contact/wall/gap"),
    (delete_attribute("case_path"), "export", "attribute case_path"),
    (attribute("case_path", 3), "export", "attribute case_path"),
    (delete_attribute("case"), "export", "attribute case"),
    (attribute("case", 3), "export", "attribute case"),
    (attribute("case", 3), "run --resume", "attribute case"),
    (attribute("case", ""), "run --resume", "attribute case"),
    (attribute("case", "[solver"), "export", "attribute case"),
    (replace("geometry/contact/wall/weights", np.full(12, np.nan)), "plot pressure",
     "geometry/contact/wall/weights"),
    (replace("geometry/contact/wall/normals", np.array([b"x"] * 12)), "export",
     "geometry/contact/wall/normals"),
    (replace("checkpoint/balance", np.float64(1.0)), "run --resume", "checkpoint/balance"),
    (replace("system/signals/4", np.array([b"x"] * 0)), "run --resume", "system/signals/4"),
    (extra, "run --resume", "extra"),
])
def test_a_damaged_history_is_one_line_naming_what_is_damaged(base, tmp_path, capsys, damage,
                                                              command, key):
    path = tmp_path / "bar.h5"
    shutil.copy(base, path)
    with h5py.File(path, "r+") as f:
        damage(f)
    words = command.split()
    args = {"run": ["run", BAR, "-o", str(path), "--resume", "--quiet"] + SHORT,
            "info": ["info", str(path)] + words[1:],
            "plot": words + [str(path), "-o", str(tmp_path / "p.png")],
            "export": ["export", str(path), "--out", str(tmp_path / "export")]}[words[0]]
    err = one_error(capsys, args)
    assert f"error: {path}: {key}: " in err
