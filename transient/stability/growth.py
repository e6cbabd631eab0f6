"""The transient read on the complex modes: a run's motion projected on the complex modes of
its own system linearized at its preload, each mode's amplitude in time, and the growth rate
fitted where the mode stands out, beside the CEA's real part.

The first-order form. A reduced run integrates M a + D v + K q = f about its preload (M = I:
stability.linearize's matrices of the system the history stores, the friction's included; a
material's loss factor enters them as the viscous damping the run integrates, where the CEA
takes i H: the table's run and CEA real parts show the difference). With z = [q - q_eq; v] the
state about the equilibrium q_eq, B = [[I, 0], [0, M]] and A = [[0, I], [-K, -D]], the free
motion is B z' = A z. Its right eigenvectors x_k = [phi_k; lambda_k phi_k] (A x_k = lambda_k
B x_k) and left ones y_k (y_k^H A = lambda_k y_k^H B) are B-biorthogonal, y_j^H B x_k = 0 for
lambda_j != lambda_k, so z(t) = sum_k a_k(t) x_k over all 2n modes (conjugates included) gives
each amplitude alone:

    a_k(t) = y_k^H B z(t) / (y_k^H B x_k),     a_k(t) = a_k(0) exp(lambda_k t),

and |a_k(t)| is a pure exponential of rate Re lambda_k, with no oscillation to average out.
The x_k are scaled so that phi_k has unit mass norm (phi_k^H M phi_k = 1): |a_k| is then the
mode's amplitude in the reduced coordinates' unit, sqrt(kg) m (the motion 2 Re(a_k phi_k)
with its conjugate).

The velocity. A history stores q (output.field), not v: v comes from central differences of
the rows, h apart. For a free motion each mode's differences read sinh(lambda_k h) / h =:
mu_k instead of lambda_k, so z_h(t) = [q - q_eq; (q(t + h) - q(t - h)) / 2h] is sum_k a_k(t)
[phi_k; mu_k phi_k] exactly, at any stride. The amplitudes of the band's modes are then
G^-1 Y^H B z_h with G = Y^H B [Phi; Phi diag(mu)] over the band (Y its left eigenvectors):
exact for a motion of the band's modes, and the projection above as h -> 0. The band's modes
are told apart while sin(omega h) grows with omega, omega h < pi / 2: at least four rows a
period of the band's top (the CEA's fmax); the modes above it (the statics) leak in
through (mu_j - lambda_j), and decay.

The equilibrium. The history's first row is the preload the setup's Newton solved, to its
tolerance: a residual force that a 2 mN tap's motion does not dwarf (its static offset
projects on every mode as a constant, a beat in |a_k|). q_eq is that row moved by one Newton
step on the run's own forces there, with the loads as they stand once they stop changing:
q_eq = q0 + K^-1 a(q0, v = 0) (M = I).

The fit. The free motion starts once the loads stop changing (a tap's end); the linear phase
ends where the largest amplitude first reaches SATURATION of its peak (or the run's end while
it still grows). Within it, each mode is fitted from the start over the longest window where
log a_k(t) (its log amplitude and its phase about omega_k t) stays within `tolerance` RMS of a
line: past it the mode's own motion is no longer what the projection reads (the leaks of the
others, from the scheme's error and the contact's nonlinearity, grow with the strongest).
The growth is the least-squares slope of log|a_k| there. A mode whose window spans fewer than
MIN_PERIODS of its periods is not excited above that floor: it is marked, not fitted.
"""
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..case.signals import evaluate
from ..errors import DamagedHistory
from .linearize import linearized
from .modes import UNSTABLE_RTOL

# the RMS deviation of log a_k (amplitude and phase) from its line that a fit admits: the
# beat of a leak of the other modes' motion up to about 1.4% of the mode's own
LOG_RMS = 0.01

# the shortest window a fit takes, in the mode's periods: over fewer, a leak of a neighbour
# that beats slower than the window looks like the mode's own growth
MIN_PERIODS = 10

