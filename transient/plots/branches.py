"""The squeal map of complex modes against a parameter (`plot cea --mu`, `plot sweep`): each
branch (stability.branches) a line of frequency against the parameter coloured by its real part,
and its real part against the parameter; the points where a branch turns unstable marked."""
import numpy as np

MAP_CMAP = "coolwarm"
GROWING = ("tab:red", "tab:purple", "tab:orange", "tab:brown", "tab:pink", "tab:olive")


def branches_figure(branches, path, title, xlabel):
    """Frequency (kHz, or Hz below 1 kHz) and real part [1/s] against the parameter, a line per
    branch: on the left coloured by the real part (a diverging map centred at 0, red
    grows), on the right the branches unstable somewhere in colour, named in the legend,
    the others grey; the coupling points (where a branch turns unstable) starred on both."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.colors import TwoSlopeNorm
    real = np.concatenate([s.eigenvalues.real for s in branches.steps])
    # each side of 0 spans its own extreme: a weak growth stays red beside strong damping
    low, high = min(real.min(initial=0.0), -1e-12), max(real.max(initial=0.0), 1e-12)
    norm = TwoSlopeNorm(vmin=low, vcenter=0.0, vmax=high)
    top = max((s.eigenvalues.imag.max(initial=0.0) for s in branches.steps), default=0.0)
    scale, unit = (2e3 * np.pi, "kHz") if top >= 2e3 * np.pi else (2 * np.pi, "Hz")
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.5))
    right.axhline(0.0, color="0.6", lw=0.8)
    colours = iter(GROWING * (1 + branches.count // len(GROWING)))
    lines = [branches.line(b) for b in range(branches.count)]
    # the growing branches drawn last: a flutter pair shares its frequency, the growing
    # member on top
    for b in sorted(range(branches.count), key=lambda b: lines[b][1].real.max()):
        x, lam, bad = lines[b]
        f = lam.imag / scale
        if len(x) > 1:
            points = np.stack([x, f], axis=1)
            segments = LineCollection(np.stack([points[:-1], points[1:]], axis=1),
                                      cmap=MAP_CMAP, norm=norm, linewidths=2.0)
            segments.set_array(0.5 * (lam.real[:-1] + lam.real[1:]))
            left.add_collection(segments)
        left.scatter(x, f, c=lam.real, cmap=MAP_CMAP, norm=norm, s=12, zorder=3,
                     edgecolors=np.where(bad, "black", "none"), linewidths=0.8)
        if bad.any():
            right.plot(x, lam.real, "o-", ms=3, lw=1.6, color=next(colours), zorder=3,
                       label=f"branch {b} ({f[np.argmax(lam.real)]:.3g} {unit})")
        else:
            right.plot(x, lam.real, "-", lw=0.8, color="0.7")
    # the growth an unstable mode exceeds (cea.threshold.growth_rate), where the stars sit
    limit = max((s.threshold for s in branches.steps), default=0.0)
    if limit > 0:
        right.axhline(limit, color="black", lw=0.8, ls="--", label="threshold")
    if branches.coupling:
        at = np.array([[c[branches.parameter], 2 * np.pi * c["frequency_hz"] / scale]
                       for c in branches.coupling])
        left.plot(at[:, 0], at[:, 1], "*", ms=13, mfc="none", mec="black", mew=1.4, zorder=4,
                  label="turns unstable (or stable)")
        right.plot(at[:, 0], np.full(len(at), limit), "*", ms=13, mfc="none", mec="black",
                   mew=1.4, zorder=4)
        left.legend(loc="best", fontsize=8)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=MAP_CMAP), ax=left,
                 label="real part [1/s] (> 0 grows; outlined: unstable)")
    left.autoscale_view()
    left.set_ylabel(f"frequency [{unit}]")
    right.set_ylabel("real part [1/s] (> 0 grows)")
    if right.get_legend_handles_labels()[0]:
        right.legend(loc="best", fontsize=8)
    for ax in (left, right):
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
    fig.suptitle(f"{title}: {branches.count} branches linked by "
                 f"{'MAC of their shapes' if branches.linked_by == 'shapes' else 'eigenvalue'}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
