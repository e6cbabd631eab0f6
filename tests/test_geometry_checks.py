"""Geometry mistakes caught at load, before any stage that costs (issue 47): a pad off the
disc, an overclosure, a mesh in millimetres read as metres, a sensor, a force or a rotation's
axis off its part. Each on a small block pressed on a block, the factorization (or the
assembly) replaced by one that fails the test if it is reached."""
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest

import transient.model.model
import transient.stages
from transient.case import load
from transient.cli import main
from transient.cli.commands import _model_line
from transient.contact.gaps import bounds, gap_at, preload_pressure
from transient.contact.pair import build_contact, pair_interface
from transient.model import build_model

CASES = Path(__file__).resolve().parent.parent / "cases"

BLOCKS = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0

[parts.lower]
material = "steel"
[parts.lower.mesh]
kind = "box"
size = [0.02, 0.02, 0.01]
divisions = [2, 2, 1]

[parts.upper]
material = "steel"
[parts.upper.mesh]
kind = "box"
size = [0.02, 0.02, 0.01]
origin = [0.0, 0.0, 0.01]
divisions = [2, 2, 1]

[constraints.base]
set = "lower.zmin"

[constraints.guide]
set = "upper.xmin"
dofs = ["x", "y"]

[loads.press]
kind = "pressure"
set = "upper.zmax"
value = 1.0e6

[sensors.top]
part = "upper"
point = [0.01, 0.01, 0.02]
direction = [0.0, 0.0, 1.0]

[contact.c]
surface1 = "upper.zmin"
surface2 = "lower.zmax"
[contact.c.law]
kind = "exponential"

[motion.turn]
kind = "rotation"
part = "lower"
axis = [0.0, 0.0, 1.0]
point = [0.01, 0.01, 0.0]
omega = 1.0

[solver]
t_end = 1.0e-5
"""


class Reached(Exception):
    """The factorization (or the assembly) was reached: the check came too late."""


def _reached(*args, **kwargs):
    raise Reached


@pytest.fixture
def blocks(tmp_path, monkeypatch):
    monkeypatch.setattr(transient.stages, "factorization", _reached)
    path = tmp_path / "blocks.toml"
    path.write_text(BLOCKS)
    return path


def at(z):
    return f"parts.upper.mesh.origin=[0.0,0.0,{z!r}]"


def refused(capsys, path, *overrides):
    """The run refused in one 'error:' line naming the file (exit 2, no warning)."""
    args = ["run", str(path), "-o", str(Path(path).with_suffix(".h5"))]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(args + [a for o in overrides for a in ("--set", o)]) == 2
    err = capsys.readouterr().err.strip()
    assert not caught and len(err.splitlines()) == 1, err
    assert err.startswith(f"error: {path}: ") and "Traceback" not in err
    return err


def reaches_the_factorization(capsys, path, *overrides):
    """The run's stderr when its checks let it reach the factorization."""
    args = ["run", str(path), "-o", str(Path(path).with_suffix(".h5"))]
    with pytest.raises(Reached):
        main(args + [a for o in overrides for a in ("--set", o)])
    return capsys.readouterr().err.strip()


def test_a_pad_off_the_disc_is_refused_with_the_gap(blocks, capsys):
    err = refused(capsys, blocks, at(0.012))
    assert ": contact.c: the surfaces do not touch: the initial gap is 0.002 to 0.002 m" in err
    assert "1e+06 Pa" in err        # the preload it was judged against


def test_the_open_bound_follows_the_law(blocks, capsys):
    # 30 um open: the default law's pressure there is 3e-7 of the preload's; a law decaying
    # ten times slower still carries it
    assert "contact.c: the surfaces do not touch" in refused(capsys, blocks, at(0.01003))
    assert reaches_the_factorization(capsys, blocks, at(0.01003),
                                     "contact.c.law.lambda=5e4") == ""


def test_an_open_pair_nothing_presses_is_the_scene_s_own(blocks):
    # an impact starts open: without a constant load there is nothing the pair must carry
    case = load(blocks, [at(0.012), 'loads.press.signal.kind="step"',
                         "loads.press.signal.start=1e-6"])
    model = build_model(case)
    (pair,) = build_contact(case, model)
    assert pair.gaps.min == pytest.approx(0.002) and pair.gaps.overclosed == 0.0