# rows per period of the band's top that the central differences need (omega h < pi / 2)
ROWS_PER_PERIOD = 4

# the linear phase ends where the largest amplitude first reaches this fraction of its peak:
# a limit cycle's saturation has slowed the growth by 1% there (plots.signals, the envelopes')
SATURATION = 0.1

# rows of the history read and projected at a time
BLOCK_ROWS = 4096


@dataclass(frozen=True)
class ModalGrowth:
    """A run's modal amplitudes and fitted growth rates (`modal_growth`): one entry per mode of
    the run's linearization in the band (imaginary part >= 0, by frequency)."""
    time: np.ndarray          # (r,) [s] of the rows projected
    eigenvalues: np.ndarray   # (k,) lambda of the run's linearization at its preload [1/s]
    amplitudes: np.ndarray    # (k, r) |a_k(t)| [sqrt(kg) m]
    growth: np.ndarray        # (k,) fitted growth rate [1/s], nan where not fitted
    resolution: np.ndarray    # (k,) [1/s] the slowest rate the window tells from neutral
    rms: np.ndarray           # (k,) RMS deviation of log a_k from its line in the window
    windows: np.ndarray       # (k, 2) [s] the rows fitted, nan where not fitted
    cea: np.ndarray           # (k,) the CEA's eigenvalue paired with each, nan without one
    cea_unstable: np.ndarray  # (k,) whether that CEA mode is unstable (by its own test)
    free_from: float          # [s] the free motion's start: the loads' last change
    linear_end: float         # [s] the linear phase's end
    stride: float             # [s] between rows

    @property
    def frequency_hz(self):
        return self.eigenvalues.imag / (2 * np.pi)

    @property
    def excited(self):
        """Whether each mode was fitted (excited above the floor of the others' leaks)."""
        return np.isfinite(self.growth)

    @property
    def resolved(self):
        """Whether each fitted mode's rate stands above its window's resolution."""
        with np.errstate(invalid="ignore"):
            return self.excited & (np.abs(self.growth) > self.resolution)

    @property
    def difference(self):
        """(projected growth - CEA real part) / |CEA real part|: nan where either is missing
        or the CEA's mode is neutral (its real part within the round-off the CEA allows it,
        modes.UNSTABLE_RTOL of |lambda|, where no relative figure means anything)."""
        ref = self.cea.real
        neutral = ~(np.abs(ref) > UNSTABLE_RTOL * np.abs(self.cea))
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(neutral, np.nan, (self.growth - ref) / np.abs(ref))

    def table(self):
        """One dict per mode: frequency [Hz], the CEA's real part, the run's linearization's,
        the projected growth and its window's resolution [1/s], their relative difference,
        the fit's window [s] and RMS deviation, the amplitude's range over the window."""
        rows = []
        for k, lam in enumerate(self.eigenvalues):
            t0, t1 = self.windows[k]
            inside = (self.time >= t0) & (self.time <= t1)
            amp = self.amplitudes[k, inside] if inside.any() else self.amplitudes[k, :0]
            rows.append({"frequency_hz": float(lam.imag / (2 * np.pi)),
                         "cea_real": _number(self.cea[k].real),
                         "cea_unstable": bool(self.cea_unstable[k]),
                         "run_real": float(lam.real),
                         "growth": _number(self.growth[k]),
                         "resolution": _number(self.resolution[k]),
                         "difference": _number(self.difference[k]),
                         "window_s": [_number(t0), _number(t1)],
                         "rms": _number(self.rms[k]),
                         "amplitude": [_number(amp.min()) if amp.size else None,
                                       _number(amp.max()) if amp.size else None],
                         "excited": bool(self.excited[k]),
                         "resolved": bool(self.resolved[k])})
        return rows


def _number(x):
    return float(x) if np.isfinite(x) else None


