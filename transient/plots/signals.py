"""Signal processing of the series of a history: sample step, amplitude spectrum, transfer function.

Numbers only, nothing is drawn: the uniform sample step of the rows (checked), the one-sided
amplitude spectrum of a series through a Hann window, the default Welch segment length and the
H1 transfer function between two series with its coherence (Welch averages of half-overlapping
Hann segments). The figures of `history` draw these; tests check them directly.
"""
import numpy as np

UNIFORM = 1e-6          # relative spread of the time differences still taken as one step
MIN_SEGMENT = 16        # fewest samples of a Welch segment for a transfer function


def sample_step(stored, time):
    """The sample step of the rows [s]: their time difference, checked to be uniform."""
    if len(time) < 2:
        raise stored.error("time", f"{len(time)} row(s): a spectrum needs a time series")
    dt = np.diff(time)
    step = float(np.median(dt))
    # written so that NaN times (a damaged history) fail too
    if not (step > 0 and np.max(np.abs(dt - step)) <= UNIFORM * step):
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
