"""Squeal in time on the two-dof mode-coupling model (Hoffmann and Gaul's mass on a belt,
tests/test_cea_mode_coupling.py): its ReducedSystem integrated by every scheme of the package's
reduced kernels, started on one complex mode of the CEA (the real part of its eigenvector as
the initial perturbation of the preload), grows or decays at that mode's real part within 1%:
above the flutter threshold the growing mode and its decaying partner, below it (with modal
damping) both decaying modes. The rate is fitted on the envelope of the mass's normal motion
y, its amplitude over a sliding period (the Hilbert envelope, about the series' mean and with
its end effects, read the growth of 2.56 1/s 4% low), or for the decaying partner on the
mode's own amplitude (`follow`).

The contact is the linear spring K3 pressed by N0, far from opening, and the belt slides at 1
m/s against motions of a few mm/s, far from sticking: the system integrated is the linear one
the CEA analyses. Measured at 400 steps a period: every scheme within 1.2e-3 of the real
parts (the amplitude's fit over a period's window, the same for all), 4e-3 at 50 steps.
"""
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla

from transient.case.loading import load
from transient.case.signals import compile_signals
from transient.stability.linearize import linearized
from transient.dynamics.chunks import buffer
from transient.dynamics.schemes import initial_acceleration, stepper
from transient.plots.signals import growth_rate, running_amplitude

from test_cea_mode_coupling import mu_c_undamped, reduced_hoffmann
from test_cea import PAD

SCHEMES = [("explicit", "evaluated"), ("exponential", "evaluated"),
           ("exponential", "propagated"), ("exponential", "implicit"),
           ("implicit", "evaluated")]
PERIODS = 12          # the run's length in periods of the mode followed
STEPS = 400           # steps per period
AMPLITUDE = 1e-4      # [m] of the initial perturbation (the preload's gap: 0.067 m)


def two_dof(mu, damping=0.0):
    """(system, preload state, eigenvalues, left and right eigenvectors of the first-order
    system [q; v]) of the Hoffmann-Gaul mass at mu, with modal damping `damping` [1/s] on both
    modes (D = damping M: each eigenvalue's real part shifted by -damping / 2)."""
    system, state = reduced_hoffmann(mu)
    system = replace(system, damp=np.full(2, float(damping)), signals=compile_signals([]))
    # the belt's pressure and the friction it brings held by a constant load: the preload an
    # equilibrium (the forces at rest there, from an explicit step of length 0)
    initial_acceleration(system, state, False)
    system = replace(system, patterns=-state.a[None, :].copy(),
                     signals=compile_signals([{"kind": "constant"}]))
    _, D, K = linearized(system, state)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K, -D]])
    lam, left, right = sla.eig(A, left=True, right=True)
    return system, state, lam, left, right


def follow(mu, damping, pick, scheme, corrector, projected=False):
    """(the CEA's eigenvalue of the mode picked, the rate fitted on the transient started on
    it). pick, among the eigenvalues with Im > 0: "growing" or "decaying" (the largest or
    smallest real part), "low" or "high" (frequency). The amplitude fitted: the running
    amplitude (over a period) of the mass's normal motion y, or if `projected` the mode's own,
    |l^H (q - q0, v)| with l its left eigenvector (v by differences of the stored q): a
    decaying mode whose flutter partner grows, which the scheme's O(dt^2) error on the
    eigenvector seeds and y would soon show instead."""
    system, state, lam, left, right = two_dof(mu, damping)
    upper = np.flatnonzero(lam.imag > 0)
    key = {"growing": -lam.real, "decaying": lam.real, "low": lam.imag, "high": -lam.imag}
    j = upper[np.argmin(key[pick][upper])]
    z = right[:, j] / np.abs(right[:, j]).max()
    rest = state.q.copy()
    state.q[:] += AMPLITUDE * z[:2].real
    state.v[:] += AMPLITUDE * z[2:].real
    # observed: the mass's y (the contact row C = Cn Phi) and the modal coordinates q
    system = replace(system, sensors=np.vstack([system.C, np.eye(2)]), sensor_names=("y",),
                     n_field=2)
    initial_acceleration(system, state, False)
    period = 2 * np.pi / lam[j].imag
    dt = period / STEPS
    n = PERIODS * STEPS
    solver = replace(load(PAD).solver, scheme=scheme, corrector=corrector, corrections=1)
    rows = buffer(system, n, False)
    status, done = stepper(system, solver, dt)(state, n, 1, rows)
    assert status == 0 and done == n
    t = rows.time
    if projected:
        q = rows.sensors[:, 1:] - rest
        amplitude = np.abs(np.hstack([q, np.gradient(q, t, axis=0)]) @ left[:, j].conj())
    else:
        amplitude = running_amplitude(rows.sensors[:, 0] - (system.C @ rest)[0], STEPS)
    sigma, _, _ = growth_rate(t, amplitude, (2 * period, (PERIODS - 2) * period))
    return lam[j], sigma


@pytest.mark.parametrize("scheme, corrector", SCHEMES)
def test_above_threshold_the_flutter_pair_grows_and_decays_at_its_real_parts(scheme,
                                                                                corrector):
    """mu = 1.2 mu_c, undamped: the pair lambda = +-sigma + i omega (sigma 0.146 omega)."""
    mu = 1.2 * mu_c_undamped()
    for pick in ("growing", "decaying"):
        lam, sigma = follow(mu, 0.0, pick, scheme, corrector, projected=pick == "decaying")
        assert (lam.real > 0) == (pick == "growing")
        assert sigma == pytest.approx(lam.real, rel=1e-2)


@pytest.mark.parametrize("scheme, corrector", SCHEMES)
def test_below_threshold_both_modes_decay_at_their_real_parts(scheme, corrector):
    """mu = 0.8 mu_c with modal damping 4 1/s: two modes of distinct frequencies, each
    decaying at -2 1/s (equal damping shifts the undamped, neutral pair)."""
    mu = 0.8 * mu_c_undamped()
    for pick in ("low", "high"):
        lam, sigma = follow(mu, 4.0, pick, scheme, corrector)
        assert lam.real < 0
        assert sigma == pytest.approx(lam.real, rel=1e-2)