def modal_growth(system, preload, time, rows, fmax, free_from, cea=None, window=None,
                 tolerance=LOG_RMS):
    """The run's motion on the complex modes of its linearization at its preload.

    Parameters
    ----------
    system : ReducedSystem
        The system the run integrated (io.systems.read_system).
    preload : (n,) array
        Its preload q0, where it is linearized (a history's first row).
    time : (r,) array
        The rows' times [s], evenly spaced.
    rows : callable
        rows(i, j) -> (j - i, n) the stored q of rows i to j.
    fmax : float
        The band's top [Hz]: its modes are projected and fitted.
    free_from : float
        [s] the loads' last change: the free motion's start.
    cea : ComplexModes, optional
        The CEA's modes, each of the run's paired with its nearest (one to one).
    window : (t0, t1), optional
        [s] the rows fitted whole by every mode, instead of the free motion's linear phase
        (its start then the time whose loads the equilibrium holds).
    tolerance : float
        The RMS deviation of log a_k from its line a fit admits.

    Returns
    -------
    ModalGrowth
    """
    time = np.asarray(time, float)
    h = float(time[1] - time[0])
    q0 = np.asarray(preload, float)
    t0, t1 = (free_from, time[-1]) if window is None else window
    M, D, K = linearized(system, _Preload(q0))
    eq = equilibrium(system, q0, t0, K)
    lam, left, right = first_order_modes(M, D, K)
    band = np.abs(lam.imag) <= 2 * np.pi * fmax
    lam, left, right = lam[band], left[:, band], right[:, band]
    project = projector(lam, left, right, M, h)
    shown = np.flatnonzero(lam.imag >= 0)
    shown = shown[np.lexsort((lam[shown].real, lam[shown].imag))]
    first = max(int(np.searchsorted(time, t0)), 1)
    last = min(int(np.searchsorted(time, t1, side="right")), len(time) - 1)
    a = np.empty((len(shown), max(last - first, 0)), complex)
    for i in range(first, last, BLOCK_ROWS):
        j = min(i + BLOCK_ROWS, last)
        q = rows(i - 1, j + 1)
        z = np.hstack([q[1:-1] - eq, (q[2:] - q[:-2]) / (2 * h)])
        a[:, i - first:j - first] = project(z.T)[shown]
    t, lam = time[first:last], lam[shown]
    amp = np.abs(a)
    end = len(t) if window is not None else linear_end(amp)
    growth, resolution, rms, windows = fit_modes(t[:end], a[:, :end], lam,
                                             tolerance if window is None else np.inf)
    partner = nearest_pairs(lam, cea.eigenvalues) if cea is not None else np.full(len(lam), -1)
    found = partner >= 0
    paired = np.where(found, cea.eigenvalues[partner] if found.any() else 0j, np.nan + 0j)
    unstable = found & (cea.unstable[partner] if found.any() else False)
    return ModalGrowth(t, lam, amp, growth, resolution, rms, windows, paired, unstable,
                       float(free_from), float(t[end - 1]) if end else float(t0), h)


class _Preload:
    """The state linearize reads: the preload's q."""

    def __init__(self, q):
        self.q = q


def equilibrium(system, q0, t, K):
    """q_eq: the preload q0 moved by one Newton step on the run's forces there, at rest, with
    the loads at time t [s]: the force the setup's Newton left, and the loads' change since,
    taken by the stiffness K linearized there (M = I)."""
    from ..dynamics.schemes import initial_acceleration
    from ..dynamics.state import State
    state = State.zeros(system.n, system.n_points)
    state.q[:] = q0
    state.time = t
    initial_acceleration(system, state, False)
    return q0 + np.linalg.solve(K, state.a)


def first_order_modes(M, D, K):
    """(lambda (2n,), left (2n, 2n), right (2n, 2n)) of B z' = A z, z = [q; v], the right
    eigenvectors scaled so that their displacement part phi has phi^H M phi = 1."""
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -D]])
    # a reduced model's M = I: the standard problem (Hessenberg QR, half QZ's work)
    B = None if np.array_equal(M, np.eye(n)) else np.block([[np.eye(n), np.zeros((n, n))],
                                                            [np.zeros((n, n)), M]])
    lam, left, right = sla.eig(A, B, left=True, right=True)
    phi = right[:n]
    right = right / np.sqrt(np.real(np.einsum("ik,ij,jk->k", phi.conj(), M, phi)))
    return lam, left, right


