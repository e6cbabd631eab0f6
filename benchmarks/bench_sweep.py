"""A friction-coefficient campaign by `transient sweep` against the same variants run one by
one: `transient cea` and a short `transient run` for each mu, back to back, then the two sweeps
(kind cea, kind run) and the one sweep of both kinds on the embedded cluster; wall times, their
ratios, and the marginal cost of a variant (its own seconds in sweep.json) against the shared
stages' (their build's seconds).

--basis-mu X gives every variant contact.pad_disc.friction.basis_mu = X (the reduced basis made
at that friction, shared by the sweep's variants: reduce.reference); the one-by-one side then
runs those same variants, and --plain-alone also times the variants without it (each with its
own basis, the default method: the conservative baseline, since a variant alone at basis_mu
makes the reference's preload and basis besides its own preload). --no-two skips the two
separate sweeps.

    python benchmarks/bench_sweep.py [--case cases/pad_disc.toml] [--count 20] [--t-end 1e-3]
        [--workers 2] [--basis-mu X] [--plain-alone] [--no-two] [--out /tmp/bench_sweep]
        [--json]

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
BASIS = "contact.pad_disc.friction.basis_mu"


def timed(args):
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "transient"] + args, capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    if done.returncode not in (0, 3):
        sys.exit(f"failed: {' '.join(args)}\n{done.stderr}")
    return time.perf_counter() - t0


def one_by_one(case, mus, t_end, out, common):
    """Seconds of `transient cea` and a short `transient run` of each mu, back to back."""
    total = 0.0
    for mu in mus:
        s = ["--set", f"{KEY}={mu}"] + common
        total += timed(["cea", case, "--json"] + s)
        total += timed(["run", case, "-o", str(out / f"alone_{mu}.h5"), "--quiet",
                        "--set", f"solver.t_end={t_end}"] + s)
    return total


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--t-end", type=float, default=1e-3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--basis-mu", type=float, default=0.0)
    parser.add_argument("--plain-alone", action="store_true")
    parser.add_argument("--no-two", action="store_true")
    parser.add_argument("--out", default="/tmp/bench_sweep")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    mus = [float(f"{x:.15g}") for x in np.linspace(0.0, 0.6, args.count)]
    common = ["--set", f"{BASIS}={args.basis_mu!r}"] if args.basis_mu else []
    load0 = os.getloadavg()[0]
    alone = one_by_one(args.case, mus, args.t_end, out, common)
    plain = (one_by_one(args.case, mus, args.t_end, out, [])
             if args.plain_alone and common else None)
    grid = f"{KEY}=0:0.6:{args.count}"
    run_end = ["--set", f"solver.t_end={args.t_end}"]

    def swept(kind, more=()):
        return timed(["sweep", args.case, "--param", grid, "--kind", kind, "--workers",
                      str(args.workers), "--out", str(out / kind), "--json", *common, *more])
    kinds = ("both",) if args.no_two else ("cea", "run", "both")
    two = None if args.no_two else swept("cea") + swept("run", run_end)
    one = swept("both", run_end)

    def rows(kind):
        return json.loads((out / kind / "sweep.json").read_text())["rows"]

    def shared(kind):
        # the shared stages' builds, once per sweep (each row carries what they took)
        return max((sum(r.get("shared_s", {}).values()) for r in rows(kind)), default=0.0)
    result = {"variants": args.count, "workers": args.workers, "basis_mu": args.basis_mu,
              "alone_s": alone, "plain_alone_s": plain, "two_sweeps_s": two,
              "ratio_two": None if two is None else alone / two, "both_sweep_s": one,
              "ratio_both": alone / one,
              "ratio_both_plain": None if plain is None else plain / one,
              "variant_s_median": {k: float(np.median([r["seconds"] for r in rows(k)]))
                                   for k in kinds},
              "shared_setup_s": {k: shared(k) for k in kinds},
              "load": [load0, os.getloadavg()[0]]}
    if args.json:
        print(json.dumps(result))
        return
    med, sh = result["variant_s_median"], result["shared_setup_s"]
    basis = f" at basis_mu {args.basis_mu:g}" if args.basis_mu else ""
    print(f"{args.count} mu on {Path(args.case).name}{basis}, cea + a {args.t_end:g} s run "
          f"each: one by one {alone:.1f} s" + (
              "" if plain is None else f" ({plain:.1f} s without basis_mu, each its own "
              "basis)") + f"; on {args.workers} workers" + (
              "" if two is None else f" two sweeps (cea, run) {two:.1f} s, "
              f"{result['ratio_two']:.2f}x;") + f" one sweep of both kinds {one:.1f} s, "
          f"{result['ratio_both']:.2f}x" + (
              "" if plain is None else f" ({result['ratio_both_plain']:.2f}x against the "
              "variants without basis_mu)") + ". A variant's own median (the marginal cost): "
          + ", ".join(f"{k} {med[k]:.1f} s" for k in kinds)
          + f"; the shared stages {sh['both']:.1f} s a sweep; load {load0:.2f} -> "
          f"{result['load'][1]:.2f}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
