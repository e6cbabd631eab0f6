"""Inputs that drove a command past its bounds (a traceback, a warning, a list of 1e5 values
checked one by one): each is one line naming the key or option, exit 2, before the stage that
would have failed on it."""
import warnings
from pathlib import Path

import pytest

import transient.api
import transient.stability.stage
import transient.shared
import transient.solve.tied
import transient.stages
from transient.cli import main
from transient.campaign.variants import MAX_VARIANTS

from small_cases import PAD_DISC

CASES = Path(__file__).resolve().parent.parent / "cases"
BAR, PAD = (str(CASES / f"{n}.toml") for n in ("bar_impact", "pad_disc"))


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


@pytest.fixture
def no_setup(monkeypatch):
    """Every eigensolver and factorization of the setup fails the test if it is reached."""
    def reached(*args, **kwargs):
        raise AssertionError("the setup ran before the input was refused")
    monkeypatch.setattr(transient.stages, "factorization", reached)
    monkeypatch.setattr(transient.shared, "factorization", reached)
    monkeypatch.setattr(transient.solve.tied, "normal_modes", reached)
    monkeypatch.setattr(transient.stability.stage, "full_complex_modes", reached)


@pytest.mark.parametrize("command, case, overrides, key", [
    # (2 pi f)^2 overflowed: refused at load, or past every mode the mesh has once it is built
    ("modes", BAR, ["solver.modes.fmax=1e300"], "solver.modes.fmax"),
    ("cea", PAD, ["solver.reduction.fmax=1e300"], "solver.reduction.fmax"),
    ("modes", BAR, ["solver.modes.shift=-1e300"], "solver.modes.shift"),
    ("modes", BAR, ["solver.modes.fmax=1e12"], "solver.modes.fmax"),
    ("modes", BAR, ["solver.modes.shift=-1e12"], "solver.modes.shift"),
    ("cea", BAR, ["solver.modes.fmax=1e12"], "solver.modes.fmax"),
    ("cea", BAR, ["solver.reduction.enabled=true", "solver.reduction.fmax=1e12"],
     "solver.reduction.fmax"),
    ("run", BAR, ["solver.reduction.enabled=true", "solver.reduction.fmax=1e12"],
     "solver.reduction.fmax"),
    # the full model's Arnoldi among the modes a heavy beta spreads about its shifts
    ("cea", BAR, ["solver.damping.beta=1e-3"], "solver.damping.beta"),
    ("cea", BAR, ["solver.damping.beta=1e-5"], "solver.damping.beta"),
    # a rotation about an axis 1e300 m away: an overflow, then "nodes without sliding"
    ("cea", PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.4", "motion.disc.point=[1e300,0,0]"],
     "motion.disc.point"),
    ("cea", PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.4",
                              "motion.disc.point=[1.7e308,-1.7e308,0]"], "motion.disc.point"),
    # a wall behind the whole part (its forces overflowed: exit 3), or so far along itself
    # that the faces lost their areas ("no face faces the wall")
    ("run", BAR, ["contact.wall.wall_point=[-1e300,0,0]"], "contact.wall.wall_point"),
    ("run", BAR, ["contact.wall.wall_point=[0.10001,1e160,0]"], "contact.wall.wall_point"),
    ("run", BAR, ["initial.impact.velocity=[1e300,0,0]"], "initial.impact.velocity"),
    # a mass rule of fewer points than nodes: a singular M, a traceback of the cea's eigh
    ("cea", PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.4", "solver.quadrature.mass=1"],
     "solver.quadrature.mass"),
    ("modes", BAR, ["solver.quadrature.mass=1"], "solver.quadrature.mass"),
    # every dof clamped: a traceback of the eigensolver
    ("run", BAR, ['parts.bar.sets.s.kind="box"', "parts.bar.sets.s.min=[-1,-1,-1]",
                  "parts.bar.sets.s.max=[1,1,1]", 'constraints.c.set="bar.s"'],
     "constraints.c.set"),
])
def test_bad_input_is_one_line_before_the_setup(tmp_path, capsys, no_setup, command, case,
                                                 overrides, key):
    args = [command, case] + sets(*overrides)
    if command == "run":
        args += ["-o", str(tmp_path / "out.h5"), "--quiet"]
    err = one_error(capsys, args)
    assert f": {key}: " in err and "expected" in err


@pytest.mark.parametrize("mu, what", [
    ("a:b:c", "START:STOP:COUNT"),
    ("0:1", "START:STOP:COUNT"),
    ("0:inf:3", "START:STOP:COUNT"),
    ("-1e308:1e308:3", "START:STOP:COUNT"),
    ("0:0.5:100000", f"a COUNT from 1 to {MAX_VARIANTS}"),
    ("0:0.5:" + "9" * 30, f"a COUNT from 1 to {MAX_VARIANTS}"),
    ("0:0.5:0", f"a COUNT from 1 to {MAX_VARIANTS}"),
    pytest.param(",".join(["0.1"] * (MAX_VARIANTS + 1)), f"at most {MAX_VARIANTS} values",
                 id="a-list-over-the-cap"),
    ("0.1,nan", "finite numbers"),
    ("0.1,x", "finite numbers"),
])
def test_plot_cea_mu_is_bounded_before_any_variant(tmp_path, capsys, monkeypatch, no_setup,
                                                    mu, what):
    loads = []
    load = transient.api._load        # what the API loads the case and mu_map's variants by

    def counted(*args):
        loads.append(args)
        return load(*args)
    monkeypatch.setattr(transient.api, "_load", counted)
    err = one_error(capsys, ["plot", "cea", PAD, "--out", str(tmp_path), f"--mu={mu}"])
    assert ": --mu: expected " + what in err and len(err) < 300
    # the case alone was loaded: no variant was built, let alone checked one by one
    assert len(loads) == 1
