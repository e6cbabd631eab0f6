"""Branches of complex modes over a parameter (stability.branches): the two-dof mode-coupling
model (tests/test_cea_mode_coupling.py) against its closed forms, two modes crossing in
frequency without coupling, ties of the MAC, a degenerate pair, the tables and their CSV, and
`plot sweep` on a sweep's folder made of the two-dof model's modes."""
import csv
import json

import numpy as np
import pytest

import transient
from transient.cli import main
from transient.solve.mac import mac
from transient.stability.branches import MAC_LINK, Step, shapes_record, track
from transient.stability.modes import complex_modes

from test_cea_mode_coupling import (A_XX, D_YY, MASS, delta, lambda_growing_undamped, modes,
                                    mu_c_equal, mu_c_undamped, omegas_undamped)

# mu_c(0) = 0.6032 lies between two values of this grid (0.6 and 0.625)
MUS = np.linspace(0.3, 0.9, 25)
STEP = MUS[1] - MUS[0]


def two_dof(mus, c=0.0):
    """The Branches of the two-dof model at mus with damping c on x and y, its shapes on its
    two dofs."""
    steps = []
    for mu in mus:
        cm = modes(mu, c, c)
        steps.append(Step(float(mu), cm.eigenvalues, cm.unstable, cm.threshold, cm.vectors,
                          np.arange(2)))
    return track("mu", steps)


def at(branches, b, mu):
    """Branch b's eigenvalue at mu."""
    x, lam, _ = branches.line(b)
    return lam[np.flatnonzero(x == mu)[0]]


def test_the_two_dof_branches_are_two_lines_that_merge_at_mu_c():
    """Below mu_c one branch holds the lower frequency at every value and the other the upper
    (the closed form's two roots); above it one branch holds the growing root at every value
    (lambda^2 = (-(a + d) + i sqrt(-Delta)) / 2m) and the other its mirror -conj(lambda). The
    one coupling point: that branch turning unstable with the other as its partner at mu_c,
    to 1e-3 of the grid's step (interpolated where the pair's eigenvalues meet), at the
    coalescence's frequency sqrt((a + d) / 2m) / 2 pi."""
    found = two_dof(MUS)
    mu_c = mu_c_undamped()
    assert found.count == 2 and found.linked_by == "shapes"
    assert all(len(found.line(b)[0]) == len(MUS) for b in range(2))
    below, above = MUS[MUS < mu_c], MUS[MUS > mu_c]
    low = int(np.argmin([at(found, b, below[0]).imag for b in range(2)]))
    for mu in below:
        w = omegas_undamped(mu)
        assert abs(at(found, low, mu).imag - w[0]) <= 1e-10 * w[0]
        assert abs(at(found, 1 - low, mu).imag - w[1]) <= 1e-10 * w[1]
    growing = int(np.argmax([at(found, b, above[0]).real for b in range(2)]))
    for mu in above:
        expect = lambda_growing_undamped(mu)
        assert abs(at(found, growing, mu) - expect) <= 1e-10 * abs(expect)
        assert abs(at(found, 1 - growing, mu) + np.conj(expect)) <= 1e-10 * abs(expect)
    (point,) = found.coupling
    assert (point["branch"], point["partner"], point["becomes"]) == (growing, 1 - growing,
                                                                     "unstable")
    assert abs(point["mu"] - mu_c) <= 1e-3 * STEP
    f_c = np.sqrt((A_XX + D_YY) / (2 * MASS)) / (2 * np.pi)
    assert point["frequency_hz"] == pytest.approx(f_c, rel=1e-6)