def test_an_overclosure_is_told_and_a_deep_one_refused(blocks, capsys):
    err = reaches_the_factorization(capsys, blocks, at(0.0095))
    assert err.startswith(f"warning: {blocks}: contact.c: the surfaces overlap by up to "
                          "0.0005 m on 100% of the contact's area") and len(err.splitlines()) == 1
    # within the law's range: nothing said
    assert reaches_the_factorization(capsys, blocks, at(0.01 - 1e-5)) == ""
    err = refused(capsys, blocks, at(0.008))
    assert ": contact.c: the surfaces overlap by up to 0.002 m" in err and "0.01 m" in err


def test_a_linear_law_with_nothing_to_carry_tells_any_overclosure(blocks, capsys):
    case = load(blocks, [at(0.01 - 1e-6), 'contact.c.law.kind="linear"',
                         "loads.press.value=0.0"])
    build_contact(case, build_model(case))
    assert "contact.c: the surfaces overlap by up to 1e-06 m" in capsys.readouterr().err


def test_the_gaps_reach_the_meta_and_the_model_line(blocks, capsys, monkeypatch):
    from transient.shared import factorization
    # the fixture's stand-in is for the refusals: this one prepares
    monkeypatch.setattr(transient.stages, "factorization", factorization)
    setup = transient.stages.prepare(load(blocks, [at(0.01 + 5e-6)]))
    gap0 = setup.meta["pairs"]["c"]["gap0"]
    assert gap0["min"] == pytest.approx(5e-6) and gap0["max"] == pytest.approx(5e-6)
    assert gap0["overclosed"] == 0.0
    assert ("c: fine rule, 48 points, initial gap 5e-06 to 5e-06 m (0% of the area "
            "overclosed)") in _model_line(setup.meta)
    assert capsys.readouterr().err == ""


def test_the_law_s_gap_at_a_pressure_inverts_it():
    case = load(CASES / "pad_disc.toml")
    law = case.contact["pad_disc"].law
    for p in (1.0, 1e4, 1e6, 1e9, 1e11):
        g = gap_at(law, 5e11, p)
        g_lin = np.log(law.p0 / law.p_lin) / law.lam
        back = (law.p0 * np.exp(-law.lam * g) if g >= g_lin
                else law.p_lin * (1 + law.lam * (g_lin - g)))
        assert back == pytest.approx(p, rel=1e-9)
    opened, deep = bounds(law, 5e11, 1e6, 1e-12)
    assert opened == pytest.approx(np.log(1e4 / 1.0) / 5e5)
    assert deep == pytest.approx(np.log(1e9 / 1e4) / 5e5)


def test_a_load_through_a_tied_piston_is_the_pad_s_preload():
    # brake_corner presses its pads through pistons tied by bilateral pairs: the pad's own
    # loads are none, the piston's line pressure is what the pair carries
    case = load(CASES / "brake_corner.toml")
    model = build_model(case)
    interface = pair_interface(case, model, "pad_in_disc")
    n = interface.plane[2]
    piston = model.parts["piston_in"]
    line = model.load_patterns["line_in"].reshape(-1, 3)[
        piston.offset:piston.offset + piston.mesh.n_nodes].sum(axis=0)
    p = preload_pressure(case, model, case.contact["pad_in_disc"], n, interface.fine.area)
    assert p > 0 and p * interface.fine.area == pytest.approx(-line @ n, rel=1e-12)


@pytest.mark.parametrize("key, override, measured", [
    ("sensors.top.point", "sensors.top.point=[0.39,0.01,0.02]", "0.37 m from part 'upper'"),
    ("loads.tap.point", "loads.tap.point=[0.01,0.01,0.5]", "0.48 m from part 'upper'"),
])
def test_a_point_off_its_part_is_refused_with_the_distance(blocks, capsys, key, override,
                                                           measured):
    more = ['loads.tap.kind="force"', 'loads.tap.part="upper"',
            "loads.tap.point=[0.01,0.01,0.02]", "loads.tap.vector=[0.0,0.0,-1.0]",
            'loads.tap.signal.kind="impulse"', "loads.tap.signal.duration=1e-6"]
    err = refused(capsys, blocks, *more, override)
    assert f": {key}: " in err and measured in err


def test_a_point_between_nodes_on_its_part_is_taken(blocks, capsys):
    # a cell's width from the nearest node, on the part: its nearest node, as before
    case = load(blocks, ["sensors.top.point=[0.005,0.005,0.0199]"])
    model = build_model(case)
    assert model.sensor_names == ("top",) and capsys.readouterr().err == ""


