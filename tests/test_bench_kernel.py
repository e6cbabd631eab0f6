"""benchmarks/bench_kernel.py at a tiny size: what both modes report, and the exponential scheme's
error shrinking with its step (no timing is asserted)."""
import math

import numpy as np
import pytest

import bench_kernel as bench  # benchmarks/, studies/, tools/: pytest's pythonpath (setup.cfg)


def test_roofline_rows_are_positive_times(capsys):
    result = bench.roofline([(8, 100)], repeat=1, target_s=1e-3)
    assert {"cpu_count", "numba_threads", "load_average", "rows"} <= result.keys()
    row, = result["rows"]
    assert (row["n"], row["m"]) == (8, 100)
    keys = {"roofline_us", "explicit_1_us", "exponential0_1_us", "exponential1_1_us",
            "exponential0_us", "exponential1_us", "exponential1_pass_us", "ratio"}
    assert keys <= row.keys()
    values = [v for k, v in row.items() if k.endswith("_us") or k == "ratio"]
    assert all(math.isfinite(v) and v > 0 for v in values)
    bench.print_roofline(result)
    assert "8   100" in capsys.readouterr().out


@pytest.fixture(scope="module")
def tiny():
    # exponential steps from dt_out / 8: omega_max dt = 1.6 at 10 kHz (above about 3, the error
    # stays at the share of the unresolved mode instead of falling)
    return bench.accuracy(freqs=np.r_[np.geomspace(100.0, 2e3, 6), 1e4], m=20, t_end=4e-3,
                          dt_out=2e-4, ref_k=100, rtols=(1e-3, 1e-6), exp_ks=(8, 16, 32),
                          newmark_ks=(1, 4), explicit_factors=(1, 2), repeat=1)


def test_accuracy_reports_every_method(tiny, tmp_path, capsys):
    assert {"n", "m", "t_end", "dt_out", "reference", "runs", "time_to"} <= tiny.keys()
    methods = {"explicit", "newmark", "exp c0 PE", "exp c1 PECE", "exp c0 PEC", "RK45", "DOP853"}
    assert {r["method"] for r in tiny["runs"]} == methods
    for r in tiny["runs"]:
        assert {"setting", "seconds", "count", "status", "error"} <= r.keys()
        assert r["seconds"] > 0 and r["count"] > 0
    assert set(tiny["time_to"]) == {"0.01", "0.003"}
    assert all(set(best) == methods for best in tiny["time_to"].values())
    bench.print_accuracy(tiny)
    assert "fastest run reaching the error" in capsys.readouterr().out
    bench.plot_accuracy(tiny, tmp_path / "accuracy.png")
    assert (tmp_path / "accuracy.png").stat().st_size > 0


def test_exponential_error_decreases_when_dt_is_halved(tiny):
    errors = [r["error"] for r in tiny["runs"] if r["method"] == "exp c1 PECE"]
    assert len(errors) == 3 and None not in errors
    assert errors[1] < errors[0] and errors[2] < errors[1]
    assert tiny["reference"]["self_error"] < 0.1 * errors[-1]
