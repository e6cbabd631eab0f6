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

from ..kernels.codes import EXPONENTIAL


@dataclass(frozen=True)
class CriticalStep:
    dt: float                # at the preload [s] (inf when nothing bounds it)
    kt_checked: np.ndarray   # (m,) contact tangents it accounts for [Pa/m]
    rows: np.ndarray         # (m,) |C_i M^-1/2|^2 of each contact row
    contacts: object         # ContactSet: weights and laws of the points

    def at(self, gmin):
        """The largest stable step with every point at its smallest gap so far."""
        _, kt, _ = self.contacts.laws(gmin)
        grow = np.maximum(kt - self.kt_checked, 0.0)
        if not np.any(grow):
            return self.dt
        omega2 = (2.0 / self.dt) ** 2 if np.isfinite(self.dt) else 0.0
        return 2.0 / np.sqrt(omega2 + np.sum(self.contacts.weights * grow * self.rows))


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


def critical_tangent(contacts, tangent):
    """The preload's tangents, raised to k for the penalty laws."""
    kt = tangent.copy()
    penalty = contacts.code != EXPONENTIAL
    kt[penalty] = np.maximum(kt[penalty], contacts.params[penalty, 0])
    return kt


def reduced(omega2, Cr, contacts, tangent):
    """CriticalStep of a reduced system (M = I): eigenvalues of the small dense matrix."""
    kt = critical_tangent(contacts, tangent)
    dkw = contacts.weights * (kt - tangent)
    A = np.diag(omega2) + (Cr.T * dkw) @ Cr if len(dkw) else np.diag(omega2)
    lam = np.linalg.eigvalsh(0.5 * (A + A.T))[-1]
    dt = 2.0 / np.sqrt(lam) if lam > 0 else np.inf
    return CriticalStep(dt, kt, np.einsum("ij,ij->i", Cr, Cr), contacts)


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
    return CriticalStep(dt, kt, np.asarray(Cf.multiply(Cf) @ (1.0 / mass)).ravel(), contacts)
