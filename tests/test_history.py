"""HDF5 history: chunks streamed and readable meanwhile, aborts, checkpoints, resume, summary."""
import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.cli.report import format_summary
from transient.errors import RunAborted
from transient.io.attributes import CASE_TEXT
from transient.io.history import History
from transient.dynamics.energy import drift as energy_drift
from transient.io.reading import load_checkpoint, summary

ROOT = Path(__file__).resolve().parent.parent
M = 7
LAYOUT = {"time": (), "sensors/disc_rim": (), "contact/pad_disc/gap": (M,),
          "contact/pad_disc/pressure": (M,), "energy/kinetic": (), "energy/strain": ()}
META = {CASE_TEXT: "[parts.disc]\n", "version": "0.1.0", "rule": "greedy", "eps": 0.01,
        "dt": 1e-6, "timings": {"setup": 1.5}, "stages": ["model", "contact"]}


def chunk(k, n=50, dt=1e-6):
    """Rows of chunk k: an oscillator whose kinetic + strain energy is constant."""
    t = (k * n + 1 + np.arange(n)) * dt
    w = 2 * np.pi * 3000.0
    return {"time": t, "sensors/disc_rim": np.sin(w * t),
            "contact/pad_disc/gap": np.outer(np.cos(w * t), np.arange(M)),
            "contact/pad_disc/pressure": np.outer(t, np.ones(M)),
            "energy/kinetic": 0.5 * np.cos(w * t) ** 2, "energy/strain": 0.5 * np.sin(w * t) ** 2}


def stored(path):
    with h5py.File(path, "r") as f:
        return {name: f[name][()] for name in LAYOUT}


def joined(chunks):
    return {name: np.concatenate([c[name] for c in chunks]) for name in LAYOUT}


def assert_rows_equal(got, expected):
    for name in LAYOUT:
        np.testing.assert_array_equal(got[name], expected[name], err_msg=name)


def run_python(code, **kwargs):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-c", code], env=env, text=True, **kwargs)


