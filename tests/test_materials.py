"""Anisotropic elasticity from engineering constants: the stiffness against scikit-fem's with
the elasticity tensor built here from the constants and turned by the orientation, frequencies
against scikit-fem's eigenproblem and a bar's closed form, bad constants refused at load.

The tensor is built independently of transient.case.materials and transient.model.elasticity:
the compliance from Abaqus's definition of the constants (eps_j = -nu_ij sigma_i / E_i), the
rotation as the tensor's C_ijkl = Q_ip Q_jq Q_kr Q_ls C'_pqrs, never through a Voigt matrix.
"""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

skfem = pytest.importorskip("skfem")
from skfem import Basis, BilinearForm, ElementVector  # noqa: E402
from skfem.helpers import dot, sym_grad  # noqa: E402
from test_assembly_reference import (SKFEM, distorted_box, dof_permutation,  # noqa: E402
                                     local_order, relative, skfem_mesh, skfem_rule)

from transient.case.specs import MaterialSpec, OrientationSpec  # noqa: E402
from transient.cli import main  # noqa: E402
from transient.mesh.elements import ELEMENTS  # noqa: E402
from transient.model.assembly import CellBlock, assemble  # noqa: E402
from transient.model.elasticity import anisotropy  # noqa: E402

RHO = 2500.0
# a lining: stiffer in its plane than through its thickness
LINING = dict(E_p=8e9, nu_p=0.25, E_t=3e9, nu_pt=0.3, G_t=1.5e9)
ORTHO = dict(E1=1.5e11, E2=6e10, E3=2e10, nu12=0.32, nu13=0.25, nu23=0.4, G12=3e10,
             G13=1.2e10, G23=9e9)
A, B = (1.0, 0.4, -0.3), (0.2, 1.0, 0.5)       # a rectangular frame, not along any axis


def nine(elasticity, c):
    """The orthotropic constants of a material's keys."""
    if elasticity == "orthotropic":
        return c
    return dict(E1=c["E_p"], E2=c["E_p"], E3=c["E_t"], nu12=c["nu_p"], nu13=c["nu_pt"],
                nu23=c["nu_pt"], G12=c["E_p"] / (2 * (1 + c["nu_p"])), G13=c["G_t"],
                G23=c["G_t"])


def compliance(elasticity, c):
    """(9, 6) strain tensors of the six unit stresses (11, 22, 33, 12, 13, 23), and (9, 6)
    those stresses, in the material's axes."""
    c = nine(elasticity, c)
    E = [c["E1"], c["E2"], c["E3"]]
    nu = {(0, 1): c["nu12"], (0, 2): c["nu13"], (1, 2): c["nu23"]}
    G = {(0, 1): c["G12"], (0, 2): c["G13"], (1, 2): c["G23"]}
    stresses, strains = [], []
    for i in range(3):
        s, e = np.zeros((3, 3)), np.zeros((3, 3))
        s[i, i] = 1.0
        for j in range(3):
            # eps_j = -nu_ij / E_i = -nu_ji / E_j: the given ratio over its first modulus
            a, b = min(i, j), max(i, j)
            e[j, j] = 1.0 / E[i] if i == j else -nu[a, b] / E[a]
        stresses.append(s)
        strains.append(e)
    for (i, j), g in G.items():
        s, e = np.zeros((3, 3)), np.zeros((3, 3))
        s[i, j] = s[j, i] = 1.0
        e[i, j] = e[j, i] = 1.0 / (2 * g)
        stresses.append(s)
        strains.append(e)
    return (np.array([e.ravel() for e in strains]).T,
            np.array([s.ravel() for s in stresses]).T)


def tensor(elasticity, c):
    """(3, 3, 3, 3) elasticity tensor in the material's axes: it maps the strain of each unit
    stress back to it, and the antisymmetric tensors to zero."""
    S, T = compliance(elasticity, c)
    return (T @ np.linalg.pinv(S)).reshape(3, 3, 3, 3)


