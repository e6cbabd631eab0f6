"""Command line: `transient SUBCOMMAND CASE [--set KEY.PATH=VALUE ...] [--json]`."""
import argparse
import json
import sys
import time

from . import __version__
from .case import load
from .errors import CaseError


def _case_args(p):
    p.add_argument("case", help="case file (TOML)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case value with a TOML literal, e.g. "
                   "parts.upper.mesh.divisions=[3,3,3] (repeatable)")


def _parser():
    parser = argparse.ArgumentParser(prog="transient", description="Long transient vibrations "
                                     "of elastic solids in contact across non-conforming meshes.")
    parser.add_argument("--version", action="version", version=f"transient {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("modes", help="normal modes of the case's model")
    _case_args(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return parser


def cmd_modes(args):
    from .model import build_model
    from .modes import normal_modes
    from .meshfile import write_vtu
    t0 = time.perf_counter()
    case = load(args.case, args.overrides)
    model = build_model(case)
    settings = case["solver"]["modes"]
    modes = normal_modes(model.K, model.M, model.fixed, settings["count"], settings["fmax"],
                         settings["shift"], case["solver"]["linear_solver"])
    timings = {**model.timings, **modes.timings, "total": time.perf_counter() - t0}
    if case["output"]["vtu"]:
        _write_modes_vtu(case, model, modes, write_vtu)
    if args.json:
        print(json.dumps({"frequencies_hz": modes.frequencies.tolist(), "ndof": model.ndof,
                          "free_dofs": int((~model.fixed).sum()), "backend": modes.backend,
                          "timings": timings}))
        return 0
    print(f"{case.path}: {model.ndof} dofs ({int((~model.fixed).sum())} free), "
          f"{len(model.parts)} part(s), factorization: {modes.backend}")
    print(f"{'mode':>5} {'frequency [Hz]':>16}")
    for i, f in enumerate(modes.frequencies, 1):
        print(f"{i:>5} {f:16.6g}")
    print("time: " + ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return 0


def _write_modes_vtu(case, model, modes, write_vtu):
    data = {f"mode_{i + 1:03d}_{f:.1f}Hz": modes.shapes[:, i].reshape(-1, 3)
            for i, f in enumerate(modes.frequencies)}
    write_vtu(case.directory / case["output"]["vtu"], model.mesh(), point_data=data)


COMMANDS = {"modes": cmd_modes}


def main(argv=None):
    args = _parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except CaseError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
