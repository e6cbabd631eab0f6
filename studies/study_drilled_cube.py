"""Drilled cube, static: each contact rule's fine-side interface displacement against the
conforming reference (upper cube meshed with the lower cube's plan).

    python studies/study_drilled_cube.py [--set KEY=VALUE ...] [--json]
"""
import argparse
import json
import time
from pathlib import Path

from transient.studies.drilled_cube import drilled_cube_errors

CASE = Path(__file__).resolve().parent.parent / "cases" / "drilled_cube.toml"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(CASE))
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = []
    for norm in ("mass", "identity"):
        t0 = time.perf_counter()
        errors, _ = drilled_cube_errors(args.case, args.overrides
                                        + [f"contact.interface.norm={norm}"])
        rows += [{"norm": norm, "rule": rule, "error_l2": err} for rule, err in errors.items()]
        if not args.json:
            print(f"pseudo-inverse norm: {norm} ({time.perf_counter() - t0:.1f} s)")
            for rule, err in errors.items():
                print(f"  {rule:20s} {err:.3e}")
    if args.json:
        print(json.dumps({"rows": rows}))


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