def rotate(C, Q):
    """C in the model's axes, Q's columns the material's axes (..., 3, 3)."""
    return np.einsum("...ip,...jq,...kr,...ls,pqrs->...ijkl", Q, Q, Q, Q, C, optimize=True)


def frame(a, b):
    e1 = np.asarray(a) / np.linalg.norm(a)
    e2 = np.asarray(b) - (np.asarray(b) @ e1) * e1
    e2 /= np.linalg.norm(e2)
    return np.stack([e1, e2, np.cross(e1, e2)], axis=1)


def spec(elasticity, c, orientation=OrientationSpec("global")):
    return MaterialSpec(RHO, elasticity=elasticity, constants=tuple(c.items()),
                        orientation=orientation)


def skfem_stiffness(basis, C):
    """K of scikit-fem for the tensor C (3, 3, 3, 3), or C(x) (3, 3, 3, 3, ne, nq) at the
    rule's points x (3, ne, nq)."""
    Cx = C(np.asarray(basis.global_coordinates())) if callable(C) else C[..., None, None]

    @BilinearForm
    def form(u, v, w):
        return np.einsum("ijkl...,kl...,ij...->...", Cx, sym_grad(u), sym_grad(v))
    return form.assemble(basis).tocsr()


def ours(points, conn, cell_type, material):
    ne = len(conn)
    block = CellBlock(cell_type, conn, np.zeros(ne), np.zeros(ne), np.full(ne, RHO),
                      anisotropy({"m": material}, ["m"] * ne))
    return assemble(points, [block])


def skfem_basis(cell_type, points, conn, curved):
    element = SKFEM[cell_type][0]()
    mesh = skfem_mesh(cell_type, points, conn, curved)
    basis = Basis(mesh, ElementVector(element),
                  **skfem_rule(cell_type, ELEMENTS[cell_type].stiffness_degree))
    return basis, dof_permutation(basis, conn, local_order(cell_type, element))


@pytest.mark.parametrize("cell_type, curved", [("hexahedron", False), ("hexahedron20", True),
                                               ("tetra10", True)])
@pytest.mark.parametrize("elasticity, constants", [("transversely_isotropic", LINING),
                                                   ("orthotropic", ORTHO)])
def test_stiffness_in_a_rectangular_frame_matches_skfem(cell_type, curved, elasticity,
                                                        constants):
    points, conn = distorted_box(cell_type, curved, divisions=(2, 2, 2))
    ops = ours(points, conn, cell_type, spec(elasticity, constants,
                                             OrientationSpec("rectangular", a=A, b=B)))
    basis, perm = skfem_basis(cell_type, points, conn, curved)
    K = skfem_stiffness(basis, rotate(tensor(elasticity, constants), frame(A, B)))
    assert relative(ops.K, K[perm][:, perm]) < 1e-10


def test_cylindrical_frame_turns_at_every_integration_point():
    """A disc's radial, tangential, axial axes about an axis off the block, against
    scikit-fem's tensor evaluated at each of its rule's points."""
    cell_type = "hexahedron20"
    points, conn = distorted_box(cell_type, True, divisions=(2, 2, 2))
    point, axis = np.array([-0.3, 0.2, 0.1]), np.array([0.1, 0.2, 1.0])
    ops = ours(points, conn, cell_type,
               spec("orthotropic", ORTHO, OrientationSpec("cylindrical", point=tuple(point),
                                                          axis=tuple(axis))))
    C0 = tensor("orthotropic", ORTHO)

    def C(x):
        x = np.moveaxis(np.asarray(x), 0, -1)               # (ne, nq, 3)
        e3 = axis / np.linalg.norm(axis)
        r = (x - point) - ((x - point) @ e3)[..., None] * e3
        e1 = r / np.linalg.norm(r, axis=-1)[..., None]
        Q = np.stack([e1, np.cross(e3, e1), np.broadcast_to(e3, e1.shape)], axis=-1)
        return np.moveaxis(rotate(C0, Q), (0, 1), (-2, -1))
    basis, perm = skfem_basis(cell_type, points, conn, True)
    assert relative(ops.K, skfem_stiffness(basis, C)[perm][:, perm]) < 1e-10


