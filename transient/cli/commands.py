"""Command line: `transient SUBCOMMAND CASE [--set KEY.PATH=VALUE ...] [--json]`."""
import argparse
import json
import sys
import time
from pathlib import Path

from .. import __version__
from ..case.loading import load
from ..errors import CaseError


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
    p = sub.add_parser("bench", help="error against run time for a sweep of contact rules: "
                       "fine (reference), fine regularized at each eps, centre, centre "
                       "regularized, greedy at several m, sampled at several tolerances")
    _case_args(p)
    p.add_argument("--pair", help="contact pair to sweep (default: the first)")
    p.add_argument("--eps", default="1e-6,1e-4,1e-3,1e-2", help="eps of the regularized fine "
                   "rule, comma separated (default 1e-6,1e-4,1e-3,1e-2)")
    p.add_argument("--points", help="greedy m, comma separated, 0 the rank of the kept shapes "
                   "(default: the greedy rule's own count r, then r/2, r/4, 4r, 10r below "
                   "the fine rule's count)")
    p.add_argument("--tolerances", default="3e-2,1e-2,3e-3", help="sampling tolerances of "
                   "the sampled rule, regularized at the case's eps, comma separated (default "
                   "3e-2,1e-2,3e-3; empty for none)")
    p.add_argument("--t-end", type=float, help="simulated time [s] (default: the case's)")
    p.add_argument("--out", metavar="DIR", help="directory of bench.csv, bench.json and "
                   "bench.png (default: <case name>_bench next to the case)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    _plot_parser(sub)
    p = sub.add_parser("export", help="a history as time series for ParaView: the contact "
                       "points of each pair (gap, pressure) and, if output.field was stored, "
                       "the displacement on the mesh")
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("--out", metavar="DIR", help="directory of the files (default: next to the "
                   "history, <name>_export)")
    p.add_argument("--format", choices=("xdmf", "vtu"), default="xdmf", help="xdmf: one "
                   ".xdmf (+ .h5) per series; vtu: one .vtu per row and a .pvd collection "
                   "(default xdmf)")
    p.add_argument("--every", type=int, default=1, metavar="K", help="export one stored row "
                   "in K, and the last one (default 1)")
    p.epilog = ("The displacement field rebuilds the model's mesh from the case text kept in "
                "the history; a reduced run stores its basis with the state (output.field).")
    return parser


def _plot_parser(sub):
    """`transient plot KIND ...`: one sub-subcommand per kind of picture."""
    kinds = sub.add_parser("plot", help="pictures (PNG) of a case or a history").add_subparsers(
        dest="kind", required=True)
    p = kinds.add_parser("compat", help="compatibility of each contact pair: shapes, singular "
                         "values and C(eps), raw and regularized gap observation")
    _case_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="directory of the PNG files")
    p.add_argument("--pair", metavar="NAME", help="only this contact pair")
    p.add_argument("--shapes", metavar="I,J,...", help="shape numbers to draw, from 1 by "
                   "increasing incompatibility (default: the first, the last kept, two beyond)")
    series = ("scalar series to draw: full names (sensors/tip, energy/kinetic) or groups "
              "(sensors, energy); default: every sensor")
    p = kinds.add_parser("history", help="time histories of a history's sensors (or energy "
                         "terms), time in ms")
    _history_args(p, "history")
    p.add_argument("--series", nargs="+", metavar="NAME", help=series)
    p = kinds.add_parser("spectrum", help="amplitude spectra (Hann window, one-sided, log "
                         "amplitude) of a history's sensors, frequency in kHz")
    _history_args(p, "spectrum")
    p.add_argument("--series", nargs="+", metavar="NAME", help=series)
    p.add_argument("--fmax", type=float, metavar="HZ", help="highest frequency drawn [Hz] "
                   "(default: half the sample rate)")
    p = kinds.add_parser("frf", help="transfer function between two series of a history: "
                         "H1 = Pxy / Pxx from Welch averages, magnitude, phase and coherence")
    _history_args(p, "frf")
    p.add_argument("--input", required=True, metavar="NAME", help="input series, e.g. "
                   "sensors/tip")
    p.add_argument("--output", required=True, metavar="NAME", help="output series, e.g. "
                   "sensors/tail")
    p.add_argument("--segment", type=int, metavar="SAMPLES", help="samples per Welch segment "
                   "(default: the largest power of two up to a quarter of the rows)")
    p.add_argument("--fmax", type=float, metavar="HZ", help="highest frequency drawn [Hz] "
                   "(default: half the sample rate)")
    p = kinds.add_parser("pressure", help="contact pressure maps on Gamma, one panel per "
                         "history side by side with one colour scale (e.g. fine, centre and "
                         "regularized rules)")
    p.add_argument("file", nargs="+", help="HDF5 files written by transient run with "
                   "output.contact = true")
    p.add_argument("--pair", metavar="NAME", help="contact pair (default: the first stored)")
    p.add_argument("--time", type=float, metavar="T", help="time [s]: each panel shows its "
                   "stored row nearest to it (default: the time of the largest total contact "
                   "force in the first file)")
    p.add_argument("--labels", nargs="+", metavar="TEXT", help="one title per file (default: "
                   "the file names)")
    p.add_argument("-o", "--png", metavar="PNG", help="picture to write (default: next to "
                   "the first file, <name>_pressure.png)")


