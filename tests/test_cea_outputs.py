"""`transient cea`'s files and descriptors: each unstable mode read back by meshio equals the
CEA's eigenvector on the mesh, the CSV holds what the table prints, output.vtu = "" writes
nothing, cea.threshold.growth_rate changes what is unstable; a disc's in-plane modes are named
so and its out-of-plane ones get the nodal diameters their nodal lines count; a pad's rigid
mode is never the pad mode a shape resembles.

The small pad_disc_squeal (hex8, the divisions of tests/test_cea.py) at its mu = 0.2 has two
unstable modes, in-plane disc modes growing at 1.0 and 3.4 1/s."""
import csv
import json
import re
from pathlib import Path

import meshio
import numpy as np
import pytest

import transient
from transient.cli import main
from test_cea import SMALL

SQUEAL = Path(__file__).resolve().parent.parent / "cases" / "pad_disc_squeal.toml"
CASES = SQUEAL.parent


def _args(overrides):
    return [a for o in SMALL + overrides for a in ("--set", o)]


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """(the Analysis whose files went to DIR/sq.vtu's names, DIR)."""
    out = tmp_path_factory.mktemp("cea")
    case = transient.load(SQUEAL, SMALL + [f'output.vtu="{out / "sq.vtu"}"'])
    return transient.cea(case), out


def test_each_unstable_mode_reads_back_as_the_ceas_eigenvector(written):
    result, out = written
    unstable = np.flatnonzero(result.modes.unstable)
    assert len(unstable) == 2
    names = [f"sq_mode_{j + 1:03d}.{ext}" for j in unstable for ext in ("vtu", "pvd")]
    assert [p.name for p in result.files] == ["sq_modes.csv"] + names
    assert sorted(p.name for p in out.iterdir()) == sorted(["sq_modes.csv"] + names)
    mesh = result.model.mesh()
    for j in unstable:
        vtu = out / f"sq_mode_{j + 1:03d}.vtu"
        read = meshio.read(vtu)
        assert np.array_equal(read.points, mesh.points)
        u = read.point_data["u_real"] + 1j * read.point_data["u_imag"]
        # the eigenvector on the mesh, scaled so that its largest component is 1
        v = result.displacement(j)
        v = (v / v[np.argmax(np.abs(v))]).reshape(-1, 3)
        assert np.abs(u - v).max() < 1e-12
        k = np.unravel_index(np.argmax(np.abs(u)), u.shape)
        assert u[k] == 1.0
        assert np.allclose(read.point_data["u_magnitude"], np.abs(u), rtol=0, atol=1e-15)
        phase = np.radians(read.point_data["u_phase_deg"])
        assert np.allclose(read.point_data["u_magnitude"] * np.exp(1j * phase), u, atol=1e-15)
        field = {name: value[0] for name, value in read.field_data.items()}
        assert field["transient_cea_mode"] == j + 1 and field["unstable"] == 1
        assert field["frequency_hz"] == result.modes.frequency_hz[j]
        assert field["growth_rate_per_s"] == result.modes.real[j]
        assert (field["unit_node"], field["unit_direction"]) == k
        # the collection: the VTU at 24 phases over a period, its time the angle [rad]
        pvd = (out / f"sq_mode_{j + 1:03d}.pvd").read_text()
        steps = re.findall(r'timestep="([^"]+)" group="" part="0" file="([^"]+)"', pvd)
        assert [f for _, f in steps] == [vtu.name] * 24
        assert np.allclose([float(t) for t, _ in steps], 2 * np.pi * np.arange(24) / 24)
        assert "largest component" in pvd and "u_real cos(theta) - u_imag sin(theta)" in pvd


