"""Transient runs: bar impact against 1D wave theory, two bars exchanging velocities, clean
aborts, bit-for-bit resume, and only the stages a scene needs."""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.case.loading import load
from transient.cli import main
from transient.io.reading import summary
from transient.integration import run

CASES = Path(__file__).resolve().parent.parent / "cases"
L, C_WAVE, V0 = 0.1, np.sqrt(2.1e11 / 7800.0), 1.0


def run_case(tmp_path, text_or_path, overrides=(), name="run.h5"):
    path = Path(text_or_path) if isinstance(text_or_path, Path) else tmp_path / "case.toml"
    if not isinstance(text_or_path, Path):
        path.write_text(text_or_path)
    case = load(path, list(overrides))
    out = tmp_path / name
    return run(case, out), out


def series(path):
    with h5py.File(path, "r") as f:
        return {k: f[k][...] for k in ("time",)} | {
            name: f[name][...] for name in _names(f)}


def _names(f):
    names = []
    f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset)
                 and not n.startswith("checkpoint") else None)
    return names


IMPLICIT = ["solver.scheme=implicit", "solver.dt=2e-7"]


@pytest.mark.parametrize("overrides", [
    ["solver.scheme=explicit"],
    IMPLICIT,                                             # full model, consistent mass
    ["solver.scheme=implicit", "solver.dt=1e-7", "solver.mass=lumped",
     "solver.linear_solver=superlu"],
    IMPLICIT + ["solver.reduction.enabled=true", "solver.reduction.fmax=1e6"],
], ids=["explicit", "implicit", "implicit-lumped-superlu", "implicit-reduced"])
def test_bar_on_a_rigid_wall(tmp_path, overrides):
    # the implicit runs close the contact through Newton with the exact penalty tangent
    # (Woodbury on the fixed operator): the fixed operator alone cannot converge at k = 2e14
    result, out = run_case(tmp_path, CASES / "bar_impact.toml", overrides)
    assert result.status == "complete"
    s = series(out)
    t, p = s["time"], s["contact/wall/pressure"].max(axis=1)
    on = np.flatnonzero(p > 0)
    duration = t[on[-1]] - t[on[0]]
    assert duration == pytest.approx(2 * L / C_WAVE, rel=0.02)
    after = t > t[on[-1]] + 5e-6
    rebound = np.polyfit(t[after], s["sensors/tail"][after], 1)[0]
    assert rebound == pytest.approx(-V0, rel=0.02)
    kinetic0 = s["energy/kinetic"][0]
    assert s["energy/kinetic"][after].mean() == pytest.approx(kinetic0, rel=0.01)
    # the contact pressure of a 1D impact: rho c v0
    assert np.median(p[on]) == pytest.approx(7800.0 * C_WAVE * V0, rel=0.1)


TWO_BARS = (CASES / "two_bars.toml").read_text()


def test_two_identical_bars_exchange_velocities(tmp_path):
    result, out = run_case(tmp_path, TWO_BARS)
    assert result.status == "complete"
    s = series(out)
    t = s["time"]
    late = t > 6.5e-5      # contact from 10 us to about 10 + 2 L / c = 48.5 us
    v_left = np.polyfit(t[late], s["sensors/left_tail"][late], 1)[0]
    v_right = np.polyfit(t[late], s["sensors/right_tail"][late], 1)[0]
    assert abs(v_left) < 0.02 * V0
    assert v_right == pytest.approx(V0, rel=0.02)


def test_unstable_run_aborts_cleanly_and_keeps_its_history(tmp_path, capsys):
    case = tmp_path / "bar.toml"
    case.write_text((CASES / "bar_impact.toml").read_text())
    out = tmp_path / "bad.h5"
    # held at the user's step: subdivided, it holds (test_subdivision)
    code = main(["run", str(case), "-o", str(out), "--quiet", "--set", "solver.dt=4e-7",
                 "--set", "solver.force_dt=true", "--set", "solver.chunk=50",
                 "--set", "solver.subdivision=0"])
    assert code == 3
    assert "aborted" in capsys.readouterr().err
    info = summary(out)
    assert info["status"].startswith("aborted: ")
    assert info["steps"] > 1
    with h5py.File(out, "r") as f:
        assert np.all(np.isfinite(f["time"][...]))


