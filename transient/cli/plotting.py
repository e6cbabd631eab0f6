"""`transient plot KIND` and `transient export`: pictures and ParaView files of a case or a
history; the numbers come from the API (transient.api), the drawing from transient/plots."""
import sys
from pathlib import Path

import numpy as np

from .. import api
from ..errors import CaseError


def cmd_plot(args):
    return {"compat": _plot_compat, "history": _plot_history, "spectrum": _plot_spectrum,
            "frf": _plot_frf, "pressure": _plot_pressure, "cea": _plot_cea,
            "spectrogram": _plot_spectrogram, "envelope": _plot_envelope,
            "friction": _plot_friction, "sweep": _plot_sweep,
            "modal-frf": _plot_modal_frf, "modal-growth": _plot_modal_growth}[args.kind](args)


def _plot_sweep(args):
    from ..plots.sweep import sweep_figures
    try:
        paths = sweep_figures(args.directory, args.x, args.png)
    except OSError as exc:
        raise CaseError(args.png or args.directory, "-o", f"cannot write the picture: "
                        f"{exc}") from None
    print("\n".join(str(p) for p in paths))
    return 0


def _plot_friction(args):
    from ..plots.friction import friction_figure, friction_series
    stored = api.history(args.file)
    series = friction_series(stored, args.pair)
    path = _png_path(args, stored.path)
    rows = []
    _save(lambda: rows.append(friction_figure(stored, series, path, args.time)), path)
    t, row = series["time"], rows[0]
    p_in, p_diss = series["input"], series["dissipated"]
    print(f"friction on '{series['pair']}': mean input {p_in.mean():.6g} W, mean dissipation "
          f"{p_diss.mean():.6g} W over {t[0]:.6g}-{t[-1]:.6g} s; at t = {t[row]:.6g} s "
          + ", ".join(f"{name} {100 * x:.3g}%" for name, x in
                      zip(("open", "stick", "slip"), series["shares"][row]))
          + " of the contact area")
    return 0


def _plot_spectrogram(args):
    from ..plots.history import MIN_SEGMENT, one_series, select_series, spectrogram_figure
    stored = api.history(args.file)
    _check_fmax(stored, args.fmax)
    name = (one_series(stored, args.series, "--series") if args.series
            else select_series(stored, None)[0])
    if args.segment is not None and args.segment < MIN_SEGMENT:
        raise CaseError(stored.path, "--segment", f"expected at least {MIN_SEGMENT} samples, "
                        f"got {args.segment}")
    path = _png_path(args, stored.path)
    _save(lambda: spectrogram_figure(stored, name, path, args.segment, args.fmax), path)
    return 0


def _pair_of(stored, text, key, what):
    """'A:B' -> (a, b) floats with a < b, or None."""
    if text is None:
        return None
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise stored.error(key, f"expected {what} as A:B, got '{text}'") from None
    if not a < b:
        raise stored.error(key, f"expected A < B, got '{text}'")
    return a, b


def _plot_envelope(args):
    from ..plots.history import envelope_figure, select_series
    stored = api.history(args.file)
    names = select_series(stored, args.series)
    window = _pair_of(stored, args.window, "--window", "times [s]")
    band = _pair_of(stored, args.band, "--band", "frequencies [Hz]")
    path = _png_path(args, stored.path)
    fits = {}
    _save(lambda: fits.update(envelope_figure(stored, names, path, window, band)), path)
    for name, (sigma, (t0, t1), rms) in fits.items():
        print(f"{name}: growth rate {sigma:.6g} 1/s over {t0:.6g}-{t1:.6g} s (log-envelope "
              f"RMS deviation {rms:.2g})")
    return 0


