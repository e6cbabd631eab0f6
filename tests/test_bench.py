"""`transient bench` on a coarse pad on a disc: the sweep's rows, errors that can fail, files."""
import json
from pathlib import Path

import numpy as np
import pytest

from transient.studies.bench import bench, compare, target, write
from transient.cli import main

from small_cases import PAD_DISC, PAD_DISC_THIN

CASES = Path(__file__).resolve().parent.parent / "cases"
SMALL = PAD_DISC_THIN + ["solver.reduction.fmax=6000.0", "solver.modes.fmax=6000.0",
                         "loads.tap.signal.duration=2e-4"]


def test_compare_measures_what_it_says():
    t = np.linspace(0.0, 1.0, 101)
    ref = {"time": t, "sensors/a": 1.0 + np.sin(7 * t), "contact/pressure": np.full((101, 3), 2.0)}
    # a preload 5% off: apart from the vibration's error
    run = {"time": t, "sensors/a": 1.05 + 1.01 * np.sin(7 * t),
           "contact/pressure": np.full((101, 5), 2.2)}
    out = compare(ref, run, np.array([100.0, 200.0]), np.array([101.0, 200.0, 300.0]))
    assert out["error_rms"] == pytest.approx(0.01, rel=0.02)
    assert out["preload_error"] == pytest.approx(0.05)
    assert out["pressure_max_error"] == pytest.approx(0.1)
    assert out["frequency_error"] == pytest.approx(0.01)


@pytest.mark.slow
def test_bench_sweeps_the_rules_of_a_small_pad_on_a_disc():
    rows = bench(CASES / "pad_disc.toml", SMALL, eps_list=[1e-6, 1.0], points_list=[0, 20],
                 t_end=1e-3, tolerances=[1e-2])
    labels = [r["label"] for r in rows]
    assert labels == ["fine", "fine reg eps=1e-06", "fine reg eps=1", "centre", "centre reg",
                      "greedy m=rank", "greedy m=20", "sampled tol=0.01"]
    ref = rows[0]
    assert ref["rule"] == "fine" and ref["error_rms"] == 0.0
    assert all(r["status"] == "complete" for r in rows)
    assert rows[3]["points"] < ref["points"] and rows[6]["points"] == 20
    # eps = 1 keeps every shape: the regularized observation is the fine one
    assert rows[2]["kept"] > rows[1]["kept"]
    assert rows[2]["error_rms"] < 1e-3 and rows[2]["frequency_error"] < 1e-3
    assert rows[1]["error_rms"] > 10 * rows[2]["error_rms"]
    # the sampled rule: fewer points than the fine rule, the regularized fine rule's basis
    assert rows[7]["points"] < ref["points"] and rows[7]["regularized"]
    for r in rows:
        assert r["setup_s"] > 0 and r["kernel_s"] > 0 and r["total_s"] >= r["kernel_s"]
    best = target(rows)
    assert best is None or (best["error_rms"] <= 0.01 and best["rule"] != "fine")


@pytest.mark.slow
def test_bench_command_writes_csv_json_png(tmp_path, capsys):
    args = ["bench", str(CASES / "pad_disc.toml"), "--eps", "1e-3", "--points", "15",
            "--tolerances", "1e-2",
            "--t-end", "5e-4", "--out", str(tmp_path), "--json"]
    for o in SMALL:
        args += ["--set", o]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rows"][0]["rule"] == "fine"
    assert {"rule", "points", "setup_s", "kernel_s", "total_s", "error_rms"} <= set(out["rows"][0])
    saved = json.loads((tmp_path / "bench.json").read_text())
    assert len(saved["rows"]) == len(out["rows"]) == 6
    assert (tmp_path / "bench.csv").read_text().count("\n") == 7
    assert (tmp_path / "bench.png").stat().st_size > 10_000


def test_bench_refuses_bad_options(tmp_path, capsys):
    case = tmp_path / "c.toml"
    case.write_text((CASES / "pad_disc.toml").read_text())
    assert main(["bench", str(case), "--eps", "x"]) == 2
    assert "--eps" in capsys.readouterr().err


@pytest.mark.slow
def test_rules_a_scene_refuses_are_rows_that_say_why(tmp_path):
    """A rigid wall has no second mesh: every rule but the fine one is refused, the sweep goes
    on and its files are written."""
    rows = bench(CASES / "bar_impact.toml", eps_list=[1e-3], points_list=[0], t_end=2e-5,
                 tolerances=[1e-2])
    assert rows[0]["status"] == "complete" and len(rows) == 6
    for row in rows[1:]:
        assert row["status"].startswith("refused: contact.wall.rule:")
        assert row["error_rms"] is None and row["kernel_s"] is None
    assert target(rows) is None
    files = write(rows, tmp_path)
    assert all(f.stat().st_size > 0 for f in files)


