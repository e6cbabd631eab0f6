"""Where a piece's first stage goes (reduce.piece.Piece.condensed, the stage that sets the time
of a part reduced in pieces): the part's task in pieces pickled (bench_parts's DUMP), then one
piece assembled from its cells and its first stage run in a fresh process with every runtime
on one thread (MKL's too: transient.cluster.THREAD_ENV), as a worker runs it, its solves timed
and counted: the factorization, the fixed-cut modes (their Lanczos' solves among them), the
solves of the condensation and the loads' statics (one for each fixed-cut mode and each load
reaching the piece; with --by-solves, the condensation's reference, two for each cut dof the
piece touches), PARDISO's Schur complement (the condensation: none with --by-solves), and the
rest (the products with K and M beside the solves, the modes' orthonormalization).

    python benchmarks/bench_piece_stage.py CASE --part disc --pieces 4 [--piece 0]
                                   [--by-solves] [--mu 0.4] [--set key=value ...]
                                   [--markdown FILE] [--json FILE]
"""
import argparse
import os
import sys
import tempfile
from pathlib import Path

from bench_parts import DUMP, ROOT, child, parsed  # noqa: E402  (siblings)
from tables import publish, table  # noqa: E402
from transient.cluster import THREAD_ENV  # noqa: E402

RUN = """
import json, pickle, resource, sys, time
import numpy as np, scipy.sparse as sp
import transient
import transient.reduce.piece as piece_module
from transient.reduce.pieces import CUT, PIECE_REACH, _piece, _share
transient.configure()
with open(sys.argv[1], "rb") as f:
    task, _ = pickle.load(f)
k = int(sys.argv[2])
if sys.argv[3] == "solves":
    piece_module.schur_by_pardiso = lambda backend: False
cut = np.flatnonzero(task.piece_of == CUT)
I = np.flatnonzero(task.piece_of == k)
piece, G = _piece(task.name, task.cells.subset(task.cell_piece == k), I, cut,
                  _share(task.interface, I, False), task.shift_hz, task.backend)
seconds = {"solves": 0.0, "rhs": 0, "schur": 0.0}
solver = piece_module.Piece.solver


def timed_solver(self):
    t0 = time.perf_counter()
    solve, sigma = solver(self)
    seconds["factorization"] = time.perf_counter() - t0

    def counted(b):
        t0 = time.perf_counter()
        x = solve(b)
        seconds["solves"] += time.perf_counter() - t0
        seconds["rhs"] += b.shape[1] if b.ndim > 1 else 1
        return x
    counted.free = getattr(solve, "free", lambda: None)
    return counted, sigma


modes = piece_module.normal_modes


def timed_modes(*args, **kwargs):
    t0, s0, r0 = time.perf_counter(), seconds["solves"], seconds["rhs"]
    out = modes(*args, **kwargs)
    seconds["modes_seconds"] = time.perf_counter() - t0
    seconds["modes_solves"], seconds["modes_rhs"] = seconds["solves"] - s0, seconds["rhs"] - r0
    return out


schur = piece_module.schur_complement


def timed_schur(*args, **kwargs):
    t0 = time.perf_counter()
    out = schur(*args, **kwargs)
    seconds["schur"] = time.perf_counter() - t0
    return out


piece_module.Piece.solver = timed_solver
piece_module.normal_modes = timed_modes
piece_module.schur_complement = timed_schur
loads = sp.csr_matrix(task.loads)[I]
t0 = time.perf_counter()
with transient.blas.one_thread():
    A, small = piece.condensed(loads, PIECE_REACH * task.fmax)
total = time.perf_counter() - t0
rest = total - seconds["factorization"] - seconds["modes_seconds"] - seconds["schur"] - (
    seconds["solves"] - seconds["modes_solves"])
print(json.dumps(dict(part=task.name, piece=k, interior=len(I), touched=len(G), cut=len(cut),
                      modes=len(small[3]), seconds=total, **seconds, rest=rest,
                      peak=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9)))
"""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--part", default="disc")
    parser.add_argument("--pieces", type=int, default=4)
    parser.add_argument("--piece", type=int, default=0)
    parser.add_argument("--by-solves", action="store_true",
                        help="the condensation by solves (the reference), not by PARDISO's "
                             "Schur complement")
    args, overrides = parsed(parser, argv)
    overrides += [f"parts.{args.part}.pieces={args.pieces}", "limits.memory=1e3"]
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        child(DUMP, [folder, str(Path(args.case).resolve()), args.part, *overrides],
              str(ROOT), folder)
        import json
        # every runtime on one thread, as the embedded cluster's workers are
        row = json.loads(child(RUN, [f"{folder}/{args.part}.pkl", str(args.piece),
                                     "solves" if args.by_solves else "schur"],
                               str(ROOT), folder, THREAD_ENV))
    row.update(case=Path(args.case).name, pieces=args.pieces,
               condensation="solves" if args.by_solves else "schur",
               load=round(0.5 * (load0 + os.getloadavg()[0]), 1))
    cond = row["solves"] - row["modes_solves"]
    header = ["case", "condensation", "part", "pieces", "piece", "interior dofs",
              "cut dofs it touches (of)", "fixed-cut modes", "seconds", "factorization", "fixed-cut modes [s] (solves, "
              "right-hand sides)", "condensation and statics' solves [s] (right-hand sides)",
              "Schur complement [s]", "the rest [s]", "peak [GB]", "load"]
    cells = [row["case"], row["condensation"], row["part"], args.pieces, args.piece,
             f"{row['interior']:,}", f"{row['touched']:,} ({row['cut']:,})", row["modes"], f"{row['seconds']:.1f}",
             f"{row['factorization']:.1f}",
             f"{row['modes_seconds']:.1f} ({row['modes_solves']:.1f}, {row['modes_rhs']:,})",
             f"{cond:.1f} ({row['rhs'] - row['modes_rhs']:,})", f"{row['schur']:.1f}",
             f"{row['rest']:.1f}",
             f"{row['peak']:.2f}", row["load"]]
    publish(table(header, [cells]), args.markdown, args.json, [row])


if __name__ == "__main__":
    sys.exit(main())
