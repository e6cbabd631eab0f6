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
    p = sub.add_parser("run", help="transient: preload, then time integration to solver.t_end, "
                       "streamed to an HDF5 history")
    _case_args(p)
    p.add_argument("-o", "--output", help="HDF5 file (default: output.file, or the case's "
                   "name with .h5)")
    p.add_argument("--resume", action="store_true", help="continue the run stored in the "
                   "output file from its last checkpoint (after an abort, or to a later t_end)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p = sub.add_parser("info", help="summary of an HDF5 history")
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p = sub.add_parser("compat", help="compatibility of a contact interface: fine rule, "
                       "singular values of the gap energy, C(eps)")
    _case_args(p)
    p.add_argument("--pair", help="contact pair to report (default: the first)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    _plot_parser(sub)
    return parser


def _plot_parser(sub):
    """`transient plot KIND ...`: one sub-subcommand per kind of picture."""
    kinds = sub.add_parser("plot", help="pictures (PNG) of a case").add_subparsers(
        dest="kind", required=True)
    p = kinds.add_parser("compat", help="compatibility of each contact pair: shapes, singular "
                         "values and C(eps), raw and regularized gap observation")
    _case_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="directory of the PNG files")
    p.add_argument("--pair", metavar="NAME", help="only this contact pair")
    p.add_argument("--shapes", metavar="I,J,...", help="shape numbers to draw, from 1 by "
                   "increasing incompatibility (default: the first, the last kept, two beyond)")


def cmd_plot(args):
    return {"compat": _plot_compat}[args.kind](args)


def _plot_compat(args):
    from .contact import build_pair
    from .model import build_model
    from .plots import RenderingUnavailable, check_shapes, parse_shapes, plot_compat
    try:
        shapes = parse_shapes(args.shapes) if args.shapes is not None else None
    except ValueError as exc:
        raise CaseError(args.case, "--shapes", str(exc)) from None
    case = load(args.case, args.overrides)
    names = list(case["contact"])
    if not names:
        raise CaseError(case.path, "contact", "the case has no [contact.NAME] pair")
    if args.pair is not None and args.pair not in names:
        raise CaseError(case.path, "contact", f"no pair '{args.pair}' "
                        f"(pairs: {', '.join(names)})")
    model = build_model(case)
    pairs = [build_pair(case, model, name, need_compatibility=True)
             for name in names if args.pair in (None, name)]
    for pair in pairs:
        try:
            check_shapes(shapes or [], pair.compat)
        except ValueError as exc:
            raise CaseError(case.path, "--shapes", f"pair '{pair.name}': {exc}") from None
    for pair in pairs:
        try:
            paths = plot_compat(pair, args.out, shapes)
        except RenderingUnavailable as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        except OSError as exc:
            raise CaseError(case.path, "--out", str(exc)) from None
        print("\n".join(str(p) for p in paths))
    return 0


def cmd_modes(args):
    from .contact import build_contact, contact_stiffness
    from .meshfile import write_vtu
    from .model import build_model
    from .modes import normal_modes
    t0 = time.perf_counter()
    case = load(args.case, args.overrides)
    model = build_model(case)
    pairs = build_contact(case, model)
    # contact enters the modes as tied (bilateral linear) springs of density k on the pair's rule
    K = model.K + contact_stiffness(pairs, model.ndof) if pairs else model.K
    settings = case["solver"]["modes"]
    modes = normal_modes(K, model.M, model.fixed, settings["count"], settings["fmax"],
                         settings["shift"], case["solver"]["linear_solver"])
    stage_times = {f"contact.{p.name}.{k}": v for p in pairs for k, v in p.timings.items()}
    timings = {**model.timings, **stage_times, **modes.timings,
               "total": time.perf_counter() - t0}
    if case["output"]["vtu"]:
        _write_modes_vtu(case, model, modes, write_vtu)
    contact = [_pair_summary(p) for p in pairs]
    if args.json:
        print(json.dumps({"frequencies_hz": modes.frequencies.tolist(), "ndof": model.ndof,
                          "free_dofs": int((~model.fixed).sum()), "backend": modes.backend,
                          "contact": contact, "timings": timings}))
        return 0
    print(f"{case.path}: {model.ndof} dofs ({int((~model.fixed).sum())} free), "
          f"{len(model.parts)} part(s), factorization: {modes.backend}")
    for c in contact:
        print(f"  contact {c['pair']}: tied, k = {c['k']:.3g} Pa/m, rule {c['rule']} "
              f"({c['points']} points)" + (f", regularized eps = {c['eps']:.3g}"
                                           if c["regularized"] else ""))
    print(f"{'mode':>5} {'frequency [Hz]':>16}")
    for i, f in enumerate(modes.frequencies, 1):
        print(f"{i:>5} {f:16.6g}")
    print("time: " + ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return 0


def _pair_summary(pair):
    out = {"pair": pair.name, "rule": pair.spec["rule"], "regularized": pair.spec["regularized"],
           "k": pair.k, "points": pair.rule.n_points, "area": pair.rule.area, "eps": pair.eps,
           "kept": pair.compat.kept(pair.eps) if pair.compat else None}
    if pair.coarse is not None:
        out["coarse"] = {"m": len(pair.coarse.chosen), "energy_error": pair.coarse.energy_error,
                         "weighting": pair.coarse.weighting,
                         "setup_s": pair.timings["coarse_rule"]}
    return out


def _write_modes_vtu(case, model, modes, write_vtu):
    data = {f"mode_{i + 1:03d}_{f:.1f}Hz": modes.shapes[:, i].reshape(-1, 3)
            for i, f in enumerate(modes.frequencies)}
    write_vtu(case.directory / case["output"]["vtu"], model.mesh(), point_data=data)


def cmd_compat(args):
    import numpy as np
    from .contact import build_pair
    from .model import build_model
    t0 = time.perf_counter()
    case = load(args.case, args.overrides)
    names = list(case["contact"])
    if not names:
        raise CaseError(case.path, "contact", "the case has no [contact.NAME] pair")
    name = args.pair or names[0]
    if name not in names:
        raise CaseError(case.path, "contact", f"no pair '{name}' (pairs: {', '.join(names)})")
    model = build_model(case)
    t1 = time.perf_counter()
    pair = build_pair(case, model, name, need_compatibility=True)
    setup = time.perf_counter() - t1
    comp, fine = pair.compat, pair.interface.fine
    eps_grid = np.logspace(-16, 0, 65)
    out = {"pair": name, "n_points": fine.n_points, "area": fine.area, "n_dof_1": comp.n1,
           "n_dof_2": comp.n2, "sigma_max": float(comp.sigma.max()),
           "singular_values": comp.normalized.tolist(),
           "compatibility": {"eps": eps_grid.tolist(), "C": comp.curve(eps_grid).tolist()},
           "eps": pair.eps, "eps_source": pair.eps_source, "kept": comp.kept(pair.eps),
           "coarse": None if pair.coarse is None else {
               "m": len(pair.coarse.chosen), "energy_error": pair.coarse.energy_error,
               "setup_s": pair.timings["coarse_rule"], "rank": pair.coarse.rank,
               "weighting": pair.coarse.weighting, "area_error": pair.coarse.area_error},
           "setup_s": setup, "timings": {**model.timings, **pair.timings,
                                         **pair.interface.timings, **comp.timings,
                                         "total": time.perf_counter() - t0}}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{case.path}: contact pair '{name}': {pair.spec['surface1']} / {pair.spec['surface2']}")
    print(f"  fine rule: {fine.n_points} points (degree {pair.interface.order}), "
          f"area {fine.area:.6g} m^2")
    print(f"  interface normal dofs: {comp.n1} (surface 1) + {comp.n2} (surface 2)")
    print(f"  eps = {pair.eps:.3g} ({pair.eps_source}): {out['kept']} compatible shapes kept, "
          f"C(eps) = {comp.curve([pair.eps])[0]:.3f}")
    print(f"  {'eps':>8} {'kept':>6} {'C(eps)':>8}")
    for e in (1e-12, 1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1):
        print(f"  {e:8.0e} {comp.kept(e):6d} {comp.curve([e])[0]:8.3f}")
    if pair.coarse is not None:
        c = pair.coarse
        print(f"  greedy rule: {len(c.chosen)} points (rank {c.rank}), weights {c.weighting}, "
              f"energy error {c.energy_error:.2e}, area error {c.area_error:.1e}")
    print(f"  setup {setup:.2f} s (interface {pair.timings['interface']:.2f} s, "
          f"compatibility {pair.timings['compatibility']:.2f} s)")
    return 0


def cmd_run(args):
    import os
    from pathlib import Path
    from .run import run
    case = load(args.case, args.overrides)
    path = Path(args.output) if args.output else case.directory / (
        case["output"]["file"] or Path(case.path).with_suffix(".h5").name)
    if args.resume and not path.exists():
        raise CaseError(path, "", "--resume: no history file to resume")
    quiet = args.quiet or args.json or os.environ.get("CI") or not sys.stderr.isatty()
    result = run(case, path, resume=args.resume, progress=not quiet)
    if args.json:
        print(json.dumps({"file": result.path, "status": result.status, "steps": result.steps,
                          "t_end": result.t_end, "dt": result.dt,
                          "dt_critical": result.dt_critical, "stages": result.stages,
                          "timings": result.timings, "energy_drift": result.energy_drift}))
    else:
        print(f"{case.path}: {result.status}, {result.steps} steps of {result.dt:.4g} s "
              f"(critical {result.dt_critical:.4g} s) to t = {result.t_end:.6g} s")
        print("stages: " + ", ".join(f"{k} {v:.2f} s" for k, v in result.stages.items()))
        print(f"kernel {result.timings['kernel']:.2f} s, total {result.timings['total']:.2f} s,"
              f" energy drift {result.energy_drift:.2e}; history: {result.path}")
    if result.status != "complete":
        print(f"error: run {result.status}", file=sys.stderr)
        return 130 if result.status.endswith("interrupted") else 3
    return 0


def cmd_info(args):
    from pathlib import Path
    from .history import format_summary, summary
    path = Path(args.file)
    if not path.exists():
        raise CaseError(path, "", "file not found")
    try:
        d = summary(path)
    except (OSError, KeyError, ValueError) as exc:
        raise CaseError(path, "", f"not a transient history: {exc}") from None
    print(json.dumps(d) if args.json else format_summary(d))
    return 0


COMMANDS = {"run": cmd_run, "info": cmd_info, "modes": cmd_modes, "compat": cmd_compat, "plot": cmd_plot}


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
