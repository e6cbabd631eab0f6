"""A campaign on Dask: the variants' tasks on a cluster, their rows in sweep.csv and sweep.json.

The embedded cluster is a dask.distributed LocalCluster of N worker processes of one thread
each, with BLAS, MKL, OpenMP and Numba at one thread set in their environment before they
start (so that a worker is the one-thread `transient run` it stands for, and N of them share
the cores), and each task makes transient.configure's settings in its worker before any stage
(campaign.tasks); the Numba cache is shared, its first compile serialized by transient.jit's lock.
--scheduler ADDRESS runs the same tasks on an existing cluster instead (dask-jobqueue on
SLURM: docs/commands.md). Variants equal on the fields a first stage reads (shared.READS: the
model's structure, the contact pairs' geometry, the factorization with the contact's low-rank
update, the basis at a friction's basis_mu) share its result, built once by a task of its own
and sent to each worker once (a factorization is made again where it lands: PARDISO's handle
does not travel). A task whose worker dies is rerun on another by the scheduler; a variant
that is refused or aborts is a row with its reason. The folder is held by one campaign at a
time (folder.holding), and every path it writes is checked before any work (outputs.plan):
--resume reads back the variants whose outputs are complete and the variant's own, continues
the histories stopped short, and makes the others again.
"""
import csv
import io
import json
import time
from contextlib import ExitStack
from pathlib import Path

from ..cluster import THREAD_ENV, check_cluster, client_for  # noqa: F401 (THREAD_ENV: tests)
from ..errors import CaseError
from .folder import MARK, check_out, holding, write_whole
from .folder import modes_file
from .outputs import is_sweep_csv, is_sweep_json, outputs, plan
from .tasks import KINDS, build_shared, cea_summary, run_variant
from .variants import WHERE

FIRST = ("variant", "status", "seconds")


def check_variants(case_path, overrides, variants, kind):
    """Load every variant (and, for runs, check what the transient refuses) before anything
    runs: the first bad one is a CaseError naming it. Returns each variant's Case and its keys
    of the shareable stages (shared.stage_key, by stage: variants with equal keys share
    them), by name."""
    from ..case.checks import check_transient
    from ..case.loading import load
    from ..shared import SHARED, stage_key
    cases, keys = {}, {}
    for v in variants:
        try:
            case = load(case_path, list(overrides) + v.overrides())
            if kind in ("run", "both"):
                check_transient(case)
        except CaseError as exc:
            raise CaseError(exc.path, exc.key, f"variant {v.name} ({v.label()}): "
                            f"{exc.message}") from None
        cases[v.name] = case
        keys[v.name] = {stage: stage_key(case, stage) for stage in SHARED}
    return cases, keys


def sweep(case_path, variants, out, kind="run", overrides=(), workers=2, scheduler=None,
          resume=False, progress=None, announce=print, command=None, cache=None):
    """Run the variants; returns their rows (in variant order) and writes the campaign's
    files in out, which it holds meanwhile (command: what the lock says holds it).
    progress(done, total, failed) after each variant; announce(text) says where the dashboard
    is; cache: the folder of the components path's parts (reduce.engine.cached), which the
    variants share."""
    if kind not in KINDS:
        raise CaseError(WHERE, "--kind", f"expected one of {', '.join(KINDS)}, got '{kind}'")
    check_cluster(scheduler, workers)
    out = check_out(out)
    with ExitStack() as held:
        # a folder that exists is held at once: a second campaign is refused before its checks
        existed = out.is_dir()
        if existed:
            held.enter_context(holding(out, command))
        cases, keys = check_variants(case_path, overrides, variants, kind)
        if not existed:
            held.enter_context(holding(out, command))
        todo = plan(out, variants, cases, kind, resume)
        del cases
        rows = dict(todo.done)
        if progress:
            progress(len(rows), len(variants), 0)
        shared = {}
        if todo.todo:
            client, cluster = client_for(scheduler, workers)
            try:
                if announce:
                    announce(f"dask dashboard: {client.dashboard_link}")
                shared = _gather(client, case_path, overrides, variants, todo.todo, out, kind,
                                 rows, progress, keys, cache)
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        table = [_row(v, rows[v.name], kind, out) for v in variants]
        write(table, out, list(variants[0].values), kind, shared)
    return table