def _plot_modal_growth(args):
    from ..io.lock import check_writable
    from ..plots.growth import growth_figure, growth_rows, write_growth_csv
    stored = api.history(args.file)
    window = _pair_of(stored, args.window, "--window", "times [s]")
    if args.tolerance is not None and not args.tolerance > 0:
        raise CaseError(stored.path, "--tolerance", f"expected an RMS > 0, got "
                        f"{args.tolerance}")
    path = _png_path(args, stored.path)
    table = Path(args.csv) if args.csv else path.with_suffix(".csv")
    check_writable(path, "-o")
    check_writable(table, "--csv")
    result = api.modal_growth(stored.path, window=window, tolerance=args.tolerance)
    print(f"modes of the run's linearization to the band's top, fitted from "
          f"{result.free_from:.6g} s over the linear phase to {result.linear_end:.6g} s "
          f"(rows every {result.stride:.4g} s)")
    print("CEA: its real part; run: the run's own linearization's; fit: the projection's growth, "
          "resolution: the slowest rate its window tells from neutral")
    print(f"{'f [Hz]':>10} {'CEA [1/s]':>11} {'run [1/s]':>11} {'fit [1/s]':>11} "
          f"{'resol.':>7} {'diff':>8} {'window [ms]':>15} {'rms':>7}")
    for row in growth_rows(result):
        cea = "-" if row["cea_real"] is None else f"{row['cea_real']:.5g}"
        if row["excited"]:
            diff = "-" if row["difference"] is None else f"{100 * row['difference']:+.2f}%"
            fit = (f"{row['growth']:11.5g} {row['resolution']:7.2g} {diff:>8} "
                   f"{1e3 * row['t0']:7.3f}-{1e3 * row['t1']:<7.3f} {row['rms']:7.2g}"
                   + ("" if row["resolved"] else "  unresolved"))
        else:
            fit = f"{'not excited above the floor':>11}"
        print(f"{row['frequency_hz']:10.1f} {cea:>11} {row['run_real']:11.5g} {fit}"
              + ("  (CEA: unstable)" if row["cea_unstable"] else ""))
    try:
        write_growth_csv(result, table)
    except OSError as exc:
        raise CaseError(table, "--csv", f"cannot write: {exc}") from None
    print(table)
    _save(lambda: growth_figure(result, path, f"{stored.path.name}: modal amplitudes on the "
                                "complex modes at the preload (dashed: fits)"), path)
    return 0


