"""Pictures of a complex eigenvalue analysis: the stability diagram and the shapes of the
unstable modes on the pad and disc (the map of the modes against the friction coefficient:
plots.branches)."""
import numpy as np

from .render import offscreen


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
