"""Pictures of a history (PNG): time histories, amplitude spectra, spectrograms, envelopes and
contact pressure maps on Gamma (the paper's figure 10); transfer functions are in `frf`.

This module holds the choice of the series to draw and the figures. The numbers drawn come from
functions that draw nothing, so tests check them directly: `amplitude_spectrum` and
`spectrogram` in `signals`, `contact_force`, `plane_frame` and `pressure_panels` in
`pressure`. Figures are matplotlib `Figure`s on the Agg canvas, with no pyplot state; each
figure function returns its Figure, saved.

What a squeal engineer reads by default: a sensor drawn about its preload (the run's first row,
the state it starts from), frequency axes to the model's band (`model_band`) rather than the
rows' Nyquist frequency, and titles wrapped to the figure's width.
"""
import textwrap

import numpy as np

from .pressure import plane_frame, pressure_panels
from .signals import (MIN_SEGMENT, amplitude_spectrum, default_segment, envelope,
                      growth_rate, peak_pooled, sample_step, spectrogram)

__all__ = ["MIN_SEGMENT", "select_series", "one_series", "model_band", "history_figure",
           "spectrum_figure", "spectrogram_figure", "envelope_figure", "pressure_panels",
           "pressure_figure"]

UNITS = {"sensors": "m", "energy": "J"}      # unit of the series of each group
PRELOADED = ("sensors",)    # the groups drawn about their preload (displacements)
CONTOUR_POINTS = 100    # from this many contact points a map is filled contours, not markers
LONG_EDGE = 4.0         # triangles with an edge this many times the median edge are not drawn
CMAP = "viridis"        # sequential: pressure has one sign
MARKER_AREA = 0.5       # marker area / point weight: markers of neighbours do not overlap
TITLE_MARGIN = 0.01     # part of the figure's width left free on each side of its title


def select_series(stored, names):
    """Series names from the user's: a full name (`sensors/tip`) or a group (`energy`).

    Parameters
    ----------
    stored : stored.Stored
    names : list of str or None
        None: every sensor.

    Returns
    -------
    list of str
        Scalar series (one number per row), in the order asked.
    """
    scalars = stored.scalars()
    if names is None:
        chosen = [s for s in scalars if s.startswith("sensors/")]
        if not chosen:
            raise stored.error("--series", "no sensor series stored (output.sensors = false?); "
                               f"choose from: {', '.join(scalars) or 'none'}")
        return chosen
    chosen = []
    for name in names:
        group = [s for s in scalars if s.startswith(name.rstrip("/") + "/")]
        if name in scalars:
            chosen.append(name)
        elif group:
            chosen += group
        else:
            raise stored.error("--series", f"no scalar series '{name}' (series: "
                               f"{', '.join(scalars) or 'none'}; groups: "
                               f"{', '.join(sorted({s.split('/')[0] for s in scalars}))})")
    return list(dict.fromkeys(chosen))


def one_series(stored, name, key):
    """The scalar series called name (a full name, not a group); key names the option."""
    scalars = stored.scalars()
    if name not in scalars:
        raise stored.error(key, f"no scalar series '{name}' (series: "
                           f"{', '.join(scalars) or 'none'})")
    return name


def _figure(width, height):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)        # its renderer measures the titles
    return fig


def _title(stored):
    status = stored.meta["status"]
    return stored.path.name + ("" if status == "complete" else f" ({status})")


def _suptitle(fig, text):
    """The figure's title, wrapped onto as many lines as it takes to fit the figure's width
    (a word longer than a line, a long file name, is broken): a title one line long ran past
    both edges of the picture. Returns the Text."""
    renderer = fig.canvas.get_renderer()
    room = fig.bbox.width * (1 - 2 * TITLE_MARGIN)
    title = fig.suptitle(text)
    columns = len(text)
    while title.get_window_extent(renderer).width > room and columns > 1:
        # the columns that fit at the mean width of a character, then one fewer until it fits
        wide = title.get_window_extent(renderer).width
        longest = max(len(line) for line in title.get_text().split("\n"))
        columns = max(1, min(columns - 1, int(longest * room / wide)))
        title.set_text("\n".join(textwrap.fill(line, columns, break_on_hyphens=False)
                                  for line in text.split("\n")))
    return title