def test_three_chunks_read_back(tmp_path):
    path = tmp_path / "run.h5"
    chunks = [chunk(k) for k in range(3)]
    with History.create(path, META, LAYOUT) as h:
        for c in chunks:
            h.append(c)
        assert h.rows() == 150
        h.finish("complete", {"setup": 1.5, "kernel": 2.0, "total": 3.6})
    assert_rows_equal(stored(path), joined(chunks))
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "complete" and f.attrs[CASE_TEXT] == "[parts.disc]\n"
        assert f.attrs["dt"] == 1e-6 and json.loads(f.attrs["stages"]) == ["model", "contact"]
        assert json.loads(f.attrs["timings"]) == {"setup": 1.5, "kernel": 2.0, "total": 3.6}
        # 64 kB chunks, uncompressed, checksummed
        assert f["contact/pad_disc/gap"].chunks == (2 ** 16 // (8 * M), M)
        assert f["time"].chunks == (2 ** 13,) and f["time"].compression is None
        assert f["time"].fletcher32 and f["contact/pad_disc/gap"].fletcher32


def test_leaving_the_block_completes_the_run(tmp_path):
    with History.create(tmp_path / "run.h5", META, LAYOUT, expected_rows=100) as h:
        h.append(chunk(0))
    assert summary(h.path)["status"] == "complete"
    with h5py.File(h.path, "r") as f:
        assert f["time"].chunks == (100,)
    with pytest.raises(ValueError, match="already finished"):
        h.append(chunk(1))


def test_a_reader_sees_every_appended_chunk(tmp_path):
    path = tmp_path / "run.h5"
    chunks = [chunk(k) for k in range(3)]
    with History.create(path, META, LAYOUT) as h:
        for k, c in enumerate(chunks):
            h.append(c)
            assert summary(path)["steps"] == 50 * (k + 1)
            assert_rows_equal(stored(path), joined(chunks[:k + 1]))


def test_a_reader_holding_the_file_open_does_not_stop_the_writer(tmp_path):
    path = tmp_path / "run.h5"
    with History.create(path, META, LAYOUT) as h:
        h.append(chunk(0))
        reader = run_python("import h5py, sys\n"
                            f"f = h5py.File({str(path)!r}, 'r')\n"
                            "print(f['time'].shape[0], flush=True)\n"
                            "sys.stdin.readline()\n",
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        assert reader.stdout.readline().strip() == "50"
        h.append(chunk(1))
        reader.communicate("\n", timeout=30)
    assert summary(path)["steps"] == 100


def test_an_exception_marks_the_run_aborted_and_keeps_its_rows(tmp_path):
    path = tmp_path / "run.h5"
    with pytest.raises(RunAborted):
        with History.create(path, META, LAYOUT) as h:
            h.append(chunk(0))
            h.append(chunk(1))
            raise RunAborted("energy drift 6% > 5% at t = 1.2e-3 s")
    assert summary(path)["status"] == "aborted: energy drift 6% > 5% at t = 1.2e-3 s"
    assert_rows_equal(stored(path), joined([chunk(0), chunk(1)]))
    with pytest.raises(ZeroDivisionError):
        with History.create(path, META, LAYOUT, overwrite=True) as h:
            h.append(chunk(0))
            1 / 0
    assert summary(path)["status"] == "aborted: ZeroDivisionError: division by zero"


def test_an_interrupt_inside_an_append_keeps_the_complete_rows(tmp_path, monkeypatch):
    path = tmp_path / "run.h5"
    with pytest.raises(KeyboardInterrupt):
        with History.create(path, META, LAYOUT) as h:
            h.append(chunk(0))
            writes = []
            write = h5py.Dataset.__setitem__

            def interrupted(self, key, value):
                writes.append(key)
                if len(writes) == 3:
                    raise KeyboardInterrupt
                write(self, key, value)

            monkeypatch.setattr(h5py.Dataset, "__setitem__", interrupted)
            h.append(chunk(1))
    monkeypatch.undo()
    assert summary(path)["status"] == "aborted: interrupted by the user"
    assert_rows_equal(stored(path), chunk(0))


def test_checkpoint_round_trip_is_bit_exact(tmp_path):
    path = tmp_path / "run.h5"
    rng = np.random.default_rng(0)
    q = rng.standard_normal(40)
    q[[3, 5, 7]] = [np.nan, -0.0, 5e-324]
    state = {"q": q, "v": rng.standard_normal(40), "a": rng.standard_normal((4, 10)),
             "step": np.int64(123456789), "time": 0.1 + 0.2, "energy": np.array([1e-300, 3.0])}
    with History.create(path, META, LAYOUT) as h:
        h.append(chunk(0))
        h.checkpoint({"q": np.zeros(40), "stale": np.ones(3)})
        h.checkpoint(state)
        h.checkpoint(state)
        size = path.stat().st_size
        h.checkpoint(state)
        h.checkpoint(state)
        assert path.stat().st_size == size        # both slots rewritten in place
    loaded = load_checkpoint(path)
    assert set(loaded) == set(state)
    for name, value in state.items():
        value = np.asarray(value)
        assert loaded[name].dtype == value.dtype and loaded[name].shape == value.shape
        assert np.asarray(loaded[name]).tobytes() == value.tobytes(), name


def test_resume_appends_after_the_stored_rows(tmp_path):
    path = tmp_path / "run.h5"
    with pytest.raises(KeyboardInterrupt):
        with History.create(path, META, LAYOUT) as h:
            for k in range(2):
                h.append(chunk(k))
                h.checkpoint({"step": np.int64(50 * (k + 1))})
            raise KeyboardInterrupt
    h = History.open_for_resume(path)
    assert h.rows() == 100 and summary(path)["status"] == "running"
    assert int(load_checkpoint(path)["step"]) == 100
    with h:
        h.append(chunk(2))
        h.checkpoint({"step": np.int64(150)})
    assert_rows_equal(stored(path), joined([chunk(k) for k in range(3)]))
    with History.open_for_resume(path) as h:     # a complete run reopens too
        h.append(chunk(3))
    assert summary(path)["steps"] == 200


def test_resume_drops_the_rows_past_the_checkpoint(tmp_path):
    path = tmp_path / "run.h5"
    with History.create(path, META, LAYOUT) as h:
        h.append(chunk(0))
        h.checkpoint({"step": np.int64(50)})
        h.append(chunk(1))
        h.finish("aborted: killed")
    with History.open_for_resume(path) as h:
        assert h.rows() == 50
        h.append(chunk(1))
    assert_rows_equal(stored(path), joined([chunk(0), chunk(1)]))


def test_a_killed_writer_leaves_a_readable_file(tmp_path):
    path = tmp_path / "run.h5"
    code = ("import os, signal\nimport numpy as np\n"
            "from transient.io.history import History\n"
            f"h = History.create({str(path)!r}, {{}}, {{'time': (), 'x': (3,)}})\n"
            "with h:\n"
            "    for k in range(2):\n"
            "        h.append({'time': np.arange(10.0) + 10 * k, 'x': np.ones((10, 3))})\n"
            "        h.checkpoint({'q': np.full(5, k)})\n"
            "    os.kill(os.getpid(), signal.SIGKILL)\n")
    assert run_python(code).wait(timeout=60) == -9
    d = summary(path)
    assert d["status"] == "running" and d["steps"] == 20 and d["t_end"] == 19.0
    np.testing.assert_array_equal(load_checkpoint(path)["q"], np.ones(5, int))


def test_refuses_to_overwrite(tmp_path):
    path = tmp_path / "run.h5"
    History.create(path, META, LAYOUT).finish("complete")
    with pytest.raises(ValueError, match="exists"):
        History.create(path, META, LAYOUT)
    History.create(path, {}, {"time": ()}, overwrite=True).finish("complete")
    assert list(summary(path)["series"]) == ["time"]


def test_bad_rows_and_meta(tmp_path):
    h = History.create(tmp_path / "run.h5", META, LAYOUT)
    rows = chunk(0)
    with pytest.raises(ValueError, match="missing"):
        h.append({"time": rows["time"]})
    with pytest.raises(ValueError, match="contact/pad_disc/gap"):
        h.append(rows | {"contact/pad_disc/gap": np.zeros((50, M + 1))})
    with pytest.raises(ValueError, match="numbers of rows"):
        h.append(rows | {"time": np.zeros(49)})
    with pytest.raises(ValueError, match="status"):
        h.finish("done")
    h.finish("complete")
    with pytest.raises(ValueError, match="reserved"):
        History.create(tmp_path / "b.h5", {"status": "x"}, LAYOUT)
    with pytest.raises(TypeError, match="meta key 'when'"):
        History.create(tmp_path / "c.h5", {"when": object()}, LAYOUT)


def test_summary(tmp_path):
    path = tmp_path / "run.h5"
    with History.create(path, META, LAYOUT) as h:
        for k in range(3):
            h.append(chunk(k))
        h.finish("complete", {"setup": 1.5, "kernel": 2.0})
    d = summary(path)
    assert json.loads(json.dumps(d)) == d
    assert d["status"] == "complete" and d["steps"] == 150 and d["t_end"] == 150e-6
    assert d["timings"] == {"setup": 1.5, "kernel": 2.0}
    assert d["energy_drift"] < 1e-14             # kinetic + strain of an oscillator
    assert d["series"]["contact/pad_disc/gap"] == [M] and d["series"]["time"] == []
    assert CASE_TEXT not in d["meta"] and d["meta"]["stages"] == ["model", "contact"]
    assert d["meta"]["eps"] == 0.01 and d["file_size"] == path.stat().st_size
    text = format_summary(d)
    assert "complete" in text and "contact/pad_disc/gap (7,)" in text and text.isascii()
    History.create(path, {}, {"time": ()}, overwrite=True).finish("complete")
    assert summary(path)["energy_drift"] is None and summary(path)["t_end"] is None


def balanced_energy(t):
    """Terms whose kinetic + strain + contact - external_work + dissipated is 3.25 [J]."""
    return {"kinetic": 2 + np.sin(t), "strain": 1 - 0.5 * np.sin(t), "contact": 0.25 * np.cos(t),
            "external_work": t, "dissipated": t - 0.5 * np.sin(t) - 0.25 * np.cos(t) + 0.25}


def mechanical_peak(terms):
    """The scale of the drift: the peak of kinetic + strain + contact, or of the work in or
    the energy dissipated when larger."""
    zero = np.zeros_like(terms["kinetic"])
    held = np.abs(terms["kinetic"]) + np.abs(terms["strain"]) + np.abs(terms["contact"])
    return np.max(np.maximum(held, np.maximum(np.abs(terms.get("external_work", zero)),
                                              np.abs(terms.get("dissipated", zero)))))


def test_energy_drift():
    t = np.linspace(0.0, 10.0, 1001)
    terms = balanced_energy(t)
    assert energy_drift(terms) < 1e-14
    delta = 0.01
    terms["kinetic"] = terms["kinetic"] + delta * t
    assert energy_drift(terms) == pytest.approx(delta * 10 / mechanical_peak(terms), rel=1e-12)
    # a missing term counts as 0: without the work, E = 3.25 + t
    del terms["external_work"]
    terms["kinetic"] = 2 + np.sin(t)
    assert energy_drift(terms) == pytest.approx(10 / mechanical_peak(terms), rel=1e-12)
    assert energy_drift({}) is None


def test_energy_drift_of_a_sliding_flow_is_scaled_by_the_flow():
    """Friction on a sliding surface passes far more energy through (work in, dissipated) than
    the vibration holds: an error on that flow counts against the flow."""
    t = np.linspace(0.0, 10.0, 1001)
    terms = {"kinetic": 1e-3 * np.sin(t) ** 2, "strain": 1e-3 * np.cos(t) ** 2,
             "contact": 0 * t, "external_work": 100 * t}
    terms["dissipated"] = terms["external_work"] * (1 - 1e-4)      # 0.1 J lost of 1 kJ
    assert energy_drift(terms) == pytest.approx(1e-4, rel=1e-9)


def test_energy_drift_of_a_balance_near_zero_is_scaled_by_the_stored_energy():
    # started at rest and driven: the balance stays ~0, the stored energy does not
    t = np.linspace(0.0, 10.0, 1001)
    terms = {"kinetic": np.sin(t) ** 2, "strain": (1 - np.cos(t)) ** 2, "contact": 0 * t,
             "dissipated": 0 * t}
    terms["external_work"] = terms["kinetic"] + terms["strain"] + 1e-9 * t
    assert energy_drift(terms) == pytest.approx(1e-8 / mechanical_peak(terms), rel=1e-6)


def test_summary_energy_drift_of_a_drifting_run(tmp_path):
    path = tmp_path / "run.h5"
    t = np.linspace(0.0, 10.0, 1001)
    terms = balanced_energy(t)
    terms["dissipated"] = terms["dissipated"] - 0.02 * t
    layout = {"time": ()} | {f"energy/{name}": () for name in terms}
    with History.create(path, {}, layout) as h:
        for part in np.array_split(np.arange(len(t)), 3):
            h.append({"time": t[part]} | {f"energy/{n}": v[part] for n, v in terms.items()})
    assert summary(path)["energy_drift"] == pytest.approx(0.2 / mechanical_peak(terms), rel=1e-12)


def test_a_process_killed_while_it_checkpoints_leaves_the_previous_checkpoint_whole(
        tmp_path, monkeypatch):
    # the new slot is written and flushed, then the process dies before /checkpoint moves to
    # it: what a resume reads is the previous checkpoint, with its own rows
    import h5py
    path = tmp_path / "run.h5"
    with History.create(path, META, LAYOUT) as h:
        h.append(chunk(0))
        h.checkpoint({"q": np.zeros(4)})
        h.append(chunk(1))

        flush = h5py.File.flush

        def killed(f):
            flush(f)
            raise KeyboardInterrupt
        monkeypatch.setattr(h5py.File, "flush", killed)
        with pytest.raises(KeyboardInterrupt):
            h.checkpoint({"q": np.ones(4)})
        monkeypatch.undo()
    assert np.array_equal(load_checkpoint(path)["q"], np.zeros(4))
    with h5py.File(path, "r") as f:
        assert f["checkpoint"].attrs["rows"] == len(chunk(0)["time"])