def _history_args(p, kind):
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("-o", "--png", metavar="PNG", help="picture to write (default: next to "
                   f"the history, <name>_{kind}.png)")


def cmd_plot(args):
    return {"compat": _plot_compat, "history": _plot_history, "spectrum": _plot_spectrum,
            "frf": _plot_frf, "pressure": _plot_pressure}[args.kind](args)


def _plot_history(args):
    from ..plots.history import history_figure, select_series
    from ..io.stored import open_history
    stored = open_history(args.file)
    names = select_series(stored, args.series)
    path = _png_path(args, stored.path)
    _save(lambda: history_figure(stored, names, path), path)
    return 0


def _plot_spectrum(args):
    from ..plots.history import select_series, spectrum_figure
    from ..io.stored import open_history
    stored = open_history(args.file)
    _check_fmax(stored, args.fmax)
    names = select_series(stored, args.series)
    path = _png_path(args, stored.path)
    _save(lambda: spectrum_figure(stored, names, path, args.fmax), path)
    return 0


def _plot_frf(args):
    from ..plots.history import MIN_SEGMENT, frf_figure, one_series
    from ..io.stored import open_history
    stored = open_history(args.file)
    _check_fmax(stored, args.fmax)
    source = one_series(stored, args.input, "--input")
    response = one_series(stored, args.output, "--output")
    if args.segment is not None and args.segment < MIN_SEGMENT:
        raise CaseError(stored.path, "--segment", f"expected at least {MIN_SEGMENT} samples, "
                        f"got {args.segment}")
    path = _png_path(args, stored.path)
    _save(lambda: frf_figure(stored, source, response, path, args.segment, args.fmax), path)
    return 0


def _check_fmax(stored, fmax):
    if fmax is not None and not fmax > 0:
        raise CaseError(stored.path, "--fmax", f"expected a frequency > 0 [Hz], got {fmax}")


def _plot_pressure(args):
    from ..plots.history import pressure_figure, pressure_panels
    from ..io.stored import open_history
    histories = [open_history(f) for f in args.file]
    if args.labels is not None and len(args.labels) != len(histories):
        raise CaseError(histories[0].path, "--labels", f"expected one label per file "
                        f"({len(histories)}), got {len(args.labels)}")
    path = _png_path(args, histories[0].path)
    panels = pressure_panels(histories, args.pair, args.time, args.labels)
    _save(lambda: pressure_figure(panels, path), path)
    return 0


def _png_path(args, history):
    from pathlib import Path
    return Path(args.png) if args.png else history.with_name(
        f"{history.stem}_{args.kind}.png")


def _save(draw, path):
    try:
        draw()
    except OSError as exc:
        raise CaseError(path, "-o", f"cannot write the picture: {exc}") from None
    print(path)


def cmd_export(args):
    from ..io.export import export
    try:
        paths = export(args.file, args.out, args.format, args.every)
    except OSError as exc:
        raise CaseError(args.out or args.file, "--out", f"cannot write: {exc}") from None
    print("\n".join(str(p) for p in paths))
    return 0


