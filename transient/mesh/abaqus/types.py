"""Abaqus element types as transient reads them: the solids it models, the 2-D elements that
can give faces, the families it skips, and the faces S1-S6 of each solid family.

A solid's letters after its node count (C3D8R, C3D8I, C3D10M, C3D20RH, C3D6H...) name Abaqus'
formulation (reduced or incompatible-mode integration, hybrid pressure): the nodes are the
same, and transient integrates every cell with its own rule (solver.quadrature). C3D15V is
the exception: its 15 to 18 nodes add nodes at the centres of the quadrilateral faces, which
transient's wedge15 does not have, so it is refused as an element transient cannot use.
"""
import re

from ..elements import ELEMENTS

SOLID = "solid"          # a volume cell of the model
FACE = "face"            # a 2-D element: a face where it lies on the solids' boundary
SKIPPED = "skipped"      # a structural element transient does not model, left out with a note

_SOLIDS = {"4": "tetra", "10": "tetra10", "8": "hexahedron", "20": "hexahedron20",
           "6": "wedge", "15": "wedge15"}
_SOLID = re.compile(r"^C3D(4|10|8|20|6|15)(?!V)[A-Z]*$")
_OTHER_SOLID = re.compile(r"^C3D\d+[A-Z]*$")
# plane, axisymmetric, shell, membrane, surface and rigid elements: their first digit is
# their number of nodes (STRI65: 6)
_TWO_D = re.compile(r"^(CPEG|CPE|CPS|CGAX|CAX|SFM3D|M3D|R3D|STRI|S)(\d)")
_TWO_D_FACES = {"3": "triangle", "6": "triangle6", "4": "quad", "8": "quad8"}
_ONE_D_POINT_SHELL = re.compile(r"^(T[23]D|B[23]\d|PIPE|ELBOW|FRAME|SPRING|DASHPOT|MASS|"
                                r"ROTARYI|CONN|JOINT|GAP|ITS|DCOUP|HEATCAP|RB[23]D|R2D|RAX|"
                                r"SAX|SC\d)")
ACCEPTED = ("C3D4, C3D10, C3D8, C3D20, C3D6 and C3D15, with any formulation letters (C3D8R, "
            "C3D10M, C3D20R, C3D6H)")

# The faces of the solid families as the Abaqus Analysis User's Guide's element library
# numbers them (S1, S2, ... by corner nodes, 1-based); CalculiX numbers them alike.
ABAQUS_FACES = {
    "hex": ((1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4), (4, 8, 5, 1)),
    "tet": ((1, 2, 3), (1, 4, 2), (2, 4, 3), (3, 4, 1)),
    "wedge": ((1, 2, 3), (4, 6, 5), (1, 4, 5, 2), (2, 5, 6, 3), (3, 6, 4, 1)),
}


def classify(abaqus_type):
    """(kind, meshio cell type) of an element type given in upper case: SOLID with its volume
    type, FACE with its face type, SKIPPED with '', or None with '' for a type transient
    cannot use (a pyramid, C3D15V, an unknown or user element)."""
    solid = _SOLID.match(abaqus_type)
    if solid:
        return SOLID, _SOLIDS[solid.group(1)]
    if _OTHER_SOLID.match(abaqus_type):
        return None, ""
    two_d = _TWO_D.match(abaqus_type)
    if two_d:
        face = _TWO_D_FACES.get(two_d.group(2), "")
        return (FACE, face) if face else (SKIPPED, "")
    if _ONE_D_POINT_SHELL.match(abaqus_type):
        return SKIPPED, ""
    return None, ""


def _faces_in_abaqus_order(ctype):
    """Each face of a solid of type ctype (meshio name) as local node indices, outward and
    with its midside nodes (transient.mesh.elements), in the order S1, S2, ..."""
    el = ELEMENTS[ctype]
    by_corners = {frozenset(f[:len(f) // (2 if el.edges else 1)]): f for f in el.faces}
    return tuple(by_corners[frozenset(c - 1 for c in corners)]
                 for corners in ABAQUS_FACES[el.shape])


FACES = {ctype: _faces_in_abaqus_order(ctype) for ctype in _SOLIDS.values()}
