"""Squeal in time: friction in the transient kernels against the complex modes.

The small pad and disc of test_cea at mu = 0.4 (the disc turning at 50 rad/s), preloaded at
steady sliding and tapped lightly: in the linear phase, the amplitude of each complex mode in
the transient, c_j(t) = y_j^H z(t) with y_j its left eigenvector and z = (q - q0, v) the
first-order state, evolves as exp(lambda_j t). Its fitted growth rate must be the CEA's real
part of the very system integrated (linearized at its preload by stability.linearize): for the
unstable mode (growth) and its flutter partner (decay), with every scheme that integrates
friction, converging as the step shrinks.
"""
import numpy as np
import pytest
import scipy.linalg as sla

from transient.stability.linearize import linearized
from transient.dynamics.chunks import buffer
from transient.stages import choose_dt, prepare, stepper

from test_cea import small

T_END = 8e-3


def modal_rates(scheme, corrector, dt=0.0):
    """(CEA eigenvalues, fitted rates) of the unstable mode and its partner, and the run's
    energy balance error relative to the peak mechanical energy."""
    case = small("contact.pad_disc.friction.mu=0.4", "loads.tap.vector=[0.0,0.0,-0.02]",
                 f"solver.t_end={T_END}", f'solver.scheme="{scheme}"',
                 f'solver.corrector="{corrector}"', "output.field=true", f"solver.dt={dt}")
    setup = prepare(case)
    system = setup.system
    _, D, K = linearized(system, setup.state)
    n = system.n
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -D]])
    lam, left = sla.eig(A, left=True, right=False)
    step = choose_dt(case, setup)
    steps = int(round(T_END / step))
    state = setup.state.copy()
    q0 = state.q.copy()
    out = buffer(system, steps, False)
    status, done = stepper(case, system, step)(state, steps, 1, out)
    assert status == 0 and done == steps
    t = out.time
    q = out.sensors[:, len(system.sensor_names):]
    z = np.hstack([q - q0, np.gradient(q, t, axis=0)])
    grow = np.argmax(np.where(lam.imag > 0, lam.real, -np.inf))
    partner = np.argmin(np.where((lam.imag > 0) & (np.abs(lam.imag - lam[grow].imag)
                                                   < 1e-3 * lam[grow].imag), lam.real, np.inf))
    sel = (t > 1e-3) & (t < T_END - 0.5e-3)
    rates = []
    for j in (grow, partner):
        c = np.abs(z @ left[:, j].conj())
        fit = (t < 2e-3) & (t > 0.2e-3) if j == partner else sel
        rates.append(np.polyfit(t[fit], np.log(c[fit]), 1)[0])
    e = out.energy
    balance = e[:, 0] + e[:, 1] + e[:, 2] - e[:, 3] + e[:, 4]
    drift = np.abs(balance - balance[0]).max() / (e[:, 0] + e[:, 1] + e[:, 2]).max()
    return lam[[grow, partner]], np.array(rates), drift


@pytest.mark.parametrize("scheme, corrector", [("exponential", "evaluated"),
                                               ("exponential", "propagated"),
                                               ("exponential", "implicit"),
                                               ("implicit", "evaluated"),
                                               ("explicit", "evaluated")])
def test_growth_in_time_is_the_complex_modes_real_part(scheme, corrector):
    """The unstable mode grows at the CEA's real part within 1% at the scheme's step (the
    exponential's and Newmark's at half the exponential's default: 0.39% and 0.33% measured,
    1.6% and 1.3% at the default), and its partner decays at its own within 5% over the first
    ms, before the growing one swamps it."""
    dt = 0.0 if scheme == "explicit" else 1.5625e-6
    lam, rates, drift = modal_rates(scheme, corrector, dt)
    assert lam[0].real > 500 and lam[1].real < -500     # a flutter pair: one grows, one decays
    assert rates[0] == pytest.approx(lam[0].real, rel=1e-2)
    assert rates[1] == pytest.approx(lam[1].real, rel=5e-2)
    assert drift < 1e-3


