"""Modes with the contact tied (solver.modes.tie) and the rich gauss rule, on a block pressed on
another through non-matching meshes: the exact tie against the constrained problem solved
densely by its null space, the penalty rising to it, the preload tie against the law's tangent
of a uniform pressure, the gauss rule's exactness, and `transient plot modal-frf`."""
import json

import numpy as np
import pytest
import scipy.linalg as sla

from transient.case.loading import load
from transient.cli import main
from transient.contact.pair import build_contact
from transient.model.dofs import free_block
from transient.model.model import build_model
from transient.solve.modes import frequencies_hz
from transient.solve.tied import contact_modes

from test_contact_static import P, PATCH

LAMBDA = 5.0e5

# the contact patch test's blocks (rollers: under the pressure the stress is uniform, and so
# is the contact pressure; the upper block is held along z by the contact alone), 0.25 m
# thick, meshed hex20 below and tet10 above, with two sensors and twelve modes
BLOCKS = PATCH + """
[sensors.below]
part = "lower"
point = [1.0, 1.0, 0.25]
direction = [0.0, 0.0, 1.0]

[sensors.above]
part = "upper"
point = [1.0, 1.0, 0.5]
direction = [0.0, 0.0, 1.0]

[solver.modes]
count = 12
"""
MESHES = ["parts.lower.mesh.size=[1.0,1.0,0.25]", "parts.lower.mesh.divisions=[4,4,1]",
          "parts.lower.mesh.element=hex20", "parts.upper.mesh.size=[1.0,1.0,0.25]",
          "parts.upper.mesh.origin=[0.0,0.0,0.25]", "parts.upper.mesh.divisions=[3,3,1]",
          "parts.upper.mesh.element=tet10"]


@pytest.fixture(scope="module")
def blocks(tmp_path_factory):
    path = tmp_path_factory.mktemp("blocks") / "blocks.toml"
    path.write_text(BLOCKS)
    model = build_model(load(path, MESHES))
    return path, model


def modes_of(blocks, *overrides):
    path, model = blocks
    case = load(path, MESHES + list(overrides))
    pairs = build_contact(case, model)
    return contact_modes(case, model, pairs), pairs


@pytest.mark.slow
def test_gauss_rule_holds_each_master_faces_gauss_points_and_integrates_exactly(blocks):
    (_, _), (gauss,) = modes_of(blocks, "contact.c.rule=gauss")
    (_, _), (fine,) = modes_of(blocks, "contact.c.rule=fine")
    (_, _), (centre,) = modes_of(blocks, "contact.c.rule=centre")
    faces = len(gauss.interface.side1.faces)
    assert gauss.rule.n_points == 6 * faces == 6 * centre.rule.n_points    # tri6, degree 4
    np.testing.assert_allclose(gauss.rule.weights.sum(), 1.0, rtol=1e-13)

    # a tilted plane of normal displacement on the upper side: its gap energy is the integral
    # of a quadratic, exact at degree 4 on flat faces, for the gauss rule as for the fine one;
    # the centre rule's one point is not
    def energy(pair):
        x = pair.interface.side1.points[pair.interface.side1.nodes]
        u = 1e-6 * (1.0 + 2.0 * x[:, 0] - 3.0 * x[:, 1])
        return np.sum(pair.rule.weights * (pair.rule.C1 @ u) ** 2)
    # the integral of (1 + 2 x - 3 y)^2 over the unit square: 1 + 4/3 + 3 + 2 - 3 - 3
    exact = 1e-12 * 4.0 / 3.0
    np.testing.assert_allclose(energy(gauss), energy(fine), rtol=1e-12)
    np.testing.assert_allclose(energy(fine), exact, rtol=1e-12)
    assert abs(energy(centre) / exact - 1) > 1e-3


def dense_constrained_modes(model, pair, count):
    """The exact tie solved by another road: the null space of the rule's rows on the free dofs
    (their singular values above 1e-6 of the largest, as the tie holds), K and M projected on
    it, a dense symmetric eigensolver."""
    free = model.free
    C = pair.observation(model.ndof)[:, free]
    C = C.toarray() if hasattr(C, "toarray") else np.asarray(C)
    _, s, Vt = np.linalg.svd(C, full_matrices=True)
    rank = int(np.sum(s > 1e-6 * s[0]))
    N = Vt[rank:].T
    K = free_block(model.K, free).toarray()
    M = free_block(model.M, free).toarray()
    lam = sla.eigh(N.T @ K @ N, N.T @ M @ N, eigvals_only=True, subset_by_index=[0, count - 1])
    return frequencies_hz(lam), rank


