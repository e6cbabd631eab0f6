"""The cut's shapes of a part in pieces (reduce.pieces.cut_basis) alone: the part's task in
pieces pickled (bench_parts's DUMP) and reduced up to its cut, whose condensation S, Mh, loads
B and the pieces' couplings are saved; then cut_basis run on them in a fresh process (one
thread, as the client runs it), by this package and, with --base DIR (a `git worktree` of
another commit), by that one, A B A B with --repeat 2: its seconds, its peak resident memory
above its inputs, its shapes, and how far each basis's shapes lie from the other's span.

    python benchmarks/bench_cut.py CASE --part disc --pieces 8 [--reach 1.5] [--base DIR]
                              [--repeat N] [--keep FILE.npz | --inputs FILE.npz]
                              [--set key=value ...] [--markdown FILE] [--json FILE]

--keep saves the cut's inputs, --inputs takes them from such a file instead of the case.
"""
import argparse
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench_parts import DUMP, ROOT, child, parsed  # noqa: E402  (siblings)
from tables import publish, table  # noqa: E402

SAVE = """
import json, pickle, sys
import numpy as np
import transient
import transient.reduce.pieces as pieces
transient.configure()
with open(sys.argv[1], "rb") as f:
    task, _ = pickle.load(f)
if float(sys.argv[3]):
    pieces.PIECE_REACH = float(sys.argv[3])


class Saved(Exception):
    pass


def save(S, Mh, B, couplings, fmax, shift_hz):
    arrays = dict(S=S, Mh=Mh, B=B, fmax=fmax, shift_hz=shift_hz, part=task.name,
                  reach=pieces.PIECE_REACH)
    for i, (G, omega2, C) in enumerate(couplings):
        arrays.update({f"G{i}": G, f"omega2{i}": omega2, f"C{i}": C})
    np.savez(sys.argv[2], **arrays)
    print(sys.argv[2])
    raise Saved


pieces.cut_basis = save
try:
    task.run()
except Saved:
    pass
"""

RUN = """
import json, resource, sys, time
import numpy as np
import transient
from transient.reduce.pieces import cut_basis
transient.configure()
z = np.load(sys.argv[1])
S, Mh, B = z["S"], z["Mh"], z["B"]
couplings = [(z[f"G{i}"], z[f"omega2{i}"], z[f"C{i}"])
             for i in range(sum(k.startswith("omega2") for k in z.files))]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t0 = time.perf_counter()
with transient.blas.one_thread():
    V = cut_basis(S, Mh, B, couplings, float(z["fmax"]), float(z["shift_hz"]))
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
np.save(sys.argv[2], V)
print(json.dumps(dict(seconds=seconds, above=(peak - base) / 1e9, inputs=base / 1e9,
                      shapes=V.shape[1])))
"""


def sizes(inputs):
    """The cut's sizes in the saved inputs."""
    z = np.load(inputs)
    couplings = [k for k in z.files if k.startswith("omega2")]
    return dict(part=str(z["part"]), pieces=len(couplings), cut=len(z["S"]),
                modes=sum(len(z[k]) for k in couplings), reach=float(z["reach"]))


def outside(V, W, Mh):
    """The largest Mh-norm of W's columns, each of unit Mh-norm, outside V's span."""
    W = W / np.sqrt(np.einsum("ij,ij->j", W, Mh @ W))
    left = W - V @ np.linalg.solve(V.T @ (Mh @ V), V.T @ (Mh @ W))
    return float(np.sqrt(np.einsum("ij,ij->j", left, Mh @ left)).max(initial=0.0))


def markdown(rows, load):
    header = ["part", "pieces", "reach", "cut dofs", "pieces' modes", "package", "seconds",
              "above its inputs [GB]", "inputs [GB]", "shapes", "outside the other's span",
              "load"]
    return table(header, [[r["part"], r["pieces"], f"{r['reach']:g}", f"{r['cut']:,}",
                           f"{r['modes']:,}", r["package"], f"{r['seconds']:.1f}",
                           f"{r['above']:.2f}", f"{r['inputs']:.2f}", r["shapes"],
                           "-" if r["outside"] is None else f"{r['outside']:.1e}",
                           f"{load:.1f}"] for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--part", required=True)
    parser.add_argument("--pieces", type=int, default=4)
    parser.add_argument("--reach", type=float, default=0.0,
                        help="PIECE_REACH (0: the package's)")
    parser.add_argument("--base", help="another package's folder, run in turn")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--keep", help="save the cut's inputs to this .npz")
    parser.add_argument("--inputs", help="the cut's inputs saved by --keep")
    args, overrides = parsed(parser, argv)
    load0, rows = os.getloadavg()[0], []
    packages = [("HEAD", str(ROOT))] + ([("base", args.base)] if args.base else [])
    with tempfile.TemporaryDirectory() as folder:
        inputs = args.inputs or f"{folder}/cut.npz"
        if not args.inputs:
            child(DUMP, [folder, str(Path(args.case).resolve()), args.part, *overrides,
                         f"parts.{args.part}.pieces={args.pieces}"], str(ROOT), folder)
            child(SAVE, [f"{folder}/{args.part}.pkl", inputs, str(args.reach)], str(ROOT),
                  folder)
        if args.keep:
            shutil.copyfile(inputs, args.keep)
        cut = sizes(inputs)
        print(f"{cut['part']} in {cut['pieces']}: {cut['cut']:,} cut dofs, "
              f"{cut['modes']:,} pieces' modes", flush=True)
        for turn in range(args.repeat):
            for label, where in packages:
                row = json.loads(child(RUN, [inputs, f"{folder}/{label}.npy"],
                                       str(Path(where).resolve()), folder))
                rows.append(dict(cut, **row, package=label, outside=None))
                print(f"{label}: {row['seconds']:.1f} s, {row['above']:.2f} GB above its "
                      f"inputs, {row['shapes']} shapes", flush=True)
        if args.base:
            Mh = np.load(inputs)["Mh"]
            V, W = np.load(f"{folder}/HEAD.npy"), np.load(f"{folder}/base.npy")
            for r in rows:
                r["outside"] = outside(W, V, Mh) if r["package"] == "HEAD" else outside(V, W, Mh)
    publish(markdown(rows, 0.5 * (load0 + os.getloadavg()[0])), args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
