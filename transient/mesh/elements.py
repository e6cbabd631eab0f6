"""Reference elements: node coordinates, shape functions, faces and default quadrature.

Node orderings are VTK's (and so meshio's and Abaqus'), so meshes move between tools unchanged.
The wedges' triangle 0-1-2 turns counterclockwise seen from the triangle 3-4-5, as in gmsh,
Abaqus, meshio and VTK's cells (transient.mesh.meshfile on meshio's VTK files).
Volume types: hexahedron (hex8), hexahedron20 (hex20), tetra (tet4), tetra10 (tet10), wedge
(wedge6: a triangular prism), wedge15.
Face types: quad (quad4), quad8, triangle (tri3), triangle6 (tri6).
"""
from dataclasses import dataclass

import numpy as np

from . import quadrature


@dataclass(frozen=True)
class Element:
    name: str                 # meshio cell type
    shape: str                # reference shape: hex, quad, tet, tri, wedge
    dim: int
    nodes: np.ndarray         # (nen, dim) reference coordinates
    edges: tuple              # corner pairs of the midside nodes, in node order
    faces: tuple              # outward-oriented local node lists (volume types only)
    stiffness_degree: int     # default quadrature degree for K
    mass_degree: int          # default quadrature degree for M
    n_corners: int

    @property
    def nen(self):
        return len(self.nodes)

    @property
    def face_types(self):
        """The element type of each face, in the order of faces (a wedge has two kinds)."""
        return tuple(FACE_TYPE_OF[len(f)] for f in self.faces)

    @property
    def face_groups(self):
        """Face type -> the local node lists (k, nfn) of the faces of that type, so that they
        are taken from a connectivity in one indexing."""
        out = {}
        for ftype, face in zip(self.face_types, self.faces):
            out.setdefault(ftype, []).append(face)
        return {t: np.array(f) for t, f in out.items()}

    def shape_functions(self, xi):
        """Values (n, nen) at reference points xi (n, dim)."""
        return _SHAPE[self.name](np.atleast_2d(xi))[0]

    def shape_derivatives(self, xi):
        """Reference derivatives (n, nen, dim) at reference points xi (n, dim)."""
        return _SHAPE[self.name](np.atleast_2d(xi))[1]

    def rule(self, degree):
        return quadrature.rule(self.shape, degree)


def _quad4(xi):
    x, y = xi[:, 0], xi[:, 1]
    sx = np.array([-1, 1, 1, -1.0])
    sy = np.array([-1, -1, 1, 1.0])
    N = 0.25 * (1 + np.outer(x, sx)) * (1 + np.outer(y, sy))
    dN = np.empty((len(xi), 4, 2))
    dN[:, :, 0] = 0.25 * sx * (1 + np.outer(y, sy))
    dN[:, :, 1] = 0.25 * sy * (1 + np.outer(x, sx))
    return N, dN


def _quad8(xi):
    x, y = xi[:, 0:1], xi[:, 1:2]
    sx = np.array([-1, 1, 1, -1.0])
    sy = np.array([-1, -1, 1, 1.0])
    n = len(xi)
    N = np.empty((n, 8))
    dN = np.empty((n, 8, 2))
    a, b = 1 + x * sx, 1 + y * sy
    N[:, :4] = 0.25 * a * b * (x * sx + y * sy - 1)
    dN[:, :4, 0] = 0.25 * sx * b * (2 * x * sx + y * sy)
    dN[:, :4, 1] = 0.25 * sy * a * (x * sx + 2 * y * sy)
    x, y = x[:, 0], y[:, 0]
    # midsides on y = -1, x = 1, y = 1, x = -1
    for k, (mx, my) in enumerate(((0, -1), (1, 0), (0, 1), (-1, 0))):
        if mx == 0:
            N[:, 4 + k] = 0.5 * (1 - x * x) * (1 + y * my)
            dN[:, 4 + k, 0] = -x * (1 + y * my)
            dN[:, 4 + k, 1] = 0.5 * (1 - x * x) * my
        else:
            N[:, 4 + k] = 0.5 * (1 - y * y) * (1 + x * mx)
            dN[:, 4 + k, 0] = 0.5 * (1 - y * y) * mx
            dN[:, 4 + k, 1] = -y * (1 + x * mx)
    return N, dN


def _tri3(xi):
    n = len(xi)
    N = np.stack([1 - xi[:, 0] - xi[:, 1], xi[:, 0], xi[:, 1]], axis=1)
    dN = np.broadcast_to(np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]), (n, 3, 2)).copy()
    return N, dN


