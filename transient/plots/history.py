"""Pictures of a history (PNG): time histories, amplitude spectra, the transfer function between
two sensors (the paper's figure 11) and contact pressure maps on Gamma (figure 10).

The numbers drawn come from functions that draw nothing (`amplitude_spectrum`,
`transfer_function`, `contact_force`, `plane_frame`, `pressure_panels`), so tests check them
directly. Figures are matplotlib `Figure`s saved through the Agg canvas, with no pyplot state.
"""
import numpy as np

UNITS = {"sensors": "m", "energy": "J"}      # unit of the series of each group
UNIFORM = 1e-6          # relative spread of the time differences still taken as one step
MIN_SEGMENT = 16        # fewest samples of a Welch segment for a transfer function
MIN_DB_SPAN = 20.0      # smallest range of the magnitude axis of a transfer function [dB]
CONTOUR_POINTS = 100    # from this many contact points a map is filled contours, not markers
LONG_EDGE = 4.0         # triangles with an edge this many times the median edge are not drawn
FORCE_CHUNK = 4096      # rows of pressure read at a time for the total force
CMAP = "viridis"        # sequential: pressure has one sign
MARKER_AREA = 0.5       # marker area / point weight: markers of neighbours do not overlap


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


def sample_step(stored, time):
    """The sample step of the rows [s]: their time difference, checked to be uniform."""
    if len(time) < 2:
        raise stored.error("time", f"{len(time)} row(s): a spectrum needs a time series")
    dt = np.diff(time)
    step = float(np.median(dt))
    if step <= 0 or np.max(np.abs(dt - step)) > UNIFORM * step:
        raise stored.error("time", f"the rows are not evenly spaced (steps from {dt.min():.6g} "
                           f"to {dt.max():.6g} s): spectra need a uniform sample step")
    return step


def amplitude_spectrum(x, dt):
    """One-sided amplitude spectrum of a signal through a Hann window.

    The mean is removed first: a static offset (the preload) would otherwise leak into the
    lowest bins. A sine of amplitude a on a bin frequency reads a.

    Parameters
    ----------
    x : (n,) array
        Samples, any unit.
    dt : float
        Sample step [s].

    Returns
    -------
    f : (n // 2 + 1,) array
        Frequencies [Hz].
    amplitude : (n // 2 + 1,) array
        Amplitudes, the unit of x.
    """
    from scipy.signal import get_window
    x = np.asarray(x, dtype=float)
    w = get_window("hann", len(x))
    amplitude = 2.0 * np.abs(np.fft.rfft((x - x.mean()) * w)) / w.sum()
    amplitude[0] /= 2.0
    if len(x) % 2 == 0:
        amplitude[-1] /= 2.0
    return np.fft.rfftfreq(len(x), dt), amplitude