def projector(lam, left, right, M, h):
    """z_h (2n, r) -> the amplitudes a (k, r) of the modes given (lambda (k,), their left and
    right eigenvectors), from states whose velocity is the central difference of q over rows
    h [s] apart: G^-1 Y^H B z_h, G = Y^H B [Phi; Phi diag(mu)], mu = sinh(lambda h) / h."""
    n = M.shape[0]
    phi = right[:n]
    mu = np.sinh(lam * h) / h
    YB = np.hstack([left[:n].conj().T, left[n:].conj().T @ M])
    lu = sla.lu_factor(YB @ np.vstack([phi, phi * mu]))
    return lambda z: sla.lu_solve(lu, YB @ z)


def linear_end(amp):
    """Rows of the linear phase: up to where the largest amplitude, growing from its lowest
    before its peak, first reaches SATURATION of that peak; all of them while it still grows
    at the end, or when it never grows (a decay from the loads' motion)."""
    largest = amp.max(axis=0) if amp.size else amp.sum(axis=0)
    if not len(largest):
        return 0
    peak = int(np.argmax(largest))
    low = int(np.argmin(largest[:peak + 1]))
    if peak == len(largest) - 1 or low == peak:
        return len(largest)
    return low + int(np.argmax(largest[low:] >= SATURATION * largest[peak])) + 1


def fit_modes(t, a, lam, tolerance):
    """(growth, resolution, rms, windows) of amplitudes a (k, r) at times t: for each mode,
    the least-squares line of log a_k (log amplitude and phase about Im lambda_k t) from the
    first row over the most rows whose RMS deviation is within tolerance, its window at least
    MIN_PERIODS periods long; nan where there is none.

    The resolution is the rate whose own line over the window, |sigma| T / (2 sqrt 3) about
    its mean, is as large as the log amplitude's RMS deviation from the fit: a slower rate is
    buried in what the fit leaves, and its sign is not an answer."""
    k, r = a.shape
    growth, resolution, rms = (np.full(k, np.nan) for _ in range(3))
    windows = np.full((k, 2), np.nan)
    if r < 3:
        return growth, resolution, rms, windows
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.log(a * np.exp(-1j * lam.imag[:, None] * (t - t[0])))
    y = y.real + 1j * np.unwrap(y.imag, axis=1)
    # every window from the first row at once, by cumulative sums, on a centred time
    s = (t - t[0]) / max(t[-1] - t[0], 1e-300)
    count = np.arange(1, r + 1)
    St, Stt = np.cumsum(s), np.cumsum(s * s)
    var_t = Stt - St ** 2 / count
    with np.errstate(divide="ignore", invalid="ignore"):
        rss = sum(_rss(part, s, count, St, var_t) for part in (y.real, y.imag))
        dev = np.sqrt(np.maximum(rss, 0.0) / count)
    periods = (t - t[0]) * lam.imag[:, None] / (2 * np.pi)
    ok = (dev <= tolerance) & (periods >= MIN_PERIODS) & np.isfinite(dev)
    ok[:, :2] = False
    for m in np.flatnonzero(ok.any(axis=1)):
        e = int(np.flatnonzero(ok[m])[-1]) + 1
        tw, yw = t[:e], y[m, :e].real
        tc = tw - tw.mean()
        slope = float(tc @ (yw - yw.mean()) / (tc @ tc))
        res = yw - yw.mean() - slope * tc
        growth[m] = slope
        resolution[m] = 2 * np.sqrt(3.0) * np.sqrt(res @ res / e) / (tw[-1] - tw[0])
        rms[m] = dev[m, e - 1]
        windows[m] = t[0], t[e - 1]
    return growth, resolution, rms, windows


