"""How well this machine's calibration estimates a setup's time before any setup of its kind
was timed here (`--dry-run`'s fallback, setuptimes.estimate from transient.calibration).

For each kind of setup asked, the calibration is made as the estimate makes it (a child
process, setuptimes.measure), then pad_disc is set up at each size asked (fractions of its
dofs, its divisions scaled) by the command line in a child process with a setup-time log of
the benchmark's own, its setup's seconds read from the line it writes. Each row: the
calibration's estimate range (its seconds scaled at setuptimes.GROWTH) against the setup's
seconds, and the power of the entries' ratio that would have hit it. `--rows` makes the
table again from the rows of earlier runs (their JSON), at the GROWTH of the code now.

    python benchmarks/bench_estimate.py [--sizes 1/8,1/4,1/2,1] [--kinds assembled/cea,...]
        [--repeat 1] [--rows A.json,B.json] [--markdown docs/performance.md] [--json rows.json]
"""
import argparse
import json
import math
import os
import sys
import tempfile
from fractions import Fraction
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_long import timed_child  # noqa: E402
from bench_scale import DISC, PAD, refined  # noqa: E402
from tables import publish, table  # noqa: E402

CASE = str(ROOT / "cases" / "pad_disc.toml")
# kind: the command and its settings on pad_disc (friction, so that a cea linearizes; a run
# stopped early: its setup is what is timed)
KINDS = {
    "assembled/cea": ("cea", ["contact.pad_disc.friction.mu=0.4",
                              'solver.reduction.method="assembled"']),
    "assembled/run": ("run", ["solver.t_end=1e-4", 'solver.reduction.method="assembled"']),
    "components/cea": ("cea", ["contact.pad_disc.friction.mu=0.4",
                               'solver.reduction.method="components"']),
    "modes": ("modes", []),
}


def load():
    return float(open("/proc/loadavg").read().split()[0])


def setup(kind, size, log, out):
    """The log's line of pad_disc's setup of a kind at a size (a fraction of its dofs)."""
    command, sets = KINDS[kind]
    log.unlink(missing_ok=True)
    sets = sets + [f"parts.disc.mesh.divisions={refined(DISC, size)}",
                   f"parts.pad.mesh.divisions={refined(PAD, size)}"]
    words = [command, CASE] + (["-o", str(out)] if command == "run" else [])
    timed_child(words + ["--json"], sets)
    (line,) = [json.loads(x) for x in log.read_text().splitlines()]
    assert line["path"] == kind, line
    return line


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1/8,1/4,1/2,1", help="fractions of pad_disc's dofs")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--rows", help="earlier runs' rows (JSON files, comma-separated)")
    parser.add_argument("--markdown")
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    from transient import setuptimes
    if args.rows:
        rows = [r for f in args.rows.split(",") for r in json.loads(Path(f).read_text())]
    else:
        rows = measured(args, setuptimes)
    for r in rows:
        cal, ratio = r["calibration"], r["entries"] / r["calibration"]["entries"]
        scaled = [cal["seconds"] * ratio ** p for p in setuptimes.GROWTH]
        r.update(low=min(scaled), high=max(scaled),
                 power=math.log(r["seconds"] / cal["seconds"]) / math.log(ratio))
    publish(markdown(rows, args), args.markdown, args.json, rows)


def measured(args, setuptimes):
    """A row a kind, size and repeat: the kind's calibration and pad_disc's setup."""
    sizes = [Fraction(s) for s in args.sizes.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "setups.jsonl"
        os.environ["TRANSIENT_SETUP_LOG"] = str(log)
        for repeat in range(args.repeat):
            for kind in args.kinds.split(","):
                before = load()
                cal = setuptimes.measure(kind)
                if cal is None:
                    sys.exit(f"the calibration of {kind} failed")
                for size in sizes:
                    line = setup(kind, size, log, Path(tmp) / "run.h5")
                    rows.append({"kind": kind, "size": str(size), "repeat": repeat,
                                 "entries": line["entries"], "seconds": line["seconds"],
                                 "calibration": cal, "load": (before, load())})
                    print(json.dumps(rows[-1]), flush=True)
    return rows


def markdown(rows, args):
    """A line saying where and how, then a row a setup."""
    import datetime
    import platform
    from transient.setuptimes import GROWTH
    loads = [x for r in rows for x in r["load"]]
    head = (f"{datetime.date.today()}, {platform.node()} ({os.cpu_count()} cores), load "
            f"{min(loads):.1f}-{max(loads):.1f}, GROWTH {GROWTH}: `python "
            f"benchmarks/bench_estimate.py " + (f"--rows {args.rows}" if args.rows else
                                                f"--sizes {args.sizes} --kinds {args.kinds} "
                                                f"--repeat {args.repeat}") + "`")
    cells = [[r["kind"], f"pad_disc x{r['size']}", f"{r['entries'] / 1e6:.2f} M",
              "-".join(f"{x:.1f}" for x in r["load"]),
              f"{r['calibration']['seconds']:.2f}", f"{r['seconds']:.1f}",
              f"{r['low']:.1f}-{r['high']:.1f}",
              f"{r['seconds'] / math.sqrt(r['low'] * r['high']):.2f}",
              "yes" if r["low"] <= r["seconds"] <= r["high"] else "no", f"{r['power']:.2f}"]
             for r in rows]
    return head + "\n\n" + table(
        ["kind", "model", "entries", "load", "calibration [s]", "setup [s]", "estimate [s]",
         "setup / middle", "in range", "power that hits it"], cells) + "\n"


if __name__ == "__main__":
    main()
