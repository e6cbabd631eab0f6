"""A squeal run's wall time, and its step against the contact pass's roofline on its own arrays.

Runs `transient run CASE` in a child process (imports and setup included, as a user sees them)
and reads its history: setup and kernel seconds, the steps run on each Numba thread count and
their median us per step. Then, on the run's own reduced system (the history's /system: the
rows C, Ct, Cc, m x n), it times with NumPy/BLAS, in a Python loop (about 1 us of call overhead
a product), on one and on two OpenBLAS threads (threadpoolctl), best of --repeat:
- read_once: C q, Ct v, Cc v, every row read once, the memory traffic a contact pass cannot
  do without (the kernel reads each row once: its dot and its update of the force share it);
- numpy_pass: what NumPy needs for a pass, the three products, the law's exp on m values and
  the three products back (C^T r + Ct^T a + Cc^T b), each row read twice.
A step makes corrections + 1 passes (the exponential scheme; 1 for central differences); the
kernel adds the modal propagation, the energies and the output rows.

--compare T: also runs the case and its half step to T (history every 12.5 us) and gives the
sensors' RMS and dominant frequency over each window of --windows in both, and their changes.
--history H: times the roofline on an existing history instead of running the case.

    python benchmarks/bench_squeal.py [CASE] [--set KEY=VALUE ...] [--repeat 300] [--compare 0.5]
        [--windows 0.1:0.2,0.2:0.5] [--keep DIR] [--history H] [--json]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def run(case, overrides, out):
    """(wall seconds, the history's summary) of `transient run CASE -o OUT`."""
    args = [sys.executable, "-m", "transient", "run", str(case), "-o", str(out), "--quiet"]
    for o in overrides:
        args += ["--set", o]
    t0 = time.perf_counter()
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        sys.exit(f"transient run failed ({done.returncode}): {done.stderr.strip()}")
    info = subprocess.run([sys.executable, "-m", "transient", "info", str(out), "--json"],
                          cwd=ROOT, capture_output=True, text=True, check=True)
    return wall, json.loads(info.stdout)


def roofline(path, repeat):
    """{"read_once" | "numpy_pass": {threads: us per contact pass}} on the history's rows
    (module docstring), and (m, n)."""
    from threadpoolctl import threadpool_limits
    with h5py.File(path) as f:
        rows = [f["system/C"][()]] + [f[f"system/{k}"][()] for k in ("Ct", "Cc")
                                      if f"system/{k}" in f]
    m, n = rows[0].shape
    rng = np.random.default_rng(0)
    x = rng.standard_normal(n)
    y = [rng.standard_normal(m) for _ in rows]

    def read_once():
        for R in rows:
            R @ x

    def numpy_pass():
        f = rows[0].T @ np.exp(-(rows[0] @ x))
        for R, z in zip(rows[1:], y[1:]):
            R @ x
            f += R.T @ z

    out = {"read_once": {}, "numpy_pass": {}}
    for threads in (1, 2):
        with threadpool_limits(limits=threads, user_api="blas"):
            for name, fn in (("read_once", read_once), ("numpy_pass", numpy_pass)):
                best = np.inf
                for _ in range(repeat):
                    t0 = time.perf_counter()
                    fn()
                    best = min(best, time.perf_counter() - t0)
                out[name][threads] = 1e6 * best
    return out, (m, n)


def passes(summary):
    """Contact passes a step makes, from the case the history ran."""
    from transient.case import load
    meta = summary["meta"]
    case = load(meta["case_path"], meta.get("overrides", []))
    solver = case.solver
    return solver.corrections + 1 if solver.scheme == "exponential" else 1


def oscillation(path, windows):
    """[(window, RMS per sensor, dominant frequency)] of a history's sensors."""
    from transient.studies.bench import oscillation as summary_of
    with h5py.File(path) as f:
        series = {"time": f["time"][()]}
        names = sorted(f["sensors"])
        for k in names:
            series[f"sensors/{k}"] = f[f"sensors/{k}"][()]
    rows = []
    for a, b in windows:
        keep = (series["time"] >= a) & (series["time"] <= b)
        part = {k: x[keep] for k, x in series.items()}
        o, rms = summary_of(part, a)
        rows.append({"window": [a, b], "rms": dict(zip(names, map(float, rms))),
                     "frequency_hz": float(o["cycle_frequency"])})
    return rows


def compare(case, overrides, t_end, windows, directory):
    """The case and its half step to t_end: each window's RMS and frequency, and changes."""
    from transient.case import load
    dt = load(case, overrides).solver.dt
    if dt <= 0:
        sys.exit("--compare needs the case's solver.dt")
    rows = {}
    for label, step in (("dt", dt), ("dt/2", dt / 2)):
        every = max(1, int(round(12.5e-6 / step)))
        out = Path(directory) / f"compare_{label.replace('/', '_')}.h5"
        run(case, overrides + [f"solver.t_end={t_end}", f"solver.dt={step}",
                               f"output.every={every}", "output.contact=false"], out)
        rows[label] = oscillation(out, windows)
    changes = []
    for a, b in zip(rows["dt"], rows["dt/2"]):
        changes.append({"window": a["window"],
                        "rms": {k: abs(a["rms"][k] / b["rms"][k] - 1) for k in a["rms"]},
                        "frequency": abs(a["frequency_hz"] / b["frequency_hz"] - 1)})
    return {"runs": rows, "changes": changes}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc_squeal.toml"))
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--repeat", type=int, default=300)
    parser.add_argument("--compare", type=float, default=0.0, metavar="T_END")
    parser.add_argument("--windows", default="0.1:0.2,0.2:0.5")
    parser.add_argument("--keep", help="directory for the histories (default: a temporary one)")
    parser.add_argument("--history", help="time the roofline on this history, run nothing")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    windows = [tuple(float(x) for x in w.split(":")) for w in args.windows.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        directory = args.keep or tmp
        os.makedirs(directory, exist_ok=True)
        if args.history:
            out, wall = Path(args.history), float("nan")
            info = subprocess.run([sys.executable, "-m", "transient", "info", str(out),
                                   "--json"], cwd=ROOT, capture_output=True, text=True,
                                  check=True)
            summary = json.loads(info.stdout)
        else:
            out = Path(directory) / "squeal.h5"
            wall, summary = run(args.case, args.set, out)
        timings = summary["timings"]
        per_thread = {k: v for k, v in timings.get("kernel_threads", {}).items() if v[1]}
        best = min(per_thread, key=lambda k: per_thread[k][1]) if per_thread else None
        roof, (m, n) = roofline(out, args.repeat)
        k = passes(summary)
        result = {"case": Path(summary["meta"]["case_path"]).name,
                  "overrides": summary["meta"].get("overrides", []), "wall_s": wall,
                  "setup_s": timings["setup"], "kernel_s": timings["kernel"],
                  "steps": sum(v[0] for v in per_thread.values()), "t_end": summary["t_end"],
                  "kernel_threads": per_thread, "points": m, "dofs": n,
                  "passes_per_step": k, "roofline_us_per_pass": roof,
                  "load": os.getloadavg()[0]}
        if best is not None:
            step_us = per_thread[best][1]
            result["us_per_step"] = step_us
            result["us_per_pass"] = step_us / k
            # thread count 0: the stepper's own setting, a single row block, run serially
            result["roofline_ratio"] = step_us / k / roof["read_once"][int(best) or 1]
        if args.compare:
            result["compare"] = compare(args.case, args.set, args.compare, windows, directory)
    if args.json:
        print(json.dumps(result))
        return
    wall_text = "as its history says" if args.history else f"in {wall:.1f} s wall"
    print(f"{result['case']}: {result['steps']} steps to {result['t_end']:g} s "
          f"{wall_text} (setup {result['setup_s']:.1f} s, kernel "
          f"{result['kernel_s']:.1f} s); {m} points, {n} dofs, {k} contact passes a step")
    for threads, (steps, us) in sorted(per_thread.items()):
        who = "one row block, serial" if threads == "0" else f"{threads} Numba thread(s)"
        print(f"  {who}: {steps} steps at {us:.1f} us a step")
    for name, what in (("read_once", "every row read once"),
                       ("numpy_pass", "NumPy's pass, rows read twice")):
        print(f"  {what}: " + ", ".join(f"{t} BLAS thread(s) {us:.1f} us"
                                        for t, us in roof[name].items()))
    if "roofline_ratio" in result:
        print(f"  the kernel's pass ({result['us_per_pass']:.1f} us) against every row read "
              f"once on as many threads: {result['roofline_ratio']:.2f}")
    for c in result.get("compare", {}).get("changes", []):
        a, b = c["window"]
        print(f"  dt against dt/2 over {a:g}-{b:g} s: RMS " + ", ".join(
            f"{name} {100 * x:.2f}%" for name, x in c["rms"].items())
            + f"; frequency {c['frequency']:.1e}")
    print(f"load {result['load']:.1f}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
