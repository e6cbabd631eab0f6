"""What the basis' cutoff costs a run: `transient run` with the normal modes to factor x fmax
(solver.reduction.cutoff), the factors taken in turn (A B A B: the machine's drift falls on
both), the reduced dofs, the sampled points, the setup and the kernel's microseconds a step
read from each history. The gain is the CEA's across its band (studies/study_cea_band.py).

    python benchmarks/bench_cutoff.py [CASE] [--factors 1,2] [--repeats 2] [--set key=value ...]
                                 [--markdown FILE] [--json FILE]
"""
import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

from bench_long import run_timed
from tables import publish

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--factors", default="1,2")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--markdown")
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    from transient.case.loading import load
    from transient.io.stored import read_summary
    fmax = load(args.case, args.set).solver.reduction.fmax
    factors = [float(f) for f in args.factors.split(",")]
    runs = {f: [] for f in factors}
    loads = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory(prefix="bench_cutoff_") as work:
        for r in range(args.repeats):
            for f in factors:
                out = Path(work) / f"cutoff_{f}_{r}.h5"
                done = run_timed(args.case, args.set + [f"solver.reduction.cutoff={f * fmax}"],
                                 out)
                d = read_summary(out)
                steps = d["meta"]["steps_planned"]
                runs[f].append({"wall_s": done["wall_s"], "setup_s": d["timings"]["setup"],
                                "kernel_us": 1e6 * d["timings"]["kernel"] / steps,
                                "reduced_dofs": d["meta"]["reduced_dofs"],
                                "points": d["meta"]["n_points"], "status": d["status"]})
                loads.append(os.getloadavg()[0])
                print(f"cutoff {f:g} fmax: {runs[f][-1]}", file=sys.stderr, flush=True)
    rows = [{"case": Path(args.case).name, "cutoff": f"{f:g} fmax",
             "reduced_dofs": runs[f][0]["reduced_dofs"], "points": runs[f][0]["points"],
             "setup_s": statistics.median(x["setup_s"] for x in runs[f]),
             "kernel_us": statistics.median(x["kernel_us"] for x in runs[f]),
             "status": ",".join(sorted({x["status"] for x in runs[f]}))} for f in factors]
    lines = [f"Load {min(loads):.1f}-{max(loads):.1f}; medians of {args.repeats} runs each, "
             "taken in turn.", "",
             "| case | cutoff | reduced dofs | points | setup [s] | kernel [us a step] | status |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['case']} | {r['cutoff']} | {r['reduced_dofs']} | {r['points']} | "
              f"{r['setup_s']:.1f} | {r['kernel_us']:.1f} | {r['status']} |" for r in rows]
    publish("\n".join(lines) + "\n", args.markdown, args.json, rows)


if __name__ == "__main__":
    main()
