"""Wall time and peak memory of a whole `transient run`: by default cases/pad_disc_long.toml,
one second of the pad on the disc at 20 steps per period of 16 kHz (320,000 steps).

The run is a child process (`transient run --quiet`), so its wall time includes start-up and
imports as a user sees them, and ru_maxrss is its own peak. The history's stages and timings
say where the time went. A first run that compiles the Numba kernels is not representative:
--warm runs the case once for a few steps before.

    python benchmarks/bench_long.py [CASE] [--warm] [--set key=value ...] [--json]
"""
import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(case, overrides, out):
    """(wall seconds, peak RSS bytes) of `transient run` in a child process."""
    done = run_timed(case, overrides, out)
    return done["wall_s"], done["peak_rss_bytes"]


def run_timed(case, overrides, out):
    """`transient run` in a child process: its wall seconds, peak RSS bytes and CPU seconds in
    user and system mode. The system's share is mostly page faults: on this VM a first touch
    of memory is zeroed through the host, so it tells a machine's state from the code's."""
    return timed_child(["run", str(case), "-o", str(out), "--quiet"], overrides)[1]


def timed_child(words, overrides):
    """(stdout, figures) of `transient WORDS --set ...` in a child process: figures its wall
    seconds, peak RSS bytes and CPU seconds in user and system mode (run_timed)."""
    args = [sys.executable, "-m", "transient", *words]
    for o in overrides:
        args += ["--set", o]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        sys.exit(f"transient {words[0]} failed ({done.returncode}): {done.stderr.strip()}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # ru_maxrss of children is the largest child so far: meaningful when this run is the largest
    return done.stdout, {"wall_s": wall,
                         "peak_rss_bytes": max(after.ru_maxrss, before.ru_maxrss) * 1024,
                         "user_s": after.ru_utime - before.ru_utime,
                         "system_s": after.ru_stime - before.ru_stime}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc_long.toml"))
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--warm", action="store_true", help="compile the kernels first")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    from transient.io.reading import summary
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run.h5"
        if args.warm:
            run(args.case, args.set + ["solver.t_end=1e-4"], out)
        done = run_timed(args.case, args.set, out)
        info = summary(out)
    meta = info["meta"]
    wall, peak = done["wall_s"], done["peak_rss_bytes"]
    row = {"case": Path(args.case).name, "status": info["status"], "wall_s": wall,
           "peak_rss_gb": peak / 1e9, "user_s": done["user_s"], "system_s": done["system_s"],
           "steps": meta["steps_planned"], "dt": meta["dt"],
           "t_end": info["t_end"], "reduced_dofs": meta.get("reduced_dofs"),
           "contact_points": meta.get("n_points"), "timings": info["timings"],
           "stages": meta["stages"], "energy_drift": info["energy_drift"],
           "kernel_us_per_step": 1e6 * info["timings"]["kernel"] / meta["steps_planned"],
           "kernel_threads": info["timings"].get("kernel_threads")}
    if args.json:
        print(json.dumps(row))
        return
    print(f"{row['case']}: {row['status']}, {row['steps']} steps of {row['dt']:.4g} s to "
          f"t = {row['t_end']:.4g} s, {row['reduced_dofs']} reduced dofs, "
          f"{row['contact_points']} contact points")
    print(f"wall {wall:.1f} s, peak RSS {peak / 1e9:.2f} GB; setup "
          f"{info['timings']['setup']:.1f} s, kernel {info['timings']['kernel']:.1f} s "
          f"({row['kernel_us_per_step']:.1f} us/step; threads: [steps, median us/step] "
          f"{row['kernel_threads']}), energy drift {info['energy_drift']:.2e}")
    print("stages: " + ", ".join(f"{k} {v:.2f} s" for k, v in row["stages"].items()))
    print(f"CPU: user {row['user_s']:.1f} s, system {row['system_s']:.1f} s")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
