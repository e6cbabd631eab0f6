"""The steps of a run to t_end: whole steps of dt, and a last one shortened to end on t_end when
dt does not divide it; the rows on a grid of every `every` steps, the run's end a row of its
own when off that grid. And what a step subdivided changes: the step halves, `every` doubles
(the rows keep their times) and the exponential scheme's predictor its slope.

A shortened last step, rather than dt adjusted to divide t_end, keeps the step independent of
t_end: a run resumed to a longer t_end then goes on from its last whole step as a fresh run to
that t_end does, bit for bit. The last step's state is stored as the end row and never
checkpointed, so a resume drops it (io.history.History.open_for_resume).
"""
import math
from dataclasses import dataclass

from ..kernels.layout import FORCES_ROW

WHOLE = 1e-9      # t_end / dt within this of an integer (relative) is a whole number of steps:
#                   0.01 / 3.125e-6 is 3200 only to round-off, and the shipped cases must run
#                   the whole steps they ran before


@dataclass(frozen=True)
class Plan:
    t_end: float
    dt: float
    every: int
    steps: int           # whole steps of dt from t = 0
    partial: bool        # a last step shorter than dt, from steps * dt to t_end

    @classmethod
    def of(cls, t_end, dt, every):
        ratio = t_end / dt
        n = round(ratio)
        if abs(ratio - n) <= WHOLE * max(ratio, 1.0):
            return cls(t_end, dt, every, int(n), False)
        return cls(t_end, dt, every, int(math.floor(ratio)), True)

    @property
    def grid(self):
        """The last whole step on the row grid: the rows up to it are checkpointed with it."""
        return self.steps // self.every * self.every

    @property
    def end_row(self):
        """Whether the run's end is a row of its own, off the grid of the rows before it."""
        return self.partial or self.grid < self.steps

    def halved(self):
        """The plan at half the step, the rows at the same times (its step counts are twice
        this one's: t_end / dt doubles exactly)."""
        return Plan.of(self.t_end, self.dt / 2, 2 * self.every)


def retime(state, scheme, ratio):
    """Make the state's carried forces predict a step `ratio` times the last one's: the
    exponential scheme extrapolates the forces linearly from the previous step's start,
    F(t + dt) = 2 F(t) - F(t - dt), which assumes the same step (the other schemes carry no
    slope)."""
    if scheme == "exponential":
        f0, before = state.start, state.array[FORCES_ROW]
        before[:] = f0 - ratio * (f0 - before)