def _tri6(xi):
    L, dL = _tri3(xi)   # barycentric coordinates and their constant derivatives
    pairs = ((0, 1), (1, 2), (2, 0))
    N = np.empty((len(xi), 6))
    dN = np.empty((len(xi), 6, 2))
    for a in range(3):
        N[:, a] = L[:, a] * (2 * L[:, a] - 1)
        dN[:, a, :] = (4 * L[:, a:a + 1] - 1) * dL[:, a, :]
    for k, (a, b) in enumerate(pairs):
        N[:, 3 + k] = 4 * L[:, a] * L[:, b]
        dN[:, 3 + k, :] = 4 * (L[:, a:a + 1] * dL[:, b, :] + L[:, b:b + 1] * dL[:, a, :])
    return N, dN


_HEX_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
              (0, 4), (1, 5), (2, 6), (3, 7))
_HEX_FACES = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))


def _hex8(xi):
    s = _HEX_CORNERS
    f = 1 + xi[:, None, :] * s[None, :, :]          # (n, 8, 3)
    N = 0.125 * f.prod(axis=2)
    dN = np.empty((len(xi), 8, 3))
    for d in range(3):
        others = [e for e in range(3) if e != d]
        dN[:, :, d] = 0.125 * s[:, d] * f[:, :, others[0]] * f[:, :, others[1]]
    return N, dN


def _hex20(xi):
    n = len(xi)
    N = np.empty((n, 20))
    dN = np.empty((n, 20, 3))
    s = _HEX_CORNERS
    f = 1 + xi[:, None, :] * s[None, :, :]
    t = (xi[:, None, :] * s[None, :, :]).sum(axis=2) - 2
    N[:, :8] = 0.125 * f.prod(axis=2) * t
    for d in range(3):
        o1, o2 = [e for e in range(3) if e != d]
        dN[:, :8, d] = 0.125 * s[:, d] * f[:, :, o1] * f[:, :, o2] * (t + f[:, :, d])
    for k, (a, b) in enumerate(_HEX_EDGES):
        m = 0.5 * (s[a] + s[b])
        d = int(np.flatnonzero(m == 0)[0])   # direction along the edge
        o1, o2 = [e for e in range(3) if e != d]
        g1, g2 = 1 + xi[:, o1] * m[o1], 1 + xi[:, o2] * m[o2]
        q = 1 - xi[:, d] ** 2
        N[:, 8 + k] = 0.25 * q * g1 * g2
        dN[:, 8 + k, d] = -0.5 * xi[:, d] * g1 * g2
        dN[:, 8 + k, o1] = 0.25 * q * m[o1] * g2
        dN[:, 8 + k, o2] = 0.25 * q * g1 * m[o2]
    return N, dN


_TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
_TET_FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))


def _tet4(xi):
    n = len(xi)
    N = np.stack([1 - xi.sum(axis=1), xi[:, 0], xi[:, 1], xi[:, 2]], axis=1)
    d = np.array([[-1.0, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    return N, np.broadcast_to(d, (n, 4, 3)).copy()


def _tet10(xi):
    L, dL = _tet4(xi)
    N = np.empty((len(xi), 10))
    dN = np.empty((len(xi), 10, 3))
    for a in range(4):
        N[:, a] = L[:, a] * (2 * L[:, a] - 1)
        dN[:, a, :] = (4 * L[:, a:a + 1] - 1) * dL[:, a, :]
    for k, (a, b) in enumerate(_TET_EDGES):
        N[:, 4 + k] = 4 * L[:, a] * L[:, b]
        dN[:, 4 + k, :] = 4 * (L[:, a:a + 1] * dL[:, b, :] + L[:, b:b + 1] * dL[:, a, :])
    return N, dN


# The wedge is the triangle (xi, eta) times the segment zeta in [-1, 1], as gmsh's prism.
_WEDGE_CORNERS = np.array([[0, 0, -1], [1, 0, -1], [0, 1, -1],
                           [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float)
_WEDGE_EDGES = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5))
_WEDGE_FACES = ((0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5))


def _wedge6(xi):
    L, dL = _tri3(xi[:, :2])
    n = len(xi)
    s = np.array([-1.0, 1.0])                            # zeta of the bottom and top corners
    h = 0.5 * (1 + xi[:, 2:3] * s)                       # (n, 2)
    N = (h[:, :, None] * L[:, None, :]).reshape(n, 6)
    dN = np.empty((n, 6, 3))
    dN[:, :, :2] = (h[:, :, None, None] * dL[:, None, :, :]).reshape(n, 6, 2)
    dN[:, :, 2] = (0.5 * s[None, :, None] * L[:, None, :]).reshape(n, 6)
    return N, dN


def _wedge15(xi):
    """Serendipity wedge: quadratic on the triangles, quadratic along zeta, no face nodes."""
    L, dL = _tri3(xi[:, :2])
    z = xi[:, 2]
    n = len(xi)
    N = np.empty((n, 15))
    dN = np.empty((n, 15, 3))
    for a in range(6):
        i, s = a % 3, (-1.0 if a < 3 else 1.0)
        g = 1 + s * z
        t = 2 * L[:, i] + s * z - 2
        N[:, a] = 0.5 * L[:, i] * g * t
        dN[:, a, :2] = (0.5 * g * (t + 2 * L[:, i]))[:, None] * dL[:, i, :]
        dN[:, a, 2] = 0.5 * s * L[:, i] * (t + g)
    for k, (a, b) in enumerate(_WEDGE_EDGES):
        m = 6 + k
        if k < 6:                                        # on the bottom or top triangle
            i, j, s = a % 3, b % 3, (-1.0 if k < 3 else 1.0)
            g = 1 + s * z
            N[:, m] = 2 * L[:, i] * L[:, j] * g
            dN[:, m, :2] = 2 * g[:, None] * (L[:, i:i + 1] * dL[:, j, :]
                                             + L[:, j:j + 1] * dL[:, i, :])
            dN[:, m, 2] = 2 * s * L[:, i] * L[:, j]
        else:                                            # along zeta, from corner a
            N[:, m] = L[:, a] * (1 - z * z)
            dN[:, m, :2] = (1 - z * z)[:, None] * dL[:, a, :]
            dN[:, m, 2] = -2 * z * L[:, a]
    return N, dN


_SHAPE = {"quad": _quad4, "quad8": _quad8, "triangle": _tri3, "triangle6": _tri6,
          "hexahedron": _hex8, "hexahedron20": _hex20, "tetra": _tet4, "tetra10": _tet10,
          "wedge": _wedge6, "wedge15": _wedge15}
# a face's element type by its number of nodes
FACE_TYPE_OF = {3: "triangle", 4: "quad", 6: "triangle6", 8: "quad8"}


def _with_midsides(corners, edges):
    return np.vstack([corners] + [0.5 * (corners[a] + corners[b]) for a, b in edges]) \
        if edges else corners


def _quadratic_faces(faces, edges, n_corners):
    """Face node lists with midside nodes appended, in the face's own edge order."""
    index = {frozenset(e): n_corners + k for k, e in enumerate(edges)}
    out = []
    for f in faces:
        mids = [index[frozenset((f[i], f[(i + 1) % len(f)]))] for i in range(len(f))]
        out.append(tuple(f) + tuple(mids))
    return tuple(out)


_QUAD_CORNERS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
_QUAD_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0))
_TRI_CORNERS = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
_TRI_EDGES = ((0, 1), (1, 2), (2, 0))
_TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)

