"""A part's interface reduced to the fields of its loaded interface (reduce/fields.py): their
count is set by the cutoff, not by the interface's mesh, and they hold the tractions of the
part's rigid motions (a uniform pressure) exactly."""
import numpy as np
import scipy.sparse as sp

from transient.case.loading import load
from transient.model import build_model
from transient.reduce.fields import field_map, part_rigid_motions

K_CONTACT = 5e11      # [Pa/m], a lining's contact at 1 MPa
CUTOFF = 40000.0      # [Hz]


def plate(tmp_path, n):
    """A free steel plate 0.1 x 0.1 x 0.02 m in hex8, n x n cells in plane: its model, and
    its upper face's normal dofs with their share of the face's area [m^2]."""
    path = tmp_path / f"plate{n}.toml"
    path.write_text('[materials.steel]\nE = 2.1e11\nnu = 0.3\nrho = 7850.0\n'
                    '[parts.plate]\nmaterial = "steel"\n[parts.plate.mesh]\nkind = "box"\n'
                    f'size = [0.1, 0.1, 0.02]\ndivisions = [{n}, {n}, {max(1, n // 4)}]\n'
                    'element = "hex8"\n[solver]\nt_end = 1e-4\n')
    model = build_model(load(path))
    top = np.flatnonzero(np.isclose(model.points[:, 2], model.points[:, 2].max()))
    x, y = model.points[top, 0], model.points[top, 1]
    h = 0.1 / n
    # the bilinear face's nodal areas: h^2 inside, halved on an edge, quartered at a corner
    area = h * h * np.where(np.isclose(x, 0) | np.isclose(x, 0.1), 0.5, 1.0) * np.where(
        np.isclose(y, 0) | np.isclose(y, 0.1), 0.5, 1.0)
    return model, 3 * top + 2, area


def fields(model, dofs, area):
    """P of the plate's upper face loaded by springs K_CONTACT over it: one load column (a
    compatible shape of its own) per normal dof."""
    ndof, k = model.ndof, len(dofs)
    E = sp.csc_matrix((np.ones(k), (dofs, np.arange(k))), shape=(ndof, k))
    G = np.diag(K_CONTACT * area)
    support = sp.csr_matrix((K_CONTACT * area, (dofs, dofs)), shape=(ndof, ndof))
    rigid = part_rigid_motions(model.points, np.arange(ndof))
    return field_map(model.K, model.M, support, E, G, np.arange(k), np.zeros(k, int), rigid,
                     CUTOFF, 1.0, "auto")


def test_the_fields_count_is_set_by_the_cutoff_not_the_mesh(tmp_path):
    counts = {}
    for n in (8, 16):
        model, dofs, area = plate(tmp_path, n)
        P = fields(model, dofs, area)
        counts[n] = (len(dofs), P.shape[1])
        np.testing.assert_allclose(P.T @ P, np.eye(P.shape[1]), atol=1e-12)
        # a uniform pressure (the tractions of the rigid motion along the normal) is a field
        w = area / np.linalg.norm(area)
        assert np.linalg.norm(w - P @ (P.T @ w)) < 1e-10
    (loads8, fields8), (loads16, fields16) = counts[8], counts[16]
    assert loads16 > 3 * loads8
    assert fields16 <= 1.25 * fields8 and fields16 < loads16 / 4


def test_rigid_motions_are_rigid(tmp_path):
    """K R = 0 on a free part: each column a rigid translation or rotation."""
    model, _, _ = plate(tmp_path, 4)
    R = part_rigid_motions(model.points, np.arange(model.ndof))
    assert np.linalg.norm(model.K @ R) <= 1e-9 * sp.linalg.norm(model.K) * np.linalg.norm(R)
    assert np.linalg.matrix_rank(R) == 6
