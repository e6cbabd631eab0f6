"""`transient plot KIND` and `transient export`: pictures and ParaView files of a case or a
history; the drawing lives in transient/plots, the files in transient/io."""
import sys
from pathlib import Path

from ..case.checks import check_two_surfaces
from ..case.loading import load
from ..errors import CaseError


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
    for name in names:
        if args.pair in (None, name):
            check_two_surfaces(case, name)
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