def _rss(y, s, count, St, var_t):
    """Residual sums of squares of the least-squares lines of y (k, r) on s over each prefix
    of the rows, (k, r), from cumulative sums (y about its mean, for the differences' sake)."""
    y = y - y.mean(axis=1, keepdims=True)
    Sy, Sty, Syy = np.cumsum(y, axis=1), np.cumsum(s * y, axis=1), np.cumsum(y * y, axis=1)
    cov = Sty - St * Sy / count
    return Syy - Sy ** 2 / count - cov ** 2 / var_t


def nearest_pairs(lam, reference):
    """(k,) the index of the eigenvalue of reference paired with each of lam, one to one by
    the nearest (scipy's assignment on |lambda - lambda_ref|); -1 where none is left. Not
    stability.compare.pair_modes, which pairs the unstable modes of two analyses, each with
    its nearest, for their comparison's tolerances."""
    from scipy.optimize import linear_sum_assignment
    out = np.full(len(lam), -1)
    if len(lam) and len(reference):
        i, j = linear_sum_assignment(np.abs(lam[:, None] - reference[None, :]))
        out[i] = j
    return out


def loads_end(case, dt, t_last):
    """[s] the run's first step after which no load changes (the loads' signals evaluated on
    the steps k dt up to t_last, as the kernels take them): 0 without any that changes, and
    ({load: its end}) of each, for messages."""
    steps = np.arange(int(round(t_last / dt)) + 1) * dt
    ends = {}
    for name, load in case.loads.items():
        if load.signal["kind"] == "constant":
            continue
        s = evaluate(load.signal, steps)
        changed = np.flatnonzero(s != s[-1])
        if len(changed):
            ends[name] = float(steps[changed[-1] + 1])
    return max(ends.values(), default=0.0), ends


def history_growth(stored, modes=None, window=None, tolerance=LOG_RMS):
    """modal_growth of a history (io.stored.Stored), its rows checked: the state stored, a
    reduced system, rows evenly spaced and often enough for the band, loads that stop
    changing. modes: the CEA's ComplexModes to pair with, or a callable that makes them of
    the history's case once the checks pass (None: no pairing)."""
    from ..io.systems import read_system
    from .stage import fmax_of
    stored = stored.uniform()
    if "field/q" not in stored.series:
        raise stored.error("output.field", "the run stored no state to project: run with "
                           "output.field = true")
    case = stored.case()
    time = stored.time()
    if len(time) < 4:
        raise stored.error("time", f"{len(time)} rows: too few to project")
    h = float(time[1] - time[0])
    if not np.allclose(np.diff(time), h, rtol=1e-6, atol=0.0):
        raise stored.error("time", "rows not evenly spaced: the central differences need "
                           "one stride")
    fmax = fmax_of(case)
    if ROWS_PER_PERIOD * h * fmax > 1.0:
        raise stored.error("output.every", f"a row every {h:.4g} s, {1 / (h * fmax):.3g} a "
                           f"period of the band's top ({fmax:g} Hz): the projection's central "
                           f"differences need {ROWS_PER_PERIOD}; store rows more often "
                           f"(output.every = {case.output.every} now)")
    free_from, ends = loads_end(case, stored.meta.get("dt", h), time[-1])
    if window is None and free_from >= time[-3]:
        name = max(ends, key=ends.get)
        raise stored.error(f"loads.{name}.signal", "changes up to the run's end: no free "
                           "motion to fit (give a window)")
    with stored.open() as f:
        try:
            system = read_system(f)
        except (KeyError, DamagedHistory) as exc:
            raise stored.error("system", f"damaged history, or one without the system it "
                               f"integrated (written before this version kept it): {exc}") \
                from None
        if not system.reduced:
            raise stored.error("solver.reduction.enabled", "a full model's run: the "
                               "projection takes the dense complex modes of a reduced one")
        if callable(modes):
            modes = modes(case)
        series = f["field/q"]
        return modal_growth(system, series[0], time, lambda i, j: series[i:j], fmax,
                            free_from, modes, window, tolerance)