def model_band(stored):
    """(fmax [Hz], its case key) of the model a history was run with, the band its answer
    holds (stability.stage.fmax_of, the band `transient cea` reports: solver.reduction.fmax of
    a reduced model, of a full one solver.modes.fmax when set), from the case the history
    keeps; (None, reason) when it keeps none that loads, or a full model sets no band: the
    frequency axes then run to the rows' Nyquist frequency."""
    from ..errors import CaseError
    from ..stability.stage import fmax_of
    try:
        case = stored.case()
    except CaseError as exc:
        return None, exc.message
    solver = case.solver
    if not solver.reduction.enabled and not solver.modes.fmax:
        # a full model holds every mode its mesh resolves: solver.reduction.fmax, unused,
        # is no band of it (bar_impact's first mode is above its default)
        return None, "a full model without solver.modes.fmax"
    key = "solver.modes.fmax" if not solver.reduction.enabled else "solver.reduction.fmax"
    return float(fmax_of(case)), key


def frequency_top(stored, dt, fmax=None):
    """The top of a frequency axis [Hz] and what set it: fmax asked, else the model's band,
    at most the Nyquist frequency 1 / (2 dt) of the rows."""
    nyquist = 0.5 / dt
    if fmax is not None:
        return min(fmax, nyquist), ("--fmax" if fmax < nyquist else "the Nyquist frequency")
    band, key = model_band(stored)
    if band is None or band >= nyquist:
        return nyquist, "the Nyquist frequency"
    return band, f"the model's band, {key}"


def _groups(names):
    """Series names by group (sensors, energy...), in order of first appearance."""
    groups = {}
    for name in names:
        groups.setdefault(name.split("/")[0], []).append(name)
    return groups


def _label(group):
    unit = UNITS.get(group)
    return f"{group} [{unit}]" if unit else group


def history_figure(stored, names, path, keep_preload=False):
    """Time histories of scalar series, one panel per group, time in ms; each sensor drawn
    about its preload, its value at the run's first row (the state the run starts from, which
    the stages' preload sets), unless keep_preload: the vibration is a small part of a sensor's
    static offset under the clamp force, and would be drawn flat on its scale."""
    t = stored.time()
    groups = _groups(names)
    fig = _figure(10, 1.2 + 2.6 * len(groups))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (group, members) in zip(axes, groups.items()):
        about = group in PRELOADED and not keep_preload and len(t) > 0
        for name in members:
            x, label = stored.read(name), name.split("/", 1)[1]
            if about:
                x, label = x - x[0], f"{label} (preload {x[0]:.4g} {UNITS[group]})"
            ax.plot(t * 1e3, x, lw=1, label=label)
        ax.set_ylabel(f"{group} about the preload [{UNITS[group]}]" if about
                      else _label(group))
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("time [ms]")
    _suptitle(fig, f"{_title(stored)}: time histories")
    fig.savefig(path, dpi=110)
    return fig


def spectrum_figure(stored, names, path, fmax=None):
    """Amplitude spectra (Hann window, one-sided, log amplitude) of scalar series, frequency in
    kHz, one panel per group, to fmax [Hz] or the model's band (`frequency_top`)."""
    stored = stored.uniform()
    t = stored.time()
    dt = sample_step(stored, t)
    top, why = frequency_top(stored, dt, fmax)
    groups = _groups(names)
    fig = _figure(10, 1.2 + 2.8 * len(groups))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (group, members) in zip(axes, groups.items()):
        for name in members:
            f, a = amplitude_spectrum(stored.read(name), dt)
            shown = f <= top       # so that the amplitude axis fits what is drawn
            # exact zeros (a series that never moves) cannot be drawn on a log scale
            ax.semilogy(f[shown] / 1e3, np.maximum(a[shown], 1e-300), lw=1,
                        label=name.split("/", 1)[1])
        ax.set_ylabel(f"amplitude of {_label(group)}")
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlim(0, top / 1e3)
    axes[-1].set_xlabel("frequency [kHz]")
    _suptitle(fig, f"{_title(stored)}: amplitude spectra ({len(t)} samples of "
              f"{dt * 1e6:.4g} us, Hann window, resolution {1e-3 / (len(t) * dt):.3g} kHz; "
              f"to {top / 1e3:.4g} kHz, {why})")
    fig.savefig(path, dpi=110)
    return fig