# The wedges' degrees are those of their triangle rule; the rule along zeta, Gauss with
# degree // 2 + 1 points, is exact to the same degree there. Products of shape functions and of
# their derivatives reach degree 2 in each (wedge) and 4 (wedge15).
ELEMENTS = {
    "quad": Element("quad", "quad", 2, _QUAD_CORNERS, (), (), 2, 2, 4),
    "quad8": Element("quad8", "quad", 2, _with_midsides(_QUAD_CORNERS, _QUAD_EDGES),
                     _QUAD_EDGES, (), 4, 4, 4),
    "triangle": Element("triangle", "tri", 2, _TRI_CORNERS, (), (), 1, 2, 3),
    "triangle6": Element("triangle6", "tri", 2, _with_midsides(_TRI_CORNERS, _TRI_EDGES),
                         _TRI_EDGES, (), 2, 4, 3),
    "hexahedron": Element("hexahedron", "hex", 3, _HEX_CORNERS, (), _HEX_FACES, 3, 3, 8),
    "hexahedron20": Element("hexahedron20", "hex", 3, _with_midsides(_HEX_CORNERS, _HEX_EDGES),
                            _HEX_EDGES, _quadratic_faces(_HEX_FACES, _HEX_EDGES, 8), 5, 5, 8),
    "tetra": Element("tetra", "tet", 3, _TET_CORNERS, (), _TET_FACES, 1, 2, 4),
    "tetra10": Element("tetra10", "tet", 3, _with_midsides(_TET_CORNERS, _TET_EDGES),
                       _TET_EDGES, _quadratic_faces(_TET_FACES, _TET_EDGES, 4), 2, 4, 4),
    "wedge": Element("wedge", "wedge", 3, _WEDGE_CORNERS, (), _WEDGE_FACES, 2, 2, 6),
    "wedge15": Element("wedge15", "wedge", 3, _with_midsides(_WEDGE_CORNERS, _WEDGE_EDGES),
                       _WEDGE_EDGES, _quadratic_faces(_WEDGE_FACES, _WEDGE_EDGES, 6), 4, 4, 6),
}

VOLUME_TYPES = ("hexahedron", "hexahedron20", "tetra", "tetra10", "wedge", "wedge15")
FACE_TYPES = ("quad", "quad8", "triangle", "triangle6")
# Short names used in case files.
ALIASES = {"hex8": "hexahedron", "hex20": "hexahedron20", "tet4": "tetra", "tet10": "tetra10",
           "wedge6": "wedge", "wedge15": "wedge15"}
QUADRATIC = {"hexahedron": "hexahedron20", "tetra": "tetra10", "wedge": "wedge15"}
