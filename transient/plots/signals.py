"""Signal processing of the series of a history: sample step, amplitude spectrum, transfer function.

Numbers only, nothing is drawn: the uniform sample step of the rows (checked), the one-sided
amplitude spectrum of a series through a Hann window, the default Welch segment length and the
H1 transfer function to a series with its coherence (Welch averages of half-overlapping Hann
segments, or rectangular ones end to end; an input sampled finer than the rows), as a
receptance, mobility or accelerance. The figures of `history` and `frf` draw these; tests check
them directly.
"""
import numpy as np

UNIFORM = 1e-6          # relative spread of the time differences still taken as one step
MIN_SEGMENT = 16        # fewest samples of a Welch segment for a transfer function
WINDOWS = {"hann": "hann", "rectangular": "boxcar"}     # Welch windows by name (SciPy's)
# a transfer function per unit force [m/N] as a receptance, and times i omega, (i omega)^2
FRF_KINDS = {"receptance": 0, "mobility": 1, "accelerance": 2}


def sample_step(stored, time):
    """The sample step of the rows [s]: their time difference, checked to be uniform; the run's
    own step times its rows' stride (attributes dt and every) where they agree with it.

    The rows' times are sums of steps, each rounded to the time reached: their differences
    are off the step by up to half a unit in the last place of that time (1.4e-12 of a 5 us
    step at 0.128 s), which the frequencies of a spectrum would carry (a lightly damped
    peak's FRF by 1 / damping ratio times as much)."""
    if len(time) < 2:
        raise stored.error("time", f"{len(time)} row(s): a spectrum needs a time series")
    dt = np.diff(time)
    step = float(np.median(dt))
    # written so that NaN times (a damaged history) fail too
    if not (step > 0 and np.max(np.abs(dt - step)) <= UNIFORM * step):
        raise stored.error("time", f"the rows are not evenly spaced (steps from {dt.min():.6g} "
                           f"to {dt.max():.6g} s): spectra need a uniform sample step")
    meta = stored.meta
    run = float(meta.get("dt") or 0.0) * int(meta.get("every") or 0)
    return run if abs(run - step) <= UNIFORM * step else step


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


