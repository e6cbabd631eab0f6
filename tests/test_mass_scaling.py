"""Mass scaling of the reduced statics (solver.reduction.mass_scaling_hz).

The basis' vectors above the cap get the mass that brings them to it: the stiffness, every
static response and the displacement of a state stay what they were, the critical steps grow,
and the complex modes below fmax move by the statics' lag (f / f_c)^2 only.
"""
import numpy as np
import pytest

from transient.case import load
from transient.stability.stage import analyse
from transient.errors import CaseError
from transient.reduce.stage import ReducedModel, mass_scaled
from transient.stages import prepare

from test_cea import PAD, small

CAP = 64000.0
CASE_CAP = 48000.0       # 3 fmax, above the modes' cutoff (2 fmax); the statics reach 117 kHz


def _model(rng, n=12, ndof=30):
    X = rng.standard_normal((ndof, n))
    AW = rng.standard_normal((n, n))
    omega2 = np.sort((2 * np.pi * np.geomspace(1e2, 1e6, n)) ** 2)
    return ReducedModel(X, AW, omega2, rng.standard_normal(n), rng.standard_normal(n),
                        None, [], None, {})


def test_no_cap_is_the_model_itself():
    red = _model(np.random.default_rng(0))
    assert mass_scaled(red, 0.0) is red


def test_scaling_keeps_stiffness_statics_and_displacement():
    """T diag(omega2)^-1 T^T (the flexibility: every static response) and T q (the state's
    displacement) are the same; only the frequencies above the cap change, to the cap."""
    red = _model(np.random.default_rng(1))
    out = mass_scaled(red, CAP)
    T, Ts = red.X @ red.AW, out.X @ out.AW
    assert np.allclose(Ts @ np.diag(1 / out.omega2) @ Ts.T, T @ np.diag(1 / red.omega2) @ T.T,
                       rtol=1e-12, atol=0)
    assert np.allclose(Ts @ out.q0, T @ red.q0, rtol=1e-12)
    assert np.allclose(Ts @ out.v0, T @ red.v0, rtol=1e-12)
    cap2 = (2 * np.pi * CAP) ** 2
    above = red.omega2 > cap2
    assert above.any() and not above.all()
    assert np.array_equal(out.omega2[~above], red.omega2[~above])
    assert np.allclose(out.omega2[above], cap2, rtol=1e-14)
    assert out.meta["mass_scaling"]["vectors"] == above.sum()


@pytest.fixture(scope="module")
def pair():
    over = ("contact.pad_disc.friction.mu=0.4", "solver.corrector=\"evaluated\"")
    return (small(*over), small(*over, f"solver.reduction.mass_scaling_hz={CASE_CAP}"))


def test_critical_steps_grow_with_the_statics_capped(pair):
    """The statics of the small pad and disc reach 117 kHz: capped at 48 kHz, the central
    differences' step doubles, the preload stays."""
    plain, scaled = (prepare(case) for case in pair)
    assert np.sqrt(plain.system.omega2.max()) > 2 * np.pi * 2 * CASE_CAP
    assert np.sqrt(scaled.system.omega2.max()) == pytest.approx(2 * np.pi * CASE_CAP, rel=1e-12)
    assert scaled.system.critical.dt > 1.5 * plain.system.critical.dt
    # (the sliding friction's bound lies in the modes here: it may only grow)
    assert scaled.system.critical.friction_dt >= plain.system.critical.friction_dt
    u, us = (s.basis[0] @ (s.basis[1] @ s.state.q) for s in (plain, scaled))
    assert np.allclose(us, u, rtol=0, atol=1e-12 * np.abs(u).max())


def test_complex_modes_below_fmax_barely_move(pair):
    """The statics' lag at f / f_c = 1/3 and below moves the complex modes of the band by
    (f / f_c)^2 of the statics' share of them: frequencies within 5e-4,
    the unstable modes' real parts within 1% of the largest."""
    plain, scaled = (analyse(case).modes for case in pair)
    assert len(plain.frequency_hz) == len(scaled.frequency_hz)
    assert np.allclose(scaled.frequency_hz, plain.frequency_hz, rtol=5e-4)
    assert np.array_equal(scaled.unstable, plain.unstable) and plain.unstable.any()
    largest = np.abs(plain.real[plain.unstable]).max()
    assert np.abs(scaled.real - plain.real)[plain.unstable].max() < 1e-2 * largest


@pytest.mark.parametrize("more, reason", [
    (["solver.reduction.mass_scaling_hz=32000"], "not above the basis' cutoff (32000 Hz)"),
    (["solver.reduction.enabled=false", "solver.scheme=\"explicit\"",
      "solver.reduction.mass_scaling_hz=64000"], "set solver.reduction.enabled = true")])
def test_bad_caps_are_refused_at_load(more, reason):
    with pytest.raises(CaseError) as info:
        load(PAD, more)
    assert "solver.reduction.mass_scaling_hz" in str(info.value) and reason in str(info.value)
