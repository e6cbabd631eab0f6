"""The transfer function of two modal models of one case and their frequency shifts, side by
side (the paper's figure 11: a rich contact rule's locking against the regularized one)."""
import numpy as np


def modal_frf_figure(f, curves, labels, shifts, path, title):
    """Left: |H| of each curve against frequency [kHz]; right: each mode's frequency shift of
    the second model over the first [%] against the mode number (pairs by MAC)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5),
                                 gridspec_kw={"width_ratios": [1.6, 1]})
    for H, label, style in zip(curves, labels, ("-", "--")):
        ax.semilogy(f / 1e3, np.abs(H), style, lw=1.2, label=label)
    ax.set_xlabel("frequency [kHz]")
    ax.set_ylabel("|H| [m/N]")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    numbers = np.arange(1, len(shifts) + 1)
    bx.bar(numbers, shifts, color=np.where(shifts >= 0, "tab:red", "tab:blue"))
    bx.axhline(0.0, color="0.4", lw=0.8)
    bx.set_xlabel(f"mode number ({labels[0]})")
    bx.set_ylabel(f"frequency shift of {labels[1]} [%]")
    bx.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
