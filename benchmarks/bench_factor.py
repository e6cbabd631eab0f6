"""What the factorization stage of a case will take, before it is tried: the model is built,
then PARDISO's symbolic analysis (its ordering, phase 11) of K - sigma M on the free dofs
reports the factors' nonzeros and memory and the factorization's flops, without allocating the
factors. --factor also factorizes it and times the factorization and one solve.

    python benchmarks/bench_factor.py CASE [--set key=value ...] [--factor] [--json]

The model stage's peak resident memory is printed beside it: together they say whether the
setup's first two stages fit the machine (the reduction then adds a few n x (modes + static
shapes) arrays).
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def main(argv=None):
    from transient.case.loading import load
    from transient.case.sizes import peak_rss_gb
    from transient.model import build_model
    from transient.model.dofs import free_block
    from transient.solve.linsolve import factorize, pardiso_analysis
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--factor", action="store_true")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    case = load(args.case, args.set)
    t0 = time.perf_counter()
    model = build_model(case)
    sigma = -(2 * np.pi * case.solver.shift_hz) ** 2
    A = free_block(model.K, model.free) - sigma * free_block(model.M, model.free)
    row = {"case": args.case, "free_dofs": A.shape[0], "nnz": int(A.nnz),
           "model_s": time.perf_counter() - t0, "model_peak_rss_gb": peak_rss_gb()}
    t0 = time.perf_counter()
    row.update(pardiso_analysis(A, definite=sigma <= 0))
    row["analysis_s"] = time.perf_counter() - t0
    if args.factor:
        t0 = time.perf_counter()
        solve = factorize(A, "pardiso", definite=sigma <= 0)
        row["factorization_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        solve(np.ones(A.shape[0]))
        row["solve_s"] = time.perf_counter() - t0
        row["peak_rss_gb"] = peak_rss_gb()
    if args.json:
        print(json.dumps(row))
        return
    print(f"{args.case}: {row['free_dofs']} free dofs, {row['nnz']} nonzeros in K; model "
          f"{row['model_s']:.1f} s, peak RSS {row['model_peak_rss_gb']:.2f} GB")
    print(f"PARDISO analysis ({row['analysis_s']:.1f} s): {row['factor_nnz']:.4g} nonzeros in "
          f"the factors, {row['factor_gb']:.2f} GB for the factorization and solves, peak "
          f"{row['peak_gb']:.2f} GB, {row['gflop']:.4g} GFLOP")
    if args.factor:
        print(f"factorization {row['factorization_s']:.1f} s, one solve {row['solve_s']:.2f} s, "
              f"peak RSS {row['peak_rss_gb']:.2f} GB")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