def _gather(client, case_path, overrides, variants, todo, out, kind, rows, progress, keys,
            cache=None):
    """Submit the variants to do (name -> 'fresh' or 'continue') and collect their rows;
    returns how many results of each stage were built to be shared. Fresh variants equal on a
    stage's key (two or more) take its result from a task of its own, which goes on from the
    shallower stage's shared result: a future that is an argument of theirs, so it is built
    once and travels to each worker once (the scheduler keeps it where it is needed). A
    continued history needs no setup."""
    from dask.distributed import as_completed
    from ..shared import SHARED
    fresh = [v for v in variants if todo.get(v.name) == "fresh"]
    built, counts, before = {}, {}, {v.name: None for v in fresh}
    for depth in SHARED:
        groups = {}
        for v in fresh:
            groups.setdefault(keys[v.name][depth], []).append(v)
        counts[depth] = 0
        for key, members in groups.items():
            if len(members) < 2:
                continue
            future = client.submit(build_shared, str(case_path),
                                   list(overrides) + members[0].overrides(), depth,
                                   before[members[0].name], kind,
                                   key=f"{depth}-{counts[depth]}-{time.time_ns()}", pure=False)
            counts[depth] += 1
            for v in members:
                built[v.name] = before[v.name] = future
    if cache is not None and fresh:
        _prime(client, case_path, list(overrides) + fresh[0].overrides(), kind, cache)
    futures = {client.submit(run_variant, str(case_path), list(overrides) + v.overrides(),
                             str(outputs(out, v.name, kind)[0]), kind, built.get(v.name),
                             todo[v.name] == "continue", cache,
                             key=f"{v.name}-{time.time_ns()}", pure=False): v
               for v in variants if v.name in todo}
    failed = 0
    for future in as_completed(futures):
        v = futures[future]
        try:
            row = future.result()
        except Exception as exc:       # the task itself failed (a worker lost too often)
            row = {"status": f"failed: {type(exc).__name__}: {exc}"}
        if todo[v.name] == "continue":
            row["continued"] = True
            if kind == "both":         # its complex modes are complete: read back
                row.update(cea_summary(modes_file(outputs(out, v.name, kind)[1])["modes"]))
        rows[v.name] = row
        failed += row["status"] != "complete"
        if progress:
            progress(len(rows), len(variants), failed)
    return counts


def _prime(client, case_path, overrides, kind, cache):
    """The components path's parts of one variant reduced on the cluster, one task a part,
    into the cache, before the variants fan out: the parts they share (a lining campaign's
    disc, caliper and bracket) are then reduced once on every worker, not once by each
    variant of the first round on its one thread, and read back by all. A variant refused
    here says why in its own row."""
    from ..case.loading import load
    from ..reduce.engine import Engine
    from ..stability.stage import analysed_case
    from ..stages import prepare_parts
    case = load(case_path, overrides)
    if not case.solver.reduction.components:
        return
    try:
        prepare_parts(analysed_case(case) if kind == "cea" else case,
                      Engine(client=client, cache=Path(cache)))
    except CaseError:
        pass


def _row(v, row, kind, out):
    paths = outputs(out, v.name, kind)
    return {"variant": v.name, **v.values,
            **{k: row.get(k) for k in row if k not in ("resumed", "continued")},
            "resumed": bool(row.get("resumed")), "continued": bool(row.get("continued")),
            "output": paths[0].name, **({"modes_output": paths[1].name} if len(paths) > 1
                                        else {})}


def write(table, out, parameters, kind, shared=None):
    """sweep.json (every row, the parameters' keys, the kind and the count of each stage's
    results built to be shared) and sweep.csv (its scalar columns), each replaced whole, and
    only if it is absent or a campaign's."""
    out = Path(out)
    columns = list(FIRST)
    for row in table:
        columns += [k for k, x in row.items()
                    if k not in columns and not isinstance(x, (list, dict))]
    for name, check in (("sweep.json", is_sweep_json), ("sweep.csv", is_sweep_csv)):
        path = out / name
        if path.exists() and path.stat().st_size and not check(path):
            raise CaseError(path, "--out", "exists and is not a table written by transient "
                            "sweep: not overwritten")
    write_whole(out / "sweep.json", json.dumps(
        {"written_by": MARK, "kind": kind, "parameters": parameters, "shared": shared or {},
         "rows": table}, indent=1))
    text = io.StringIO(newline="")
    w = csv.DictWriter(text, fieldnames=columns, extrasaction="ignore")
    w.writeheader()
    for row in table:
        w.writerow({k: row.get(k) for k in columns})
    write_whole(out / "sweep.csv", text.getvalue())
    return [out / "sweep.csv", out / "sweep.json"]
