"""The elasticity matrix D of anisotropic cells in the model's axes: each material's D in its
own axes (case.materials) turned by its orientation, at the stiffness rule's points.

A cylindrical orientation is evaluated at every integration point, as Abaqus does, so a
disc's radial and tangential axes turn within a cell; a fixed frame gives one D per cell.
Voigt order 11, 22, 33, 23, 13, 12 with engineering shear strains, as the kernel's B.
"""
from dataclasses import dataclass

import numpy as np

from ..case.materials import elasticity
from ..errors import CaseError

# the index pairs of Voigt's order
PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def bond(Q):
    """(..., 6, 6) Bond matrices of rotations Q (..., 3, 3) whose columns are the material's
    axes in the model's: a stress sigma_m in the material's axes is K sigma_m in the model's,
    and D_model = K D_m K^T."""
    K = np.empty(Q.shape[:-2] + (6, 6))
    for I, (i, j) in enumerate(PAIRS):
        for J, (k, l) in enumerate(PAIRS):
            # sigma_ij = Q_ik Q_jl sigma_kl summed over the tensor's (k, l) and (l, k)
            K[..., I, J] = Q[..., i, k] * Q[..., j, l]
            if k != l:
                K[..., I, J] += Q[..., i, l] * Q[..., j, k]
    return K


def rectangular(a, b):
    """(3, 3) columns e1 along a, e2 the part of b normal to a, e3 = e1 x e2."""
    e1 = np.asarray(a, float) / np.linalg.norm(a)
    e3 = np.cross(e1, b)
    e3 /= np.linalg.norm(e3)
    return np.stack([e1, np.cross(e3, e1), e3], axis=-1)


def cylindrical(point, axis, x):
    """(..., 3, 3) columns radial, tangential, axial at points x (..., 3); (..., ) the
    points' distances to the axis [m]."""
    e3 = np.asarray(axis, float) / np.linalg.norm(axis)
    d = x - np.asarray(point, float)
    r = d - (d @ e3)[..., None] * e3
    dist = np.linalg.norm(r, axis=-1)
    e1 = r / np.maximum(dist, 1e-300)[..., None]
    e2 = np.cross(e3, e1)
    return np.stack([e1, e2, np.broadcast_to(e3, e1.shape)], axis=-1), dist


def frames(orientation):
    """(3, 3) the fixed frame of an OrientationSpec (None for a cylindrical one)."""
    if orientation.kind == "rectangular":
        return rectangular(orientation.a, orientation.b)
    return np.eye(3) if orientation.kind == "global" else None


@dataclass(frozen=True)
class Anisotropy:
    """The elasticity of a block of cells some of whose materials are anisotropic."""
    material: np.ndarray      # (ne,) index of each cell's material into D and orientations
    D: np.ndarray             # (k, 6, 6) each material's D in its own axes [Pa]
    orientations: tuple       # (k,) their OrientationSpecs
    names: tuple              # (k,) their names, and
    path: str = ""            # the case file: what an error names

    @property
    def varies(self):
        """Whether D varies within a cell (a cylindrical orientation)."""
        return any(o.kind == "cylindrical" for o in self.orientations)

    def at(self, x):
        """(ne, ng or 1, 6, 6) D in the model's axes at the cells' rule points x (ne, ng, 3)
        [m]; one per cell when no orientation varies within it."""
        ne, ng = x.shape[:2]
        out = np.empty((ne, ng if self.varies else 1, 6, 6))
        for k, (D, o) in enumerate(zip(self.D, self.orientations)):
            cells = np.flatnonzero(self.material == k)
            if not len(cells):
                continue
            Q = frames(o)
            if Q is None:
                Q, dist = cylindrical(o.point, o.axis, x[cells])
                extent = np.ptp(x.reshape(-1, 3), axis=0).max()
                if dist.min() <= 1e-9 * extent:
                    raise CaseError(self.path, f"materials.{self.names[k]}.orientation.point",
                                    "the cylindrical axis passes through an integration point "
                                    "of a cell of the material, where no radial direction is "
                                    "defined: an axis off the material's cells")
            K = bond(Q)
            out[cells] = K @ D @ np.swapaxes(K, -1, -2)
        return out


def anisotropy(materials, names, path=""):
    """The Anisotropy of cells whose materials (MaterialSpec) are named by names (ne,), or
    None when every one is isotropic (their block keeps the Lame constants' kernel); path:
    the case file."""
    used = list(dict.fromkeys(names))
    if all(materials[m].elasticity == "isotropic" for m in used):
        return None
    index = {m: k for k, m in enumerate(used)}
    return Anisotropy(np.array([index[m] for m in names], np.int64),
                      np.array([elasticity(materials[m]) for m in used]),
                      tuple(materials[m].orientation for m in used), tuple(used), str(path))
