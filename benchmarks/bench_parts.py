"""Each part's reduction alone, as a worker of the components path runs it: the case's part
tasks pickled, then each reduced in a fresh process from its pickle (one thread, as on a
worker), its seconds by stage and its peak resident memory above the task loaded (its K and M
assembled from its cells included, as on a worker), against the part's element-matrix entries
(the unit case/sizes.py bounds a part by). With --base DIR, the
same pickles also reduced by the package at DIR (a `git worktree` of another commit) in turn,
A B A B, so that a change of the machine's load shows in both.

    python benchmarks/bench_parts.py CASE [--mu 0.4] [--parts disc,pad_in] [--base DIR]
                                [--set key=value ...] [--markdown FILE] [--json FILE]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from tables import publish  # noqa: E402  (a sibling in benchmarks/)

ROOT = Path(__file__).resolve().parent.parent

DUMP = """
import pickle, sys
import transient
transient.configure()
from transient.case.loading import load
from transient.contact.contactset import stack
from transient.contact.pair import build_contact
from transient.model import build_model, constant_load
from transient.reduce.components import part_tasks, part_work
from transient.stability.stage import analysed_case
from transient.case.sizes import entries
folder, path, wanted, overrides = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
case = analysed_case(load(path, overrides))
m = build_model(case)
pairs = build_contact(case, m)
names = []
for t in part_work(case, part_tasks(case, m, pairs, stack(pairs, m.ndof),
                                    [m.load_patterns[n] for n in case.loads],
                                    constant_load(case, m))):
    if wanted and t.name not in wanted.split(","):
        continue
    cells = [(len(c), c.shape[1]) for c in m.parts[t.name].mesh.cells.values()]
    with open(f"{folder}/{t.name}.pkl", "wb") as f:
        pickle.dump((t, entries(cells)), f)
    names.append(t.name)
print(" ".join(names))
"""

RUN = """
import json, pickle, resource, sys, time
import transient
transient.configure()
with open(sys.argv[1], "rb") as f:
    task, entries = pickle.load(f)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t0 = time.perf_counter()
p = task.run()
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
k_nnz = task.cells.matrices()[0].nnz     # after the peak: the task assembles its own
print(json.dumps(dict(part=task.name, ndof=task.n, k_nnz=int(k_nnz),
                      entries=int(entries), columns=int(p.T.shape[1]), seconds=seconds,
                      above=(peak - base) / 1e9, per_entry=(peak - base) / entries,
                      stages=p.seconds)))
"""


def child(code, args, pythonpath, folder, env=None):
    """Runs code in a fresh process on the package at pythonpath, from folder: from here
    `python -c` would put this checkout's package first whatever PYTHONPATH says; env: more
    of its environment."""
    env = dict(os.environ, PYTHONPATH=pythonpath, **(env or {}))
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                         env=env, cwd=folder)
    if out.returncode:
        sys.exit(out.stderr)
    return out.stdout.strip().splitlines()[-1]


def parsed(parser, argv):
    """(args, overrides): the parser's arguments with --mu, --set, --markdown and --json
    added, and the overrides that reduce the case by its parts (components_overrides)."""
    parser.add_argument("--mu", type=float, default=0.4)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--markdown")
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    return args, components_overrides(args.case, args.set, args.mu)


def components_overrides(case, sets, mu):
    """The overrides that reduce the case by its parts at friction mu on every sliding pair
    (after the caller's sets)."""
    sys.path.insert(0, str(ROOT))
    from transient.case.loading import load
    pairs = load(case, sets).contact
    return (list(sets) + ['solver.reduction.method="components"']
            + [f"contact.{p}.friction.mu={mu}" for p, c in pairs.items()
               if c.law.kind != "bilateral"])


def markdown(rows, load):
    lines = ["| part | package | free dofs | K entries | element-matrix entries | basis columns "
             "| seconds | stages [s] | above the task [GB] | bytes per entry | load |",
             "|" + "---|" * 11]
    for r in rows:
        stages = ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
        lines.append(f"| {r['part']} | {r['package']} | {r['ndof']:,} | {r['k_nnz'] / 1e6:.2f} M "
                     f"| {r['entries'] / 1e6:.1f} M | {r['columns']} | {r['seconds']:.1f} | "
                     f"{stages} | {r['above']:.2f} | {r['per_entry']:.0f} | {load:.1f} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--parts", default="", help="comma-separated names (default: all)")
    parser.add_argument("--base", help="another package's folder, reduced in turn")
    args, overrides = parsed(parser, argv)
    load0, rows = os.getloadavg()[0], []
    packages = [("HEAD", str(ROOT))] + ([("base", args.base)] if args.base else [])
    with tempfile.TemporaryDirectory() as folder:
        names = child(DUMP, [folder, str(Path(args.case).resolve()), args.parts, *overrides],
                      str(ROOT), folder).split()
        for name in names:
            for label, where in packages:
                row = json.loads(child(RUN, [f"{folder}/{name}.pkl"], str(Path(where).resolve()),
                                        folder))
                rows.append(dict(row, package=label))
                print(f"{name} ({label}): {row['seconds']:.1f} s, {row['above']:.2f} GB above "
                      f"the task, {row['per_entry']:.0f} B/entry", flush=True)
    publish(markdown(rows, 0.5 * (load0 + os.getloadavg()[0])), args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