def transfer_function(x, y, dt, segment, window="hann", oversample=1):
    """H1 estimate of the transfer function from x to y and its coherence (Welch averages).

    H1 = P_xy / P_xx, coherence |P_xy|^2 / (P_xx P_yy), each segment with its mean removed:
    Hann segments overlapping by half, or rectangular ones end to end (an impulse's: the force
    and the response it starts are not tapered, and the coherence is the share of the
    response's power that the segment holding the impulse holds).

    Parameters
    ----------
    x : (n * oversample,) array
        Input samples, `oversample` of them per sample of y, the first at y's first: a load
        evaluated finer than the rows. Each segment's transform is then that of the finer
        samples, kept to the rows' frequencies: the input's spectrum above the rows' Nyquist
        frequency is left out where the rows' own samples would fold it back onto the band (a
        tap a few rows long has a few percent of its spectrum there).
    y : (n,) array
        Output samples.
    dt : float
        Sample step of y [s].
    segment : int
        Samples of y per segment, at most n.
    window : str
        "hann" or "rectangular".
    oversample : int
        Samples of x per sample of y.

    Returns
    -------
    f : array
        Frequencies [Hz].
    H : complex array
        The unit of y per unit of x; NaN where x has no power.
    coherence : array
        Between 0 and 1; NaN where x or y has no power.
    """
    y = np.asarray(y, dtype=float)
    starts = np.arange(0, len(y) - segment + 1, _segment_step(segment, window))
    X = _segment_spectra(x, starts * oversample, segment * oversample, window)
    X = X[:, :segment // 2 + 1] / oversample
    Y = _segment_spectra(y, starts, segment, window)
    pxy = np.sum(np.conj(X) * Y, axis=0)
    pxx = np.sum(np.abs(X) ** 2, axis=0)
    pyy = np.sum(np.abs(Y) ** 2, axis=0)
    # no power: at the round-off of the largest, as the mean removed leaves at 0 Hz
    floor = (np.finfo(float).eps * segment) ** 2
    powered = (pxx > floor * pxx.max()) & (pyy > floor * pyy.max())
    with np.errstate(divide="ignore", invalid="ignore"):
        H = np.where(pxx > floor * pxx.max(), pxy / pxx, np.nan)
        coherence = np.where(powered, np.abs(pxy) ** 2 / (pxx * pyy), np.nan)
    return np.fft.rfftfreq(segment, dt), H, coherence


def _segment_spectra(x, starts, length, window):
    """(k, length // 2 + 1) the one-sided DFT of each segment of x from `starts`, its mean
    removed, through the window (SciPy's periodic Hann, as Welch takes it, or none)."""
    from scipy.signal import get_window
    segments = np.lib.stride_tricks.sliding_window_view(np.asarray(x, float), length)[starts]
    segments = segments - segments.mean(axis=1, keepdims=True)
    return np.fft.rfft(segments * get_window(WINDOWS[window], length), axis=1)


def segments_averaged(n, segment, window):
    """The number of Welch segments of `segment` samples in n: half-overlapping Hann ones, or
    rectangular ones end to end."""
    return 1 + (n - segment) // _segment_step(segment, window)


def _segment_step(segment, window):
    """Samples from one Welch segment's start to the next's: half a Hann one, a whole
    rectangular one."""
    return segment - segment // 2 if window == "hann" else segment


def derived(f, H, kind):
    """A receptance H (displacement per input) as the kind asked: itself, the mobility
    i omega H (velocity) or the accelerance -omega^2 H (acceleration), omega = 2 pi f: the
    derivatives of the response in time, exact on its Fourier transform."""
    return H * (2j * np.pi * np.asarray(f)) ** FRF_KINDS[kind]


def envelope(x, dt, band=None):
    """Amplitude envelope |x + i H(x)| of a series about its mean (H: the Hilbert transform),
    optionally of its part in a frequency band (f0, f1) [Hz] only: the growth of one mode
    among others.

    Returns (n,) in the unit of x.
    """
    from scipy.signal import hilbert
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = len(x)
    # zeros after the series: the FFT's wrap-around would put its (large, grown) end next to
    # its (small) start, whose envelope its ringing would then swamp
    if band is not None:
        X = np.fft.rfft(x, 2 * n)
        f = np.fft.rfftfreq(2 * n, dt)
        X[(f < band[0]) | (f > band[1])] = 0.0
        x = np.fft.irfft(X, 2 * n)[:n]
    return np.abs(hilbert(x, 2 * n)[:n])


def running_amplitude(x, samples):
    """The amplitude of a series' oscillation, sqrt(2) times its RMS about its running mean,
    both over a sliding window of `samples` (a period of the oscillation), centred, the ends
    held. Local, unlike the Hilbert envelope: a squeal growing over decades keeps its early,
    small amplitude, where the FFT's leakage from the large saturated end would swamp it.
    Returns (n,) in the unit of x."""
    x = np.asarray(x, dtype=float)
    n, w = len(x), max(1, min(int(samples), len(x)))

    def mean(y):
        c = np.concatenate([[0.0], np.cumsum(y)])
        m = (c[w:] - c[:-w]) / w
        lead = (n - len(m)) // 2
        return np.concatenate([np.full(lead, m[0]), m, np.full(n - len(m) - lead, m[-1])])
    return np.sqrt(2.0 * np.maximum(mean((x - mean(x)) ** 2), 0.0))


EDGE = 0.05          # fraction of the rows at each end left out of a fit (Hilbert's end effects)
SATURATION = 0.1     # a growth is fitted until the envelope first reaches this fraction of its
#                      peak: a limit cycle's saturation has slowed the growth by 1% there
DECAYED = 1e-3       # a decay is fitted from the peak until the envelope falls to this fraction


def growth_rate(t, env, window=None):
    """Exponential growth rate sigma [1/s] of an envelope, env ~ exp(sigma t), by least squares
    on log(env) over the linear phase: the window (t0, t1) given, or found: a growth from the
    start until the envelope first reaches SATURATION of its peak (a limit cycle begins), a
    decay from the peak until it falls to DECAYED of it; EDGE of the rows left out at each end.

    Returns (sigma, (t0, t1), rms): rms is the RMS deviation of log(env) from the line, how far
    from exponential the phase fitted is (0 for a pure exponential).
    """
    t, env = np.asarray(t, float), np.asarray(env, float)
    n = len(t)
    lo, hi = int(EDGE * n), n - int(EDGE * n)
    if window is not None:
        sel = (t >= window[0]) & (t <= window[1])
    else:
        inner = env[lo:hi]
        peak = lo + int(np.argmax(inner))
        if peak > lo + 0.5 * (hi - lo) or inner[0] < SATURATION * env[peak]:
            # growing: up to the first sample at SATURATION of the peak
            first = lo + int(np.argmax(inner >= SATURATION * env[peak]))
            sel = np.zeros(n, bool)
            sel[lo:max(first, lo + 2) + 1] = True
        else:
            above = np.flatnonzero(env[peak:hi] >= DECAYED * env[peak])
            sel = np.zeros(n, bool)
            sel[peak:peak + above[-1] + 1] = True
    sel &= env > 0
    if sel.sum() < 3:
        raise ValueError("fewer than 3 samples in the window fitted")
    A = np.stack([np.ones(sel.sum()), t[sel]], axis=1)
    y = np.log(env[sel])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    rms = float(np.sqrt(np.mean((A @ coef - y) ** 2)))
    return float(coef[1]), (float(t[sel][0]), float(t[sel][-1])), rms


def spectrogram(x, dt, segment):
    """Short-time amplitude spectra of a series: Hann segments of `segment` samples overlapping
    by three quarters. Returns (f (nf,) [Hz], t (nt,) [s] at segment centres, amplitude
    (nf, nt) in the unit of x, a sine of amplitude a reading about a)."""
    from scipy.signal import spectrogram as stft
    f, tc, S = stft(np.asarray(x, float), fs=1.0 / dt, window="hann", nperseg=segment,
                    noverlap=3 * segment // 4, detrend="constant", mode="magnitude",
                    scaling="spectrum")
    return f, tc, 2.0 * S


def peak_pooled(f, A, rows):
    """(f, A) with the frequency bins grouped by as many as make at most `rows` rows, each
    group drawn at its centre with its peak: a picture rasterizes thousands of bins into a few
    hundred pixels, where a stationary tone one bin wide (a limit cycle over 0.1 s segments:
    10 Hz in 40 kHz) falls between pixels and vanishes."""
    group = -(-len(f) // rows)
    if group <= 1:
        return f, A
    cut = list(range(0, len(f), group))
    return (np.add.reduceat(f, cut) / np.diff(cut + [len(f)]),
            np.maximum.reduceat(A, cut, axis=0))