@pytest.mark.slow
def test_growth_rate_converges_with_the_step():
    """The exponential scheme's error on the growth rate falls at least 3 times as dt halves
    (second order: 1.6%, 0.39%, 0.09% measured)."""
    errors = []
    for dt in (3.125e-6, 1.5625e-6):
        lam, rates, _ = modal_rates("exponential", "evaluated", dt)
        errors.append(abs(rates[0] / lam[0].real - 1))
    assert errors[1] < errors[0] / 3


@pytest.mark.slow
def test_newmark_growth_rate_converges_with_the_step():
    """So does implicit Newmark's, which integrates friction with its exact Jacobian
    (1.3%, 0.33%, 0.08% measured as dt halves from 3.125 us)."""
    errors = []
    for dt in (3.125e-6, 1.5625e-6, 7.8125e-7):
        lam, rates, _ = modal_rates("implicit", "evaluated", dt)
        errors.append(abs(rates[0] / lam[0].real - 1))
    assert errors[1] < errors[0] / 3 and errors[2] < errors[1] / 3


@pytest.mark.slow
def test_newmark_on_the_full_model_grows_at_the_full_models_complex_mode():
    """Newmark on the full model (852 free dofs, the 492 fine points: its friction's exact
    terms through S^-1 [C; Ct; Cc]^T) grows at the real part of the full model's own complex
    mode within 1% at the reduced kernels' half step (0.33% measured, as reduced Newmark's),
    at its frequency, and closes its energy balance."""
    case = small("contact.pad_disc.friction.mu=0.4", "loads.tap.vector=[0.0,0.0,-0.02]",
                 f"solver.t_end={T_END}", 'solver.scheme="implicit"',
                 "solver.reduction.enabled=false", 'contact.pad_disc.rule="fine"',
                 "output.field=true", "solver.dt=1.5625e-6")
    setup = prepare(case)
    system = setup.system
    assert not system.reduced and system.contacts.friction is not None
    M, D, K = (x.toarray() for x in linearized(system, setup.state))
    n = K.shape[0]
    Mi = np.linalg.inv(M)
    lam, left = sla.eig(np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ D]]),
                        left=True, right=False)
    steps = int(round(T_END / choose_dt(case, setup)))
    state = setup.state.copy()
    q0 = state.q.copy()
    out = buffer(system, steps, False)
    status, done = stepper(case, system, 1.5625e-6)(state, steps, 1, out)
    assert status == 0 and done == steps
    t = out.time
    q = out.sensors[:, len(system.sensor_names):]
    z = np.hstack([q - q0, np.gradient(q, t, axis=0)])
    grow = np.argmax(np.where(lam.imag > 0, lam.real, -np.inf))
    assert 11e3 < lam[grow].imag / (2 * np.pi) < 12.5e3 and lam[grow].real > 500
    c = np.abs(z @ left[:, grow].conj())
    sel = (t > 1e-3) & (t < T_END - 0.5e-3)
    assert np.polyfit(t[sel], np.log(c[sel]), 1)[0] == pytest.approx(lam[grow].real, rel=1e-2)
    e = out.energy
    balance = e[:, 0] + e[:, 1] + e[:, 2] - e[:, 3] + e[:, 4]
    assert np.abs(balance - balance[0]).max() < 1e-6 * (e[:, 0] + e[:, 1] + e[:, 2]).max()


def sticking_point(v_eps=1e-3, mu=0.4, wp=10.0):
    """One mode carrying one contact point held at a constant pressure (a linear penalty
    pressed in, its gap row zero) whose surface does not slide (V = 0): the tanh law makes
    it a damping w p mu / v_eps at rest, the stiffest the friction gets."""
    from types import SimpleNamespace
    import naive as nv
    k = 1e10
    g0 = np.array([-wp / k])                              # w = 1: p = k (-g0) = wp
    law = (np.ones((1, 1)), np.zeros((1, 1)), np.zeros(1), np.array([nv.TANH]),
           np.array([v_eps]), np.zeros(1, np.int64), np.zeros((1, 1)), np.full((1, 1), mu),
           np.ones(1, np.int64))
    friction = SimpleNamespace(dm=np.zeros(1), turn=np.zeros(1), code=law[3], v_eps=law[4],
                               table=law[5], tables=(law[6], law[7], law[8]))
    contacts = SimpleNamespace(friction=friction, weights=np.ones(1))
    return law, contacts, g0, nv.penalty_params(k)