def default_segment(n):
    """Welch segment length for n samples: the largest power of two up to n / 4 (so about seven
    half-overlapping segments are averaged), at least MIN_SEGMENT."""
    return max(MIN_SEGMENT, 2 ** int(np.floor(np.log2(max(n // 4, 1)))))


def transfer_function(x, y, dt, segment):
    """H1 estimate of the transfer function from x to y and its coherence (Welch averages).

    H1 = P_xy / P_xx, coherence |P_xy|^2 / (P_xx P_yy), with Hann segments overlapping by half,
    each with its mean removed.

    Parameters
    ----------
    x, y : (n,) arrays
        Input and output samples.
    dt : float
        Sample step [s].
    segment : int
        Samples per segment, at most n.

    Returns
    -------
    f : array
        Frequencies [Hz].
    H : complex array
        The unit of y per unit of x; NaN where x has no power.
    coherence : array
        Between 0 and 1; NaN where x or y has no power.
    """
    from scipy.signal import csd, welch
    kw = {"fs": 1.0 / dt, "window": "hann", "nperseg": segment, "detrend": "constant"}
    f, pxx = welch(x, **kw)
    _, pyy = welch(y, **kw)
    _, pxy = csd(x, y, **kw)
    with np.errstate(divide="ignore", invalid="ignore"):
        H = np.where(pxx > 0, pxy / pxx, np.nan)
        coherence = np.where((pxx > 0) & (pyy > 0), np.abs(pxy) ** 2 / (pxx * pyy), np.nan)
    return f, H, coherence


def contact_force(stored, pair):
    """Total normal contact force sum_i w_i p_i [N] of a pair at every row."""
    w = stored.geometry(f"contact/{pair}/weights")
    force = np.zeros(stored.rows)
    with stored.open() as f:
        ds = f[f"contact/{pair}/pressure"]
        for start in range(0, stored.rows, FORCE_CHUNK):
            stop = min(start + FORCE_CHUNK, stored.rows)
            force[start:stop] = ds[start:stop] @ w
    return force


def plane_frame(points, normals):
    """Centre and in-plane axes of the best-fit plane of contact points, seen from surface 1.

    The plane is the SVD's (its normal the direction of least spread), its normal n oriented
    as the mean stored contact normal (surface 2 towards surface 1); with fewer than three
    points off a line, the plane normal to the mean stored normal. The first axis is the global
    axis most nearly in the plane, projected on it, so that the maps of different rules, runs
    and meshes are drawn the same way round.

    Parameters
    ----------
    points : (m, 3) array [m]
    normals : (m, 3) array
        Contact normals at the points.

    Returns
    -------
    centre : (3,) array [m]
    axes : (2, 3) array
        In-plane unit vectors e1, e2 with e1 x e2 = n.
    """
    centre = points.mean(axis=0)
    n_mean = normals.mean(axis=0)
    _, s, vt = np.linalg.svd(points - centre, full_matrices=True)
    if len(s) >= 2 and s[1] > 1e-9 * s[0]:
        n = vt[2] if vt[2] @ n_mean >= 0 else -vt[2]
    else:
        n = n_mean / np.linalg.norm(n_mean)
    # rounded: of two axes both in the plane up to round-off, x before y before z
    e1 = np.eye(3)[np.argmin(np.round(np.abs(n), 9))]
    e1 = e1 - (e1 @ n) * n
    e1 /= np.linalg.norm(e1)
    return centre, np.array([e1, np.cross(n, e1)])


def _figure(width, height):
    from matplotlib.figure import Figure
    return Figure(figsize=(width, height), layout="constrained")


def _title(stored):
    status = stored.meta["status"]
    return stored.path.name + ("" if status == "complete" else f" ({status})")


def _groups(names):
    """Series names by group (sensors, energy...), in order of first appearance."""
    groups = {}
    for name in names:
        groups.setdefault(name.split("/")[0], []).append(name)
    return groups


def _label(group):
    unit = UNITS.get(group)
    return f"{group} [{unit}]" if unit else group


def history_figure(stored, names, path):
    """Time histories of scalar series, one panel per group, time in ms."""
    t = stored.time()
    groups = _groups(names)
    fig = _figure(10, 1.2 + 2.6 * len(groups))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (group, members) in zip(axes, groups.items()):
        for name in members:
            ax.plot(t * 1e3, stored.read(name), lw=1, label=name.split("/", 1)[1])
        ax.set_ylabel(_label(group))
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("time [ms]")
    fig.suptitle(f"{_title(stored)}: time histories")
    fig.savefig(path, dpi=110)


def spectrum_figure(stored, names, path, fmax=None):
    """Amplitude spectra (Hann window, one-sided, log amplitude) of scalar series, frequency in
    kHz, one panel per group."""
    t = stored.time()
    dt = sample_step(stored, t)
    top = min(fmax or np.inf, 0.5 / dt)        # at most the Nyquist frequency [Hz]
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
    fig.suptitle(f"{_title(stored)}: amplitude spectra ({len(t)} samples of "
                 f"{dt * 1e6:.4g} us, Hann window, resolution {1e-3 / (len(t) * dt):.3g} kHz)")
    fig.savefig(path, dpi=110)


def frf_figure(stored, source, response, path, segment=None, fmax=None):
    """Transfer function from one series to another (H1, Welch): magnitude in dB, phase and
    coherence against frequency in kHz, the paper's figure 11.

    Raises CaseError when the history has fewer rows than a segment.
    """
    t = stored.time()
    dt = sample_step(stored, t)
    n = len(t)
    if segment is None:
        if n < MIN_SEGMENT:
            raise stored.error("--segment", f"{n} rows: too short for a transfer function "
                               f"(at least {MIN_SEGMENT} rows; run longer)")
        segment = default_segment(n)
    if segment > n:
        raise stored.error("--segment", f"the history has {n} rows, fewer than the segment of "
                           f"{segment} samples (use --segment <= {n}, or run longer)")
    f, H, coherence = transfer_function(stored.read(source), stored.read(response), dt, segment)
    averages = 1 + (n - segment) // (segment - segment // 2)
    top = min(fmax or np.inf, 0.5 / dt)        # at most the Nyquist frequency [Hz]
    shown = f <= top                           # so that each axis fits what is drawn
    f, H, coherence = f[shown] / 1e3, H[shown], coherence[shown]
    fig = _figure(10, 8)
    ax, bx, cx = fig.subplots(3, 1, sharex=True, height_ratios=(2, 1, 1))
    with np.errstate(divide="ignore"):
        db = 20 * np.log10(np.abs(H))
    ax.plot(f, db, lw=1, color="tab:blue")
    finite = db[np.isfinite(db)]
    if len(finite) and np.ptp(finite) < MIN_DB_SPAN:
        # a flat |H| (a sensor against itself) would show round-off across the whole axis
        middle = 0.5 * (finite.min() + finite.max())
        ax.set_ylim(middle - MIN_DB_SPAN / 2, middle + MIN_DB_SPAN / 2)
    ax.set_ylabel(f"|H| [dB re 1{_unit_ratio(source, response)}]")
    bx.plot(f, np.degrees(np.angle(H)), lw=1, color="tab:blue")
    bx.set(ylabel="phase [deg]", ylim=(-185, 185), yticks=(-180, -90, 0, 90, 180))
    cx.plot(f, coherence, lw=1, color="tab:green")
    cx.set(ylabel="coherence", ylim=(-0.02, 1.05), xlabel="frequency [kHz]")
    cx.set_xlim(0, top / 1e3)
    for a in (ax, bx, cx):
        a.grid(alpha=0.3)
    fig.suptitle(f"{_title(stored)}: H1 from {source} to {response} ({averages} Hann segments "
                 f"of {segment} samples, half overlapping; resolution "
                 f"{1e-3 / (segment * dt):.3g} kHz)")
    fig.savefig(path, dpi=110)


def _unit_ratio(source, response):
    units = UNITS.get(source.split("/")[0], "-"), UNITS.get(response.split("/")[0], "-")
    return "" if units[0] == units[1] else f" {units[1]}/{units[0]}"


def contact_pair(stored, pair):
    """The pair to map (default the first stored), checked to have its pressures and points."""
    stored_pairs = [name.split("/")[1] for name in stored.series
                    if name.startswith("contact/") and name.endswith("/pressure")]
    if not stored_pairs:
        raise stored.error("contact", "no contact pressures stored: run with "
                           "output.contact = true")
    pair = pair or stored_pairs[0]
    if pair not in stored_pairs:
        raise stored.error("--pair", f"no contact pair '{pair}' stored (pairs: "
                           f"{', '.join(stored_pairs)})")
    if stored.geometry(f"contact/{pair}/points") is None:
        raise stored.error(f"geometry/contact/{pair}/points", "no contact point positions: "
                           "run with output.contact = true (this version stores them)")
    return pair


def rule_text(description):
    """'fine rule', 'centre rule, regularized (eps = 1e-08)'... from a history's pairs entry."""
    text = f"{description.get('rule', '?')} rule"
    if description.get("regularized"):
        eps = description.get("eps")
        text += ", regularized" + (f" (eps = {eps:.2g})" if eps is not None else "")
    return text


def pressure_panels(histories, pair=None, time=None, labels=None):
    """The data of the pressure maps: one panel per history, at one time.

    Parameters
    ----------
    histories : list of stored.Stored
    pair : str, optional
        Contact pair (default the first of the first history).
    time : float, optional
        Time [s]: each panel shows its stored row nearest to it. Default: the time of the
        largest total contact force of the first history.
    labels : list of str, optional
        Panel names (default the file names).

    Returns
    -------
    list of dict
        Each with points (m, 3) [m], normals (m, 3), weights (m,) [m^2], pressure (m,) [Pa],
        time [s] and force [N] (the total) of the row shown, pair (its name), rule (a text
        from the history's `pairs`) and label.
    """
    pair = contact_pair(histories[0], pair)
    panels = []
    for k, stored in enumerate(histories):
        contact_pair(stored, pair)
        t = stored.time()
        force = contact_force(stored, pair)
        if k == 0 and time is None:
            time = float(t[np.argmax(force)])
        row = int(np.argmin(np.abs(t - time)))
        with stored.open() as f:
            pressure = f[f"contact/{pair}/pressure"][row]
        geometry = {key: stored.geometry(f"contact/{pair}/{key}")
                    for key in ("points", "normals", "weights")}
        panels.append({**geometry, "pressure": pressure, "time": float(t[row]),
                       "force": float(force[row]), "pair": pair,
                       "rule": rule_text(stored.pairs().get(pair, {})),
                       "label": labels[k] if labels else stored.path.stem})
    return panels


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
    fig.suptitle(f"contact pressure on pair '{panels[0]['pair']}', seen from surface 1"
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
