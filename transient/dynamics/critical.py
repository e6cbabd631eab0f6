"""The critical step of central differences, at the preload and at the deepest penetration
reached since.

At the preload it is 2 / omega_max of the system with the contact tangents it may meet: the
preload's, and k for penalty laws (they may close during the run). During the run the bound
omega_max^2 <= omega_0^2 + sum_i w_i dk_t,i |C_i M^-1/2|^2 (on the safe side) follows the
tangents' growth dk_t beyond those, at the smallest gap each point has reached.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..kernels.codes import ATAN, EXPONENTIAL, FRICTIONLESS

# An explicit impact keeps its energy (drift within 1% of the peak) while the penalties alone
# on the lumped mass oscillate at omega_c dt <= 0.7, though central differences stay stable
# to omega_max dt = 2: studies/study_contact_step.py, 90 bars (steel and aluminium, 16 to 100
# elements, k from 2e13 to 2e15 Pa/m, 3 phases of the first contact) gave a worst drift of
# 3.4e-3 up to omega_c dt = 0.7, 7.1e-3 to 0.75, 2.0e-2 to 0.8, 0.23 to 1.2 and 0.8-0.94
# above 1.4 (each chatter of the end face gains energy there).
CONTACT_OMEGA_DT = 0.7
# The exponential scheme's explicit correctors take the contact beyond the preload's tangent
# explicitly: a penalty open at the preload bounds their step like an explicit scheme's, by
# omega_r dt with omega_r that remainder's own frequency on the reduced model. Measured on the
# Hertz ball of tests/test_hertz.py (omega_r = 1.04e9 rad/s): "evaluated" ran at 1.25 and
# diverged at 2.5 (the bar of bar_impact runs at 1.6); "propagated" ran at 0.31 and drifted at
# 0.62, and at 833 it completed with every contact bounced within one step, unseen by the rows.
# The implicit corrector solves for the remainder and has no such bound.
REMAINDER_OMEGA_DT = {"evaluated": 2.0, "propagated": 0.5}


@dataclass(frozen=True)
class CriticalStep:
    dt: float                # at the preload [s] (inf when nothing bounds it)
    kt_checked: np.ndarray   # (m,) contact tangents it accounts for [Pa/m]
    rows: np.ndarray         # (m,) |C_i M^-1/2|^2 of each contact row
    contacts: object         # ContactSet: weights and laws of the points
    omega_contact: float = 0.0   # the contact's own highest frequency, penalty closed [rad/s]
    omega_remainder: float = 0.0  # the same of what the linear part leaves out (reduced) [rad/s]
    friction_dt: float = np.inf   # the explicit friction's bound at steady sliding [s]
    stick_dt: float = np.inf      # and with every point sticking (friction_steps) [s]

    def at(self, gmin):
        """The largest stable step with every point at its smallest gap so far."""
        _, kt, _ = self.contacts.laws(gmin)
        grow = np.maximum(kt - self.kt_checked, 0.0)
        if not np.any(grow):
            return self.dt
        omega2 = (2.0 / self.dt) ** 2 if np.isfinite(self.dt) else 0.0
        return 2.0 / np.sqrt(omega2 + np.sum(self.contacts.weights * grow * self.rows))

    @property
    def contact_dt(self):
        """The largest step at which an impact keeps its energy (CONTACT_OMEGA_DT)."""
        return CONTACT_OMEGA_DT / self.omega_contact if self.omega_contact > 0 else np.inf

    def remainder_dt(self, corrector):
        """The largest step the exponential scheme's corrector takes the contact remainder
        at (REMAINDER_OMEGA_DT), and the sliding friction (friction_dt); unbounded for the
        implicit one."""
        limit = REMAINDER_OMEGA_DT.get(corrector, np.inf)
        contact = limit / self.omega_remainder if self.omega_remainder > 0 else np.inf
        return contact if corrector == "implicit" else min(contact, self.friction_dt)

    def stick_hint(self, dt, scheme, corrector):
        """What a run with friction taken explicitly that went unstable should be told, ''
        when its step would hold a sticking point."""
        if scheme == "implicit" or (scheme == "exponential" and corrector == "implicit") or \
                dt <= self.stick_dt:
            return ""
        return (f"; friction taken explicitly: a point sticking needs dt <= {self.stick_dt:.2e}"
                f" s (proportional to contact.*.friction.v_eps), solver.corrector = "
                f'"implicit" takes it exactly')

    def drift_hint(self, dt):
        """What an explicit run losing its energy balance at step dt should be told: the
        frequencies of the step, and the keys that drive them ('' without contact)."""
        point = self.stiffest_point(dt)
        if point is None:
            return ""
        return (f"; with the penalty closed the step runs at omega_max dt = {point[0]:.2f} "
                f"(limit 2), the contact at omega_c dt = {dt * self.omega_contact:.2f} "
                f"(impacts keep their energy to {CONTACT_OMEGA_DT}): lower "
                f"contact.{point[1]}.k ({point[2]:.3g} Pa/m) or solver.dt ({dt:.3g} s)")

    def stiffest_point(self, dt):
        """(omega_max dt, pair, tangent) at step dt: the system's highest frequency (penalty
        contact closed) times dt, and the pair and tangent of the contact point whose own
        oscillator is the fastest (w k_t |C_i M^-1/2|^2); None without contact. What an
        explicit run losing its energy balance to a stiff penalty should be told."""
        if not len(self.rows):
            return None
        omega2 = self.contacts.weights * self.kt_checked * self.rows
        i = int(np.argmax(omega2))
        name = next(n for n, s in self.contacts.slices.items() if s.start <= i < s.stop)
        return 2.0 * dt / self.dt, name, float(self.kt_checked[i])


def friction_steps(Ct, Cc, contacts, pressure):
    """(sliding, sticking) bounds on the step of the schemes that take friction explicitly
    (central differences at the half step's velocity, the exponential scheme's explicit
    correctors): the friction is a damping there, D = Ct^T diag(w p d tau_t / d s_t) Ct +
    Cc^T diag(w p d tau_c / d s_c) Cc per unit pressure's slope, and an explicit damping is
    stable to dt lambda_max(D) = 2. Sliding at V the slopes are the law's (FrictionSet.dm
    along, .turn = m / V across: small for V >> v_eps); a point sticking has mu(0) / v_eps
    both ways (tanh; 2 / pi of it for atan), so its bound is proportional to v_eps: pad_disc at
    mu = 0.4 slides at 6.2e-6 s and would stick at 7.6e-9 s. Reduced systems (dense Ct, Cc)
    only; (inf, inf) without friction."""
    f = contacts.friction
    if f is None or Ct is None:
        return np.inf, np.inf
    wp = contacts.weights * np.maximum(pressure, 0.0)
    mu0 = f.tables[1][f.table, 0]
    at_rest = np.where(f.code == ATAN, 2.0 / np.pi, 1.0) * np.where(
        f.code == FRICTIONLESS, 0.0, mu0 / f.v_eps)

    def bound(along, across):
        lam = _largest((Ct.T * (wp * along)) @ Ct + (Cc.T * (wp * across)) @ Cc)
        return 2.0 / lam if lam > 0 else np.inf
    return bound(np.abs(f.dm), f.turn), bound(at_rest, at_rest)


def critical_tangent(contacts, tangent):
    """The preload's tangents, raised to k for the penalty laws."""
    kt = tangent.copy()
    penalty = contacts.code != EXPONENTIAL
    kt[penalty] = np.maximum(kt[penalty], contacts.params[penalty, 0])
    return kt


