"""A countermeasure campaign on the pads' lining, the components path against the assembled
one: N lining moduli, the complex modes of each.

- assembled, back to back: `transient cea` of each variant in one process after the other
  (--assembled K: the first K variants only, the whole projected from their mean: the
  variants differ in a modulus, not in size);
- assembled, swept: `transient sweep --kind cea` on W workers (--assembled-sweep);
- components, swept through a parts cache: `transient sweep --kind cea --cache DIR` on W
  workers, each variant reducing the parts the lining changes and reading the others back.

Each is timed from a child process (start-up included), in that order; the cache starts
empty. Each variant's unstable modes are compared between the assembled path and the
components sweep, where both have it.

    python benchmarks/bench_parts_campaign.py [CASE] [--moduli 3e9:8e9:10] [--material lining]
                                         [--mu 0.4] [--workers 2] [--assembled K]
                                         [--assembled-sweep] [--set key=value ...]
                                         [--markdown FILE]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COMPONENTS = 'solver.reduction.method="components"'


def transient(args):
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "transient"] + args, cwd=ROOT,
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"transient {args[0]} failed ({done.returncode}): {done.stderr.strip()}")
    return time.perf_counter() - t0, done.stdout


def sets(overrides):
    return [a for o in overrides for a in ("--set", o)]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "brake_corner.toml"))
    parser.add_argument("--moduli", default="3e9:8e9:10")
    parser.add_argument("--material", default="lining")
    parser.add_argument("--mu", type=float, default=0.4)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--assembled", type=int, default=None, metavar="K")
    parser.add_argument("--assembled-sweep", action="store_true")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--markdown")
    args = parser.parse_args(argv)
    import numpy as np
    from tables import publish
    from transient.case.loading import load
    from transient.stability.compare import pair_modes
    from transient.stability.modes import ComplexModes
    start, stop, count = args.moduli.split(":")
    moduli = np.linspace(float(start), float(stop), int(count))
    pairs = [n for n, c in load(args.case, args.set).contact.items()
             if c.law.kind != "bilateral"]
    overrides = args.set + [f"contact.{p}.friction.mu={args.mu}" for p in pairs]
    key = f"materials.{args.material}.E"
    work = Path(tempfile.mkdtemp(prefix="bench_parts_"))
    load0, rows, assembled = os.getloadavg()[0], {}, {}
    k = len(moduli) if args.assembled is None else min(args.assembled, len(moduli))
    try:
        t0 = time.perf_counter()
        for E in moduli[:k]:
            _, out = transient(["cea", args.case, "--json"] + sets(overrides + [f"{key}={E}"]))
            assembled[float(E)] = json.loads(out)["modes"]
        name = "assembled, back to back" + ("" if k == len(moduli) else
                                            f" (projected from the first {k})")
        rows[name] = (time.perf_counter() - t0) * len(moduli) / k
        grid = [f"{key}={json.dumps([float(E) for E in moduli])}"]
        if args.assembled_sweep:
            rows[f"assembled, sweep on {args.workers} workers"], _ = transient(
                ["sweep", args.case, "--kind", "cea", "--out", str(work / "assembled"),
                 "--workers", str(args.workers), "--param", grid[0]] + sets(overrides))
        rows[f"components, sweep on {args.workers} workers, parts cache"], _ = transient(
            ["sweep", args.case, "--kind", "cea", "--out", str(work / "components"),
             "--workers", str(args.workers), "--cache", str(work / "parts"),
             "--param", grid[0]] + sets(overrides + [COMPONENTS]))
        parts = len(list((work / "parts").glob("part-*.npz")))
        # each variant's unstable modes, assembled against components (the same variant)
        compared = []
        for row in json.loads((work / "components" / "sweep.json").read_text())["rows"]:
            E = float(row[key])
            if E in assembled:
                compared.append((row["variant"], assembled[E], json.loads(
                    (work / "components" / row["output"]).read_text())["modes"],
                    row.get("parts_reduced")))
    finally:
        load1 = os.getloadavg()[0]
        shutil.rmtree(work, ignore_errors=True)
    base = next(iter(rows.values()))
    lines = [f"{len(moduli)} moduli of {key} on {Path(args.case).name} (mu {args.mu}), load "
             f"{load0:.1f}-{load1:.1f}; {parts} parts reduced in all", "",
             "| path | seconds | against back to back |", "|---|---|---|"]
    lines += [f"| {name} | {s:.0f} | {base / s:.2f}x |" for name, s in rows.items()]
    for name, ref, mine, reduced in compared:
        # stability.compare.pair_modes: every mode unstable in either, with its nearest
        pairs = pair_modes(*(ComplexModes(np.array([m["real"] + 2j * np.pi * m["frequency_hz"]
                                                    for m in modes]), None)
                             for modes in (ref, mine)), np.inf)
        lines.append(f"- {name} (parts reduced: {', '.join(reduced or []) or 'none'}): "
                     f"{sum(p.unstable for p in pairs)} unstable assembled, "
                     f"{sum(p.other_unstable for p in pairs)} components; " + ", ".join(
                         f"{p.frequency_hz:.0f} Hz {p.real:.2f} -> {p.other_real:.2f} 1/s"
                         for p in pairs))
    publish("\n".join(lines), args.markdown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
