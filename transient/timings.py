"""The setup's stages timed: one home below the stages that run them (stages.prepare) and the
shared ones a campaign builds once (shared.build_shared)."""
import time

from . import progress
from .case.sizes import peak_rss_gb


class Stages(dict):
    """Stage -> seconds, the process's peak memory when each ended (`peaks`, GB), the check
    run between stages (a stop requested meanwhile) and report(name, seconds, peak GB) as each
    ends (None: nothing said)."""

    def __init__(self, check=None, report=None):
        super().__init__()
        self.check = check or (lambda: None)
        self.report = report
        self.peaks = {}

    def __setitem__(self, name, seconds):
        super().__setitem__(name, seconds)
        self.peaks[name] = peak_rss_gb()
        if self.report is not None:
            self.report(name, seconds, self.peaks[name])

    def timed(self, name, fn, *args):
        self.check()
        progress.started(f"stage {name}")
        t0 = time.perf_counter()
        out = fn(*args)
        self[name] = time.perf_counter() - t0
        return out