def reduced(omega2, Cr, contacts, tangent, Ct=None, Cc=None, pressure=None):
    """CriticalStep of a reduced system (M = I): eigenvalues of the small dense matrix; with
    friction (Ct, Cc and the preload's pressure), its explicit bounds too."""
    kt = critical_tangent(contacts, tangent)
    dkw = contacts.weights * (kt - tangent)
    # the remainder's stiffness, what the linear part leaves out of the penalties
    R = (Cr.T * dkw) @ Cr if len(dkw) else np.zeros((len(omega2),) * 2)
    lam = _largest(np.diag(omega2) + R)
    dt = 2.0 / np.sqrt(lam) if lam > 0 else np.inf
    omega_c = np.sqrt(_largest((Cr.T * (contacts.weights * kt)) @ Cr)) if len(dkw) else 0.0
    slide, stick = (friction_steps(Ct, Cc, contacts, pressure) if pressure is not None
                    else (np.inf, np.inf))
    return CriticalStep(dt, kt, np.einsum("ij,ij->i", Cr, Cr), contacts, float(omega_c),
                        float(np.sqrt(_largest(R))), float(slide), float(stick))


def _largest(A):
    """The largest eigenvalue of a symmetric A, 0 at least (and for an empty one)."""
    return max(np.linalg.eigvalsh(0.5 * (A + A.T))[-1], 0.0) if len(A) else 0.0


def full(K, mass, Cf, contacts, tangent):
    """CriticalStep of the full model with a diagonal mass (Lanczos on D^-1/2 K D^-1/2)."""
    kt = critical_tangent(contacts, tangent)
    Kc = (K + (Cf.T @ sp.diags(contacts.weights * (kt - tangent)) @ Cf)).tocsr()
    d = sp.diags(1.0 / np.sqrt(mass))
    A = (d @ Kc @ d).tocsr()
    v0 = np.ones(A.shape[0])      # a fixed start: the same dt on every run of a case
    lam = spla.eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-6, v0=v0)[0]
    # Lanczos converges from below: a small margin keeps the estimate an upper bound
    dt = 2.0 / np.sqrt(1.01 * lam)
    return CriticalStep(dt, kt, np.asarray(Cf.multiply(Cf) @ (1.0 / mass)).ravel(), contacts,
                        _contact_omega(Cf, contacts.weights * kt, mass))


def _contact_omega(Cf, kw, mass):
    """sqrt of the largest eigenvalue of D^-1/2 C^T diag(w k) C D^-1/2, the penalties alone on
    the lumped mass, from the m x m B B^T (B = diag(w k)^1/2 C D^-1/2): points share nodes, so
    it is sparse and far smaller than the model."""
    if Cf.shape[0] == 0:
        return 0.0
    B = (sp.diags(np.sqrt(kw)) @ Cf @ sp.diags(1.0 / np.sqrt(mass))).tocsr()
    G = (B @ B.T).tocsr()
    if G.shape[0] < 64:
        lam = np.linalg.eigvalsh(G.toarray())[-1]
    else:
        lam = spla.eigsh(G, k=1, which="LA", return_eigenvectors=False, tol=1e-6,
                         v0=np.ones(G.shape[0]))[0]
    return float(np.sqrt(max(lam, 0.0)))