def test_the_csv_holds_what_the_table_prints_and_no_output_writes_nothing(
        written, tmp_path, monkeypatch, capsys):
    """The table of `transient cea` (output.vtu = "", the default: no file anywhere) against
    the CSV of the same case: every mode, then every number of the described modes' lines."""
    result, out = written
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in CASES.iterdir())
    assert main(["cea", str(SQUEAL)] + _args([])) == 0
    printed = capsys.readouterr().out
    assert list(tmp_path.iterdir()) == [] and sorted(p.name for p in CASES.iterdir()) == before
    assert "files:" not in printed
    with open(out / "sq_modes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    table = re.findall(r"^ *(\d+) +(\S+) +(\S+) +(\S+)( +unstable)?$", printed, re.M)
    assert len(table) == len(rows) == len(result.modes.eigenvalues)
    for (mode, f, real, zeta, unstable), row in zip(table, rows):
        assert mode == row["mode"]
        assert f == f"{float(row['frequency_hz']):.6g}"
        assert real == f"{float(row['real_per_s']):.5g}"
        assert zeta == f"{float(row['damping_ratio']):.4e}"
        assert bool(unstable) == (row["unstable"] == "true")
    lines = re.findall(r"^  mode (\d+) at (.*)$", printed, re.M)
    described = [row for row in rows if row["disc_motion"]]
    assert len(lines) == len(described) == 2
    for (mode, text), row in zip(lines, described):
        assert mode == row["mode"]
        numbers = re.findall(r"\d+(?:\.\d+)?(?:e[-+]\d+)?", text)
        pc = "{:.0f}".format
        expected = [f"{float(row['frequency_hz']):.1f}", pc(100 * float(row["energy_share_disc"])),
                    pc(100 * float(row["energy_share_pad"])),
                    pc(100 * float(row["disc_axial_share"])), row["disc_nodal_diameters"],
                    pc(100 * float(row["disc_order_share"])), row["pad_mode"],
                    pc(float(row["pad_mode_hz"])), f"{float(row['pad_mac']):.2f}",
                    f"{float(row['residual']):.1e}"]
        assert numbers == expected
        assert f"disc: {row['disc_motion']} (" in text


def test_the_threshold_decides_what_is_unstable(written, tmp_path, capsys):
    """cea.threshold.growth_rate = 2 1/s: the mode growing at 1.0 1/s is no longer unstable,
    in the JSON, the CSV and the files (written over a copy of the fixture's: the earlier
    files of that mode go, the other's are rewritten)."""
    import shutil
    result, written_to = written
    out = tmp_path / "out"
    shutil.copytree(written_to, out)
    real = result.modes.real
    assert sorted(real[result.modes.unstable].round(1)) == [1.0, 3.4]
    args = ["cea", str(SQUEAL), "--json"] + _args(
        [f'output.vtu="{out / "sq.vtu"}"', "cea.threshold.growth_rate=2.0"])
    assert main(args) == 0
    found = json.loads(capsys.readouterr().out)
    unstable = [m["unstable"] for m in found["modes"]]
    assert unstable == list(result.modes.unstable & (real > 2.0)) and sum(unstable) == 1
    j = unstable.index(True)
    assert [s["mode"] for s in found["shapes"]] == [j + 1]
    assert found["growth_rate_threshold"] == 2.0
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["sq_modes.csv", f"sq_mode_{j + 1:03d}.vtu", f"sq_mode_{j + 1:03d}.pvd"])
    with open(out / "sq_modes.csv", newline="") as f:
        assert [r["unstable"] == "true" for r in csv.DictReader(f)] == unstable


@pytest.mark.parametrize("name", ["sq_modes.csv", "sq_mode_007.vtu"])
def test_a_file_not_ours_is_refused_before_the_analysis(tmp_path, capsys, monkeypatch, name):
    import transient.stability.stage as stage

    def never(*args, **kwargs):
        raise AssertionError("the analysis ran")
    monkeypatch.setattr(stage, "analyse", never)
    (tmp_path / name).write_text("a user's file\n")
    code = main(["cea", str(SQUEAL), "--set", f'output.vtu="{tmp_path / "sq.vtu"}"'])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert f"{name}: output.vtu: exists and is not written by transient cea" in err
    assert (tmp_path / name).read_text() == "a user's file\n"