@pytest.mark.parametrize("c, within", [(2.0, 1e-3), (8.0, 0.1)])
def test_with_equal_damping_the_branch_turns_unstable_at_the_damped_threshold(c, within):
    """D = c I: the frequencies still meet at mu_c(0), and the growing branch's real part
    -c/2m + Re sqrt(c^2/4m^2 + s) crosses 0 later, at mu_c(c) = ((a - d)^2 + 4 b^2 + 2 c^2
    (a + d) / m) / (4 |b| k3). With c = 2 both lie between the same two values (the pair's
    coalescence law places it to 1e-3 of the step), with c = 8 in a later interval, where the
    real part crosses as a straight line (to a tenth of the step)."""
    found = two_dof(MUS, c)
    (point,) = found.coupling
    assert found.count == 2 and point["becomes"] == "unstable"
    assert point["partner"] == 1 - point["branch"]
    assert abs(point["mu"] - mu_c_equal(c)) <= within * STEP
    # the branch: unstable exactly above mu_c(c), the growing root wherever they have met
    x, lam, bad = found.line(point["branch"])
    assert np.array_equal(bad, x > mu_c_equal(c))
    gamma = c / MASS
    for mu, value in zip(x[x > mu_c_undamped()], lam[x > mu_c_undamped()]):
        s = (-(A_XX + D_YY) + 1j * np.sqrt(-delta(mu))) / (2 * MASS)
        expect = -gamma / 2 + np.sqrt(gamma ** 2 / 4 + s)
        assert abs(value - expect) <= 1e-10 * abs(expect)


def three_dof(p):
    """(M, D, K) of three dofs whose modes are the fixed shapes PHI with frequencies that
    cross as p grows: mode 0 rises through mode 1, which falls; mode 2 stays above. Modal
    damping ratios 1%, 2%, 1%."""
    omega = np.array([9.7 + 0.8 * p, 10.1 - 0.2 * p, 20.0])
    zeta = np.array([0.01, 0.02, 0.01])
    M = np.diag(MASSES)
    MPhi = M @ PHI
    K = MPhi @ np.diag(omega ** 2) @ MPhi.T
    D = MPhi @ np.diag(2 * zeta * omega) @ MPhi.T
    return M, D, K


def _rotation(i, j, angle):
    R = np.eye(3)
    R[[i, j], [i, j]] = np.cos(angle)
    R[i, j], R[j, i] = -np.sin(angle), np.sin(angle)
    return R


MASSES = [1.0, 4.0, 1.5]
# M^-1/2 times a rotation: M-orthonormal shapes whose plain MAC is not 0
PHI = np.diag(1 / np.sqrt(MASSES)) @ _rotation(0, 1, np.pi / 4) @ _rotation(1, 2, np.pi / 6)


def test_two_modes_crossing_in_frequency_without_coupling_keep_their_branches():
    """Mode 0 (frequency 8.1 -> 12.1 rad/s) crosses mode 1 (10.5 -> 9.5) between p = 0 and
    p = 1. Sorted by frequency, or paired by the nearest eigenvalues alone, the two swap
    there; by the MAC each branch keeps its shape at every value."""
    ps = np.arange(-2.0, 4.0)
    steps = []
    for p in ps:
        cm = complex_modes(*three_dof(p))
        steps.append(Step(p, cm.eigenvalues, cm.unstable, 0.0, cm.vectors, np.arange(3)))
    # the shapes differ but are not orthogonal: their MAC is neither 0 nor 1
    assert 0.05 < mac(PHI[:, [0]], PHI[:, [1]])[0, 0] < 0.5

    def shapes_along(found, b):
        """The mode shape (column of PHI) branch b holds at each value."""
        out = []
        for k, s in enumerate(steps):
            j = np.flatnonzero(found.branch[k] == b)[0]
            alike = mac(PHI, s.shapes[:, [j]])[:, 0]
            assert alike.max() > 1 - 1e-10
            out.append(int(np.argmax(alike)))
        return out
    found = track("p", steps)
    assert found.count == 3 and found.linked_by == "shapes"
    assert sorted(shapes_along(found, b)[0] for b in range(3)) == [0, 1, 2]
    for b in range(3):
        along = shapes_along(found, b)
        assert along == [along[0]] * len(ps)
    # sorted by frequency: the lower of the two is mode 0 before the crossing, 1 after
    assert [int(np.argmax(mac(PHI, s.shapes[:, [0]])[:, 0])) for s in steps] == [
        0, 0, 0, 1, 1, 1]
    # by the eigenvalue alone: the branch that starts on mode 0 ends on mode 1
    blind = track("p", [Step(s.value, s.eigenvalues, s.unstable) for s in steps])
    assert blind.linked_by == "eigenvalues" and blind.count == 3
    starts = int(blind.branch[0][np.argmax(mac(PHI[:, [0]], steps[0].shapes)[0])])
    ends = [int(np.argmax(mac(PHI, s.shapes[:, blind.branch[k] == starts])[:, 0]))
            for k, s in enumerate(steps)]
    assert ends == [0, 0, 0, 1, 1, 1]


