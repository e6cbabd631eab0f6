"""The case keys of a material (isotropic, transversely isotropic or orthotropic elasticity
from the engineering constants an Abaqus user types, its orientation, its density and loss
factor) and their check at load: the compliance positive definite, the frame defined.

Engineering constants follow Abaqus's *ELASTIC, TYPE=ENGINEERING CONSTANTS: nu_ij is the
strain along j per strain along i under a stress along i alone (eps_j = -nu_ij sigma_i / E_i),
so nu_ji = nu_ij E_j / E_i. Voigt order here: 11, 22, 33, 23, 13, 12, engineering shears.
"""
import numpy as np

from .geometry import positive, vector3
from .nodes import Value, Variant

ORIENTATION = Variant("the material's axes 1, 2, 3 (anisotropic materials)", {
    "global": {},
    "rectangular": {
        "a": Value("floats", "direction of the material's 1-axis (Abaqus *ORIENTATION, "
                   "SYSTEM=RECTANGULAR: the point a with the origin at 0)", length=3),
        "b": Value("floats", "a direction in the material's 1-2 plane, not along a: the "
                   "2-axis is its part normal to a, and 3 = 1 x 2", length=3),
    },
    "cylindrical": {
        "point": vector3("a point of the axis"),
        "axis": Value("floats", "direction of the axis, the material's 3-axis; 1 is radial "
                      "and 2 = 3 x 1 tangential at each integration point (a disc's "
                      "radial, tangential, axial)", length=3),
    },
}, default="global")

_MODULUS = "Young's modulus along the material's"

MATERIAL = Variant("the material's linear elasticity, by its engineering constants", {
    "isotropic": {
        "E": positive("Young's modulus", "Pa"),
        "nu": Value("float", "Poisson's ratio", open_min=-1.0, open_max=0.5),
    },
    "transversely_isotropic": {
        "E_p": positive("Young's modulus in the plane of isotropy, the material's 1-2 plane "
                        "(a lining's plane, normal to its thickness)", "Pa"),
        "nu_p": Value("float", "Poisson's ratio in the plane of isotropy (its shear modulus "
                      "is E_p / (2 (1 + nu_p)))", open_min=-1.0, open_max=1.0),
        "E_t": positive("Young's modulus along the normal to the plane, the material's "
                        "3-axis (a lining's thickness)", "Pa"),
        "nu_pt": Value("float", "Poisson's ratio nu_pt = nu13 = nu23 as Abaqus's engineering "
                       "constants take it: the strain along the normal per in-plane strain "
                       "under an in-plane stress (nu_tp = nu_pt E_t / E_p)"),
        "G_t": positive("shear modulus in the planes through the normal (G13 = G23)", "Pa"),
    },
    "orthotropic": {
        "E1": positive(f"{_MODULUS} 1-axis", "Pa"),
        "E2": positive(f"{_MODULUS} 2-axis", "Pa"),
        "E3": positive(f"{_MODULUS} 3-axis", "Pa"),
        "nu12": Value("float", "Poisson's ratio: strain along 2 per strain along 1 under a "
                      "stress along 1 (Abaqus's nu12)"),
        "nu13": Value("float", "Poisson's ratio: strain along 3 per strain along 1 under a "
                      "stress along 1"),
        "nu23": Value("float", "Poisson's ratio: strain along 3 per strain along 2 under a "
                      "stress along 2"),
        "G12": positive("shear modulus in the 1-2 plane", "Pa"),
        "G13": positive("shear modulus in the 1-3 plane", "Pa"),
        "G23": positive("shear modulus in the 2-3 plane", "Pa"),
    },
}, common={
    "rho": positive("mass density", "kg/m^3"),
    "loss_factor": Value("float", "structural damping eta of the material: `transient cea` "
                         "adds i eta K_m to the stiffness (K_m its cells' stiffness, on the "
                         "reduced basis T^T K_m T), a run the viscous damping eta / omega_ref "
                         "K_m at solver.damping.loss_frequency, where the two agree "
                         "(reduced models; 0: none)", 0.0, minimum=0.0, maximum=2.0),
    "orientation": ORIENTATION,
}, default="isotropic", key="elasticity", implicit=True)

# the orthotropic constants of each elasticity, from its own keys
ORTHOTROPIC = ("E1", "E2", "E3", "nu12", "nu13", "nu23", "G12", "G13", "G23")


def orthotropic_constants(spec):
    """The nine constants (ORTHOTROPIC) of a MaterialSpec, by name."""
    c = dict(spec.constants)
    if spec.elasticity == "orthotropic":
        return c
    if spec.elasticity == "transversely_isotropic":
        Ep, nup, Et, nupt, Gt = c["E_p"], c["nu_p"], c["E_t"], c["nu_pt"], c["G_t"]
        return dict(E1=Ep, E2=Ep, E3=Et, nu12=nup, nu13=nupt, nu23=nupt,
                    G12=Ep / (2 * (1 + nup)), G13=Gt, G23=Gt)
    E, nu = spec.E, spec.nu
    G = E / (2 * (1 + nu))
    return dict(E1=E, E2=E, E3=E, nu12=nu, nu13=nu, nu23=nu, G12=G, G13=G, G23=G)


