"""What the kernels update in place, under names: the integrated state and a chunk's output rows.

The kernels take the state as one (STATE_ROWS, n) array (q, v, a, the time, the forces at
the start of the previous step and of the next, which the exponential scheme carries between
chunks, and the friction force at the next step's start: the rows kernels.layout names) and
the outputs as five arrays.
"""
from dataclasses import dataclass

import numpy as np

from ..kernels.codes import ENERGY_TERMS
from ..kernels.layout import (A_ROW, ACC_SLOTS, FORCES_ROW, Q_ROW, START_ROW, STATE_ROWS,
                              TIME_ROW, V_ROW)


class State:
    """The state of a system between chunks: displacement, velocity, acceleration and time,
    the forces at the start of the previous and of the next step, the external work and
    dissipated energy so far (and a damping power carried by explicit_full), and the smallest
    gap each contact point has reached (the critical step is rechecked against it)."""

    def __init__(self, array, acc, gmin):
        self.array = array          # (7, n), the kernels' layout
        self.acc = acc              # (4,) external work, dissipated energy [J], a damping
        #                             power and the sliding's input power [W] carried
        self.gmin = gmin            # (m,) [m]

    @classmethod
    def zeros(cls, n, m):
        return cls(np.zeros((STATE_ROWS, n)), np.zeros(ACC_SLOTS), np.zeros(m))

    q = property(lambda self: self.array[Q_ROW])
    v = property(lambda self: self.array[V_ROW])
    a = property(lambda self: self.array[A_ROW])
    forces = property(lambda self: self.array[FORCES_ROW])
    start = property(lambda self: self.array[START_ROW])

    @property
    def time(self):
        return float(self.array[TIME_ROW, 0])

    @time.setter
    def time(self, t):
        self.array[TIME_ROW, 0] = t

    def copy(self):
        return State(self.array.copy(), self.acc.copy(), self.gmin.copy())

    def arrays(self):
        """Name -> array, as a checkpoint stores them (bit for bit)."""
        return {"state": self.array, "acc": self.acc, "gmin": self.gmin}


@dataclass(frozen=True)
class Rows:
    """Output rows of a chunk: time [s], sensors (then the state itself when the field is
    stored), gaps [m] and pressures [Pa] of the contact points if stored, and their slip
    velocities along and across the sliding [m/s] if stored with friction, energy terms
    [J]."""
    time: np.ndarray         # (r,)
    sensors: np.ndarray      # (r, s)
    gap: np.ndarray          # (r, m) or (r, 0)
    pressure: np.ndarray
    slip: np.ndarray         # (r, 2, m) or (r, 2, 0)
    energy: np.ndarray       # (r, 5), columns ENERGY_TERMS

    @classmethod
    def empty(cls, rows, n_sensors, n_contact, n_slip=0):
        return cls(np.zeros(rows), np.zeros((rows, n_sensors)), np.zeros((rows, n_contact)),
                   np.zeros((rows, n_contact)), np.zeros((rows, 2, n_slip)),
                   np.zeros((rows, len(ENERGY_TERMS))))

    @classmethod
    def of(cls, system, rows, store_contact):
        """The rows of a system's outputs: contact ones if stored, slips with friction."""
        m = system.n_points if store_contact else 0
        slips = m if system.contacts.friction is not None else 0
        return cls.empty(rows, system.sensors.shape[0], m, slips)

    @property
    def arrays(self):
        """The outputs in the kernels' order."""
        return self.time, self.sensors, self.gap, self.pressure, self.slip, self.energy

    def head(self, n):
        """The first n rows."""
        return Rows(*(x[:n] for x in self.arrays))

    def finite_rows(self, n):
        """How many of the first n rows are finite in every output."""
        if n <= 0:
            return 0
        bad = np.zeros(n, bool)
        for x in self.arrays:
            bad |= ~np.isfinite(x[:n].reshape(n, -1)).all(axis=1)
        return int(np.argmax(bad)) if bad.any() else n