def parse_values(text):
    """'START:STOP:COUNT' (COUNT values, ends included) or 'A,B,...' -> finite floats, at most
    a sweep's MAX_VARIANTS of them (each is one analysis), counted before any list is built;
    ValueError saying what was expected."""
    from ..campaign.variants import MAX_VARIANTS
    if ":" in text:
        parts = text.split(":")
        try:
            start, stop = (_finite(x) for x in parts[:2]) if len(parts) == 3 else (None, None)
            count = int(parts[2]) if len(parts) == 3 else None
            _finite(stop - start)
        except (ValueError, TypeError, OverflowError):
            count = None
        if count is None:
            raise ValueError(f"expected START:STOP:COUNT (two finite numbers and an integer "
                             f"count), got {_quoted(text)}")
        if not 1 <= count <= MAX_VARIANTS:
            raise ValueError(f"expected a COUNT from 1 to {MAX_VARIANTS} (each value is one "
                             f"analysis), got {_quoted(parts[2])}")
        return [float(x) for x in np.linspace(start, stop, count)]
    if text.count(",") >= MAX_VARIANTS:
        raise ValueError(f"expected at most {MAX_VARIANTS} values (each is one analysis), got "
                         f"{text.count(',') + 1}")
    try:
        return [_finite(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"expected finite numbers separated by commas, or START:STOP:COUNT, "
                         f"got {_quoted(text)}") from None


def _quoted(text, most=60):
    """'text' in a message, its middle cut when long."""
    return f"'{text}'" if len(text) <= most else f"'{text[:most // 2]}...{text[-most // 4:]}'"


def _finite(text):
    value = float(text)
    if not np.isfinite(value):
        raise ValueError(text)
    return value


def _plot_cea(args):
    from ..plots.branches import branches_figure
    from ..plots.cea import mode_figure, out_of_plane, stability_figure
    from ..plots.render import RenderingUnavailable
    case = api.load(args.case, args.overrides)
    names = list(case.contact)
    pair = args.pair or (names[0] if names else None)
    if pair is None or pair not in names:
        raise CaseError(case.path, "contact", f"no pair '{pair}' to vary mu on (pairs: "
                        f"{', '.join(names) or 'none'})")
    mus = []
    if args.mu is not None:
        try:
            mus = parse_values(args.mu)
        except ValueError as exc:
            raise CaseError(case.path, "--mu", str(exc)) from None
        if not mus or min(mus) < 0:
            raise CaseError(case.path, "--mu", "expected friction coefficients >= 0")
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CaseError(case.path, "--out", f"cannot create: {exc}") from None
    stem = Path(case.path).stem
    # the map's values share their stages (api.mu_map), each checked at load before any
    analyses = api.mu_map(case, mus, pair) if mus else []
    result, own = api.cea(case), case.contact[pair].friction.mu
    paths = [out / f"{stem}_stability.png"]
    stability_figure(result, paths[0], f"{stem}: complex modes at mu = {own:g}")
    direction, along = out_of_plane(case, result.model)
    try:
        for row in result.shapes:
            j = row["mode"] - 1
            path = out / f"{stem}_mode_{row['mode']:03d}.png"
            mode_figure(result.model, result.displacement(j), path,
                        f"mode {row['mode']}, {row['frequency_hz']:.0f} Hz, "
                        f"real {row['real']:.3g} 1/s", direction, args.colour, along)
            paths.append(path)
    except RenderingUnavailable as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    if mus:
        path = out / f"{stem}_mu_map.png"
        found = api.branches(mus, analyses)
        branches_figure(found, path, f"{stem}: complex modes against mu ({pair})",
                        "friction coefficient mu")
        paths += [path] + found.write(out / f"{stem}_mu_map_unstable.csv",
                                      out / f"{stem}_mu_map_coupling.csv")
    print("\n".join(str(p) for p in paths))
    return 0


def _plot_modal_frf(args):
    from ..io.lock import check_writable
    from ..plots.modal import modal_frf_figure
    case = api.load(args.case, args.overrides)
    against = api.load(args.case, args.overrides + args.against)
    labels = args.labels or ["case", " ".join(args.against) or "case"]
    if len(labels) != 2:
        raise CaseError(case.path, "--labels", f"expected two labels, got {len(labels)}")
    path = Path(args.png or f"{Path(case.path).stem}_modal_frf.png")
    check_writable(path, "-o")
    result = api.compare_modes(case, against, args.input, args.output, args.damping,
                               args.fmax)
    fa, fb = result.frequencies
    paired = result.partner >= 0
    by = "order" if np.isnan(result.mac).all() else "MAC"
    print(f"{labels[0]}: {len(fa)} modes ({result.ties[0].kind} tie); {labels[1]}: {len(fb)} "
          f"modes ({result.ties[1].kind} tie); paired by {by}")
    print(f"{'mode':>5} {'f [Hz]':>12} {'partner [Hz]':>13} {'shift [%]':>10} {'MAC':>6}")
    for i, f in enumerate(fa):
        j = result.partner[i]
        print(f"{i + 1:>5} {f:12.6g} " + (f"{fb[j]:13.6g} {result.shifts[i]:10.3f} "
                                          f"{result.mac[i]:6.3f}" if j >= 0 else
                                          f"{'-':>13} {'-':>10} {'-':>6}"))
    s, order = result.shifts[paired], result.by_order
    if len(s):
        # a locked mode may change its shape too: a partner of low MAC is another mode
        alike = paired & (np.nan_to_num(result.mac) >= 0.5)
        print(f"shift of {labels[1]} over {labels[0]}: max {s.max():.3g}%, min {s.min():.3g}%, "
              f"mean {s.mean():.3g}% over {len(s)} paired modes"
              + (f" (max {result.shifts[alike].max():.3g}% over the {int(alike.sum())} of MAC "
                 ">= 0.5)" if alike.any() else "")
              + f"; mode by mode, max {order.max():.3g}%, mean {order.mean():.3g}%")
    _save(lambda: modal_frf_figure(result.f, result.transfer, labels, result.shifts, path,
                                   f"{Path(case.path).stem}: {args.input} -> {args.output}, "
                                   f"modal damping {args.damping:g}"), path)
    return 0


def _plot_history(args):
    from ..plots.history import history_figure, select_series
    stored = api.history(args.file)
    names = select_series(stored, args.series)
    path = _png_path(args, stored.path)
    _save(lambda: history_figure(stored, names, path, args.keep_preload), path)
    return 0


def _plot_spectrum(args):
    from ..plots.history import select_series, spectrum_figure
    stored = api.history(args.file)
    _check_fmax(stored, args.fmax)
    names = select_series(stored, args.series)
    path = _png_path(args, stored.path)
    _save(lambda: spectrum_figure(stored, names, path, args.fmax), path)
    return 0


def _plot_frf(args):
    from ..plots.frf import LOADS, frf_figure
    from ..plots.history import MIN_SEGMENT, one_series
    stored = api.history(args.file)
    _check_fmax(stored, args.fmax)
    source = args.input or LOADS + _varying_load(stored)
    if not source.startswith(LOADS):
        source = one_series(stored, source, "--input")
    response = one_series(stored, args.output, "--output")
    if args.segment is not None and args.segment < MIN_SEGMENT:
        raise CaseError(stored.path, "--segment", f"expected at least {MIN_SEGMENT} samples, "
                        f"got {args.segment}")
    path = _png_path(args, stored.path)
    _save(lambda: frf_figure(stored, source, response, path, args.segment, args.fmax,
                             args.frf_kind, args.window), path)
    return 0


def _varying_load(stored):
    """The name of the one load of a history's case whose signal is not constant: the
    input a transfer function is from when none is named."""
    varying = [n for n, load in stored.case().loads.items()
               if load.signal["kind"] != "constant"]
    if len(varying) != 1:
        raise stored.error("--input", f"{len(varying)} loads of the run vary in time "
                           f"({', '.join(varying) or 'none'}): name the input, loads/NAME or a "
                           "series such as sensors/tip")
    return varying[0]


def _check_fmax(stored, fmax):
    if fmax is not None and not fmax > 0:
        raise CaseError(stored.path, "--fmax", f"expected a frequency > 0 [Hz], got {fmax}")


def _plot_pressure(args):
    from ..plots.history import pressure_figure, pressure_panels
    histories = [api.history(f) for f in args.file]
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
    paths = api.export(args.file, args.out, args.format, args.every)
    print("\n".join(str(p) for p in paths))
    return 0


def _plot_compat(args):
    from ..plots.compat import RenderingUnavailable, check_shapes, parse_shapes, plot_compat
    try:
        shapes = parse_shapes(args.shapes) if args.shapes is not None else None
    except ValueError as exc:
        raise CaseError(args.case, "--shapes", str(exc)) from None
    case = api.load(args.case, args.overrides)
    found = api.compat_pairs(case, None if args.pair is None else [args.pair])
    for pair in (f.pair for f in found):
        try:
            check_shapes(shapes or [], pair.compat)
        except ValueError as exc:
            raise CaseError(case.path, "--shapes", f"pair '{pair.name}': {exc}") from None
    for pair in (f.pair for f in found):
        try:
            paths = plot_compat(pair, args.out, shapes)
        except RenderingUnavailable as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        except OSError as exc:
            raise CaseError(case.path, "--out", str(exc)) from None
        print("\n".join(str(p) for p in paths))
    return 0
