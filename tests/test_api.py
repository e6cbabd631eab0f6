"""The public Python API (transient.load, prepare, run, modes, cea, compat, sweep): what it
returns is what the command line prints, its bad input is a CaseError naming the file and
the key, and importing it changes nothing."""
import json
import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import transient
from transient.cli import main
from transient.errors import CaseError

from small_cases import PAD_DISC_THIN

ROOT = Path(__file__).resolve().parent.parent
PAD, BAR, CUBE = (ROOT / "cases" / f"{n}.toml" for n in ("pad_disc", "bar_impact",
                                                          "drilled_cube"))
SMALL = PAD_DISC_THIN + ["solver.reduction.fmax=6000.0", "solver.modes.fmax=6000.0"]
SHORT = ["solver.t_end=2e-5"]


def cli_json(capsys, *args, overrides=()):
    code = main([*map(str, args), "--json"] + [a for o in overrides for a in ("--set", o)])
    out = capsys.readouterr().out
    assert code == 0
    return json.loads(out)


def test_importing_transient_loads_no_stage_and_changes_nothing():
    code = """
import json, os, sys
before = dict(os.environ)
import transient
# dir() lists the API before it is imported
listed = set(transient.__all__) <= set(dir(transient)) and "transient.api" not in sys.modules
names = [transient.load, transient.prepare, transient.modes, transient.compat]
heavy = [m for m in ("numba", "scipy", "h5py", "transient.stages") if m in sys.modules]
print(json.dumps([dict(os.environ) == before, heavy, callable(transient.run), listed]))
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True)
    assert json.loads(done.stdout.splitlines()[-1]) == [True, [], True, True]


def test_the_public_functions_stay_functions_when_the_stages_are_imported():
    """The stages' modules (integration, stability, campaign) have names of their own: importing
    them leaves transient.run, .cea and .sweep the API's functions."""
    import transient.api
    import transient.campaign.campaign
    import transient.integration
    import transient.stability.stage
    from transient import cea, run, sweep
    assert (run, cea, sweep) == (transient.api.run, transient.api.cea, transient.api.sweep)
    assert transient.run is run and transient.cea is cea and transient.sweep is sweep
    assert set(transient.__all__) <= set(dir(transient))
    assert "Complex eigenvalue analysis" in transient.stability.__doc__
    with pytest.raises(AttributeError):
        transient.no_such_name


def test_bad_input_is_a_case_error_naming_the_file_and_the_key(tmp_path):
    with pytest.raises(CaseError) as exc:
        transient.load(BAR, ["solver.t_end=-1.0"])
    assert exc.value.path == str(BAR) and exc.value.key == "solver.t_end"
    assert "expected" in exc.value.message
    with pytest.raises(CaseError) as exc:
        transient.load(tmp_path / "none.toml")
    assert exc.value.path == str(tmp_path / "none.toml")
    with pytest.raises(CaseError) as exc:
        transient.compat(transient.load(CUBE), "nowhere")
    assert exc.value.path == str(CUBE) and exc.value.key == "contact"
    with pytest.raises(CaseError) as exc:
        transient.sweep(BAR, ["initial.impact.velocity"], tmp_path / "campaign")
    assert exc.value.key == "--param" and not (tmp_path / "campaign").exists()


@pytest.mark.slow
def test_run_writes_the_history_and_returns_its_path_and_summary(tmp_path, capsys):
    case = transient.load(BAR, SHORT)
    result = transient.run(case, tmp_path / "api.h5")
    assert result.path == str(tmp_path / "api.h5") and result.status == "complete"
    with h5py.File(result.path) as history:
        assert history["time"][-1] == result.t_end
        assert history.attrs["status"] == "complete"
    out = cli_json(capsys, "run", BAR, "-o", tmp_path / "cli.h5", overrides=SHORT)
    summary = result.summary()
    for key in ("status", "steps", "t_end", "dt", "dt_critical", "energy_drift",
                "subdivisions"):
        assert summary[key] == out[key], key
    # by default the history is the case's own, next to its file
    (tmp_path / "bar.toml").write_text(BAR.read_text())
    mine = transient.run(transient.load(tmp_path / "bar.toml", SHORT))
    assert mine.path == str(tmp_path / "bar.h5") and Path(mine.path).is_file()


def test_prepare_gives_the_system_and_the_models_matrices():
    setup = transient.prepare(transient.load(BAR, SHORT))
    model = setup.model
    assert model.K.shape == model.M.shape == (model.ndof, model.ndof)
    assert setup.system.n == int((~model.fixed).sum()) and "model" in setup.stages


@pytest.fixture(scope="module")
def small_pad():
    return transient.load(PAD, SMALL)


def test_modes_equal_the_commands(small_pad, capsys):
    result = transient.modes(small_pad, matrices=True)
    out = cli_json(capsys, "modes", PAD, overrides=SMALL)
    assert out["frequencies_hz"] == result.frequencies.tolist()
    summary = result.summary()
    assert {k: v for k, v in summary.items() if k != "timings"} == {
        k: v for k, v in out.items() if k != "timings"}
    assert set(out["timings"]) == set(summary["timings"]) | {"total"}
    # the shapes are mass-normalized on the model's matrices
    phi, n = result.shapes, len(result.frequencies)
    assert phi.shape == (result.ndof, n) and n > 0
    assert np.allclose(phi.T @ (result.M @ phi), np.eye(n), atol=1e-8)
    assert not phi[result.fixed].any()