def compliance(spec):
    """(6, 6) compliance S of a MaterialSpec in its own axes [1/Pa]: strain = S stress."""
    c = orthotropic_constants(spec)
    E = np.array([c["E1"], c["E2"], c["E3"]])
    S = np.diag(1.0 / E)
    for (i, j), nu in zip(((0, 1), (0, 2), (1, 2)), (c["nu12"], c["nu13"], c["nu23"])):
        S[i, j] = S[j, i] = -nu / E[i]
    S = np.pad(S, ((0, 3), (0, 3)))
    S[3, 3], S[4, 4], S[5, 5] = 1.0 / c["G23"], 1.0 / c["G13"], 1.0 / c["G12"]
    return S


def elasticity(spec):
    """(6, 6) elasticity matrix D = S^-1 of a MaterialSpec in its own axes [Pa]."""
    return np.linalg.inv(compliance(spec))


def check_materials(case):
    """Each material's compliance positive definite (E and G > 0 are the schema's) and its
    orientation defined: one error naming the key and the value that breaks it."""
    for name, spec in case.materials.items():
        key = f"materials.{name}"
        if spec.elasticity == "isotropic":
            if spec.orientation.kind != "global":
                raise case.error(f"{key}.orientation", "an isotropic material has no axes to "
                                 "orient: leave the orientation out, or give the material's "
                                 "elasticity")
            continue
        _check_orientation(case, key, spec.orientation)
        if spec.elasticity == "transversely_isotropic":
            _transversely_isotropic(case, key, dict(spec.constants))
        else:
            _orthotropic(case, key, dict(spec.constants))


def _not_definite(case, key, what, value, bound, expected):
    raise case.error(key, f"{what} = {value:.4g} is not below {bound:.4g}: the compliance is "
                     f"not positive definite (expected {expected})")


def _transversely_isotropic(case, key, c):
    """Positive definite iff -1 < nu_p < 1 (the schema's bounds) and
    2 nu_pt^2 E_t / E_p < 1 - nu_p."""
    ratio = 2 * c["nu_pt"] ** 2 * c["E_t"] / c["E_p"]
    if not ratio < 1 - c["nu_p"]:
        bound = np.sqrt((1 - c["nu_p"]) * c["E_p"] / (2 * c["E_t"]))
        _not_definite(case, f"{key}.nu_pt", "2 nu_pt^2 E_t/E_p", ratio, 1 - c["nu_p"],
                      f"|nu_pt| < sqrt((1 - nu_p) E_p / (2 E_t)) = {bound:.4g}")


def _orthotropic(case, key, c):
    """Positive definite iff nu_ij^2 E_j / E_i < 1 for each pair and
    1 - nu12 nu21 - nu13 nu31 - nu23 nu32 - 2 nu21 nu32 nu13 > 0 (Lempriere)."""
    products = {}
    for i, j in ((1, 2), (1, 3), (2, 3)):
        nu = f"nu{i}{j}"
        ratio = c[nu] ** 2 * c[f"E{j}"] / c[f"E{i}"]
        if not ratio < 1.0:
            _not_definite(case, f"{key}.{nu}", f"{nu}^2 E{j}/E{i}", ratio, 1.0,
                          f"|{nu}| < sqrt(E{i}/E{j}) = {np.sqrt(c[f'E{i}'] / c[f'E{j}']):.4g}")
        products[nu] = ratio
    nu21 = c["nu12"] * c["E2"] / c["E1"]
    nu32 = c["nu23"] * c["E3"] / c["E2"]
    rest = 1.0 - sum(products.values()) - 2 * nu21 * nu32 * c["nu13"]
    if not rest > 0.0:
        # the ratio of the largest product, the one that most likely went wrong
        worst = max(products, key=products.get)
        raise case.error(f"{key}.{worst}", f"1 - nu12 nu21 - nu13 nu31 - nu23 nu32 - 2 nu21 "
                         f"nu32 nu13 = {rest:.4g} is not above 0: the compliance is not "
                         f"positive definite (the three Poisson's ratios together are too "
                         f"large; {worst} contributes the most)")


def _check_orientation(case, key, o):
    """The orientation's vectors define a frame."""
    if o.kind == "rectangular":
        a, b = np.asarray(o.a), np.asarray(o.b)
        if not np.linalg.norm(a) > 0:
            raise case.error(f"{key}.orientation.a", "expected a non-zero vector")
        if not np.linalg.norm(np.cross(a, b)) > 1e-9 * np.linalg.norm(a) * np.linalg.norm(b):
            raise case.error(f"{key}.orientation.b", f"{list(o.b)} is along a = {list(o.a)} "
                             "(or zero): expected a direction in the 1-2 plane, not along the "
                             "1-axis")
    elif o.kind == "cylindrical" and not np.linalg.norm(o.axis) > 0:
        raise case.error(f"{key}.orientation.axis", "expected a non-zero vector")