SQUEAL = PAD_DISC + ["motion.disc.omega=50.0", "solver.damping.residual=0.0",
                     "contact.pad_disc.friction.mu=0.4", "loads.tap.vector=[0.0,0.0,-0.02]"]


@pytest.mark.slow
def test_bench_measures_a_squeal_against_half_the_step(tmp_path, capsys):
    """With friction and reference 'case': the case's rule at dt / 2 first, then at dt, then
    the sweep; each row's growth rate (the small pad and disc's flutter mode grows at the CEA's
    real part, test_squeal) and the oscillation's frequency and RMS, with their errors against
    the reference: about 1% on the growth at dt against dt / 2 (1.2% measured), and the
    same frequency to a small fraction of the spectrum's bin (1e-5 measured)."""
    import scipy.linalg as sla
    from transient.case.loading import load
    from transient.stability.linearize import linearized
    from transient.stages import prepare
    setup = prepare(load(CASES / "pad_disc.toml", SQUEAL))
    _, D, K = linearized(setup.system, setup.state)
    n = setup.system.n
    lam = sla.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-K, -D]]))
    fastest = lam[np.argmax(np.where(lam.imag > 0, lam.real, -np.inf))]
    rows = bench(CASES / "pad_disc.toml", SQUEAL, eps_list=[], points_list=[], tolerances=[],
                 t_end=6e-3, reference="case")
    assert [r["label"] for r in rows] == ["case dt/2", "case", "centre", "centre reg"]
    ref, own = rows[0], rows[1]
    assert ref["steps"] == 2 * own["steps"] and ref["error_rms"] == 0.0
    assert ref["growth_error"] == 0.0 and ref["cycle_rms_error"] == 0.0
    assert ref["growth_rate"] == pytest.approx(fastest.real, rel=1e-2)
    assert ref["cycle_frequency"] == pytest.approx(fastest.imag / (2 * np.pi), rel=2e-3)
    assert 1e-4 < own["growth_error"] < 3e-2 and own["cycle_frequency_error"] < 1e-3
    # a growth over the last quarter: the RMS there follows the growth's error (6% measured)
    assert own["cycle_rms_error"] < 0.2
    # the regularized centre rule: as many points, a slower growth (39% measured)
    reg = rows[3]
    assert reg["status"] == "complete" and reg["growth_error"] > 0.1
    files = write(rows, tmp_path)
    saved = json.loads(files[1].read_text())["rows"]
    assert saved[1]["growth_error"] == pytest.approx(own["growth_error"])
    assert "cycle_rms_error" in files[0].read_text().splitlines()[0]


def test_bench_refuses_a_cycle_window_outside_the_run(capsys):
    assert main(["bench", str(CASES / "pad_disc.toml"), "--cycle-from", "1.0",
                 "--t-end", "1e-3"]) == 2
    err = capsys.readouterr().err
    assert "--cycle-from" in err and "[0, 0.001)" in err
    assert main(["bench", str(CASES / "pad_disc.toml"), "--reference", "coarse"]) == 2
    assert "--reference" in capsys.readouterr().err


def test_growth_is_fitted_before_a_wandering_limit_cycle():
    """A growth at 2000 1/s over 4 decades, then a limit cycle whose amplitude wanders by a
    third, up by 1.6x over the run's last tenth: the growth is the linear phase's (within 2%),
    not the limit cycle's wander (pad_disc_squeal's 20 ms at mu = 0.4 read -13 1/s)."""
    from transient.studies.bench import oscillation
    f, sigma = 10e3, 2000.0
    t = np.arange(0.0, 0.02, 1.0 / (8 * f))
    saturated = 1e-6 * (1.0 + 0.35 * np.sin(2 * np.pi * 150.0 * t + 2.0))
    amplitude = np.minimum(1e-10 * np.exp(sigma * t), saturated)
    x = amplitude * np.sin(2 * np.pi * f * t)
    summary, _ = oscillation({"time": t, "sensors/a": x}, 0.01)
    assert summary["growth_rate"] == pytest.approx(sigma, rel=2e-2)
    assert summary["cycle_frequency"] == pytest.approx(f, rel=1e-3)
