"""A run read mode by mode (stability.growth): the modal amplitudes |a_k(t)| on a log axis with
their fitted exponentials, and the table beside the CEA's as CSV."""
import numpy as np

from ..io.tables import write_csv

# the stable modes drawn beside the unstable ones: the strongest at the free motion's start
STABLE_SHOWN = 6

COLUMNS = ("frequency_hz", "cea_real", "cea_unstable", "run_real", "growth", "resolution",
           "difference", "t0", "t1", "rms", "amplitude_min", "amplitude_max", "excited",
           "resolved")


def growth_rows(result):
    """The table of a ModalGrowth as flat rows (COLUMNS; None where there is no value)."""
    rows = []
    for row in result.table():
        flat = dict(row)
        flat["t0"], flat["t1"] = flat.pop("window_s")
        flat["amplitude_min"], flat["amplitude_max"] = flat.pop("amplitude")
        rows.append({name: flat[name] for name in COLUMNS})
    return rows


def write_growth_csv(result, path):
    """The table of a ModalGrowth as CSV, one line per mode, empty cells where no value."""
    write_csv(path, COLUMNS, growth_rows(result))


def shown_modes(result):
    """Indices of the modes drawn: the unstable ones (by the CEA, or by the run's own
    linearization where no CEA mode is paired, by the CEA's test), then the STABLE_SHOWN
    stable ones fitted with the largest amplitude."""
    from ..stability.modes import UNSTABLE_RTOL
    lam = result.eigenvalues
    own = (lam.real > UNSTABLE_RTOL * np.abs(lam)) & ~np.isfinite(result.cea)
    unstable = result.cea_unstable | own
    start = result.amplitudes[:, 0] if result.amplitudes.shape[1] else np.zeros(len(unstable))
    stable = np.flatnonzero(~unstable & result.excited)
    stable = stable[np.argsort(-start[stable])][:STABLE_SHOWN]
    return np.concatenate([np.flatnonzero(unstable), np.sort(stable)])


def growth_figure(result, path, title):
    """|a_k(t)| of the modes shown_modes picks against time [ms], log amplitude; each fit
    dashed over its window, the linear phase's end dotted."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 6))
    t = result.time
    for k in shown_modes(result):
        cea = result.cea[k].real
        label = (f"{result.frequency_hz[k]:.0f} Hz: "
                 + (f"{result.growth[k]:.4g} 1/s" if result.excited[k] else "not excited")
                 + (f" (CEA {cea:.4g})" if np.isfinite(cea) else ""))
        line, = ax.semilogy(t * 1e3, np.maximum(result.amplitudes[k], 1e-300), lw=1.1,
                            label=label)
        if result.excited[k]:
            t0, t1 = result.windows[k]
            sel = (t >= t0) & (t <= t1)
            log_a = np.log(np.maximum(result.amplitudes[k, sel], 1e-300))
            c = np.mean(log_a - result.growth[k] * t[sel])
            ax.semilogy(t[sel] * 1e3, np.exp(c + result.growth[k] * t[sel]), "--", lw=1.8,
                        color=line.get_color())
    ax.axvline(result.linear_end * 1e3, color="0.4", ls=":", lw=1)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("modal amplitude |a_k| [sqrt(kg) m]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
