"""A friction-coefficient campaign by `transient sweep` against the same variants run one by
one: `transient cea` and a short `transient run` for each mu, back to back, then the two sweeps
(kind cea, kind run) on the embedded cluster; wall times, their ratio, and the marginal cost of
a variant (its own seconds in sweep.json) against the shared stages' (their build's seconds).

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
    swept = timed(["sweep", args.case, "--param", grid, "--kind", "cea", "--workers",
                   str(args.workers), "--out", str(out / "cea"), "--json"])
    swept += timed(["sweep", args.case, "--param", grid, "--kind", "run", "--workers",
                    str(args.workers), "--set", f"solver.t_end={args.t_end}", "--out",
                    str(out / "run"), "--json"])
    rows = [r for kind in ("cea", "run")
            for r in json.loads((out / kind / "sweep.json").read_text())["rows"]]
    # the shared stages' builds, once per sweep (each row carries what its shared ones took)
    shared = sum(max((sum(r.get("shared_s", {}).values()) for r in json.loads(
        (out / kind / "sweep.json").read_text())["rows"]), default=0.0)
        for kind in ("cea", "run"))
    result = {"variants": args.count, "workers": args.workers, "alone_s": alone,
              "sweep_s": swept, "ratio": alone / swept,
              "variant_s_median": float(np.median([r["seconds"] for r in rows])),
              "shared_setup_s": shared, "load": [load0, os.getloadavg()[0]]}
    if args.json:
        print(json.dumps(result))
    else:
        print(f"{args.count} mu on {Path(args.case).name}, cea + a {args.t_end:g} s run each: "
              f"one by one {alone:.1f} s, two sweeps on {args.workers} workers {swept:.1f} s: "
              f"{result['ratio']:.2f}x; a variant's own median {result['variant_s_median']:.1f}"
              f" s (the marginal cost), the shared stages {shared:.1f} s (both sweeps); load "
              f"{load0:.2f} -> {result['load'][1]:.2f}")


if __name__ == "__main__":
    main()
