"""A friction-coefficient campaign by `transient sweep` against the same variants run one by
one: `transient cea` and a short `transient run` for each mu, back to back, then the two sweeps
(kind cea, kind run) and the one sweep of both kinds on the embedded cluster; wall times, their
ratios, and the marginal cost of a variant (its own seconds in sweep.json) against the shared
stages' (their build's seconds).

    python tools/bench_sweep.py [--case cases/pad_disc.toml] [--count 20] [--t-end 1e-3]
        [--workers 2] [--out /tmp/bench_sweep] [--json]

The load of the machine is printed before and after: a shared machine slows both sides.
"""
import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
KEY = "contact.pad_disc.friction.mu"


def timed(args):
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "transient"] + args, capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    if done.returncode not in (0, 3):
        sys.exit(f"failed: {' '.join(args)}\n{done.stderr}")
    return time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--t-end", type=float, default=1e-3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="/tmp/bench_sweep")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    mus = [float(f"{x:.15g}") for x in np.linspace(0.0, 0.6, args.count)]
    load0 = os.getloadavg()[0]
    alone = 0.0
    for mu in mus:
        s = ["--set", f"{KEY}={mu}"]
        alone += timed(["cea", args.case, "--json"] + s)
        alone += timed(["run", args.case, "-o", str(out / f"alone_{mu}.h5"), "--quiet",
                        "--set", f"solver.t_end={args.t_end}"] + s)
    grid = f"{KEY}=0:0.6:{args.count}"
    run_end = ["--set", f"solver.t_end={args.t_end}"]

    def swept(kind, more=()):
        return timed(["sweep", args.case, "--param", grid, "--kind", kind, "--workers",
                      str(args.workers), "--out", str(out / kind), "--json", *more])
    two = swept("cea") + swept("run", run_end)
    one = swept("both", run_end)

    def rows(kind):
        return json.loads((out / kind / "sweep.json").read_text())["rows"]

    def shared(kind):
        # the shared stages' builds, once per sweep (each row carries what they took)
        return max((sum(r.get("shared_s", {}).values()) for r in rows(kind)), default=0.0)
    result = {"variants": args.count, "workers": args.workers, "alone_s": alone,
              "two_sweeps_s": two, "ratio_two": alone / two, "both_sweep_s": one,
              "ratio_both": alone / one,
              "variant_s_median": {k: float(np.median([r["seconds"] for r in rows(k)]))
                                   for k in ("cea", "run", "both")},
              "shared_setup_s": {k: shared(k) for k in ("cea", "run", "both")},
              "load": [load0, os.getloadavg()[0]]}
    if args.json:
        print(json.dumps(result))
    else:
        med, sh = result["variant_s_median"], result["shared_setup_s"]
        print(f"{args.count} mu on {Path(args.case).name}, cea + a {args.t_end:g} s run each: "
              f"one by one {alone:.1f} s; on {args.workers} workers two sweeps (cea, run) "
              f"{two:.1f} s, {result['ratio_two']:.2f}x; one sweep of both kinds {one:.1f} s, "
              f"{result['ratio_both']:.2f}x. A variant's own median (the marginal cost): cea "
              f"{med['cea']:.1f} s, run {med['run']:.1f} s, both {med['both']:.1f} s; the "
              f"shared stages {sh['both']:.1f} s a sweep; load {load0:.2f} -> "
              f"{result['load'][1]:.2f}")


if __name__ == "__main__":
    main()
