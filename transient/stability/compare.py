"""Two analyses' complex modes set side by side, mode by mode: a reduced CEA against the full
model's (its reference), or one basis against another.

Each mode of the reference in the band is paired with the nearest eigenvalue of the other; its
real part is judged against its own size (a weak mode 40% off is wrong however small it is
beside the strongest), with an absolute floor for the modes near neutral, whose real part is
round-off and the regularized friction law's slope. A mode unstable in one analysis must be
unstable in the other: a pair that differs only inside the floor is not counted (a neutral
mode's sign is not an answer either analysis can give).
"""
from dataclasses import dataclass

import numpy as np

REAL_RTOL = 0.05        # of the mode's own real part
REAL_FLOOR = 5.0        # [1/s]
FREQUENCY_RTOL = 1e-3


@dataclass(frozen=True)
class ModePair:
    frequency_hz: float      # the reference's
    real: float              # the reference's [1/s]
    other_frequency_hz: float
    other_real: float
    unstable: bool           # in the reference
    other_unstable: bool

    @property
    def frequency_error(self):
        return self.other_frequency_hz / self.frequency_hz - 1.0

    @property
    def real_error(self):
        return self.other_real - self.real

    def within(self, rtol=REAL_RTOL, floor=REAL_FLOOR, frequency_rtol=FREQUENCY_RTOL):
        """Frequency within frequency_rtol, the real part within rtol of its own size or the
        floor, and the same stability unless both real parts lie inside the floor."""
        real_ok = abs(self.real_error) <= max(rtol * abs(self.real), floor)
        neutral = abs(self.real) <= floor and abs(self.other_real) <= floor
        return (abs(self.frequency_error) <= frequency_rtol and real_ok
                and (self.unstable == self.other_unstable or neutral))


def pair_modes(reference, other, fmax):
    """A ModePair for every mode of reference (ComplexModes) up to fmax [Hz] that is unstable
    in either analysis, each with its nearest eigenvalue of other; then every unstable mode of
    other whose nearest reference mode is stable (so a spurious instability is counted once
    too). Ordered by the reference's frequency."""
    ref_lam, lam = reference.eigenvalues, other.eigenvalues
    pairs, seen = [], set()
    for j in np.flatnonzero(reference.frequency_hz <= fmax):
        i = int(np.argmin(np.abs(lam - ref_lam[j])))
        if reference.unstable[j] or other.unstable[i]:
            pairs.append(_pair(reference, j, other, i))
            seen.add(i)
    for i in np.flatnonzero(other.unstable & (other.frequency_hz <= fmax)):
        if int(i) not in seen:
            j = int(np.argmin(np.abs(ref_lam - lam[i])))
            pairs.append(_pair(reference, j, other, i))
    return sorted(pairs, key=lambda p: p.frequency_hz)


def _pair(reference, j, other, i):
    return ModePair(float(reference.frequency_hz[j]), float(reference.real[j]),
                    float(other.frequency_hz[i]), float(other.real[i]),
                    bool(reference.unstable[j]), bool(other.unstable[i]))