FREE_DISC = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0
[parts.disc]
material = "steel"
[parts.disc.mesh]
kind = "annular_disc"
inner_radius = 0.05
outer_radius = 0.14
thickness = 0.01
divisions = [2, 24, 1]
element = "hex8"
[motion.disc]
kind = "rotation"
part = "disc"
axis = [0.0, 0.0, 1.0]
point = [0.0, 0.0, 0.0]
omega = 1.0
"""


def _sign_changes(w):
    """Sign changes of w around a closed ring of samples (in angle order)."""
    s = np.sign(w)
    return int(np.sum(s != np.roll(s, 1)))


def test_a_free_discs_in_plane_modes_are_named_so_and_its_bending_modes_counted(tmp_path):
    """The 15 lowest modes of a free annular plate: 6 rigid, then the bending modes of 2 nodal
    diameters (a pair: a free plate's fundamental, Leissa), 0, 1 and 3 (pairs), and the first
    in-plane pair (the annulus' elliptic mode). Which is which is found without the descriptor: a
    bending mode's axial motion is even about the mid-plane, an in-plane mode's odd. Each
    in-plane mode is named so, with no count of its axial motion but that of its radial
    motion's nodal lines on the rim; each bending mode is out-of-plane with the nodal
    diameters its axial motion's nodal lines make on the rim."""
    from transient.model import build_model
    from transient.solve.modes import normal_modes
    from transient.stability.diameters import disc_motion
    path = tmp_path / "disc.toml"
    path.write_text(FREE_DISC)
    case = transient.load(path)
    model = build_model(case)
    modes = normal_modes(model.K, model.M, model.fixed, count=15)
    elastic = modes.frequencies > 100.0
    assert elastic.sum() == 9
    shapes = modes.shapes[:, elastic]
    found = disc_motion(model, case.motion["disc"], shapes)
    x = model.points
    top, bottom = np.isclose(x[:, 2], 0.01), np.isclose(x[:, 2], 0.0)
    rim = np.isclose(np.hypot(x[:, 0], x[:, 1]), 0.14)
    order = lambda nodes: nodes[np.argsort(np.arctan2(x[nodes, 1], x[nodes, 0]))]  # noqa: E731
    up, down = order(np.flatnonzero(top & rim)), order(np.flatnonzero(bottom & rim))
    kinds = []
    for u, d in zip(shapes.T, found):
        uz_up, uz_down = u[3 * up + 2], u[3 * down + 2]
        bending = np.abs(uz_up - uz_down).max() < 1e-6 * np.abs(uz_up).max()
        membrane = np.abs(uz_up + uz_down).max() <= 1e-6 * np.abs(u).max()
        assert bending != membrane
        if bending:
            assert d["motion"] == "out-of-plane" and d["axial_share"] > 0.9
            assert 2 * d["order"] == _sign_changes(uz_up) and d["share"] > 0.99
        else:
            # named in-plane, its count that of its radial motion's nodal lines
            radial = (u[3 * up] * x[up, 0] + u[3 * up + 1] * x[up, 1]) / 0.14
            assert d["motion"] == "in-plane" and d["axial_share"] < 1e-3
            assert 2 * d["order"] == _sign_changes(radial) == 4 and d["share"] > 0.99
        kinds.append("bending" if bending else "in-plane")
    assert kinds == ["bending"] * 7 + ["in-plane"] * 2
    assert [d["order"] for d in found[:2]] == [2, 2]
    assert sorted(d["order"] for d in found[:7]) == [0, 1, 1, 2, 2, 3, 3]


def test_a_rigid_mode_of_the_pad_is_never_the_mode_it_resembles():
    """The pad on its abutments slides freely along the axis (one rigid mode at round-off):
    a motion that is mostly that slide and some of its third elastic mode resembles the
    latter (MAC 0.04), not the rigid one (0.96)."""
    from transient.model import build_model
    from transient.stability.shapes import matched_part_modes, part_modes
    model = build_model(transient.load(SQUEAL, SMALL))
    f, Phi, dofs, _ = part_modes(model, "pad", 16000.0)
    assert abs(f[0]) < 0.1 and f[1] > 1000.0
    u = np.zeros((model.ndof, 1), complex)
    u[dofs, 0] = Phi[:, 0] + 0.2j * Phi[:, 3]
    (index, freq, mac), = matched_part_modes(model, u, ["pad"], 16000.0).values()
    assert index[0] == 3 and freq[0] == f[3]
    assert mac[0] == pytest.approx(0.04 / 1.04)