def _plot_compat(args):
    from ..contact.pair import build_pair
    from ..model.model import build_model
    from ..plots.compat import RenderingUnavailable, check_shapes, parse_shapes, plot_compat
    try:
        shapes = parse_shapes(args.shapes) if args.shapes is not None else None
    except ValueError as exc:
        raise CaseError(args.case, "--shapes", str(exc)) from None
    case = load(args.case, args.overrides)
    names = list(case.contact)
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
    from ..contact.pair import build_contact, contact_stiffness
    from ..mesh.meshfile import write_vtu
    from ..model.model import build_model
    from ..solve.modes import normal_modes
    t0 = time.perf_counter()
    case = load(args.case, args.overrides)
    model = build_model(case)
    pairs = build_contact(case, model)
    # contact enters the modes as tied (bilateral linear) springs of density k on the pair's rule
    K = model.K + contact_stiffness(pairs, model.ndof) if pairs else model.K
    settings = case.solver.modes
    modes = normal_modes(K, model.M, model.fixed, settings.count, settings.fmax,
                         settings.shift, case.solver.linear_solver)
    stage_times = {f"contact.{p.name}.{k}": v for p in pairs for k, v in p.timings.items()}
    timings = {**model.timings, **stage_times, **modes.timings,
               "total": time.perf_counter() - t0}
    if case.output.vtu:
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
    out = {"pair": pair.name, "rule": pair.spec.rule, "regularized": pair.spec.regularized,
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
    write_vtu(case.directory / case.output.vtu, model.mesh(), point_data=data)


def cmd_compat(args):
    import numpy as np
    from ..contact.pair import build_pair
    from ..model.model import build_model
    t0 = time.perf_counter()
    case = load(args.case, args.overrides)
    names = list(case.contact)
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
    print(f"{case.path}: contact pair '{name}': {pair.spec.surface1} / {pair.spec.surface2}")
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


def _model_line(meta):
    """What was integrated: the reduced model's size and each pair's contact points."""
    parts = []
    if meta.get("reduced_dofs"):
        parts.append(f"reduced model {meta['reduced_dofs']} dofs")
    for name, p in meta.get("pairs", {}).items():
        of = f" of {p['candidates']}" if p.get("candidates") else ""
        parts.append(f"{name}: {p['rule']} rule, {p['points']}{of} points")
    if "sampling" in meta:
        parts.append(f"sampling residual {meta['sampling']['residual']:.1e} on "
                     f"{meta['sampling']['band_modes']} modes")
    return "; ".join(parts)


def cmd_run(args):
    import os
    from pathlib import Path
    from ..run import run
    case = load(args.case, args.overrides)
    path = Path(args.output) if args.output else case.directory / (
        case.output.file or Path(case.path).with_suffix(".h5").name)
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
        model = _model_line(result.meta or {})
        if model:
            print(model)
        print(f"kernel {result.timings['kernel']:.2f} s, total {result.timings['total']:.2f} s,"
              f" energy drift {result.energy_drift:.2e}; history: {result.path}")
    if result.status != "complete":
        print(f"error: run {result.status}", file=sys.stderr)
        return 130 if result.status.endswith("interrupted") else 3
    return 0


def cmd_info(args):
    from ..io.history import format_summary
    from ..io.stored import read_summary
    d = read_summary(args.file)
    print(json.dumps(d) if args.json else format_summary(d))
    return 0


def _numbers(text, key, kind):
    try:
        return [kind(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CaseError("command line", key, f"expected comma separated numbers, got "
                        f"'{text}'") from None


def cmd_bench(args):
    from ..studies.bench import HEADER, bench, format_row, target, write
    eps = _numbers(args.eps, "--eps", float)
    points = _numbers(args.points, "--points", int) if args.points else None
    tolerances = _numbers(args.tolerances, "--tolerances", float)
    if not args.json:
        print(HEADER)

    def show(row):
        if not args.json:
            print(format_row(row), flush=True)
    rows = bench(args.case, args.overrides, args.pair, eps, points, args.t_end, show,
                 tolerances)
    out = args.out or Path(args.case).with_name(Path(args.case).stem + "_bench")
    files = write(rows, out)
    best = target(rows)
    if args.json:
        print(json.dumps({"rows": rows, "target": best}))
        return 0
    if best:
        print(f"target met: {best['label']} within {best['error_rms']:.2%} of the fine rule at "
              f"{best['kernel_s'] / rows[0]['kernel_s']:.2f} of its kernel time")
    else:
        print("target not met: no regularized coarse rule within 1% of the fine rule at a "
              "third or less of its kernel time")
    print("wrote " + ", ".join(str(f) for f in files))
    return 0


COMMANDS = {"run": cmd_run, "info": cmd_info, "modes": cmd_modes, "compat": cmd_compat,
            "bench": cmd_bench, "plot": cmd_plot, "export": cmd_export}


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
    except BrokenPipeError:
        # the reader of the output went away (`transient info F | head`): nothing to report
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
