"""A command's resident memory, every process it starts counted (a Dask cluster's workers and
nanny processes too): sampled every --every seconds, each process's peak and the peak of
their sum, which is what a machine's memory must hold. Each is counted twice: resident
(every page mapped in, a file's too) and anonymous (resident less the pages a file backs:
those of a mapped file, which the system reads back and lets go as memory asks, cost no
memory that another process needs). With --limit GB the command's processes are stopped once
the sum of their anonymous memory passes it (a run that would exhaust a shared machine is
cut short and says so). With --base DIR the same command also runs on the package at DIR (a
`git worktree` of another commit), A B A B, --rounds times.

    python benchmarks/bench_processes.py [--every 1] [--limit 22] [--base DIR] [--rounds 1]
                                  [--timeline FILE] [--output FILE] [--markdown FILE]
                                  [--json FILE]
                                  -- transient cea CASE ...
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

from tables import publish, table  # noqa: E402  (a sibling in benchmarks/)

ROOT = Path(__file__).resolve().parent.parent


def sampled(command, pythonpath, every, limit_gb, timeline=None, output=None):
    """{"seconds", "sum_gb", "peaks_gb" (the largest first), "anon_gb", "anon_peaks_gb",
    "killed", "returncode"} of the command run on the package at pythonpath; timeline (a
    path or None): each sample's seconds, the sums and every process's resident and
    anonymous GB (pid:resident/anonymous), a line each; output (a path or None): where the
    command's standard output goes (a --json report's stages)."""
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    if command[0] == "transient":
        command = [sys.executable, "-m", "transient"] + command[1:]
    t0 = time.perf_counter()
    # standard error to a file: a pipe read only at the end would stall a long, chatty run
    errors = tempfile.TemporaryFile("w+")
    out = open(output, "w") if output else subprocess.DEVNULL
    proc = subprocess.Popen(command, env=env, stdout=out, stderr=errors, text=True)
    root, peaks, top, killed = psutil.Process(proc.pid), {}, 0.0, False
    anon_peaks, anon_top = {}, 0.0
    log = open(timeline, "w") if timeline else None
    while proc.poll() is None:
        total, anon, now = 0, 0, {}
        try:
            tree = [root] + root.children(recursive=True)
        except psutil.NoSuchProcess:
            break
        for p in tree:
            try:
                info = p.memory_info()
            except psutil.NoSuchProcess:
                continue
            # Linux's shared: the resident pages a file (or shared memory) backs
            rss, own = info.rss, info.rss - getattr(info, "shared", 0)
            total += rss
            anon += own
            now[p.pid] = (rss, own)
            peaks[p.pid] = max(peaks.get(p.pid, 0), rss)
            anon_peaks[p.pid] = max(anon_peaks.get(p.pid, 0), own)
        top, anon_top = max(top, total), max(anon_top, anon)
        if log is not None:
            log.write(f"{time.perf_counter() - t0:.1f} {total / 1e9:.2f} {anon / 1e9:.2f} "
                      + " ".join(f"{pid}:{now[pid][0] / 1e9:.2f}/{now[pid][1] / 1e9:.2f}"
                                 for pid in sorted(now)) + "\n")
            log.flush()
        if limit_gb and anon > limit_gb * 1e9:
            killed = True
            for p in reversed(tree):
                try:
                    p.kill()
                except psutil.NoSuchProcess:
                    pass
            break
        time.sleep(every)
    if log is not None:
        log.close()
    proc.wait()
    if output:
        out.close()
    errors.seek(0)
    err = errors.read()
    errors.close()
    seconds = time.perf_counter() - t0
    if proc.returncode and not killed:
        sys.stderr.write(err)
    return {"seconds": seconds, "sum_gb": top / 1e9,
            "peaks_gb": sorted((v / 1e9 for v in peaks.values() if v > 50e6), reverse=True),
            "anon_gb": anon_top / 1e9,
            "anon_peaks_gb": sorted((v / 1e9 for v in anon_peaks.values() if v > 50e6),
                                    reverse=True),
            "killed": killed, "returncode": proc.returncode}


def markdown(rows, load):
    return table(["package", "seconds", "all processes' peak [GB]",
                  "each process's peak [GB] (above 0.05)", "anonymous: all", "each", "ended",
                  "load"],
                 [[r["package"], f"{r['seconds']:.1f}", f"{r['sum_gb']:.2f}",
                   ", ".join(f"{p:.2f}" for p in r["peaks_gb"]), f"{r['anon_gb']:.2f}",
                   ", ".join(f"{p:.2f}" for p in r["anon_peaks_gb"]),
                   "stopped at the limit" if r["killed"] else f"exit {r['returncode']}",
                   f"{load:.1f}"] for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=float, default=1.0)
    parser.add_argument("--limit", type=float, default=0.0, help="GB (0: none)")
    parser.add_argument("--base")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--timeline", help="a file: each sample's seconds and GB")
    parser.add_argument("--output", help="a file: the command's standard output")
    parser.add_argument("--markdown")
    parser.add_argument("--json")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("the command to measure comes after --")
    packages = [("this", ROOT)] + ([("base", Path(args.base).resolve())] if args.base else [])
    load0, rows = os.getloadavg()[0], []
    for _ in range(args.rounds):
        for name, path in packages:
            row = dict(sampled(command, path, args.every, args.limit, args.timeline,
                               args.output),
                       package=name)
            rows.append(row)
            print(f"{name}: {row['seconds']:.1f} s, all {row['sum_gb']:.2f} GB, each "
                  f"{[round(p, 2) for p in row['peaks_gb']]}; anonymous all "
                  f"{row['anon_gb']:.2f} GB, each {[round(p, 2) for p in row['anon_peaks_gb']]}"
                  f"{', stopped at the limit' if row['killed'] else ''}", flush=True)
    publish(markdown(rows, 0.5 * (load0 + os.getloadavg()[0])), args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
