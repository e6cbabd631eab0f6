"""Wall time of `transient cea` against `transient modes` on the same case, back to back.

Each command is a child process (start-up and imports included, as a user sees them); the two
alternate `--repeat` times so that a change of the machine's load shows in both. The cea's
stages (setup, the complex modes themselves) come from its JSON. The issue's targets: the CEA
of pad_disc (setup included) within 1.5x of `transient modes`, the complex modes under 1 s.

    python benchmarks/bench_cea.py [CASE] [--mu 0.4] [--repeat 2] [--set key=value ...] [--json]
"""
import argparse
import json
import os
from pathlib import Path

from bench_long import timed_child  # a sibling in benchmarks/

ROOT = Path(__file__).resolve().parent.parent


def timed(command, case, overrides):
    """(wall seconds, the command's JSON with its CPU seconds) of `transient COMMAND CASE
    --json` in a child process (bench_long.timed_child)."""
    out, figures = timed_child([command, str(case), "--json"], overrides)
    # the system's CPU seconds are mostly page faults (benchmarks/bench_long.py: run_timed)
    cpu = {"user_s": figures["user_s"], "system_s": figures["system_s"]}
    return figures["wall_s"], dict(json.loads(out), cpu=cpu)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--mu", type=float, default=0.4)
    parser.add_argument("--pair", default="pad_disc")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    friction = args.set + [f"contact.{args.pair}.friction.mu={args.mu}"]
    timed("cea", args.case, friction)          # compiles what the cache lacks
    rows = []
    for _ in range(args.repeat):
        wall_modes, modes = timed("modes", args.case, args.set)
        wall_cea, cea = timed("cea", args.case, friction)
        rows.append({"modes_s": wall_modes, "cea_s": wall_cea, "ratio": wall_cea / wall_modes,
                     "complex_modes_s": cea["stages"]["complex_modes"],
                     "cea_stages": cea["stages"], "reduced_dofs": cea["reduced"],
                     "unstable": [m for m in cea["modes"] if m["unstable"]],
                     "modes_count": len(modes["frequencies_hz"]),
                     "modes_cpu": modes["cpu"], "cea_cpu": cea["cpu"]})
    load = os.getloadavg()[0]
    if args.json:
        print(json.dumps({"case": Path(args.case).name, "mu": args.mu, "load": load,
                          "rows": rows}))
        return
    for r in rows:
        print(f"modes {r['modes_s']:.1f} s, cea {r['cea_s']:.1f} s: ratio {r['ratio']:.2f}; "
              f"complex modes {r['complex_modes_s']:.2f} s on {r['reduced_dofs']} dofs; "
              f"{len(r['unstable'])} unstable; CPU user/system: modes "
              f"{r['modes_cpu']['user_s']:.1f}/{r['modes_cpu']['system_s']:.1f} s, cea "
              f"{r['cea_cpu']['user_s']:.1f}/{r['cea_cpu']['system_s']:.1f} s")
    print(f"load {load:.1f}")
    for m in rows[-1]["unstable"]:
        print(f"  unstable {m['frequency_hz']:.1f} Hz, real {m['real']:.4g} 1/s, "
              f"damping ratio {m['damping_ratio']:.3e}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