def test_a_rotation_about_an_axis_off_its_part_is_refused(blocks, capsys):
    err = refused(capsys, blocks, "motion.turn.point=[10.0,10.0,0.0]")
    assert ": motion.turn.point: [10.0, 10.0, 0.0]: the axis passes 14.1 m from" in err


def test_a_mesh_in_millimetres_read_as_metres_is_refused_with_the_hint(tmp_path, capsys,
                                                                       monkeypatch):
    monkeypatch.setattr(transient.model.model, "assemble", _reached)
    # a 240 mm by 240 mm by 20 mm plate, its coordinates in millimetres
    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                        [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    meshio.write(tmp_path / "plate.msh", meshio.Mesh(corners * [240.0, 240.0, 20.0],
                                                     [("hexahedron", [list(range(8))])]),
                 file_format="gmsh")
    (tmp_path / "plate.toml").write_text(
        '[materials.steel]\nE = 2.1e11\nnu = 0.3\nrho = 7850.0\n'
        '[parts.plate]\nmaterial = "steel"\n'
        '[parts.plate.mesh]\nkind = "file"\npath = "plate.msh"\n')
    path = tmp_path / "plate.toml"
    for command in ("modes", "run"):
        args = [command, str(path)] + (["-o", str(tmp_path / "p.h5")] if command == "run"
                                       else [])
        assert main(args + ["--set", "solver.t_end=1e-5"]) == 2
        err = capsys.readouterr().err.strip()
        assert err == (f"error: {path}: parts.plate.mesh.scale: the mesh of part 'plate' spans "
                       "240 m at scale 1, more than limits.part_span (10 m): a file in "
                       "millimetres? set parts.plate.mesh.scale = 1e-3 (or raise "
                       "limits.part_span for a part that large)")
    with pytest.raises(Reached):
        main(["modes", str(path), "--set", "parts.plate.mesh.scale=1e-3"])
    # a part that large in metres: the bound raised, the mesh taken as it is
    with pytest.raises(Reached):
        main(["modes", str(path), "--set", "limits.part_span=300.0"])


@pytest.mark.parametrize("case", sorted(p.name for p in CASES.glob("*.toml")))
def test_every_shipped_case_passes_the_checks_in_silence(case, capsys):
    loaded = load(CASES / case)
    model = build_model(loaded)
    from transient.contact.gaps import check_gaps, initial_gaps
    from transient.model.placement import check_motions
    check_motions(loaded, model.parts)
    for name in loaded.contact:
        interface = pair_interface(loaded, model, name)
        gaps = initial_gaps(interface)
        check_gaps(loaded, model, name, interface, gaps)
        assert gaps.overclosed == 0.0 and abs(gaps.min) < 1.1e-5
    assert capsys.readouterr().err == ""


def test_a_dry_run_checks_and_measures_then_stops(blocks, capsys, monkeypatch, tmp_path):
    """`--dry-run` on run, modes and cea: the model and the pairs' fine rules built and
    checked (a pad off the disc refused as the command would refuse it), the dofs by part,
    the fine points and gaps, the memory estimate and a run's steps said; nothing factorized
    (the factorization is never reached) and nothing written."""
    monkeypatch.setattr(transient.shared, "factorization", _reached)
    out = tmp_path / "never.h5"
    for command in ("run", "modes", "cea"):
        args = [command, str(blocks), "--dry-run"] + (["-o", str(out)] if command == "run"
                                                      else [])
        assert main(args) == 0
        text = capsys.readouterr().out
        assert f"{command} would take" in text and "contact c: " in text
        assert "memory: about" in text and "nothing factorized or written" in text
    assert not out.exists()
    assert main(["run", str(blocks), "--dry-run", "--set", at(0.012)]) == 2
    assert "the surfaces do not touch" in capsys.readouterr().err
    case = load(blocks, ["solver.dt=1e-6", "solver.t_end=1.5e-5"])
    d = transient.api.dry_run(case, "run")
    assert d["steps"] == {"steps": 15, "exact": True}
    assert sum(p["dofs"] for p in d["parts"].values()) == d["dofs"]
    assert d["pairs"]["c"]["fine_points"] > 0 and d["memory"]["estimate_gb"] > 0
