"""The progress bar of `transient run` (tqdm on stderr), and the notes a run prints meanwhile
(a subdivided step) without breaking it."""
import sys


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