def test_where_the_shapes_tie_the_eigenvalue_decides():
    """Two modes of one shape (MAC 1 with each other at every value) whose eigenvalues
    +-s + i w come in either order: each branch keeps the sign of its real part. The MAC
    alone would leave the pairing to the order the modes come in."""
    shape = np.array([[1.0, 1.0], [0.5j, 0.5j], [0.2, 0.2]])
    steps = []
    for k, s in enumerate(np.linspace(1.0, 3.0, 6)):
        lam = np.array([s + 35j, -s + 35j])[::(-1) ** k]
        steps.append(Step(float(k), lam, lam.real > 0, 0.0, shape, np.arange(3)))
    found = track("k", steps)
    assert found.count == 2
    for b in range(2):
        _, lam, _ = found.line(b)
        assert len(lam) == 6 and len(set(np.sign(lam.real))) == 1


def test_a_degenerate_pair_continues_whatever_shapes_the_solver_gave_it():
    """At the first value two modes share one eigenvalue (to 1e-6: a disc's doublet), and the
    solver's pick of their shapes resembles neither mode of the split pair at the next value
    by more than MAC_LINK; their span holds both, so both branches go on."""
    e = np.eye(3)
    y = np.stack([e[0], (e[0] + 0.8 * e[1]) / np.sqrt(1.64)], axis=1)
    x = np.stack([e[1], (e[0] - e[1]) / np.sqrt(2.0)], axis=1)
    plain = mac(x, y)
    assert min(plain[0, 1], plain[1, 0]) < MAC_LINK and plain[0, 0] < MAC_LINK
    lam0 = np.array([50j, 50j * (1 + 1e-6)])
    lam1 = np.array([-0.1 + 49.5j, -0.2 + 50.5j])
    found = track("mu", [Step(0.0, lam0, np.zeros(2, bool), 0.0, x, np.arange(3)),
                         Step(0.1, lam1, np.zeros(2, bool), 0.0, y, np.arange(3))])
    assert found.count == 2 and sorted(found.branch[1]) == [0, 1]
    assert np.allclose(found.mac[1], 1.0)


def test_a_mode_that_resembles_none_before_starts_a_branch():
    """The upper mode leaves the band and another of an unrelated shape (MAC 0 with it)
    enters near its frequency: the one-to-one assignment pairs them, but below MAC_LINK the
    pair is cut, one branch ends and a third starts. The lower mode goes on."""
    e = np.eye(3)
    lower = (e[0] + 0.1 * e[1])[:, None]
    found = track("mu", [
        Step(0.0, np.array([10j, 20j]), np.zeros(2, bool), 0.0,
             np.hstack([lower, e[:, [1]]]), np.arange(3)),
        Step(0.1, np.array([10.1j, 20.2j]), np.zeros(2, bool), 0.0,
             np.hstack([lower, e[:, [2]]]), np.arange(3))])
    assert found.count == 3 and found.branch[1].tolist() == [0, 2]
    assert found.mac[1][0] == pytest.approx(1.0) and np.isnan(found.mac[1][1])
    assert [len(found.line(b)[0]) for b in range(3)] == [2, 1, 1]


