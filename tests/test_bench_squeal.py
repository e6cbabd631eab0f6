"""benchmarks/bench_squeal.py on a short squeal of the small pad and disc: what it reads of the
history and the roofline it times on the run's own rows."""
import json

import h5py
import pytest

from transient.integration import run

from test_cea import small

import bench_squeal as bench  # benchmarks/, studies/, tools/: pytest's pythonpath (setup.cfg)


@pytest.mark.slow
def test_roofline_of_a_squeal_history(tmp_path, capsys):
    path = tmp_path / "squeal.h5"
    case = small("contact.pad_disc.friction.mu=0.4", "solver.dt=2e-6", "solver.t_end=4e-4")
    run(case, path)
    bench.main(["--history", str(path), "--repeat", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    with h5py.File(path) as f:
        assert (out["points"], out["dofs"]) == f["system/Ct"].shape
    assert out["steps"] == 200 and out["passes_per_step"] == 2      # evaluated, 1 correction
    for name in ("read_once", "numpy_pass"):
        times = out["roofline_us_per_pass"][name]
        assert set(times) == {"1", "2"} and all(us > 0 for us in times.values())
    assert out["us_per_pass"] == out["us_per_step"] / 2 and out["roofline_ratio"] > 0
    bench.main(["--history", str(path), "--repeat", "3"])
    text = capsys.readouterr().out
    assert "200 steps" in text and "one row block, serial" in text
    assert "against every row read once" in text
