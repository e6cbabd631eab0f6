"""The transfer function of a history (PNG): from a load of the run to a sensor, the receptance,
mobility or accelerance an NVH engineer reads, or from one series to another (the paper's
figure 11); H1 = P_xy / P_xx from Welch averages, its magnitude, phase and coherence.

`transfer_data` computes the numbers (nothing drawn), `frf_figure` draws them. A load's input
is rebuilt from the case the history keeps (io.stored.AppliedLoad): its size times its time
signal at the rows' times, as the kernels evaluate it at each step.
"""
from dataclasses import dataclass

import numpy as np

from .history import UNITS, _figure, _suptitle, _title, frequency_top
from .signals import (MIN_SEGMENT, default_segment, derived, sample_step, segments_averaged,
                      transfer_function)

LOADS = "loads/"        # an input named loads/NAME is the load NAME of the run's case
MIN_DB_SPAN = 20.0      # smallest range of the magnitude axis of a transfer function [dB]
KIND_UNITS = {"receptance": "m", "mobility": "m/s", "accelerance": "m/s^2"}   # the response's
# a load's samples per row: its spectrum's images then fold back from 16 times the rows'
# sample rate, where a tap's half-sine has fallen 256 times below its level at the rate itself
OVERSAMPLE = 16


@dataclass(frozen=True)
class Transfer:
    """A transfer function estimated from a history's rows, and how."""
    f: np.ndarray            # (k,) frequencies [Hz]
    H: np.ndarray            # (k,) complex, in `unit`; NaN where the input has no power
    coherence: np.ndarray    # (k,) between 0 and 1
    what: str                # receptance, mobility, accelerance, or H1 between two series
    unit: str                # of H ("m/N", "(m/s)/N"...), "" for a ratio of like series
    source: str              # the input, described
    segment: int             # samples per Welch segment
    averages: int            # segments averaged
    window: str              # hann or rectangular
    dt: float                # sample step [s]
    t0: float                # time of the first row taken [s]
    left: float              # from a tap: the response's largest deviation from its first row
    #                          over the last tenth of the tap's segment, over its largest in it:
    #                          the ringing the segment cuts (NaN for other inputs)


