"""A part reduced in pieces (parts.NAME.pieces) against the part reduced whole: each count's
task pickled, then reduced in a fresh process (one thread, as on a worker), or with
--workers N its pieces' stages on a LocalCluster of N one-thread workers; its seconds by
stage, the peak resident memory above the task loaded (and each worker's peak), and its modes
in the band (the part's reach over 1.5) against the part whole.

    python benchmarks/bench_pieces.py CASE --part disc [--pieces 2,4] [--reach 1,1.5]
                                 [--workers N] [--mu 0.4] [--set key=value ...]
                                 [--markdown FILE] [--json FILE]
"""
import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench_parts import DUMP, ROOT, child, parsed  # noqa: E402  (siblings)
from tables import publish, table  # noqa: E402

RUN = """
import json, pickle, resource, sys, time
import transient
import transient.reduce.pieces
transient.configure()
with open(sys.argv[1], "rb") as f:
    task, entries = pickle.load(f)
workers, reach = int(sys.argv[2]), float(sys.argv[3])
if reach:
    import transient.reduce.pieces
    transient.reduce.pieces.PIECE_REACH = reach
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
peaks = []
t0 = time.perf_counter()
if workers and getattr(task, "piece_of", None) is not None:
    from transient.cluster import client_for
    from transient.reduce.pieces import OnCluster

    def peak():
        import resource
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9
    client, cluster = client_for(None, workers)
    t0 = time.perf_counter()
    p = task.run(OnCluster(client))
    seconds = time.perf_counter() - t0
    peaks = sorted(client.run(peak).values())
    client.close()
    cluster.close()
else:
    p = task.run()
    seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
piece_of = getattr(task, "piece_of", None)
print(json.dumps(dict(part=task.name, ndof=task.n, entries=int(entries),
                      pieces=1 if piece_of is None else int(piece_of.max()) + 1,
                      cut=0 if piece_of is None else int((piece_of < 0).sum()),
                      columns=int(p.T.shape[1]), seconds=seconds, above=(peak - base) / 1e9,
                      workers=peaks, stages=p.seconds, mode_hz=p.mode_hz.tolist(),
                      band=task.fmax / 1.5, reach=transient.reduce.pieces.PIECE_REACH)))
"""


def markdown(rows, load):
    header = ["part", "pieces", "reach", "free dofs", "cut dofs", "basis columns", "workers",
              "seconds", "stages [s]", "above the task [GB]", "workers' peaks [GB]",
              "band modes", "largest error in the band", "load"]
    return table(header, [[r["part"], r["pieces"], f"{r['reach']:g}" if r["pieces"] > 1 else "-",
                           f"{r['ndof']:,}", f"{r['cut']:,}", r["columns"], r["n_workers"],
                           f"{r['seconds']:.1f}",
                           ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items()),
                           f"{r['above']:.2f}",
                           ", ".join(f"{p:.2f}" for p in r["workers"]) or "-",
                           r["band_modes"], f"{r['error']:.1e}", f"{load:.1f}"] for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--part", required=True)
    parser.add_argument("--pieces", default="2,4", help="comma-separated counts")
    parser.add_argument("--workers", type=int, default=0)
    parser.add_argument("--reach", default="0", help="comma-separated PIECE_REACH values for "
                        "each count (0: the package's)")
    args, overrides = parsed(parser, argv)
    load0, rows = os.getloadavg()[0], []
    case = str(Path(args.case).resolve())
    with tempfile.TemporaryDirectory() as folder:
        runs = [(1, 0.0)] + [(int(n), float(r)) for n in args.pieces.split(",")
                             for r in args.reach.split(",")]
        for count, reach in runs:
            sub = Path(folder) / str(count)
            if not sub.exists():
                sub.mkdir()
                child(DUMP, [str(sub), case, args.part, *overrides,
                             f"parts.{args.part}.pieces={count}"], str(ROOT), str(sub))
            workers = args.workers if count > 1 else 0
            row = json.loads(child(RUN, [f"{sub}/{args.part}.pkl", str(workers), str(reach)],
                                   str(ROOT), str(sub)))
            f = np.array(row.pop("mode_hz"))
            if count == 1:
                reference = f
            band = reference <= row["band"]
            n = min(len(f), len(reference))
            error = float(np.max(np.abs(f[:n][band[:n]] - reference[:n][band[:n]])
                                / reference[:n][band[:n]]))
            rows.append(dict(row, n_workers=workers, band_modes=int(band.sum()), error=error))
            print(f"{args.part} in {count} (reach {row['reach']:g}): {row['seconds']:.1f} s, "
                  f"{row['above']:.2f} GB above the task, workers {row['workers']}, band error "
                  f"{error:.1e}", flush=True)
    publish(markdown(rows, 0.5 * (load0 + os.getloadavg()[0])), args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