def test_cea_equals_the_commands_json(small_pad, capsys):
    case = transient.load(PAD, SMALL + ["contact.pad_disc.friction.mu=0.4"])
    result = transient.cea(case, matrices=True)
    out = cli_json(capsys, "cea", PAD, overrides=SMALL + ["contact.pad_disc.friction.mu=0.4"])
    summary = json.loads(json.dumps(result.summary()))
    assert {k: v for k, v in summary.items() if k != "stages"} == {
        k: v for k, v in out.items() if k not in ("stages", "total")}
    assert set(summary["stages"]) == set(out["stages"])
    # each complex mode solves the linearized (lambda^2 M + lambda D + K) v = 0 it returns
    M, D, K = result.matrices
    lam, v = result.modes.eigenvalues, result.modes.vectors
    assert len(lam) > 0 and M.shape == (result.reduced, result.reduced)
    for j in range(len(lam)):
        r = (lam[j] ** 2 * M + lam[j] * D + K) @ v[:, j]
        scale = (abs(lam[j]) ** 2 * np.abs(M) + np.abs(K)) @ np.abs(v[:, j])
        assert np.linalg.norm(r) <= 1e-8 * np.linalg.norm(scale)


def test_a_mu_map_equals_the_cea_of_each_variant():
    """mu_map shares the model, the contact and the factorization among its values: each
    analysis equals `cea` of the case at that mu, bit for bit (the values a NumPy array's).
    Its branches: each mode at 0.2 linked to one at 0.4, the unstable ones tabled."""
    case = transient.load(PAD, SMALL)
    found = transient.mu_map(case, np.array([0.2, 0.4]))
    assert len(found) == 2
    for mu, analysis in zip([0.2, 0.4], found):
        alone = transient.cea(transient.load(PAD, SMALL + [f"contact.pad_disc.friction.mu={mu}"]))
        assert np.array_equal(analysis.modes.eigenvalues, alone.modes.eigenvalues)
    branches = transient.branches([0.4, 0.2], found[::-1])
    assert branches.linked_by == "shapes" and list(branches.values) == [0.2, 0.4]
    assert branches.count == len(found[0].modes.eigenvalues) == len(found[1].modes.eigenvalues)
    assert np.nanmin(branches.mac[1]) > 0.5
    assert [(r["mu"], r["frequency_hz"]) for r in branches.unstable_modes()] == [
        (mu, f) for mu, a in zip([0.2, 0.4], found)
        for f in a.modes.frequency_hz[a.modes.unstable]]
    with pytest.raises(CaseError, match="mus"):
        transient.mu_map(case, [-0.1])
    with pytest.raises(CaseError, match="mus"):
        transient.branches([0.2], found)


@pytest.mark.slow
def test_compat_equals_the_commands_json(capsys):
    result = transient.compat(transient.load(CUBE))
    out = cli_json(capsys, "compat", CUBE)
    summary = result.summary(np.logspace(-16, 0, 65))
    timed = ("setup_s", "timings", "coarse")
    assert {k: v for k, v in summary.items() if k not in timed} == {
        k: v for k, v in out.items() if k not in timed}
    comp = result.compatibility
    assert comp.kept(result.pair.eps) == out["kept"] == 25
    assert comp.shapes.shape == (comp.n1 + comp.n2, comp.n1 + comp.n2)


@pytest.mark.slow
def test_sweep_runs_the_variants_the_command_would(tmp_path):
    campaign = transient.sweep(BAR, {"initial.impact.velocity": [[1.0, 0.0, 0.0],
                                                                [2.0, 0.0, 0.0]]},
                               tmp_path / "campaign", overrides=SHORT, workers=1)
    assert [r["status"] for r in campaign.rows] == ["complete", "complete"]
    assert campaign.table == tmp_path / "campaign" / "sweep.csv" and campaign.table.is_file()
    for v in campaign.variants:
        assert (tmp_path / "campaign" / f"{v.name}.h5").is_file()
    # the dict names the variants as the command line's --param does
    from transient.campaign.variants import make_variants, parse_parameter
    same = make_variants([parse_parameter("initial.impact.velocity=[[1.0,0.0,0.0],"
                                          "[2.0,0.0,0.0]]")])
    assert [v.name for v in same] == [v.name for v in campaign.variants]


@pytest.mark.slow
def test_the_api_pages_example_runs(tmp_path):
    """docs/api.md's examples as a user runs them from a checkout, one after the other as the
    page reads, on a coarser mesh and a shorter run (every load appends them): a test of the
    calls, not of pad_disc's setup."""
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), re.S)
    assert len(blocks) == 4
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    coarser = ("import transient.api\n"
               "real = transient.api.load\n"
               f"transient.api.load = lambda path, overrides=(): real(path, [*overrides, "
               f"*{SMALL + ['solver.t_end=2e-4']!r}])\n")
    script = "\nprint('-- next example')\n".join(blocks)
    done = subprocess.run([sys.executable, "-c", coarser + script], cwd=tmp_path,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    outputs = [part.splitlines() for part in done.stdout.split("-- next example\n")]
    assert outputs[0][-1].split()[:2] == ["pad.h5", "complete"]
    assert (tmp_path / "pad.h5").is_file() and (tmp_path / "pad_export").is_dir()
    # the history's rows and series, the squeal run's modes, the bench's rows (the reference
    # first)
    assert outputs[1][0].split()[:2] == [str(transient.summary(tmp_path / "pad.h5")["steps"]),
                                         "complete"]
    # a line per mode of the squeal run's band, by frequency
    frequencies = [float(line.split()[0]) for line in outputs[2]]
    assert frequencies and frequencies == sorted(frequencies)
    assert [line.split()[0] for line in outputs[3]] == ["fine"] * 2 + ["centre"] * 2 + [
        "greedy"]
