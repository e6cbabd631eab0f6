"""Command line: `transient SUBCOMMAND CASE [--set KEY.PATH=VALUE ...] [--json]`."""
import json
import os
import sys
import time

from .. import api, progress
from ..settings import configure
from ..errors import CaseError, FactorizationError, stop_reason
from .benching import cmd_bench
from .parser import build_parser
from .plotting import cmd_export, cmd_plot
from .sweeping import cmd_sweep


def cmd_modes(args):
    t0 = time.perf_counter()
    case = api.load(args.case, args.overrides)
    if args.dry_run:
        return _dry(case, "modes", args.json)
    result = api.modes(case)
    timings = {**result.timings, "total": time.perf_counter() - t0}
    tie, contact = result.tie, result.contact
    if args.json:
        print(json.dumps({**result.summary(), "timings": timings}))
        return 0
    print(f"{case.path}: {result.ndof} dofs ({result.free_dofs} free), "
          f"{result.parts} part(s), factorization: {result.backend}")
    for c in contact:
        print(f"  contact {c['pair']}: {_tie_text(tie, c)}, rule {c['rule']} "
              f"({c['points']} points)" + (f", regularized eps = {c['eps']:.3g}"
                                           if c["regularized"] else ""))
    print(f"{'mode':>5} {'frequency [Hz]':>16}")
    for i, f in enumerate(result.frequencies, 1):
        print(f"{i:>5} {f:16.6g}")
    print("time: " + ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return 0


def _tie_text(tie, pair):
    if tie.kind == "exact":
        return (f"tied exactly (the gap held at zero on {tie.held} directions of the rows, "
                f"of the {tie.dofs} dofs they touch)")
    if tie.kind == "preload":
        return f"at the preload ({tie.preload.iterations} Newton iterations), law {pair['law']}"
    return f"tied, k = {pair['k']:.3g} Pa/m"


def _parts(args, quiet=False):
    """The API's keywords of where the components path reduces its parts, and a line on
    standard error as each part is reduced (unless quiet) and, on a terminal, as each stage
    of the setup ends: a long setup says where it is and what it holds."""
    def on_part(name, seconds, cached):
        print(f"part {name}: " + ("read back from the cache" if cached
                                  else f"reduced in {seconds:.1f} s"), file=sys.stderr)

    def on_stage(name, seconds, peak_gb):
        print(f"stage {name}: {seconds:.1f} s, peak {peak_gb:.2f} GB", file=sys.stderr)
    return {"workers": args.workers, "scheduler": args.scheduler, "cache": args.cache,
            "on_part": None if quiet else on_part,
            "on_stage": None if quiet or not _interactive() else on_stage}


def _interactive():
    return sys.stderr.isatty() and not os.environ.get("CI")


def _load_for_parts(args):
    """The case, its memory bounded for where --workers and --scheduler reduce the parts; a
    line on standard error where "auto" chose the assembled path and they go unused."""
    case = api.load(args.case, args.overrides, args.workers, args.scheduler)
    given = [o for o, v in (("--workers", args.workers), ("--scheduler", args.scheduler),
                            ("--cache", args.cache)) if v]
    if given and case.reduction_auto and not case.solver.reduction.components:
        print(f"{', '.join(given)}: not used: {case.reduction_auto}", file=sys.stderr)
    return case


def cmd_cea(args):
    t0 = time.perf_counter()
    case = _load_for_parts(args)
    if args.dry_run:
        return _dry(case, "cea", args.json, args)
    result = api.cea(case, **_parts(args))
    modes = result.modes
    total = time.perf_counter() - t0
    if args.json:
        print(json.dumps({**result.summary(), "total": total}))
        return 0
    friction = {n: c.friction for n, c in case.contact.items() if c.friction.active}
    what = "full model (shift-invert Arnoldi)"
    if result.reduced:
        notes = _basis_notes(result.meta)
        what = f"reduced model {result.reduced} dofs" + (f" ({'; '.join(notes)})" if notes
                                                          else "")
    print(f"{case.path}: {result.ndof} free dofs, {what}, complex modes to "
          f"{result.fmax:g} Hz; " + (", ".join(
              f"contact {n}: mu = {f.mu:g}" if not f.speeds else f"contact {n}: mu(v) table"
              for n, f in friction.items()) or "no friction"))
    print(f"{'mode':>5} {'frequency [Hz]':>16} {'real [1/s]':>14} {'damping ratio':>14}")
    for i, row in enumerate(modes.table(), 1):
        mark = "  unstable" if row["unstable"] else ""
        print(f"{i:>5} {row['frequency_hz']:16.6g} {row['real']:14.5g} "
              f"{row['damping_ratio']:14.4e}{mark}")
    above = (f" (growing faster than {modes.threshold:g} 1/s, cea.threshold.growth_rate)"
             if modes.threshold > 0 else "")
    print(f"{int(modes.unstable.sum())} unstable mode(s) below {result.fmax:g} Hz{above}")
    for row in result.shapes:
        parts = ", ".join(f"{p} {100 * v:.0f}%" for p, v in row["shares"].items())
        nd = "".join(f"; {p}: {_motion_text(d)}"
                     for p, d in row.get("nodal_diameters", {}).items())
        own = "".join(f"; {p}: like its mode {d['mode']} alone "
                      f"({d['frequency_hz']:.0f} Hz, MAC {d['mac']:.2f})"
                      for p, d in row.get("part_modes", {}).items())
        residual = (f"; residual {row['residual']:.1e} of the full model's equations"
                    if "residual" in row else "")
        print(f"  mode {row['mode']} at {row['frequency_hz']:.1f} Hz: kinetic energy "
              f"{parts}{nd}{own}{residual}")
    if result.files:
        # the CSV, then a VTU file and its collection per mode described
        table, numbers = result.files[0], ", ".join(str(r["mode"]) for r in result.shapes)
        stem = table.parent / table.name[:-len("_modes.csv")]
        print(f"files: {table}" + (f"; {stem}_mode_NNN.vtu and .pvd for mode(s) {numbers}"
                                   if result.shapes else ""))
    print("stages: " + ", ".join(f"{k} {v:.2f} s" for k, v in result.stages.items())
          + f"; total {total:.2f} s")
    return 0


def _motion_text(d):
    """What a rotating part does in a mode (stability.diameters.disc_motion's dict)."""
    what = f"{d['motion']} (axial {100 * d['axial_share']:.0f}% of its kinetic energy)"
    if d["motion"] == "out-of-plane":
        return (f"{what}, {d['order']} nodal diameters ({100 * d['share']:.0f}% of its axial "
                "motion)")
    if d["motion"] == "in-plane":
        return (f"{what}, {d['order']} nodal diameters of its radial and tangential motion "
                f"({100 * d['share']:.0f}% of it)")
    return what


def cmd_compat(args):
    import numpy as np
    t0 = time.perf_counter()
    case = api.load(args.case, args.overrides)
    result = api.compat(case, args.pair)
    pair, comp, setup = result.pair, result.compatibility, result.setup_s
    fine, name = pair.interface.fine, pair.name
    out = result.summary(np.logspace(-16, 0, 65))
    out["timings"]["total"] = time.perf_counter() - t0
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


def _basis_notes(meta):
    """What the model line says of a reduced basis: its modes' reach, the parts reduced on
    their own, their interfaces' loads and fields (reduce.fields) and the fields' statics
    error (the largest flexibility dropped), its band
    modes' residual in the whole model (from meta or a history's attributes, any of which may
    be missing)."""
    notes = []
    if meta.get("modes_fmax_hz"):
        notes.append(f"its modes to {meta['modes_fmax_hz']:g} Hz")
    if meta.get("reduction_auto"):
        notes.append(meta["reduction_auto"])
    if meta.get("reduction_method") == "components":
        notes.append("each part reduced on its own")
        interfaces = (meta.get("basis_timings") or {}).get("part_interfaces") or {}
        if interfaces:
            worst = max(i["statics_error"] for i in interfaces.values())
            loads = sum(i["loads"] for i in interfaces.values())
            fields = sum(i.get("fields", i["loads"]) for i in interfaces.values())
            notes.append(f"its interfaces' {loads} contact loads as {fields} fields, their "
                         f"statics within {worst:.1e} of the contact's flexibility")
    if meta.get("band_residual") is not None:
        notes.append(f"its band modes' residual in the whole model {meta['band_residual']:.1e}")
    return notes


def _model_line(meta):
    """What was integrated: the reduced model's size and each pair's contact points (from a
    resumed history's attributes, any of which may be missing)."""
    parts = []
    if meta.get("reduced_dofs"):
        asked, kept = meta.get("static_shapes", (0, 0))
        to = (f" to {meta['modes_fmax_hz']:g} Hz" if meta.get("modes_fmax_hz") else "")
        parts.append(f"reduced model {meta['reduced_dofs']} dofs "
                     f"({meta.get('normal_modes', '?')} modes{to} and {kept} of {asked} static "
                     "shapes" + ("; the others lie in the span of the rest" if kept < asked
                                 else "") + "".join(f"; {n}" for n in _basis_notes(meta)[
                                     1 if meta.get("modes_fmax_hz") else 0:]) + ")")
    for name, mu in (meta.get("basis_mu") or {}).items():
        parts.append(f"its basis and sampled points made at mu = {mu:g} on {name}, then given "
                     "this preload")
    for name, p in (meta.get("pairs") or {}).items():
        of = f" of {p['candidates']}" if p.get("candidates") else ""
        parts.append(f"{name}: {p.get('rule', '?')} rule, {p.get('points', '?')}{of} points"
                     + _gap_text(p.get("gap0")))
    if "sampling" in meta:
        parts.append(f"sampling residual {meta['sampling']['residual']:.1e} on "
                     f"{meta['sampling']['band_modes']} modes")
    factorized = {**meta.get("factorizations", {})}
    if "iteration_operator" in meta:
        factorized["iteration operator"] = meta["iteration_operator"].get("why", "?")
    line = "; ".join(parts)
    if factorized:
        line += ("\n" if line else "") + "factorizations: " + ", ".join(
            f"{k} {v}" for k, v in factorized.items())
    return line


def _gap_text(gap0):
    """', initial gap MIN to MAX m (S% of the area overclosed)' of a pair's meta (none in a
    history written before the gaps were measured)."""
    if not isinstance(gap0, dict):
        return ""
    return (f", initial gap {gap0['min']:.3g} to {gap0['max']:.3g} m "
            f"({100 * gap0['overclosed']:.3g}% of the area overclosed)")


def cmd_run(args):
    case = _load_for_parts(args)
    if args.dry_run:
        return _dry(case, "run", args.json, args)
    quiet = args.quiet or args.json or not _interactive()
    result = api.run(case, args.output, resume=args.resume, progress=not quiet,
                     key="-o" if args.output else None, **_parts(args, quiet))
    if args.json:
        print(json.dumps(result.summary()))
    else:
        step = f"{result.dt:.4g} s"
        if result.subdivisions:
            step = (f"{2 * result.subdivisions[0]['dt']:.4g} s subdivided to {step} "
                    f"from t = {result.subdivisions[0]['t']:.6g} s")
        why = f" ({result.dt_reason})" if result.dt_reason else ""
        print(f"{case.path}: {result.status}, {result.steps} steps of {step}{why} to "
              f"t = {result.t_end:.6g} s")
        print("stages: " + ", ".join(f"{k} {v:.2f} s" for k, v in result.stages.items()))
        model = _model_line(result.meta or {})
        if model:
            print(model)
        print(f"kernel {result.timings['kernel']:.2f} s, total {result.timings['total']:.2f} s,"
              f"{_peak_line(result.meta or {})} energy drift {result.energy_drift:.2e}; "
              f"history: {result.path}")
    if result.status != "complete":
        print(f"error: run {result.status}", file=sys.stderr)
        if result.status.endswith("interrupted"):
            return 130
        return 143 if "terminated" in result.status else 3
    return 0


def _dry(case, command, as_json, args=None):
    """--dry-run: what the command would take (api.dry_run), said, then exit 0; args: the
    command's --workers, --scheduler and --cache, where it has them; a calibration said."""
    where = {} if args is None else {"workers": args.workers, "scheduler": args.scheduler,
                                     "cache": args.cache}
    with progress.shown(not as_json):
        d = api.dry_run(case, command, **where)
    if as_json:
        print(json.dumps(d))
        return 0
    print(f"{case.path}: {command} would take {d['dofs']} dofs ({d['free_dofs']} free)")
    for name, p in d["parts"].items():
        pieces = f", in {p['pieces']} pieces" if p["pieces"] > 1 else ""
        print(f"  part {name}: {p['dofs']} dofs ({p['free_dofs']} free), {p['cells']} cells"
              f"{pieces}")
    for name, p in d["pairs"].items():
        print(f"  contact {name}: {p['fine_points']} fine points" + _gap_text(p["gap0"]))
    for line in _memory_lines(d["memory"]):
        print("  " + line)
    if "steps" in d:
        s = d["steps"]
        print("  steps: " + (f"{s['steps']}" if s["exact"] else
                             f"at least {s['steps']} (the automatic step, at most 1/(20 "
                             "solver.reduction.fmax))" if s["steps"] is not None else
                             "set by the setup's critical step (central differences)"))
    if "setup_seconds" in d:
        t = d["setup_seconds"]
        source = (f"{t['setups']} setup(s) of its kind timed on this machine" if t and
                  t["source"] == "setups" else "this machine's calibration")
        print("  setup: " + (f"about {_duration(t['low'])} to {_duration(t['high'])} (from "
                             f"{source})" if t else "no estimate (TRANSIENT_SETUP_LOG is off, "
                             "or this machine's calibration failed)"))
    print("nothing factorized or written (--dry-run)")
    return 0


def _memory_lines(m):
    """What the dry run says of the memory: the path "auto" chose, and each process's
    estimate against its bound."""
    lines = [m["auto"]] if m["auto"] else []
    terms = ", ".join(f"{what} {gb:.3g} GB" for what, gb in m["terms_gb"].items())
    who = " this process, the cluster's client," if m["client"] else ""
    lines.append(f"memory:{who} about {m['estimate_gb']:.3g} GB"
                 + (f" ({terms})" if terms else "") + f", limits.memory {m['limit_gb']:.3g} GB")
    if m["client"]:
        bound = (f", each worker's share of limits.memory {m['budget_gb']:.3g} GB"
                 if m["budget_gb"] is not None else ", checked against the scheduler's "
                 "workers once reached")
        piece = f"a piece of {m['worker_pieces']} of " if m["worker_pieces"] > 1 else ""
        lines.append(f"memory: a worker about {m['worker_gb']:.3g} GB at most (the "
                     f"reduction of {piece}{m['worker_part']}{bound})")
    if m["disk_gb"]:
        lines.append(f"disk: the parts' bases about {m['disk_gb']:.3g} GB in files of the "
                     "temporary directory (TMPDIR), removed at the end")
    return lines


def _duration(seconds):
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def _peak_line(meta):
    """' setup peak memory X GB (in STAGE),': the first stage that reached the setup's peak."""
    peaks = meta.get("peak_rss_gb") or {}
    if not peaks:
        return ""
    top = max(peaks.values())
    stage = next(name for name, gb in peaks.items() if gb == top)
    return f" setup peak memory {top:.2f} GB (in {stage}),"


def cmd_info(args):
    from .report import format_summary
    d = api.summary(args.file)
    print(json.dumps(d) if args.json else format_summary(d))
    return 0


COMMANDS = {"run": cmd_run, "info": cmd_info, "modes": cmd_modes, "cea": cmd_cea,
            "compat": cmd_compat,
            "bench": cmd_bench, "plot": cmd_plot, "export": cmd_export, "sweep": cmd_sweep}


def main(argv=None):
    args = build_parser().parse_args(argv)
    # the command line as given: a campaign's lock names it
    args.argv = list(sys.argv[1:] if argv is None else argv)
    try:
        # the setup's long inner work drawn as bars on a terminal, not into a JSON reader's
        with progress.shown(_interactive() and not getattr(args, "json", False)):
            return COMMANDS[args.command](args)
    except CaseError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except FactorizationError as exc:
        # a singular or indefinite stiffness: what the case says of it is what to check
        print(f"error: {getattr(args, 'case', '')}: constraints, contact.NAME.k: the stiffness "
              f"cannot be factorized ({exc}): a part free to move, or a contact stiffness far "
              "beyond the structure's", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, SystemError) as exc:
        reason = stop_reason(exc)
        if not reason:
            raise
        # a SIGTERM taken over the setup ends it as Ctrl-C does, under its own name and code
        print(reason, file=sys.stderr)
        return 143 if reason.startswith("terminated") else 130
    except BrokenPipeError:
        # the reader of the output went away (`transient info F | head`): nothing to report
        sys.stderr.close()
        return 0


def console(argv=None):
    """main as a process, with the settings that speed it up (transient.configure): its code
    is the process's exit status. A stop (130, 143) leaves through os._exit once the output is
    flushed and every history closed (main has returned): CPython kills itself with SIGINT
    at exit, status -2 instead of 130, when a KeyboardInterrupt once left code it ran through
    PyRun_* (an import's), even when caught after (seen in CI)."""
    configure()
    code = main(argv)
    if code in (130, 143):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


if __name__ == "__main__":
    sys.exit(console())
