"""A box of any cell type with its nodes moved: the element tests' meshes that no
generator makes."""
import numpy as np

from transient.mesh import generators
from transient.mesh.elements import ELEMENTS


def distorted_box(cell_type, curved=False, seed=0, divisions=(3, 3, 3),
                  size=(1.0, 0.8, 0.6)):
    """Box with every corner node moved by up to 20 % of the cell size per axis.

    Midside nodes go to the midpoints of the straight perturbed edges, or with curved=True are
    then moved by up to 6 % of the cell size (curved edges and faces).
    """
    mesh = generators.box(size, divisions, element=cell_type)
    el = ELEMENTS[cell_type]
    conn = mesh.cells[cell_type]
    h = np.asarray(size) / np.array(divisions)
    rng = np.random.default_rng(seed)
    points = mesh.points.copy()
    corners = np.unique(conn[:, :el.n_corners])
    points[corners] += rng.uniform(-0.2, 0.2, (len(corners), 3)) * h
    for k, (a, b) in enumerate(el.edges):
        points[conn[:, el.n_corners + k]] = 0.5 * (points[conn[:, a]] + points[conn[:, b]])
    if curved:
        mids = np.unique(conn[:, el.n_corners:])
        points[mids] += rng.uniform(-0.06, 0.06, (len(mids), 3)) * h
    return points, conn
