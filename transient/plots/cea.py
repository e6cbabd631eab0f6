"""Pictures of a complex eigenvalue analysis: the stability diagram and the shapes of the
unstable modes on the pad and disc (the map of the modes against the friction coefficient:
plots.branches)."""
import numpy as np

from .render import offscreen

WARP = 0.05             # the largest displacement of a mode drawn as this part of the model's size
DIVERGING = "coolwarm"  # signed colours centred at zero: the nodal lines are where it is white
CORNERS = {"lower_left": 0, "upper_left": 2}     # vtkCornerAnnotation's numbers of its corners


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


def out_of_plane(case, model):
    """(3,) the direction a mode's picture colours by, and its name: the axis of the case's
    rotation, the disc's axial direction that the descriptors call out of plane
    (stability.diameters), else the model's thinnest principal direction (a plate's normal)."""
    rotation = next((m for m in case.motion.values() if m.kind == "rotation"), None)
    if rotation is not None:
        axis = np.asarray(rotation.axis, float)
        return axis / np.linalg.norm(axis), f"the axis of {rotation.part}'s rotation"
    x = model.points - model.points.mean(axis=0)
    thinnest = np.linalg.eigh(x.T @ x)[1][:, 0]
    # a fixed sign: the picture does not flip its colours between meshes
    thinnest = thinnest if thinnest[np.argmax(np.abs(thinnest))] > 0 else -thinnest
    return thinnest, "the model's thinnest direction"


def mode_panels(points, u, direction, colour="out-of-plane"):
    """The numbers of a complex mode's picture, nothing drawn: for its real and imaginary
    parts, the displacement drawn at each point (the shape scaled so that its largest
    displacement, over both parts, is WARP of the model's size) and the colour, the signed
    displacement along `direction` over that largest one (its zero is the nodal lines; the
    magnitude of the part's displacement with colour = "magnitude").

    Parameters
    ----------
    points : (n, 3) array
        The model's points [m].
    u : (3 n,) complex array
        The mode's displacement, any normalization.
    direction : (3,) unit vector
        Out of plane.

    Returns
    -------
    dict
        "scale" (drawn displacement per unit of u), "size" (the model's largest extent
        [m]), "panels" [{"name", "warp" (n, 3) [m], "colour" (n,)}], "caption" (the warp
        scale stated).
    """
    u = np.asarray(u).reshape(-1, 3)
    largest = np.sqrt(np.max(np.sum(np.abs(u) ** 2, axis=1)))
    size = float(np.ptp(points, axis=0).max())
    scale = WARP * size / largest
    panels = []
    for name, part in (("real part", u.real), ("imaginary part", u.imag)):
        value = (part @ direction if colour == "out-of-plane"
                 else np.linalg.norm(part, axis=1)) / largest
        panels.append({"name": name, "warp": scale * part, "colour": value})
    caption = (f"warp x {scale:.3g}: the largest displacement drawn as {WARP:.0%} of the "
               f"model's size ({size * 1e3:.4g} mm)")
    return {"scale": scale, "size": size, "panels": panels, "caption": caption}


def mode_figure(model, u, path, title, direction, colour="out-of-plane", along=""):
    """The real and imaginary parts of a complex mode on the parts' surfaces, warped by a
    stated scale (`mode_panels`), coloured by the signed displacement along `direction`
    (named by `along`) on a diverging map centred at zero, where the nodal lines show, or by
    its magnitude. Returns the numbers drawn and the texts placed ({"panels"..., "texts"})."""
    import meshio
    pv = offscreen()
    mesh = model.mesh()
    grid = pv.from_meshio(meshio.Mesh(mesh.points, list(mesh.cells.items())))
    drawn = mode_panels(mesh.points, u, direction, colour)
    signed = colour == "out-of-plane"
    # (no vertical bars: the bar's font draws them as blanks)
    bar = ("u along " + (along or "(" + ", ".join(f"{c + 0.0:.2f}" for c in direction) + ")")
           if signed else "magnitude of u") + ", over the largest displacement"
    plotter = pv.Plotter(shape=(1, 2), off_screen=True, window_size=(1400, 680),
                         theme=pv.themes.DocumentTheme())
    texts = []
    for k, panel in enumerate(drawn["panels"]):
        plotter.subplot(0, k)
        g = grid.copy()
        g.point_data["warp"] = panel["warp"]
        g.point_data["colour"] = panel["colour"]
        surface = g.extract_surface(algorithm="dataset_surface")
        warped = surface.warp_by_vector("warp", factor=1.0)
        plotter.add_mesh(warped, scalars="colour", cmap=DIVERGING if signed else "viridis",
                         clim=(-1.0, 1.0) if signed else (0.0, 1.0), show_scalar_bar=k == 1,
                         scalar_bar_args={"title": bar, "color": "black"})
        for text, where in ((f"{title}: {panel['name']}", "upper_left"),
                            (drawn["caption"], "lower_left")):
            actor = plotter.add_text(text, position=where, font_size=9, color="black")
            # read back from the picture's own text (a CornerAnnotation, one text a corner)
            texts.append(actor.GetText(CORNERS[where]))
        plotter.view_isometric()
    plotter.screenshot(str(path))
    plotter.close()
    return dict(drawn, texts=texts)