@pytest.mark.parametrize("factor, grows", [(0.95, False), (1.05, True)])
def test_stick_bound_is_where_explicit_friction_turns_unstable(factor, grows):
    """critical.friction_steps' sticking bound, 2 v_eps / (w p mu) for this point, is the
    explicit kernel's own: just below it a vibration dies out, just above it grows."""
    from transient.dynamics import critical
    from transient.kernels import codes, stepping
    law, contacts, g0, params = sticking_point()
    slide, stick = critical.friction_steps(law[0], law[1], contacts, np.array([10.0]))
    assert stick == pytest.approx(2 * 1e-3 / (10.0 * 0.4), rel=1e-12)
    assert slide == np.inf                                # no slope where it slides
    dt = factor * stick
    n, steps = 1, 60
    state = np.zeros((7, n))
    state[1, 0] = 1e-5                                   # a slip of 1% of v_eps
    out = (np.zeros(steps), np.zeros((steps, 0)), np.zeros((steps, 0)), np.zeros((steps, 0)),
           np.zeros((steps, 2, 1)), np.zeros((steps, 5)))
    code = np.array([codes.LINEAR], np.int64)
    contact = (np.zeros((1, 1)), g0, np.ones(1), np.zeros(1), code, params[None, :])
    signals = (np.zeros((0, 1)), (np.zeros(0, np.int64), np.zeros((0, 8)), np.zeros((0, 1)),
                                  np.zeros((0, 1)), np.zeros(0, np.int64)), np.zeros((0, 1)))
    status, _ = stepping.explicit_reduced(state, np.zeros(4), steps, 1, dt, np.zeros(1),
                                          np.zeros(1), contact, law, signals, np.array([0, 1]),
                                          np.zeros(1), out)
    assert status == codes.OK
    # the slip, at the half step's velocity, changes sign and by 1 - c dt each step
    slip = np.abs(out[4][:, 0, 0])
    assert (slip[-1] > 1e-5) == grows and (slip[-1] < 1e-6) != grows


@pytest.mark.slow
@pytest.mark.parametrize("name", ["brake_corner", "pad_disc"])
def test_the_friction_terms_through_the_factors_are_the_rows_own(name):
    """stability.linearize takes a factored reduced system's friction stiffness and damping a
    pair at a time through its points' gram, Yt^T (L^T diag(d) L) Y: equal to Ct^T diag(d) C
    of its dense rows, on the brake corner's eleven pairs (two with friction) and on the pad
    and disc's one, each relative to its own size."""
    from dataclasses import replace
    from pathlib import Path

    from transient.case.loading import load
    from transient.stability.stage import analysed_case
    pads = (["contact.pad_in_disc.friction.mu=0.4", "contact.pad_out_disc.friction.mu=0.4"]
            if name == "brake_corner" else ["contact.pad_disc.friction.mu=0.4",
                                            "parts.disc.mesh.divisions=[4,48,1]",
                                            "parts.pad.mesh.divisions=[3,8,1,1]"])
    case = load(Path(__file__).resolve().parent.parent / "cases" / f"{name}.toml", pads)
    setup = prepare(analysed_case(case), analysis=True)
    system = setup.system
    assert system.shape_rows is not None and system.contacts.friction is not None
    factored = linearized(system, setup.state)
    rows = linearized(replace(system, shape_rows=None), setup.state)
    for a, b in zip(factored, rows):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-10 * np.abs(b).max())
    # the friction's own part, not only the diagonal that holds it
    Kf = factored[2] - np.diag(system.omega2)
    np.testing.assert_allclose(Kf, rows[2] - np.diag(system.omega2), rtol=1e-8,
                               atol=1e-10 * np.abs(Kf).max())
