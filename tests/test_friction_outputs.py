"""The friction's outputs of a run (output.contact with friction): each point's slip velocity,
the powers and statuses derived from them (contact.friction), and `transient plot friction`.

On the small pad and disc of test_cea at mu = 0.4: at the preload the points slide at the
imposed speed, so the sliding's input equals the slip's dissipation, sum w p mu sgn_reg(V) V;
at the run's last step the input power derived from the stored pressures and slips is the
kernel's own (the accumulator a checkpoint keeps), to round-off.
"""
import h5py
import numpy as np
import pytest
from matplotlib.image import imread

from transient.cli import main
from transient.contact.friction import OPEN, SLIP, contact_status, friction_powers
from transient.io.stored import open_history
from transient.integration import run

from test_cea import small
from test_history_plots import CASE as BAR, SHORT

STEPS = 400


@pytest.fixture(scope="module")
def history(tmp_path_factory):
    path = tmp_path_factory.mktemp("friction") / "squeal.h5"
    case = small("contact.pad_disc.friction.mu=0.4", "output.contact=true", "output.every=1",
                 "solver.dt=2e-6", f"solver.t_end={STEPS * 2e-6}")
    run(case, path)
    return path


def test_slips_are_stored_and_steady_at_the_preload(history):
    stored = open_history(history)
    slip = stored.read("contact/pad_disc/slip")
    press = stored.read("contact/pad_disc/pressure")
    gap = stored.read("contact/pad_disc/gap")
    assert slip.shape == (stored.rows, 2, press.shape[1])
    law = stored.friction_law("pad_disc")
    code, v_eps, _, _, V = law
    assert V.min() > 0
    np.testing.assert_array_equal(slip[0, 0], V)           # v = 0 at the preload
    np.testing.assert_array_equal(slip[0, 1], 0.0)
    w = stored.contact_geometry("pad_disc")["weights"]
    p_in, p_diss = friction_powers(law, w, press, slip)
    steady = np.sum(w * press[0] * 0.4 * np.tanh(V / v_eps) * V)
    assert p_in[0] == pytest.approx(steady, rel=1e-12)
    assert p_diss[0] == pytest.approx(steady, rel=1e-12)
    assert np.all(p_diss >= 0)
    status = contact_status(gap, slip, v_eps)
    assert np.all(status[0] == SLIP) and not np.any(status == OPEN)
    # the vibration grows: the slip moves away from the imposed sliding
    assert np.abs(slip[-1, 0] - V).max() > 1e-3 * V.max()


def test_input_power_is_the_kernels(history):
    """The input power derived from the last row's pressures and slips is the one the kernel
    carried to the next step (acc[3] of the final checkpoint)."""
    stored = open_history(history)
    with h5py.File(history) as f:
        # the slot the checkpoint links to: the last written whole
        acc = f["checkpoint/acc"][()]
        assert f["checkpoint/step"][0] == STEPS
    law = stored.friction_law("pad_disc")
    w = stored.contact_geometry("pad_disc")["weights"]
    p_in, _ = friction_powers(law, w, stored.read("contact/pad_disc/pressure")[-1:],
                              stored.read("contact/pad_disc/slip")[-1:])
    assert p_in[0] == pytest.approx(acc[3], rel=1e-10)


def test_plot_friction(history, tmp_path, capsys):
    png = tmp_path / "f.png"
    assert main(["plot", "friction", str(history), "-o", str(png), "--time", "4e-4"]) == 0
    out = capsys.readouterr().out
    assert "mean input" in out and "slip 100%" in out
    assert imread(png).shape[1] >= 800


def test_plot_friction_refuses_a_run_without_friction(tmp_path, capsys):
    path = tmp_path / "bar.h5"
    assert main(["run", str(BAR), "-o", str(path), "--quiet", "--set", *SHORT,
                 "--set", "output.contact=true"]) == 0
    capsys.readouterr()
    assert main(["plot", "friction", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "slip" in err, err
