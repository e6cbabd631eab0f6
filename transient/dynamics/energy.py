"""The energy balance, written once: for the run between chunks and for a stored history.

E = kinetic + strain + contact - external_work + dissipated [J] is constant for an exact
integration. Its drift is measured against the largest energy the run holds or has exchanged:
the peak mechanical energy (kinetic + strain + contact), or the work put in or dissipated when
larger. E itself may stay near zero throughout (a structure started at rest and driven by
loads), where a ratio to it would only measure round-off; and friction on a sliding surface
passes far more energy than the vibration holds (pad_disc_squeal: about 0.5 J a millisecond
of sliding input against 27 mJ of vibration in its limit cycle; at mu = 0.4, 1 J against 0.15
J at most), so that the step's small error on that flow, summed over a second, would measure
against the vibration alone as a runaway.
"""
import numpy as np

from ..kernels.codes import ENERGY_TERMS

SIGNS = dict(zip(ENERGY_TERMS, (1.0, 1.0, 1.0, -1.0, 1.0)))
MECHANICAL = ("kinetic", "strain", "contact")


def total(energy):
    """E of rows (..., 5) in the ENERGY_TERMS column order."""
    return energy @ np.array([SIGNS[t] for t in ENERGY_TERMS])


def mechanical(energy):
    """|kinetic| + |strain| + |contact| of rows (..., 5)."""
    return np.abs(energy[..., :len(MECHANICAL)]).sum(axis=-1)


def scale(energy):
    """The drift's scale of rows (..., 5): the mechanical energy, or the external work or the
    dissipated energy when larger (in absolute value)."""
    flows = np.abs(energy[..., len(MECHANICAL):])
    return np.maximum(mechanical(energy), flows.max(axis=-1))


class Balance:
    """The drift of a run so far, updated chunk by chunk from its first row's energies: the
    largest deviation of E over the largest scale (module docstring), each a running maximum,
    so the figure does not depend on where the run was cut into chunks."""

    def __init__(self, initial):
        self.e0 = float(total(initial))
        self.peak = max(float(scale(initial)), 1e-300)
        self.deviation = 0.0

    @property
    def drift(self):
        return self.deviation / self.peak

    def update(self, energy):
        """Add the rows (r, 5) of a chunk; returns the drift so far."""
        if len(energy):
            self.peak = max(self.peak, float(scale(energy).max()))
            self.deviation = max(self.deviation, float(np.abs(total(energy) - self.e0).max()))
        return self.drift

    def first_over(self, energy, tolerance, judged=0):
        """(row, drift) of the first of the rows (r, 5) at which the drift so far exceeds
        tolerance, or None: where a run's balance failed, whatever chunks it was cut into.
        The rows before `judged` only add to the balance: at a run's start the energy held is
        still small, and the step's error on it a large share of it (a load setting a body at
        rest in motion)."""
        if not len(energy):
            return None
        peak = np.maximum(self.peak, np.maximum.accumulate(scale(energy)))
        deviation = np.maximum(self.deviation,
                               np.maximum.accumulate(np.abs(total(energy) - self.e0)))
        over = deviation / peak > tolerance
        over[:max(judged, 0)] = False
        if not over.any():
            return None
        row = int(np.argmax(over))
        return row, float(deviation[row] / peak[row])

    def copy(self):
        return Balance.restore(self.arrays())

    def arrays(self):
        """(E(0), peak, largest deviation), as a checkpoint keeps them."""
        return np.array([self.e0, self.peak, self.deviation])

    @classmethod
    def restore(cls, saved):
        balance = cls.__new__(cls)
        balance.e0, balance.peak, balance.deviation = (float(x) for x in saved)
        return balance


def drift(terms):
    """Drift of stored series: max_t |E(t) - E(0)| / max_t scale(t) (module docstring).

    Parameters
    ----------
    terms : dict
        Term name (one of ENERGY_TERMS) -> series (n,); missing terms count as 0.

    Returns
    -------
    float or None
        None without any term or row; 0 when no energy is ever stored.
    """
    series = {name: np.asarray(value, dtype=float) for name, value in terms.items()}
    if not series or len(next(iter(series.values()))) == 0:
        return None
    n = len(next(iter(series.values())))
    energy = np.stack([series.get(t, np.zeros(n)) for t in ENERGY_TERMS], axis=1)
    peak = scale(energy).max()
    e = total(energy)
    return float(np.max(np.abs(e - e[0])) / peak) if peak > 0 else 0.0