SPECTROGRAM_ROWS = 400   # frequency rows drawn at most: about the map's height in pixels


def spectrogram_figure(stored, name, path, segment=None, fmax=None):
    """Time-frequency map of one series: short-time amplitude spectra in dB (Hann segments
    overlapping by three quarters), time in ms, frequency in kHz to fmax [Hz] or the model's
    band (`frequency_top`)."""
    stored = stored.uniform()
    t = stored.time()
    dt = sample_step(stored, t)
    n = len(t)
    segment = segment or default_segment(n) // 2 or MIN_SEGMENT
    if segment > n:
        raise stored.error("--segment", f"the history has {n} rows, fewer than the segment of "
                           f"{segment}")
    f, tc, A = spectrogram(stored.read(name), dt, segment)
    top, why = frequency_top(stored, dt, fmax)
    keep = f <= top
    f, A = peak_pooled(f[keep], A[keep], SPECTROGRAM_ROWS)
    with np.errstate(divide="ignore"):
        db = 20 * np.log10(A / max(A.max(), 1e-300))
    fig = _figure(10, 5)
    ax = fig.subplots()
    mesh = ax.pcolormesh((t[0] + tc) * 1e3, f / 1e3, np.maximum(db, -100.0),
                         shading="nearest", cmap=CMAP, vmin=max(-100.0, db[np.isfinite(db)].min()))
    fig.colorbar(mesh, ax=ax, label="amplitude [dB re peak]")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("frequency [kHz]")
    ax.set_ylim(0, top / 1e3)
    _suptitle(fig, f"{_title(stored)}: {name} (segments of {segment} rows; to "
              f"{top / 1e3:.4g} kHz, {why})")
    fig.savefig(path, dpi=110)
    return fig


