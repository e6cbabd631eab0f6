"""Coarse rule: greedy orthogonal selection (against LAPACK's pivoting), weights, tied modes."""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from transient.case.loading import load
from transient.cli import main
from transient.contact.pair import build_contact, contact_stiffness
from transient.kernels.greedy import greedy_rows
from transient.model.model import build_model
from transient.solve.modes import normal_modes

CASES = Path(__file__).resolve().parent.parent / "cases"


def test_greedy_order_is_lapack_column_pivoting():
    rng = np.random.default_rng(1)
    R = rng.standard_normal((400, 60)) * rng.uniform(0.1, 3.0, (400, 1))
    chosen, residual = greedy_rows(R, 60, 1e-12, False)
    _, _, pivots = sla.qr(R.T, pivoting=True, mode="economic")
    np.testing.assert_array_equal(chosen, pivots[:60])
    assert residual[0] == 1.0 and np.all(np.diff(residual) <= 1e-12)


def test_greedy_stops_at_the_rank_and_restarts_past_it():
    rng = np.random.default_rng(2)
    R = rng.standard_normal((300, 12)) @ rng.standard_normal((12, 40))    # rank 12
    chosen, _ = greedy_rows(R, 40, 1e-8, False)
    assert len(chosen) == 12
    more, _ = greedy_rows(R, 30, 1e-8, True)
    assert len(more) == 30 and len(set(more)) == 30 and np.array_equal(more[:12], chosen)


def tied_frequencies(case_path, overrides, count=30):
    case = load(case_path, overrides)
    model = build_model(case)
    pairs = build_contact(case, model)
    K = model.K + contact_stiffness(pairs, model.ndof)
    return normal_modes(K, model.M, model.fixed, count=count).frequencies, pairs[0]


GREEDY = ["contact.interface.rule=greedy", "contact.interface.regularized=true"]


@pytest.mark.slow
def test_drilled_cube_exact_weights_reproduce_the_energy():
    ref, fine = tied_frequencies(CASES / "drilled_cube.toml",
                                 ["contact.interface.regularized=true"], 12)
    f, pair = tied_frequencies(CASES / "drilled_cube.toml",
                               GREEDY + ["contact.interface.weights=exact"], 12)
    kept = pair.compat.kept(pair.eps)
    assert kept <= pair.rule.n_points < fine.rule.n_points / 10
    assert pair.coarse.energy_error < 1e-8
    np.testing.assert_allclose(f, ref, rtol=1e-8)


@pytest.mark.slow
def test_drilled_cube_greedy_rule_of_rank_size_beats_the_centre_rule():
    ref, _ = tied_frequencies(CASES / "drilled_cube.toml",
                              ["contact.interface.regularized=true"], 12)
    f, pair = tied_frequencies(CASES / "drilled_cube.toml", GREEDY, 12)
    centre, centre_pair = tied_frequencies(CASES / "drilled_cube.toml",
                                           ["contact.interface.rule=centre"], 12)
    assert pair.rule.n_points == pair.compat.kept(pair.eps) == 25
    err = np.abs(f / ref - 1).max()
    assert err < 0.01 and np.abs(centre / ref - 1).max() > 7 * err


@pytest.mark.slow
def test_pad_disc_coarse_rule_within_one_percent_on_30_tied_modes():
    path = CASES / "pad_disc.toml"
    ref, fine = tied_frequencies(path, ["contact.pad_disc.rule=fine",
                                        "contact.pad_disc.regularized=true"])
    f, pair = tied_frequencies(path, ["contact.pad_disc.rule=greedy",
                                      "contact.pad_disc.regularized=true"])
    assert pair.rule.n_points <= fine.rule.n_points / 5
    assert np.abs(f / ref - 1).max() < 0.01


def test_compat_json_reports_the_coarse_rule(capsys):
    args = ["compat", str(CASES / "drilled_cube.toml"), "--json"]
    for o in GREEDY:
        args += ["--set", o]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["coarse"]["m"] == 25 and out["coarse"]["setup_s"] > 0
    assert 0 <= out["coarse"]["energy_error"]


def test_greedy_needs_regularization(tmp_path, capsys):
    assert main(["compat", str(CASES / "drilled_cube.toml"), "--set",
                 "contact.interface.rule=greedy"]) == 2
    assert "contact.interface.regularized" in capsys.readouterr().err
