"""The progress bar of `transient run` (tqdm on stderr), and the notes a run prints meanwhile
(a subdivided step) without breaking it; the bars of a setup's long inner work (the Lanczos'
modes, the responses to the contact's directions), drawn where the command line asks
(`shown`): the library itself draws nothing, and a part reduced on a worker neither."""
import contextvars
import sys
from contextlib import contextmanager

_SHOWN = contextvars.ContextVar("transient_work_bars", default=False)


@contextmanager
def shown(on=True):
    """Within it (on true), work() draws its bars on standard error."""
    token = _SHOWN.set(bool(on))
    try:
        yield
    finally:
        _SHOWN.reset(token)


def showing():
    """Whether the lines and bars are drawn here (within shown(True))."""
    return _SHOWN.get()


def started(what):
    """A line on standard error as a long stage starts, within shown() only: the line its end
    prints (its seconds and peak memory) says when it is done."""
    if showing():
        print(f"{what} ...", file=sys.stderr, flush=True)


def work(what, total, unit):
    """A bar over `total` units of a stage's inner work, or one that shows nothing outside
    shown(): advance(to, total) moves it to `to` of a total that may grow (the Lanczos' wanted
    modes are known as its Ritz values converge); close() takes it off the terminal."""
    return _WorkBar(what, total, unit) if showing() else _NoWork()


class _NoWork:
    advance = close = staticmethod(lambda *args: None)


class _WorkBar:
    def __init__(self, what, total, unit):
        from tqdm import tqdm
        self.bar = tqdm(total=total, desc=what, unit=unit, file=sys.stderr, leave=False)

    def advance(self, to, total=None):
        if total is not None and total != self.bar.total:
            self.bar.total = total
        self.bar.update(to - self.bar.n)

    def close(self):
        self.bar.close()


def bar(progress, total, initial):
    """A bar of `total` steps from `initial`, or one that shows nothing (progress false)."""
    return _Bar(total, initial) if progress else _NoBar()


class _NoBar:
    update = close = restart = staticmethod(lambda *args: None)

    @staticmethod
    def write(line):
        print(f"note: {line}", file=sys.stderr)


class _Bar:
    """tqdm's bar, restarted on a new total when the step is subdivided."""

    def __init__(self, total, initial):
        from tqdm import tqdm
        self.bar = tqdm(total=total, initial=initial, unit="step", file=sys.stderr,
                        leave=False, smoothing=0.1)

    def update(self, n):
        self.bar.update(n)

    def restart(self, total, initial):
        self.bar.reset(total)
        self.bar.update(initial)

    def write(self, line):
        self.bar.write(f"note: {line}", file=sys.stderr)

    def close(self):
        self.bar.close()