def envelope_figure(stored, names, path, window=None, band=None):
    """Each series with its envelope (top), and the envelope on a log scale with the
    exponential fitted over its linear phase and its growth rate (bottom). Returns
    {name: (sigma [1/s], (t0, t1), rms)}."""
    stored = stored.uniform()
    t = stored.time()
    dt = sample_step(stored, t)
    fig = _figure(10, 7)
    top, bottom = fig.subplots(2, 1, sharex=True)
    fits = {}
    for name in names:
        x = stored.read(name)
        env = envelope(x, dt, band)
        try:
            sigma, (t0, t1), rms = growth_rate(t, env, window)
        except ValueError as exc:
            raise stored.error("--window", f"{name}: {exc}") from None
        fits[name] = (sigma, (t0, t1), rms)
        line, = top.plot(t * 1e3, x - np.mean(x), lw=0.6, alpha=0.6)
        top.plot(t * 1e3, env, lw=1.2, color=line.get_color(), label=name)
        bottom.semilogy(t * 1e3, np.maximum(env, 1e-300), lw=1, color=line.get_color())
        sel = (t >= t0) & (t <= t1)
        a = np.exp(np.mean(np.log(np.maximum(env[sel], 1e-300)) - sigma * t[sel]))
        bottom.semilogy(t[sel] * 1e3, a * np.exp(sigma * t[sel]), "--", lw=2, color="black")
        bottom.text(t1 * 1e3, a * np.exp(sigma * t1), f"  {sigma:.4g} 1/s", fontsize=9)
    top.set_ylabel("series and envelope")
    top.legend(loc="best", fontsize=8)
    bottom.set_ylabel("envelope (log)")
    bottom.set_xlabel("time [ms]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    what = f", band {band[0]:g}-{band[1]:g} Hz" if band else ""
    _suptitle(fig, f"{_title(stored)}: envelopes and growth rates (dashed: fit){what}")
    fig.savefig(path, dpi=110)
    return fits


def pressure_figure(panels, path):
    """Contact pressure maps side by side with one colour scale (the paper's figure 10: fine,
    centre and regularized rules), from `pressure_panels`; Gamma seen from surface 1, in the
    best-fit plane of the points of all panels."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.tri import Triangulation
    centre, axes = plane_frame(np.vstack([p["points"] for p in panels]),
                               np.vstack([p["normals"] for p in panels]))
    xy = [(p["points"] - centre) @ axes.T * 1e3 for p in panels]
    mpa = [p["pressure"] / 1e6 for p in panels]
    low = min(0.0, min(p.min() for p in mpa))
    norm = Normalize(low, max(max(p.max() for p in mpa), low + 1e-12))
    levels = np.linspace(norm.vmin, norm.vmax, 21)
    every = np.vstack(xy)
    # room for the marker of the heaviest point past the outermost ones
    pad = 0.5 * np.sqrt(max(p["weights"].max() for p in panels)) * 1e3 + 0.02 * np.ptp(every)
    fig = _figure(max(6.0, 0.8 + 4.4 * len(panels)), 5.2)
    ax_list = fig.subplots(1, len(panels), sharex=True, sharey=True, squeeze=False)[0]
    markers = []
    for ax, p, (x, y), pressure in zip(ax_list, panels, (c.T for c in xy), mpa):
        if len(x) >= CONTOUR_POINTS:
            tri = Triangulation(x, y)
            tri.set_mask(_long_triangles(tri))
            ax.tricontourf(tri, pressure, levels=levels, cmap=CMAP, norm=norm)
            ax.plot(x, y, ",", color="black", alpha=0.4)
        else:
            markers.append((ax, ax.scatter(x, y, c=pressure, cmap=CMAP, norm=norm,
                                           edgecolors="black", linewidths=0.3),
                            p["weights"]))
        ax.set_title(f"{p['label']}\n{p['rule']}, {len(x)} points\n"
                     f"t = {p['time'] * 1e3:.4g} ms, total force {p['force']:.4g} N",
                     fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel(f"along ({_direction(axes[0])}) [mm]")
    ax_list[0].set_ylabel(f"along ({_direction(axes[1])}) [mm]")
    ax_list[0].set_xlim(every[:, 0].min() - pad, every[:, 0].max() + pad)
    ax_list[0].set_ylim(every[:, 1].min() - pad, every[:, 1].max() + pad)
    fig.colorbar(ScalarMappable(norm, CMAP), ax=list(ax_list), label="contact pressure [MPa]",
                 shrink=0.9)
    _suptitle(fig, f"contact pressure on pair '{panels[0]['pair']}', seen from surface 1"
              + (f"\nmarker area: {MARKER_AREA:g} x the point's weight" if markers else ""))
    if markers:
        fig.draw_without_rendering()
        for ax, scatter, w in markers:
            # a disc of MARKER_AREA times its point's weight (an area); sizes are in points^2
            box = ax.get_window_extent()
            pt_per_mm = box.width * 72.0 / fig.dpi / np.diff(ax.get_xlim())[0]
            scatter.set_sizes(MARKER_AREA * 4 / np.pi * w * 1e6 * pt_per_mm ** 2)
    fig.savefig(path, dpi=110)


def _long_triangles(tri):
    """Triangles spanning a hole or a concave edge of Gamma: an edge far above the median."""
    x, y = tri.x[tri.triangles], tri.y[tri.triangles]
    edges = np.hypot(x - np.roll(x, 1, axis=1), y - np.roll(y, 1, axis=1)).max(axis=1)
    return edges > LONG_EDGE * np.median(edges)


def _direction(v):
    return ", ".join(f"{round(c, 2) + 0.0:.2f}" for c in v)    # + 0.0: no "-0.00"