@pytest.mark.parametrize("rule", [("fine", "false"), ("centre", "true"), ("gauss", "false")])
def test_exact_tie_is_the_constrained_problem(blocks, rule):
    """More points than dofs (fine, gauss: the rows' space) and fewer (the regularized centre
    rule: its rows), against the null-space method."""
    (modes, tie), (pair,) = modes_of(blocks, "solver.modes.tie=exact", f"contact.c.rule={rule[0]}",
                                     f"contact.c.regularized={rule[1]}", "contact.c.eps=1e-3")
    reference, rank = dense_constrained_modes(blocks[1], pair, 12)
    assert tie.kind == "exact" and tie.held == rank
    np.testing.assert_allclose(modes.frequencies, reference, rtol=1e-8)


@pytest.mark.slow
def test_penalty_modes_rise_to_the_exact_tie(blocks):
    (exact, _), _ = modes_of(blocks, "solver.modes.tie=exact")
    gaps = []
    for k in (1e11, 1e13, 1e15, 1e17):
        (modes, _), _ = modes_of(blocks, f"contact.c.k={k}")
        # a stiffer spring raises every eigenvalue; the constraint is their bound
        assert np.all(modes.frequencies <= exact.frequencies * (1 + 1e-9))
        gaps.append(np.max(exact.frequencies / modes.frequencies - 1))
    assert gaps == sorted(gaps, reverse=True) and gaps[-1] < 1e-3 < gaps[0]


@pytest.mark.slow
def test_preload_tie_is_the_exponential_laws_tangent_at_the_pressure(blocks):
    """The rollers make the contact pressure uniform, P: the tangent of p0 exp(-lambda g) there
    is lambda P at every point, so the preload tie is the penalty tie at k = lambda P."""
    law = ["contact.c.law.kind=exponential", f"contact.c.law.lambda={LAMBDA}"]
    (preload, tie), _ = modes_of(blocks, "solver.modes.tie=preload", *law)
    np.testing.assert_allclose(tie.preload.pressure, P, rtol=1e-8)
    (penalty, _), _ = modes_of(blocks, f"contact.c.k={LAMBDA * P}", *law)
    np.testing.assert_allclose(preload.frequencies, penalty.frequencies, rtol=1e-8)


def test_modes_command_says_how_the_contact_is_tied(blocks, capsys):
    path, meshes = str(blocks[0]), [a for m in MESHES for a in ("--set", m)]
    assert main(["modes", path, "--set", "solver.modes.tie=exact"] + meshes) == 0
    assert "tied exactly (the gap held at zero on" in capsys.readouterr().out
    assert main(["modes", path, "--json", "--set", "solver.modes.tie=preload"] + meshes) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["tie"] == "preload" and len(out["frequencies_hz"]) == 12


def test_plot_modal_frf_draws_both_models_and_prints_the_shifts(blocks, tmp_path, capsys):
    png = tmp_path / "frf.png"
    args = ["plot", "modal-frf", str(blocks[0]), "--input", "below", "--output", "above",
            "--set", "solver.modes.tie=exact", "--set", "contact.c.rule=centre",
            "--set", "contact.c.regularized=true", "--set", "contact.c.eps=1e-3",
            "--against", "contact.c.rule=fine", "--against", "contact.c.regularized=false",
            "-o", str(png)] + [a for m in MESHES for a in ("--set", m)]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert png.stat().st_size > 10_000
    assert "paired by MAC" in out and "shift of contact.c.rule=fine" in out
    # the rich rule tied exactly is the stiffer: every paired mode at or above its partner
    shifts = [float(line.split()[3]) for line in out.splitlines()
              if line.split() and line.split()[0].isdigit()]
    assert len(shifts) == 12 and min(shifts) > -1e-6 and max(shifts) > 0.1


@pytest.mark.parametrize("extra, key", [(["--input", "nowhere"], "--input"),
                                        (["--damping", "1.5"], "--damping"),
                                        (["--set", "sensors.below.point=[1.0, 1.0, 0.0]"],
                                         "--input")])
def test_plot_modal_frf_refuses_bad_options_in_one_line(blocks, tmp_path, capsys, extra, key):
    args = ["plot", "modal-frf", str(blocks[0]), "--input", "below", "--output", "above",
            "-o", str(tmp_path / "x.png")] + extra
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0]
    assert not (tmp_path / "x.png").exists()


@pytest.mark.slow
def test_the_compared_model_keeps_its_own_loads(blocks):
    """Two cases of one structure share its meshes and matrices, each with its own loads: the
    second's preload holds its own pressure."""
    from transient.studies.modal import compare
    path = blocks[0]
    tie = MESHES + ["solver.modes.tie=preload", "contact.c.law.kind=exponential"]
    result = compare(load(path, tie), load(path, tie + [f"loads.top.value={2 * P}"]),
                     "below", "above", 0.01)
    np.testing.assert_allclose(result.ties[0].preload.pressure, P, rtol=1e-8)
    np.testing.assert_allclose(result.ties[1].preload.pressure, 2 * P, rtol=1e-8)