def test_dt_above_critical_is_refused(tmp_path, capsys):
    code = main(["run", str(CASES / "bar_impact.toml"), "-o", str(tmp_path / "x.h5"),
                 "--set", "solver.dt=4e-7"])
    assert code == 2
    err = capsys.readouterr().err
    assert "solver.dt" in err and "critical step" in err and "Traceback" not in err


@pytest.mark.slow
def test_resumed_run_equals_an_uninterrupted_one_bit_for_bit(tmp_path):
    base = ["solver.chunk=100", "solver.t_end=6e-5"]
    whole, whole_path = run_case(tmp_path, CASES / "bar_impact.toml", base, "whole.h5")
    half, part_path = run_case(tmp_path, CASES / "bar_impact.toml",
                               ["solver.chunk=100", "solver.t_end=3e-5"], "part.h5")
    assert half.status == "complete" and half.steps < whole.steps
    case = load(CASES / "bar_impact.toml", base)
    resumed = run(case, part_path, resume=True)
    assert resumed.status == "complete" and resumed.steps == whole.steps
    a, b = series(whole_path), series(part_path)
    assert a.keys() == b.keys()
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_info_json(tmp_path, capsys):
    result, out = run_case(tmp_path, CASES / "bar_impact.toml", ["solver.t_end=2e-5"])
    assert main(["info", str(out), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in ("status", "steps", "t_end", "timings", "energy_drift"):
        assert key in d
    assert d["status"] == "complete" and d["energy_drift"] < 1e-2


def test_stages_only_what_the_scene_needs(tmp_path):
    # no contact pair: no contact stage; fine rule: no compatibility; no reduction asked: none
    text = TWO_BARS.split("[contact.impact]")[0] + TWO_BARS.split("k = 1.0e14")[1]
    result, out = run_case(tmp_path, text, ["solver.t_end=1e-6"])
    assert "contact" not in result.stages and "reduction" not in result.stages
    result, out = run_case(tmp_path, TWO_BARS, ["solver.t_end=1e-6"])
    assert "contact" in result.stages and "reduction" not in result.stages
    with h5py.File(out, "r") as f:
        stages = json.loads(f.attrs["stages"])
        assert set(stages) == set(result.stages)
        # the process's peak memory after each stage: where the setup's peak was reached
        peaks = json.loads(f.attrs["peak_rss_gb"])
        assert set(stages) <= set(peaks) and list(peaks.values()) == sorted(peaks.values())
        assert "contact/impact/gap" not in f          # not requested: not stored
        assert "geometry" not in f and "field" not in f


@pytest.mark.parametrize("reduced", [False, True])
def test_outputs_stored_are_those_asked_for(tmp_path, reduced):
    overrides = ["output.sensors=false", "output.energy=false", "output.field=true",
                 "output.every=10"]
    if reduced:
        overrides += ["solver.reduction.enabled=true", "solver.reduction.fmax=1e6",
                      "solver.scheme=exponential", "solver.dt=2e-7"]
    result, out = run_case(tmp_path, CASES / "bar_impact.toml", overrides)
    assert result.status == "complete"
    with h5py.File(out, "r") as f:
        assert "sensors" not in f and "energy" not in f
        q = f["field/q"][...]
        assert q.shape == (f["time"].shape[0], f.attrs["reduced_dofs"] if reduced
                           else f.attrs["free_dofs"])
        assert np.all(np.isfinite(q)) and np.abs(q[-1]).max() > 0
        if reduced:        # the basis u = T q, for exports
            assert f["geometry/field/basis"].shape[1] == q.shape[1]
        points = f["geometry/contact/wall/points"][...]
        assert points.shape == (f["contact/wall/gap"].shape[1], 3)
        assert np.allclose(points[:, 0], 0.1)          # on the bar's end, facing the wall
        assert f["geometry/contact/wall/weights"][...].sum() == pytest.approx(1e-4)


CANTILEVER = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0

[parts.beam]
material = "steel"
[parts.beam.mesh]
kind = "box"
size = [0.5, 0.05, 0.05]
divisions = [20, 2, 2]
element = "hex8"

[constraints.root]
set = "beam.xmin"

# a 2 kHz sine at the tip, below the reduction's fmax
[loads.shake]
kind = "force"
part = "beam"
point = [0.5, 0.025, 0.05]
vector = [0.0, 0.0, 100.0]
[loads.shake.signal]
kind = "sine"
frequency = 2000.0

[sensors.tip]
part = "beam"
point = [0.5, 0.025, 0.05]
direction = [0.0, 0.0, 1.0]

[solver]
scheme = "explicit"
t_end = 1.0e-3
[solver.reduction]
fmax = 40000.0
"""


@pytest.mark.parametrize("scheme", ["explicit", "exponential"])
def test_reduced_model_agrees_with_the_full_one_without_contact(tmp_path, scheme):
    full, full_path = run_case(tmp_path, CANTILEVER, ["solver.t_end=4e-3"], "full.h5")
    steps = full.steps
    assert steps >= 1000
    reduced, red_path = run_case(tmp_path, CANTILEVER, [
        "solver.reduction.enabled=true", f"solver.scheme={scheme}", f"solver.dt={full.dt}",
        "solver.mass=lumped",
        "solver.force_dt=true", "solver.t_end=4e-3"], "reduced.h5")
    assert reduced.steps == steps and "reduction" in reduced.stages
    a, b = series(full_path)["sensors/tip"], series(red_path)["sensors/tip"]
    assert np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(a ** 2)) < 1e-3


@pytest.mark.slow
def test_implicit_newmark_converges_to_the_exact_linear_response(tmp_path):
    # without contact the exponential scheme propagates each mode exactly; Newmark converges to
    # it, though slower than (dt)^2: the load's static shape is a very high mode whose start-up
    # transient average acceleration keeps undamped
    common = ["solver.reduction.enabled=true", "solver.mass=lumped", "solver.t_end=4e-3"]
    # the exponential scheme takes the sine linear over a step: a tenth of the finest step makes
    # its error negligible here
    exact, exact_path = run_case(tmp_path, CANTILEVER, common + [
        "solver.scheme=exponential", "solver.dt=8.75e-8"], "exact.h5")
    errors = []
    for dt in (3.5e-6, 8.75e-7):
        result, path = run_case(tmp_path, CANTILEVER, common + [
            "solver.scheme=implicit", f"solver.dt={dt}"], f"newmark_{dt}.h5")
        assert result.status == "complete"
        a = series(exact_path)
        b = series(path)
        ref = np.interp(b["time"], a["time"], a["sensors/tip"])
        errors.append(np.sqrt(np.mean((b["sensors/tip"] - ref) ** 2) / np.mean(ref ** 2)))
    assert errors[1] < 1e-3 and errors[1] < errors[0] / 2


def test_explicit_step_rechecked_at_the_deepest_penetration(tmp_path, capsys):
    # open at the start, the exponential law's tangent is nil and dt is set by the bar alone;
    # at impact lambda p reaches 4e14 Pa/m and the step is no longer stable
    code = main(["run", str(CASES / "bar_impact.toml"), "-o", str(tmp_path / "exp.h5"),
                 "--quiet", "--set", 'contact.wall.law.kind="exponential"',
                 "--set", "contact.wall.law.p0=1e3", "--set", "contact.wall.law.lambda=1e7",
                 "--set", "solver.chunk=20"])
    assert code == 3
    err = capsys.readouterr().err
    assert "above the critical step" in err and "deepest penetration" in err
    info = summary(tmp_path / "exp.h5")
    assert info["status"].startswith("aborted: dt") and info["steps"] > 20


def test_a_diverging_run_never_leaves_a_nan_in_its_file(tmp_path, capsys):
    # no drift check: the forced, unstable step runs until the state overflows (held at
    # the user's step: subdivided, it holds)
    out = tmp_path / "nan.h5"
    code = main(["run", str(CASES / "bar_impact.toml"), "-o", str(out), "--quiet",
                 "--set", "solver.dt=4e-7", "--set", "solver.force_dt=true",
                 "--set", "solver.drift_tolerance=1e300", "--set", "solver.t_end=1e-2",
                 "--set", "solver.chunk=500", "--set", "solver.subdivision=0"])
    assert code == 3
    assert "not finite" in capsys.readouterr().err
    info = summary(out)
    assert info["status"].startswith("aborted: state not finite")
    with h5py.File(out, "r") as f:
        for name in _names(f):
            assert np.all(np.isfinite(f[name][...])), name


@pytest.mark.slow
def test_a_penalty_too_stiff_for_the_explicit_step_runs_within_1_percent_or_is_stopped(
        tmp_path, capsys):
    # an aluminium bar at 5 m/s on the shipped bar's wall (k = 2e14 Pa/m). At 0.9 times the
    # critical step (2.17e-7 s) the contact oscillates at omega_c dt = 1.67 and each chatter
    # gains energy (10 J from 0.84 J by the end of a run checked only then)
    out = tmp_path / "al.h5"
    aluminium = ["materials.steel.E=7e10", "materials.steel.rho=2700.0",
                 "parts.bar.mesh.size=[0.25,0.01,0.01]", "contact.wall.wall_point=[0.25001,0,0]",
                 "sensors.tip.point=[0.25,0.005,0.005]", "initial.impact.velocity=[5.0,0,0]"]
    args = ["run", str(CASES / "bar_impact.toml"), "-o", str(out), "--quiet"] + [
        a for o in aluminium for a in ("--set", o)]
    # the automatic step keeps omega_c dt at 0.7: the impact keeps its energy
    assert main(args) == 0
    info = summary(out)
    assert info["status"] == "complete" and info["energy_drift"] < 0.01
    with h5py.File(out, "r") as f:
        assert f.attrs["dt"] == pytest.approx(0.7 / 1.67 * 2.17e-7, rel=0.01)
    capsys.readouterr()
    # that step given by hand is refused before the run, naming the keys that drive it
    assert main(args + ["--set", "solver.dt=2.17e-7"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "solver.dt" in err and "contact.wall.k" in err and "omega_c dt = 1.67" in err
    # forced and held at that step (subdivided, it runs at half of it), the balance (judged
    # from the first 5% of the run) stops it within its first 5%, by name
    assert main(args + ["--set", "solver.dt=2.17e-7", "--set", "solver.force_dt=true",
                        "--set", "solver.subdivision=0"]) == 3
    err = capsys.readouterr().err
    assert "contact.wall.k" in err and "solver.dt" in err and "omega_max dt = 1.80" in err
    info = summary(out)
    assert info["status"].startswith("aborted: energy balance drifted")
    assert info["t_end"] < 0.05 * 1.2e-4 * 1.5


def test_the_run_says_which_factorization_each_stage_used_and_why(tmp_path, capsys):
    from transient.solve.linsolve import available
    out = tmp_path / "bar.h5"
    assert main(["run", str(CASES / "bar_impact.toml"), "-o", str(out), "--quiet",
                 "--set", 'solver.scheme="implicit"', "--set", "solver.dt=1e-7",
                 "--set", "solver.t_end=1e-6"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "factorizations" in x)
    kernel = "cholmod" if "cholmod" in available() else "superlu"
    assert f"iteration operator {kernel} (explicit" in line
    with h5py.File(out, "r") as f:
        assert json.loads(f.attrs["iteration_operator"])["backend"] == kernel
    # a reduced model factorizes K - sigma M once, on the best backend installed or the asked
    assert main(["run", str(CASES / "bar_impact.toml"), "-o", str(out), "--quiet",
                 "--set", "solver.reduction.enabled=true", "--set", "solver.reduction.fmax=2e5",
                 "--set", 'solver.scheme="exponential"', "--set", "solver.dt=1e-7",
                 "--set", "solver.t_end=1e-6", "--set", 'solver.linear_solver="superlu"',
                 "--set", "parts.bar.mesh.divisions=[20,1,1]"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "factorizations" in x)
    assert "stiffness superlu (solver.linear_solver)" in line
