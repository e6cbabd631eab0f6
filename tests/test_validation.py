"""Bad input found by fuzzing, each a one-line error naming the key (exit 2, no traceback, no
warning), before the stage that would have failed on it."""
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.cli import main

from small_cases import PAD_DISC

CASES = Path(__file__).resolve().parent.parent / "cases"
BAR, TWO, PAD = (str(CASES / f"{n}.toml") for n in ("bar_impact", "two_bars", "pad_disc"))


def one_error(capsys, args):
    """Run the command line: exit 2 and one line on stderr, no warning; returns the line."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(args)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and err.startswith("error: ") and "Traceback" not in err
    assert not caught, [str(w.message) for w in caught]
    return err


def sets(*overrides):
    return [a for o in overrides for a in ("--set", o)]


@pytest.mark.parametrize("command, case, overrides, key", [
    ("run", BAR, ['loads.x.kind=["force"]'], "loads.x.kind"),
    ("run", TWO, ['contact.impact.surface1="left.all"'], "contact.impact.surface1"),
    ("run", PAD, ['loads.piston.set="pad.lining"'], "loads.piston.set"),
    ("run", PAD, ["loads.tap.signal.duration=0"], "loads.tap.signal.duration"),
    ("run", PAD, ["loads.tap.signal.duration=-1e-5"], "loads.tap.signal.duration"),
    ("run", BAR, ["solver.t_end=1e300"], "solver.t_end"),
    ("run", PAD, ["loads.piston.value=1e300"], "loads.piston.value"),
    ("run", PAD, ["loads.tap.vector=[0.0,0.0,-1e300]"], "loads.tap.vector"),
    ("modes", BAR, ["solver.quadrature.stiffness=1"], "solver.quadrature.stiffness"),
    ("modes", PAD, ["solver.quadrature.stiffness=3"], "solver.quadrature.stiffness"),
    ("run", BAR, ["solver.t_end=0"], "solver.t_end"),
    ("run", BAR, ["solver.t_end=1e-9", "solver.dt=1e-7"], "solver.t_end"),
    ("run", BAR, ["solver.t_end=1.0", "solver.dt=1e-9"], "solver.t_end"),
    ("run", BAR, ["parts.bar.mesh.divisions=[9223372036854775807,1,1]"],
     "parts.bar.mesh.divisions"),
    ("run", BAR, ["parts.bar.mesh.divisions=[10000,10000,10000]"], "parts.bar.mesh.divisions"),
    ("run", TWO, ["parts.right.mesh.size=[1e300,0.01,0.01]"], "parts.right.mesh"),
    ("run", TWO, ["parts.right.mesh.size=[1e300,1e300,0.01]"], "parts.right.mesh"),
    ("run", TWO, ["parts.right.mesh.size=[1e-300,0.01,0.01]"], "parts.right.mesh"),
    ("modes", TWO, ["contact.impact.k=1e30"], "constraints, contact.NAME.k"),
    ("run", BAR, ["contact.wall.wall_normal=[0,0,0]"], "contact.wall.wall_normal"),
    ("run", BAR, ["sensors.tip.direction=[0,0,0]"], "sensors.tip.direction"),
    ("run", BAR, ["parts.bar.sets.s.kind=\"plane\"", "parts.bar.sets.s.point=[0,0,0]",
                  "parts.bar.sets.s.normal=[0,0,0]"], "parts.bar.sets.s.normal"),
    ("run", PAD, ['loads.tap.signal.kind="constant"'], "loads.tap.signal.duration"),
    ("run", BAR, ['contact.wall.rule="fi\\nne"'], "contact.wall.rule"),
    ("run", BAR, ["solver.t_end=" + "[" * 3000 + "]" * 3000], ""),
    ("compat", BAR, [], "contact.wall.wall_point"),
    ("plot", BAR, [], "contact.wall.wall_point"),
    ("cea", PAD, ["contact.pad_disc.friction.speeds=[0.0,1.0]"],
     "contact.pad_disc.friction.values"),
    ("cea", PAD, ["contact.pad_disc.friction.speeds=[1.0,0.5]",
                  "contact.pad_disc.friction.values=[0.4,0.3]"],
     "contact.pad_disc.friction.speeds"),
    ("cea", PAD, ["contact.pad_disc.friction.mu=0.4", "contact.pad_disc.friction.speeds=[1.0]",
                  "contact.pad_disc.friction.values=[0.4]"], "contact.pad_disc.friction.mu"),
    ("cea", PAD, ["contact.pad_disc.friction.mu=0.4", "motion.disc.omega=0.0"],
     "contact.pad_disc.friction.mu"),
    ("cea", PAD, ["contact.pad_disc.friction.v_eps=0.0"], "contact.pad_disc.friction.v_eps"),
    # a reference friction for the basis: a constant mu, a reduced model, a sliding
    ("cea", PAD, ["contact.pad_disc.friction.basis_mu=0.3",
                  "contact.pad_disc.friction.speeds=[0.0,1.0]",
                  "contact.pad_disc.friction.values=[0.4,0.3]"],
     "contact.pad_disc.friction.basis_mu"),
    ("run", PAD, ["contact.pad_disc.friction.basis_mu=0.3", "solver.reduction.enabled=false",
                  'contact.pad_disc.rule="fine"'], "contact.pad_disc.friction.basis_mu"),
    ("cea", PAD, ["contact.pad_disc.friction.basis_mu=0.3", "motion.disc.omega=0.0"],
     "contact.pad_disc.friction.basis_mu"),
    # the friction's explicit step bound, known only once set up: on a coarse pad and disc
    ("run", PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.4", "solver.dt=3e-5"],
     "solver.dt"),
    # Newmark on the full model with friction keeps S^-1 [C; Ct; Cc]^T: 12 GB here
    ("run", PAD, ["contact.pad_disc.friction.mu=0.4", 'solver.scheme="implicit"',
                  "solver.reduction.enabled=false", 'contact.pad_disc.rule="fine"',
                  "solver.dt=1e-6"],
     "solver.scheme"),
    ("cea", PAD, ["motion.disc.axis=[0,0,0]"], "motion.disc.axis"),
    ("cea", PAD, ["solver.reduction.enabled=false"], "solver.reduction.enabled"),
    ("cea", PAD, ['motion.disc.part="rotor"'], "motion.disc.part"),
    ("cea", PAD, ['motion.belt.kind="translation"', 'motion.belt.part="disc"',
                  "motion.belt.velocity=[1.0,0.0,0.0]"], "motion.belt.part"),
])
def test_bad_input_is_one_line_naming_the_key(tmp_path, capsys, command, case, overrides, key):
    args = [command] + (["compat", case, "--out", str(tmp_path)] if command == "plot" else
                        [case]) + sets(*overrides)
    if command == "run":
        args += ["-o", str(tmp_path / "out.h5"), "--quiet"]
    err = one_error(capsys, args)
    assert f": {key}: " in err if key else ": tables or arrays nested too deeply" in err


@pytest.mark.slow
def test_vectors_and_sizes_of_any_magnitude_double_precision_holds(tmp_path):
    # |v|^2 of a direction of 1e-300 is 0 and of 1e300 inf; a part 1e160 m long squares past
    # 1e308 too: the same run as with unit vectors, and no warning
    short = ["solver.t_end=6e-5", "parts.bar.sets.end.kind=\"plane\"",
             "parts.bar.sets.end.point=[0,0,0]"]
    extreme = ["sensors.tip.direction=[1e-300,0,0]", "contact.wall.wall_normal=[-1e300,0,0]",
               "parts.bar.sets.end.normal=[1e-300,0,0]"]
    plain = ["parts.bar.sets.end.normal=[1,0,0]"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for name, overrides in (("extreme", extreme), ("plain", plain)):
            assert main(["run", BAR, "-o", str(tmp_path / f"{name}.h5"), "--quiet"]
                        + sets(*short, *overrides)) == 0
        assert main(["run", TWO, "-o", str(tmp_path / "long.h5"), "--quiet"]
                    + sets("parts.right.mesh.size=[1e160,0.01,0.01]")) == 0
    assert not caught, [str(w.message) for w in caught]
    with h5py.File(tmp_path / "extreme.h5") as a, h5py.File(tmp_path / "plain.h5") as b:
        for name in ("sensors/tip", "contact/wall/pressure"):
            assert np.array_equal(a[name][()], b[name][()]), name


def test_names_that_cannot_be_keys_or_series_are_refused(tmp_path, capsys):
    text = (CASES / "bar_impact.toml").read_text().replace("[sensors.tip]",
                                                           '[sensors."\\u0000"]')
    path = tmp_path / "bar.toml"
    path.write_text(text)
    err = one_error(capsys, ["run", str(path), "-o", str(tmp_path / "o.h5")])
    assert "sensors.\\x00: expected a name of letters, digits" in err


@pytest.mark.parametrize("damage", ["rows too large", "rows not a number", "no rows",
                                    "shortened series"])
@pytest.mark.parametrize("command", ["info", "plot history", "export", "run --resume"])
def test_a_damaged_history_is_one_line_in_every_reader(tmp_path, capsys, damage, command):
    path = tmp_path / "bar.h5"
    assert main(["run", BAR, "-o", str(path), "--quiet"]) == 0
    with h5py.File(path, "r+") as f:
        if damage == "rows too large":
            f.attrs["rows"] = 10 ** 6
        elif damage == "rows not a number":
            f.attrs["rows"] = "many"
        elif damage == "no rows":
            del f.attrs["rows"]
        else:
            f["sensors/tip"].resize(3, axis=0)
    capsys.readouterr()
    words = command.split()
    args = ([words[0], BAR, "-o", str(path), "--resume", "--quiet"] if words[0] == "run" else
            words + [str(path)])
    one_error(capsys, args)
