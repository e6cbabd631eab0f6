"""How the setup scales with the mesh: cases/pad_disc.toml with both meshes refined by a factor
in each direction (the contact interface refined with them), each run a child process
(`transient run`, as benchmarks/bench_long.py runs it) to a short t_end, smallest first.

For each size: dofs, setup seconds and its stages, peak RSS, reduced dofs and contact points;
then the exponents of setup time and peak memory against dofs, fitted over the range (the
issue's targets: memory no faster than n^1.1, setup no faster than n^1.3, over 4x in dofs).

    python benchmarks/bench_scale.py [--dofs-factors 1,2,4] [--t-end 1e-3] [--set KEY=VALUE] [--json]

A dofs factor f refines each division count by f^(1/3) (rounded; the thickness counts too), so
the dofs grow by about f.
"""
import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_long import run  # noqa: E402

DISC = [12, 144, 2]          # cases/pad_disc.toml's divisions
PAD = [9, 22, 2, 1]


def refined(divisions, factor):
    s = factor ** (1.0 / 3.0)
    return [max(1, int(round(d * s))) for d in divisions]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dofs-factors", default="1,2,4")
    parser.add_argument("--t-end", type=float, default=1e-3)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    from transient.io.reading import summary
    case = ROOT / "cases" / "pad_disc.toml"
    rows = []
    for f in sorted(float(x) for x in args.dofs_factors.split(",")):
        disc, pad = refined(DISC, f), refined(PAD, f)
        sets = [f"parts.disc.mesh.divisions={disc}", f"parts.pad.mesh.divisions={pad}",
                f"solver.t_end={args.t_end}"] + args.set
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "run.h5"
            wall, peak = run(case, sets, out)
            info = summary(out)
        meta = info["meta"]
        row = {"factor": f, "disc": disc, "pad": pad, "free_dofs": meta.get("free_dofs"),
               "wall_s": wall, "setup_s": info["timings"]["setup"], "peak_rss_gb": peak / 1e9,
               "stages": meta["stages"], "reduced_dofs": meta.get("reduced_dofs"),
               "contact_points": meta.get("n_points"), "status": info["status"]}
        rows.append(row)
        if not args.json:
            print(f"x{f:g}: disc {disc}, pad {pad}: {row['free_dofs']} free dofs, setup "
                  f"{row['setup_s']:.1f} s, peak {row['peak_rss_gb']:.2f} GB, "
                  f"{row['reduced_dofs']} reduced dofs, {row['contact_points']} points; "
                  + ", ".join(f"{k} {v:.1f}" for k, v in row["stages"].items()), flush=True)
    fit = {}
    if len(rows) > 1:
        n = np.log([r["free_dofs"] for r in rows])
        for key in ("setup_s", "peak_rss_gb"):
            fit[key] = float(np.polyfit(n, np.log([r[key] for r in rows]), 1)[0])
        span = rows[-1]["free_dofs"] / rows[0]["free_dofs"]
        fit["dofs_span"] = span
    if args.json:
        print(json.dumps({"rows": rows, "exponents": fit}))
    elif fit:
        print(f"over {fit['dofs_span']:.2f}x in dofs: setup time ~ n^{fit['setup_s']:.2f}, "
              f"peak memory ~ n^{fit['peak_rss_gb']:.2f}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
