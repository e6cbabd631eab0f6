"""The components path of the reduction against the assembled one on the same case: the
complex modes' analysis (`transient cea`'s) of each, alternated A B A B in child processes so
that a change of the machine's load shows in both; its seconds, the process's peak memory,
the reduced dofs, each part's stages, the contact-linearized frequencies below fmax of the
system the analysis solves (the sampled rules' candidates: each method samples its own points
for a run, which moves a run's K_lin, not the cea's), and the unstable modes of components
against assembled (frequency, and real part against 2% of its own size or 5 1/s: issue 45's
allowance). With --run T, each method's `transient run` to T (the case's own friction): its
sensors' RMS about their mean, components against assembled.

    python benchmarks/bench_components.py [CASE] [--mu 0.4] [--repeat 1] [--run T]
                                     [--set key=value ...] [--markdown FILE] [--json FILE]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from tables import publish, table  # noqa: E402  (a sibling in benchmarks/)

ROOT = Path(__file__).resolve().parent.parent
METHODS = ("assembled", "components")

CHILD = """
import json, resource, sys, time
import transient
transient.configure()
from transient.case.loading import load
import numpy as np
from transient.stability.stage import analysed_case, analysis_of
from transient.stages import prepare
t0 = time.perf_counter()
case = load(sys.argv[1], sys.argv[2:])
setup = prepare(analysed_case(case), analysis=True)
a = analysis_of(case, setup, setup.stages)
seconds = time.perf_counter() - t0
m = a.modes
linearized = np.sqrt(np.maximum(setup.system.omega2, 0.0)) / (2 * np.pi)
print(json.dumps({"seconds": seconds, "stages": a.stages, "reduced": a.reduced,
                  "ndof": a.ndof, "peak_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
                  / 1e6, "parts": a.meta.get("basis_timings", {}).get("part_stages"),
                  "real": m.eigenvalues.real.tolist(), "hz": m.frequency_hz.tolist(),
                  "fmax": a.fmax, "linearized_hz": linearized[linearized <= a.fmax].tolist()}))
"""


def analysed(case, overrides, method):
    args = [sys.executable, "-c", CHILD, str(case)] + list(overrides) + [
        f'solver.reduction.method="{method}"']
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"cea with {method} failed ({done.returncode}): {done.stderr.strip()}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_rms(case, overrides, method, t_end):
    """{sensor: RMS about its mean} of the case's `transient run` to t_end by method, and
    the run's energy drift."""
    import h5py
    with tempfile.TemporaryDirectory(prefix="bench_components_") as tmp:
        out = Path(tmp) / "run.h5"
        args = [sys.executable, "-m", "transient", "run", str(case), "-o", str(out),
                "--quiet", "--json", "--set", f"solver.t_end={t_end!r}", "--set",
                f'solver.reduction.method="{method}"']
        for o in overrides:
            args += ["--set", o]
        done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"run with {method} failed ({done.returncode}): {done.stderr.strip()}")
        with h5py.File(out) as f:
            rms = {name: float(np.std(f["sensors"][name][()])) for name in f["sensors"]}
    return rms, json.loads(done.stdout)["energy_drift"]


def runs_compared(case, overrides, t_end):
    """Rows (sensor, assembled RMS, components RMS, relative difference) and the drifts."""
    (a, da), (c, dc) = (run_rms(case, overrides, m, t_end) for m in METHODS)
    return [(name, a[name], c[name], abs(c[name] - a[name]) / a[name]) for name in a], da, dc


def linearized_error(ref, other):
    """The worst relative error of other's contact-linearized frequencies below fmax against
    ref's, mode by mode in ascending order (over the modes both hold)."""
    a, b = (np.array(r["linearized_hz"]) for r in (ref, other))
    n = min(len(a), len(b))
    return float(np.max(np.abs(b[:n] - a[:n]) / np.maximum(a[:n], 1e-300))) if n else 0.0


def compared(ref, other):
    """(unstable modes below fmax in either, worst frequency error, worst real error over
    2% of its own or 5 1/s) of other against ref, paired by stability.compare.pair_modes."""
    from transient.stability.compare import pair_modes
    from transient.stability.modes import ComplexModes
    pairs = pair_modes(*(ComplexModes(np.array(r["real"]) + 2j * np.pi * np.array(r["hz"]),
                                      None) for r in (ref, other)), ref["fmax"])
    return (len(pairs), max((abs(p.frequency_error) for p in pairs), default=0.0),
            max((abs(p.real_error) / max(0.02 * abs(p.real), 5.0) for p in pairs),
                default=0.0))


def markdown(case, mu, rows, load):
    header = ["case", "mu", "method", "dofs", "reduced", "cea [s]", "peak [GB]", "unstable",
              "linearized below fmax", "worst frequency error",
              "worst real error / (2% or 5 1/s)", "load"]
    return table(header, [[Path(case).name, mu, r["method"], r["ndof"], r["reduced"],
                           f"{r['seconds']:.1f}", f"{r['peak_gb']:.2f}", r["count"],
                           f"{len(r['linearized_hz'])} modes, {r['worst_k']:.1e}",
                           f"{r['worst_f']:.1e}", f"{r['worst_r']:.2f}", f"{load:.1f}"]
                          for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--mu", type=float, default=0.4)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--run", type=float, metavar="T")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--markdown")
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    from transient.case.loading import load
    pairs = load(args.case, args.set).contact
    # friction on the pairs that can slide: a tied (bilateral) pair holds, it does not rub
    overrides = args.set + [f"contact.{p}.friction.mu={args.mu}" for p, c in pairs.items()
                            if c.law.kind != "bilateral"]
    load0, rows = os.getloadavg()[0], []
    for _ in range(args.repeat):
        runs = {m: analysed(args.case, overrides, m) for m in METHODS}
        for m in METHODS:
            count, worst_f, worst_r = compared(runs["assembled"], runs[m])
            worst_k = linearized_error(runs["assembled"], runs[m])
            rows.append(dict(runs[m], method=m, count=count, worst_f=worst_f, worst_r=worst_r,
                             worst_k=worst_k))
            print(f"{m}: {runs[m]['seconds']:.1f} s, {runs[m]['reduced']} reduced dofs, peak "
                  f"{runs[m]['peak_gb']:.2f} GB, linearized {worst_k:.1e}, {count} unstable, "
                  f"frequency {worst_f:.1e}, "
                  f"real {worst_r:.2f} of allowed; parts {runs[m]['parts']}", flush=True)
    text = None
    if args.run:
        sensors, da, dc = runs_compared(args.case, args.set, args.run)
        text = "\n".join([f"\n`transient run` to {args.run:g} s, sensors' RMS about their mean "
                          f"(energy drift assembled {da:.1e}, components {dc:.1e}):\n",
                          "| sensor | assembled | components | difference |", "|---|---|---|---|"]
                         + [f"| {n} | {a:.4e} | {c:.4e} | {d:.1e} |" for n, a, c, d in sensors])
        print(text, flush=True)
    load = 0.5 * (load0 + os.getloadavg()[0])
    table = "\n".join(([markdown(args.case, args.mu, rows, load)] if rows else [])
                      + ([text] if text else []))
    publish(table, args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