def test_the_unstable_modes_and_the_coupling_point_as_tables_and_csv(tmp_path):
    """One row per value above mu_c, the growing branch's, with the closed form's frequency,
    real part and damping ratio; none below. The coupling CSV: its one point."""
    found = two_dof(MUS)
    growing = found.coupling[0]["branch"]
    rows = found.unstable_modes()
    assert [r["mu"] for r in rows] == list(MUS[MUS > mu_c_undamped()])
    paths = found.write(tmp_path / "unstable.csv", tmp_path / "coupling.csv")
    with open(paths[0], newline="") as f:
        read = list(csv.DictReader(f))
    assert list(read[0]) == ["mu", "branch", "frequency_hz", "real", "damping_ratio"]
    assert len(read) == len(rows)
    for row, mu in zip(read, MUS[MUS > mu_c_undamped()]):
        lam = lambda_growing_undamped(mu)
        assert float(row["mu"]) == mu and int(row["branch"]) == growing
        assert float(row["frequency_hz"]) == pytest.approx(lam.imag / (2 * np.pi), rel=1e-10)
        assert float(row["real"]) == pytest.approx(lam.real, rel=1e-9)
        assert float(row["damping_ratio"]) == pytest.approx(-lam.real / abs(lam), rel=1e-9)
    with open(paths[1], newline="") as f:
        (point,) = list(csv.DictReader(f))
    assert point == {"branch": str(growing), "partner": str(1 - growing),
                     "mu": repr(found.coupling[0]["mu"]),
                     "frequency_hz": repr(found.coupling[0]["frequency_hz"]),
                     "becomes": "unstable"}


def _sweep_folder(path, mus, shapes=True):
    """A cea sweep's folder as `transient sweep` writes it (sweep.json, a modes file per
    variant), of the two-dof model's complex modes."""
    path.mkdir()
    key = "contact.belt.friction.mu"
    rows = []
    for k, mu in enumerate(mus):
        cm = modes(mu)
        stored = {"modes": cm.table(), "growth_rate_threshold": 0.0}
        if shapes:
            stored["shapes"] = shapes_record(np.arange(2), cm.vectors)
        (path / f"v{k:03d}.json").write_text(json.dumps(stored))
        rows.append({key: float(mu), "status": "complete", "output": f"v{k:03d}.json"})
    # written in another order than mu's: the map orders them
    (path / "sweep.json").write_text(json.dumps({"kind": "cea", "parameters": [key],
                                                 "rows": rows[::-1]}))
    return key


def test_plot_sweep_links_the_variants_by_their_stored_shapes(tmp_path, capsys):
    """`plot sweep` on a cea sweep of the two-dof model: the map, then the tables of unstable
    modes and coupling points beside it, those of `transient.sweep_branches`; a folder whose
    modes files hold no shapes is linked by the eigenvalue alone."""
    key = _sweep_folder(tmp_path / "s", MUS)
    assert main(["plot", "sweep", str(tmp_path / "s")]) == 0
    paths = capsys.readouterr().out.split()
    assert [p.rsplit("/", 1)[1] for p in paths] == [
        "sweep_cea.png", "sweep_cea_unstable.csv", "sweep_cea_coupling.csv"]
    (found,) = transient.sweep_branches(tmp_path / "s").values()
    assert found.parameter == key and found.linked_by == "shapes" and found.count == 2
    assert abs(found.coupling[0][key] - mu_c_undamped()) <= 1e-3 * STEP
    with open(paths[1], newline="") as f:
        read = list(csv.DictReader(f))
    assert [(float(r[key]), int(r["branch"]), float(r["real"])) for r in read] == [
        (r[key], r["branch"], r["real"]) for r in found.unstable_modes()]
    assert len(read) == np.sum(MUS > mu_c_undamped())
    _sweep_folder(tmp_path / "old", MUS, shapes=False)
    assert main(["plot", "sweep", str(tmp_path / "old")]) == 0
    (old,) = transient.sweep_branches(tmp_path / "old").values()
    assert old.linked_by == "eigenvalues" and old.count == 2


def test_shapes_records_read_back():
    from transient.stability.branches import read_shapes
    shapes = np.array([[1.0 + 2.0j, -0.5j], [0.25, 3.0 - 1.0j], [0.0, 1e-3]])
    dofs, back = read_shapes(json.loads(json.dumps(shapes_record([4, 7, 9], shapes))))
    assert dofs.tolist() == [4, 7, 9] and np.allclose(back, shapes, rtol=1e-7)
