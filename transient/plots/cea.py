"""Pictures of a complex eigenvalue analysis: the stability diagram, the shapes of the unstable
modes on the pad and disc, and the map of the modes against the friction coefficient."""
import numpy as np

from .render import offscreen

MAP_CMAP = "coolwarm"


def stability_figure(analysis, path, title):
    """Frequency against real part and against damping ratio; unstable modes in red."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    modes = analysis.modes
    f = modes.frequency_hz / 1e3
    bad = modes.unstable
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, x, label in ((axes[0], modes.real, "real part [1/s] (> 0 grows)"),
                         (axes[1], modes.damping_ratio, "damping ratio (< 0 grows)")):
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.plot(x[~bad], f[~bad], "o", ms=4, color="0.45", label="stable")
        ax.plot(x[bad], f[bad], "o", ms=6, color="tab:red", label="unstable")
        ax.set_xlabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("frequency [kHz]")
    axes[0].legend(loc="lower right")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def mu_map_figure(mus, analyses, path, title):
    """The classic squeal map: frequency against mu, coloured by the real part; unstable modes
    outlined."""
    map_figure(mus, [a.modes for a in analyses], path, title, "friction coefficient mu")


def map_figure(values, modes, path, title, xlabel):
    """Frequency against a parameter's values, coloured by the real part, unstable modes
    outlined: modes[i] (frequency_hz, real, unstable arrays) at values[i]."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm
    mu = np.concatenate([np.full(len(m.real), x) for x, m in zip(values, modes)])
    f, real, bad = (np.concatenate([np.asarray(getattr(m, k)) for m in modes])
                    for k in ("frequency_hz", "real", "unstable"))
    # a flutter pair shares its frequency: the growing member is drawn last, on top
    order = np.argsort(real, kind="stable")
    top = max(np.abs(real).max(), 1e-300)
    norm = TwoSlopeNorm(vmin=-top, vcenter=0.0, vmax=top)
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.scatter(mu[order], f[order] / 1e3, c=real[order], cmap=MAP_CMAP, norm=norm, s=18,
               edgecolors=np.where(bad[order], "black", "none"), linewidths=0.8)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=MAP_CMAP)
    fig.colorbar(sm, ax=ax, label="real part [1/s] (outlined: unstable)")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("frequency [kHz]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def mode_figure(model, u, path, title):
    """The real and imaginary parts of a complex mode on the parts' surfaces, warped, coloured
    by the magnitude of the displacement."""
    import meshio
    pv = offscreen()
    mesh = model.mesh()
    grid = pv.from_meshio(meshio.Mesh(mesh.points, list(mesh.cells.items())))
    u = np.asarray(u).reshape(-1, 3)
    u = u / np.abs(u).max()
    extent = np.ptp(mesh.points, axis=0).max()
    plotter = pv.Plotter(shape=(1, 2), off_screen=True, window_size=(1400, 640),
                         theme=pv.themes.DocumentTheme())
    for k, (part, name) in enumerate(((u.real, "real part"), (u.imag, "imaginary part"))):
        plotter.subplot(0, k)
        g = grid.copy()
        g.point_data["u"] = part
        g.point_data["|u|"] = np.linalg.norm(part, axis=1)
        surface = g.extract_surface(algorithm="dataset_surface")
        warped = surface.warp_by_vector("u", factor=0.05 * extent)
        plotter.add_mesh(warped, scalars="|u|", cmap="viridis", show_scalar_bar=k == 1,
                         scalar_bar_args={"title": "|u| (max 1)", "color": "black"})
        plotter.add_text(f"{title}: {name}", font_size=10, color="black")
        plotter.view_isometric()
    plotter.screenshot(str(path))
    plotter.close()