def test_a_quarter_turn_about_z_permutes_the_constants():
    """Axes 1, 2 turned onto y, -x: the material of E1 along y is the one whose E2 is E1."""
    points, conn = distorted_box("tetra10", True, divisions=(2, 2, 2))
    turned = ours(points, conn, "tetra10", spec(
        "orthotropic", ORTHO, OrientationSpec("rectangular", a=(0.0, 1.0, 0.0),
                                              b=(-1.0, 0.0, 0.0))))
    c = ORTHO
    permuted = dict(E1=c["E2"], E2=c["E1"], E3=c["E3"], nu12=c["nu12"] * c["E2"] / c["E1"],
                    nu13=c["nu23"], nu23=c["nu13"], G12=c["G12"], G13=c["G23"],
                    G23=c["G13"])
    plain = ours(points, conn, "tetra10", spec("orthotropic", permuted))
    assert relative(turned.K, plain.K) < 1e-13


PAD = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7850.0

[materials.lining]
elasticity = "transversely_isotropic"
E_p = 8.0e9
nu_p = 0.25
E_t = 3.0e9
nu_pt = 0.3
G_t = 1.5e9
rho = 2500.0

[parts.pad]
material = "steel"
region_materials = { lining = "lining" }
[parts.pad.mesh]
kind = "brake_pad"
inner_radius = 0.06
outer_radius = 0.1
angle = 50.0
lining_thickness = 0.008
backplate_thickness = 0.005
divisions = [2, 4, 2, 1]
element = "tet10"

[solver.modes]
count = 12
"""


def test_lining_frequencies_match_skfem(tmp_path):
    """A free pad of a transversely isotropic lining (its plane the pad's, normal through the
    thickness: z) on a steel backplate: its first elastic modes against scikit-fem's
    eigenproblem of the same tet10 cells, its tensor per cell."""
    from transient.api import load, modes
    path = tmp_path / "pad.toml"
    path.write_text(PAD)
    found = modes(load(path))
    elastic = found.frequencies[6:]
    # scikit-fem: the same cells (their edges on the sector's arcs: quadratic geometry),
    # its own P2 space and the same rule's points, the tensor of each cell's material
    from transient.model.model import part_mesh
    part = part_mesh(load(path), "pad")
    conn = part.cells["tetra10"]
    assert 3 * part.n_nodes == found.ndof
    basis, _ = skfem_basis("tetra10", part.points, conn, True)
    lining = np.zeros(len(conn), bool)
    lining[part.cell_sets["lining"]["tetra10"]] = True
    steel = tensor("orthotropic", nine("transversely_isotropic", dict(
        E_p=2.1e11, nu_p=0.3, E_t=2.1e11, nu_pt=0.3, G_t=2.1e11 / 2.6)))
    Cs = np.where(lining[None, None, None, None, :, None],
                  tensor("transversely_isotropic", LINING)[..., None, None],
                  steel[..., None, None])
    rho = np.where(lining, 2500.0, 7850.0)[:, None]

    @BilinearForm
    def mass(u, v, w):
        return rho * dot(u, v)
    M = mass.assemble(Basis(basis.mesh, basis.elem, **skfem_rule(
        "tetra10", ELEMENTS["tetra10"].mass_degree))).tocsr()

    def frequencies(C):
        lam = spla.eigsh(skfem_stiffness(basis, lambda x: C), 12, M,
                         sigma=-(2 * np.pi * 10.0) ** 2, return_eigenvectors=False)
        return np.sqrt(np.abs(np.sort(lam))) / (2 * np.pi)
    expected = frequencies(Cs)
    assert expected[5] < 1.0 < expected[6] and elastic[0] > 100.0
    assert np.allclose(elastic, expected[6:], rtol=5e-3), (elastic, expected[6:])
    # the lining's anisotropy matters: isotropic at its in-plane constants is another pad
    isotropic = tensor("orthotropic", nine("transversely_isotropic", dict(
        LINING, E_t=LINING["E_p"], nu_pt=LINING["nu_p"],
        G_t=LINING["E_p"] / (2 * (1 + LINING["nu_p"])))))
    other = frequencies(np.where(lining[None, None, None, None, :, None],
                                 isotropic[..., None, None], steel[..., None, None]))
    assert not np.allclose(elastic, other[6:], rtol=5e-3)


BAR = """
[materials.rod]
elasticity = "orthotropic"
E1 = 2.0e11
E2 = 5.0e10
E3 = 8.0e10
nu12 = 0.3
nu13 = 0.25
nu23 = 0.2
G12 = 3.0e10
G13 = 4.0e10
G23 = 2.5e10
rho = 7800.0

