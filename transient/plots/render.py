"""Rendering set-up of the compatibility pictures: an OpenGL that needs no display, and pyvista.

`offscreen` imports pyvista for off-screen rendering (EGL or OSMesa when there is no display) or
raises `RenderingUnavailable` naming the system packages to install; the private helpers build
the plotter of a grid of panels, the arguments of a panel's colour bar, a triangulated surface
carrying a field, and the outline loops of faces lifted towards the camera.
"""
import ctypes.util
import os
import sys

import numpy as np

LIFT = 0.003         # outlines drawn this far (fraction of the length) above their faces


class RenderingUnavailable(RuntimeError):
    """No OpenGL that renders without a display: a system library is missing."""


def offscreen():
    """Import pyvista set for off-screen rendering, choosing an OpenGL that needs no display.

    VTK's wheels try X first and fall back to EGL, then OSMesa, printing a warning at each
    failure; without a display, ask for EGL (or OSMesa) directly. With none of them VTK
    crashes, so fail here with the packages to install.
    """
    headless = sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if headless and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ:
        if ctypes.util.find_library("EGL"):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
        elif ctypes.util.find_library("OSMesa"):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkOSOpenGLRenderWindow"
        else:
            raise RenderingUnavailable(
                "no display and no off-screen OpenGL: install libegl1 and libegl-mesa0 "
                "(or libosmesa6), or run under xvfb-run")
    import pyvista
    pyvista.OFF_SCREEN = True
    return pyvista


def _plotter(pv, shape, panel):
    rows, cols = shape
    return pv.Plotter(shape=shape, off_screen=True, border=False,
                      window_size=(panel[0] * cols, panel[1] * rows),
                      theme=pv.themes.DocumentTheme())


def _bar(title):
    # horizontal bar at the bottom of its panel; titles must differ between panels, pyvista
    # shares one bar between all meshes of a plotter with the same title
    return dict(title=title, vertical=False, position_x=0.2, position_y=0.02, width=0.6,
                height=0.12, fmt="%.2g", n_labels=5, title_font_size=16, label_font_size=14,
                color="black")


def _surface(pv, points, triangles, values, name):
    mesh = pv.PolyData(np.asarray(points, float),
                       np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
    mesh.point_data[name] = values
    return mesh


def _loops(pv, points, loops, view):
    # lifted towards the camera (always above the plane): lines lying exactly on their faces
    # would be half hidden by them
    points = points + LIFT * view.length * view.normal
    cells = np.concatenate([np.r_[len(lp) + 1, lp, lp[0]] for lp in loops])
    return pv.PolyData(np.asarray(points, float), lines=cells)
