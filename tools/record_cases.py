"""Record, then compare, the histories of every shipped case: the guard of a change that must
not change results (a redesign, a speed-up).

`record` runs each case of cases/ through `transient run` in a child process (so the package
imported is the one on the child's path: set PYTHONPATH to record another checkout) and keeps
every series of its history (sensors, energy terms, contact gaps and pressures if stored) in
one .npz per case. `compare` reads two such directories and prints, per case and series, the
largest difference relative to the series' peak, and whether the two are bit for bit equal.
The long case runs for a short time only (--long-t-end). `--set` passes overrides to every
case: a load scaled by 1 + 2e-16 shows how far round-off alone moves a case's history.

    python tools/record_cases.py record DIR [--long-t-end 0.02] [--cases a,b] [--set K=V ...]
    python tools/record_cases.py compare DIR_A DIR_B [--json]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LONG = "pad_disc_long"


def record(out, long_t_end, names, overrides=()):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cases = sorted((ROOT / "cases").glob("*.toml"))
    # children run in an empty directory: from a checkout, `python -m` would import the
    # package of the working directory before the PYTHONPATH one
    here = subprocess.run([sys.executable, "-c", "import transient; print(transient.__file__)"],
                          capture_output=True, text=True, env=os.environ.copy(),
                          cwd=tempfile.gettempdir(), check=True).stdout.strip()
    print(f"recording the package at {Path(here).parent}", flush=True)
    for case in cases:
        if names and case.stem not in names:
            continue
        sets = ["--set", f"solver.t_end={long_t_end!r}"] if case.stem == LONG else []
        sets += [a for o in overrides for a in ("--set", o)]
        with tempfile.TemporaryDirectory() as tmp:
            h5 = Path(tmp) / "run.h5"
            done = subprocess.run([sys.executable, "-m", "transient", "run", str(case), "-o",
                                   str(h5), "--quiet", *sets], capture_output=True, text=True,
                                  env=os.environ.copy(), cwd=tmp)
            if done.returncode != 0:
                sys.exit(f"{case.name}: transient run failed ({done.returncode}): "
                         f"{done.stderr.strip()}")
            series = {}
            with h5py.File(h5, "r") as f:
                rows = int(f.attrs["rows"])

                def visit(name, obj):
                    if isinstance(obj, h5py.Dataset) and not name.startswith(
                            ("checkpoint", "geometry/")):
                        series[name] = obj[:rows]
                f.visititems(visit)
        np.savez(out / f"{case.stem}.npz", **{k.replace("/", "|"): v for k, v in series.items()})
        print(f"{case.stem}: {rows} rows, {len(series)} series", flush=True)


def compare(a, b):
    """{case: {series: (max |a - b| / max |a|, bit for bit)}} over the cases in both."""
    out = {}
    for pa in sorted(Path(a).glob("*.npz")):
        pb = Path(b) / pa.name
        if not pb.exists():
            continue
        xa, xb = np.load(pa), np.load(pb)
        rows = {}
        for key in sorted(set(xa.files) | set(xb.files)):
            name = key.replace("|", "/")
            if key not in xa.files or key not in xb.files or xa[key].shape != xb[key].shape:
                rows[name] = (float("inf"), False)
                continue
            u, v = xa[key], xb[key]
            peak = max(float(np.abs(u).max()) if u.size else 0.0, 1e-300)
            diff = float(np.abs(u - v).max()) if u.size else 0.0
            rows[name] = (diff / peak, bool(np.array_equal(u, v)))
        out[pa.stem] = rows
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("record")
    p.add_argument("out")
    p.add_argument("--long-t-end", type=float, default=0.02)
    p.add_argument("--cases", default="")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    p = sub.add_parser("compare")
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.command == "record":
        record(args.out, args.long_t_end, [n for n in args.cases.split(",") if n], args.set)
        return
    result = compare(args.a, args.b)
    if args.json:
        print(json.dumps(result))
        return
    for case, rows in result.items():
        worst = max((r for r, _ in rows.values()), default=0.0)
        exact = all(e for _, e in rows.values())
        print(f"{case}: {'bit for bit' if exact else f'max relative difference {worst:.3g}'}")
        for name, (rel, same) in rows.items():
            if not same:
                print(f"  {name}: {rel:.3g}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