def transfer_data(stored, source, response, segment=None, kind=None, window=None):
    """The H1 transfer function from source to the series `response` (a sensor), by Welch
    averages of `segment` samples (default: every row from an impulse's start, in one
    rectangular segment; signals.default_segment of the rows otherwise).

    source: `loads/NAME`, a load of the run's case, whose amplitude (io.stored.AppliedLoad) is
    the input: H is then the kind asked (default receptance, the displacement per unit of the
    load; mobility, accelerance) and the window defaults to rectangular segments end to end
    for an impulse, taken from its start (a tap: Hann would taper it away at a segment's
    edge), Hann otherwise. Rectangular segments after the tap's first hold no input and add
    nothing to H1: one segment of every row resolves a lightly damped peak the record holds,
    which a shorter one cuts; its coherence, 1 by construction, is NaN, and `left` says how
    much ringing the record's end cuts. Or a scalar series: H is the ratio of the two, no kind.
    Raises CaseError naming the option at fault.
    """
    stored = stored.uniform()
    t = stored.time()
    dt = sample_step(stored, t)
    y = stored.read(response)
    impulse = None
    if source.startswith(LOADS):
        load = stored.applied_load(source[len(LOADS):])
        if load.signal["kind"] == "impulse":
            impulse = load.signal
            # the rows before the tap carry no input: the first segment starts with it
            after = t >= impulse["start"]
            t, y = t[after], y[after]
        oversample = OVERSAMPLE
        x = load.values(t[0] + dt * np.arange(len(t) * oversample) / oversample
                        if len(t) else t)
        window = window or ("rectangular" if impulse else "hann")
        kind = kind or "receptance"
        unit = KIND_UNITS[kind]
        unit = f"({unit})/{load.unit}" if "/" in unit else f"{unit}/{load.unit}"
        along = ("" if load.direction is None else " along ("
                 + ", ".join(f"{c + 0.0:.3g}" for c in load.direction) + ")")
        what, text = kind, (f"{source} ({load.kind} {load.size:.4g} {load.unit}{along}, "
                            f"{load.signal['kind']} signal)")
    else:
        if kind is not None:
            raise stored.error("--kind", "a receptance, mobility or accelerance is per unit "
                               "of a load: give the input as loads/NAME")
        x, oversample = stored.read(source), 1
        window = window or "hann"
        units = UNITS.get(source.split("/")[0], "-"), UNITS.get(response.split("/")[0], "-")
        what, text = "H1", source
        unit = "" if units[0] == units[1] else f"{units[1]}/{units[0]}"
    n = len(t)
    if segment is None:
        if n < MIN_SEGMENT:
            raise stored.error("--segment", f"{n} rows: too short for a transfer function "
                               f"(at least {MIN_SEGMENT} rows; run longer)")
        segment = n if impulse and window == "rectangular" else default_segment(n)
    if segment > n:
        raise stored.error("--segment", f"the history has {n} rows"
                           + (" from the impulse's start" if impulse else "")
                           + f", fewer than the segment of {segment} samples (use --segment "
                           f"<= {n}, or run longer)")
    if impulse and window == "rectangular" and impulse["duration"] > segment * dt:
        raise stored.error("--segment", f"the impulse lasts {impulse['duration']:.4g} s, "
                           f"longer than a segment of {segment} samples ({segment * dt:.4g} "
                           "s): its first segment must hold it whole")
    f, H, coherence = transfer_function(x, y, dt, segment, window, oversample)
    if what != "H1":
        H = derived(f, H, kind)
    averages = segments_averaged(n, segment, window)
    if averages == 1:
        coherence = np.full_like(coherence, np.nan)
    left = np.nan
    if impulse:
        motion = np.abs(y[:segment] - y[0])
        left = float(motion[segment - segment // 10:].max() / max(motion.max(), 1e-300))
    return Transfer(f, H, coherence, what, unit, text, segment, averages, window, dt,
                    float(t[0]) if n else 0.0, left)


def frf_figure(stored, source, response, path, segment=None, fmax=None, kind=None,
               window=None):
    """The transfer function of `transfer_data` against frequency in kHz, to fmax [Hz] or the
    model's band (history.frequency_top): magnitude in dB, phase, coherence. Returns the
    Figure, saved at path."""
    data = transfer_data(stored, source, response, segment, kind, window)
    top, why = frequency_top(stored, data.dt, fmax)
    shown = data.f <= top                      # so that each axis fits what is drawn
    f, H, coherence = data.f[shown] / 1e3, data.H[shown], data.coherence[shown]
    fig = _figure(10, 8)
    ax, bx, cx = fig.subplots(3, 1, sharex=True, height_ratios=(2, 1, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        db = 20 * np.log10(np.abs(H))
    ax.plot(f, db, lw=1, color="tab:blue")
    finite = db[np.isfinite(db)]
    if len(finite) and np.ptp(finite) < MIN_DB_SPAN:
        # a flat |H| (a sensor against itself) would show round-off across the whole axis
        middle = 0.5 * (finite.min() + finite.max())
        ax.set_ylim(middle - MIN_DB_SPAN / 2, middle + MIN_DB_SPAN / 2)
    name = "|H|" if data.what == "H1" else f"|{data.what}|"
    ax.set_ylabel(f"{name} [dB re 1 {data.unit}]" if data.unit else f"{name} [dB re 1]")
    bx.plot(f, np.degrees(np.angle(H)), lw=1, color="tab:blue")
    bx.set(ylabel="phase [deg]", ylim=(-185, 185), yticks=(-180, -90, 0, 90, 180))
    cx.plot(f, coherence, lw=1, color="tab:green")
    if data.averages == 1:
        cx.text(0.5, 0.5, "one segment: no coherence (1 by construction)", ha="center",
                va="center", transform=cx.transAxes)
    cx.set(ylabel="coherence", ylim=(-0.02, 1.05), xlabel="frequency [kHz]")
    cx.set_xlim(0, top / 1e3)
    for a in (ax, bx, cx):
        a.grid(alpha=0.3)
    how = ("half overlapping" if data.window == "hann" else "end to end, from t = "
           f"{data.t0 * 1e3:.4g} ms")
    segments = (f"one {data.window} segment" if data.averages == 1 else
                f"{data.averages} {data.window} segments")
    if data.averages == 1:
        how = how.replace("end to end, ", "")
    if np.isfinite(data.left):
        how += f"; the tap's segment ends at {data.left:.2g} of its largest motion"
    _suptitle(fig, f"{_title(stored)}: {data.what} from {data.source} to {response} "
              f"({segments} of {data.segment} samples, {how}; "
              f"resolution {1e-3 / (data.segment * data.dt):.3g} kHz; to {top / 1e3:.4g} "
              f"kHz, {why})")
    fig.savefig(path, dpi=110)
    return fig