[parts.bar]
material = "rod"
[parts.bar.mesh]
kind = "box"
size = [0.2, 0.01, 0.01]
divisions = [10, 1, 1]
element = "hex20"

[solver.modes]
count = 18
"""


@pytest.mark.parametrize("a, b, modulus", [((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 2.0e11),
                                           ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), 5.0e10)])
def test_axial_frequency_of_a_free_bar(tmp_path, a, b, modulus):
    """The first axial mode of a free slender bar, c / (2 L) with c^2 = E / rho and E the
    modulus along the bar: E1's, or E2's once the material's 2-axis is the bar's."""
    from transient.api import load, modes
    path = tmp_path / "bar.toml"
    path.write_text(BAR + f'[materials.rod.orientation]\nkind = "rectangular"\na = {list(a)}\n'
                    f"b = {list(b)}\n")
    found = modes(load(path))
    axial = np.sum(found.shapes[0::3] ** 2, axis=0) / np.sum(found.shapes ** 2, axis=0)
    f = found.frequencies[6:][np.argmax(axial[6:])]
    assert axial[6:].max() > 0.9
    assert f == pytest.approx(np.sqrt(modulus / 7800.0) / (2 * 0.2), rel=5e-3)


BAD = [
    ("orthotropic", dict(ORTHO, nu12=1.7), "nu12", "nu12^2 E2/E1"),
    ("orthotropic", dict(ORTHO, nu23=-1.8), "nu23", "nu23^2 E3/E2"),
    # each pair's within its bound, the three together not
    ("orthotropic", dict(ORTHO, nu12=1.4, nu13=2.0), "nu12", "three Poisson"),
    ("transversely_isotropic", dict(LINING, nu_pt=1.2), "nu_pt", "2 nu_pt^2 E_t/E_p"),
]
# refused by the keys' own bounds
BOUNDS = [
    ("transversely_isotropic", dict(LINING, nu_p=1.0), "nu_p", "< 1"),
    ("transversely_isotropic", dict(LINING, G_t=0.0), "G_t", "> 0"),
    ("orthotropic", dict(ORTHO, E3=-2e10), "E3", "> 0"),
]


def _case(tmp_path, elasticity, constants, orientation=""):
    keys = "\n".join(f"{k} = {float(v)!r}" for k, v in constants.items())
    text = PAD.replace('elasticity = "transversely_isotropic"\nE_p = 8.0e9\nnu_p = 0.25\n'
                       'E_t = 3.0e9\nnu_pt = 0.3\nG_t = 1.5e9\n',
                       f'elasticity = "{elasticity}"\n{keys}\n')
    path = tmp_path / "bad.toml"
    path.write_text(text + orientation)
    return path


def _refused(monkeypatch, capsys, path):
    """The one error line of `transient modes` on a case, with the assembly never reached."""
    def no_assembly(*args, **kwargs):
        raise AssertionError("the model was assembled before the case was refused")
    monkeypatch.setattr("transient.model.model.assemble", no_assembly)
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    return err


@pytest.mark.parametrize("elasticity, constants, key, words", BAD + BOUNDS,
                         ids=[f"{b[0]}-{b[2]}" for b in BAD + BOUNDS])
def test_constants_without_a_positive_compliance_are_refused(tmp_path, monkeypatch, capsys,
                                                             elasticity, constants, key, words):
    err = _refused(monkeypatch, capsys, _case(tmp_path, elasticity, constants))
    assert f": materials.lining.{key}: " in err and words in err, err
    if (elasticity, constants, key, words) in BAD:
        # the compliance refused is not positive definite indeed
        S, T = compliance(elasticity, constants)
        S = T.T @ S          # (6, 6): the work of each unit stress on the strain of each
        assert np.linalg.eigvalsh(0.5 * (S + S.T)).min() <= 0


def test_constants_within_the_bounds_are_accepted(tmp_path):
    """Just inside the bound the message gives: a lining with nu_pt at 0.999 of it loads."""
    from transient.api import load
    bound = np.sqrt((1 - LINING["nu_p"]) * LINING["E_p"] / (2 * LINING["E_t"]))
    load(_case(tmp_path, "transversely_isotropic", dict(LINING, nu_pt=0.999 * bound)))
    S, T = compliance("transversely_isotropic", dict(LINING, nu_pt=0.999 * bound))
    assert np.linalg.eigvalsh(T.T @ S).min() > 0


ORIENTATIONS = [
    ('kind = "rectangular"\na = [1.0, 0.0, 0.0]\nb = [2.0, 0.0, 0.0]\n', "orientation.b",
     "along a"),
    ('kind = "rectangular"\na = [0.0, 0.0, 0.0]\nb = [0.0, 1.0, 0.0]\n', "orientation.a",
     "non-zero"),
    ('kind = "cylindrical"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 0.0]\n',
     "orientation.axis", "non-zero"),
    ('kind = "polar"\n', "orientation.kind", "expected one of: global, rectangular"),
]


@pytest.mark.parametrize("orientation, key, words", ORIENTATIONS,
                         ids=[o[1] for o in ORIENTATIONS])
def test_an_orientation_without_a_frame_is_refused(tmp_path, monkeypatch, capsys, orientation,
                                                   key, words):
    path = _case(tmp_path, "transversely_isotropic", LINING,
                 "[materials.lining.orientation]\n" + orientation)
    err = _refused(monkeypatch, capsys, path)
    assert f": materials.lining.{key}: " in err and words in err, err


def test_an_isotropic_material_takes_no_orientation_nor_other_constants(tmp_path, monkeypatch,
                                                                        capsys):
    path = tmp_path / "iso.toml"
    path.write_text(PAD + '[materials.steel.orientation]\nkind = "rectangular"\n'
                    'a = [1.0, 0.0, 0.0]\nb = [0.0, 1.0, 0.0]\n')
    err = _refused(monkeypatch, capsys, path)
    assert ": materials.steel.orientation: an isotropic material has no axes" in err
    path.write_text(PAD.replace("nu = 0.3\n", "nu = 0.3\nE1 = 2e11\n"))
    err = _refused(monkeypatch, capsys, path)
    assert ": materials.steel.E1: unknown key" in err


def test_a_cylindrical_axis_through_the_cells_is_refused(tmp_path, capsys):
    """The radial axis is undefined on the axis: said once the rule's points are known
    (hex20's 27-point rule has one at each cell's centre, here on the axis)."""
    path = tmp_path / "axis.toml"
    path.write_text(BAR.replace("[solver.modes]", '[materials.rod.orientation]\n'
                                'kind = "cylindrical"\npoint = [0.03, 0.005, 0.0]\n'
                                "axis = [0.0, 0.0, 1.0]\n\n[solver.modes]"))
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err
    assert ": materials.rod.orientation.point: the cylindrical axis passes" in err
    assert len(err.strip().splitlines()) == 1
