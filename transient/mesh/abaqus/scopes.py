"""Where each definition of a deck belongs: a part (*PART ... *END PART), an instance of a
part placed in the assembly (*INSTANCE ... *END INSTANCE), or the assembly itself, which is
the whole model of a deck written without parts.

Only the keywords that make the mesh are kept (nodes, elements, node and element sets,
surfaces); those that would change it in ways not read here (node and element generators,
a local system for the nodes, parameters) are refused; the rest (materials, sections, steps,
boundary conditions, contact pairs...) is left to the solver the deck was written for.
"""
from dataclasses import dataclass, field

import numpy as np

from .deck import read_keywords

MESH = ("NODE", "ELEMENT", "NSET", "ELSET", "SURFACE")
# sections that make their elements structure: a 2-D element under one is a shell, a
# membrane or a plane solid of the model, not only the face of a solid (gmsh's and meshio's
# faces have no section)
STRUCTURAL = ("SHELL SECTION", "SHELL GENERAL SECTION", "MEMBRANE SECTION", "SOLID SECTION")
# keywords that make or move nodes and elements by rules this reader does not follow
REFUSED = ("NGEN", "NFILL", "NCOPY", "NMAP", "ELGEN", "ELCOPY", "PARAMETER", "NODAL THICKNESS",
           "SUBSTRUCTURE PROPERTY", "IMPORT")


@dataclass(eq=False)
class Scope:
    """The mesh keywords of one part, of one instance's own lines, or of the assembly."""
    name: str                      # as written ('' for the assembly)
    keywords: dict = field(default_factory=lambda: {k: [] for k in MESH + ("SECTION",)})


@dataclass(eq=False)
class Instance:
    """A placed copy of a part: its nodes moved by the translation, then the rotation."""
    name: str                      # as written
    part: str                      # the part's name in upper case
    translate: np.ndarray          # (3,)
    rotate: tuple                  # (point a (3,), point b (3,), angle [deg]) or None
    own: Scope                     # what the deck defines inside *INSTANCE ... *END INSTANCE
    keyword: object                # the *INSTANCE keyword, for messages


@dataclass(eq=False)
class Deck:
    path: object
    parts: dict                    # upper-case name -> Scope
    instances: list                # Instance, in the deck's order
    assembly: Scope


def read_deck_structure(path):
    """The Deck of the input file at path: its keywords sorted into parts, instances and
    the assembly. Raises MeshFileError on a keyword out of place or one not read here."""
    deck = Deck(path, {}, [], Scope(""))
    current = deck.assembly
    for keyword in read_keywords(path):
        name = keyword.name
        if name in MESH:
            current.keywords[name].append(keyword)
        elif name in STRUCTURAL and keyword.get("ELSET"):
            current.keywords["SECTION"].append(keyword)
        elif name == "PART":
            current = _part(deck, keyword, current)
        elif name == "INSTANCE":
            current = _instance(deck, keyword, current)
        elif name in ("END PART", "END INSTANCE", "END ASSEMBLY", "ASSEMBLY"):
            current = _close(deck, keyword, current)
        elif name in REFUSED or (name == "SYSTEM" and _moves_nodes(keyword)):
            raise keyword.error("not read here: expected nodes and elements listed one by "
                                "one in the global system (write the deck out flat, e.g. "
                                "from Abaqus/CAE or gmsh)")
    for instance in deck.instances:
        if instance.part not in deck.parts:
            known = ", ".join(s.name for s in deck.parts.values()) or "none"
            raise instance.keyword.error(f"no part '{instance.keyword.get('PART')}' "
                                         f"(parts: {known})")
    return deck


def _moves_nodes(keyword):
    """A *SYSTEM with a nonzero data line: the nodes after it are given in a local system."""
    try:
        return any(float(v) != 0.0 for row in keyword.data for v in row if v)
    except ValueError:
        return True


def _part(deck, keyword, current):
    name = keyword.get("NAME")
    if current is not deck.assembly or deck.instances:
        raise keyword.error("expected *PART at the top of the deck, before the assembly")
    if not name:
        raise keyword.error("expected NAME=PART, the part's name")
    if name.upper() in deck.parts:
        raise keyword.error(f"part '{name}' is defined twice")
    deck.parts[name.upper()] = scope = Scope(name)
    return scope


def _instance(deck, keyword, current):
    name, part = keyword.get("NAME"), keyword.get("PART")
    if current is not deck.assembly:
        raise keyword.error("expected *INSTANCE in the assembly")
    if not name or not part:
        raise keyword.error("expected NAME=INSTANCE and PART=PART: an instance of a part")
    if any(i.name.upper() == name.upper() for i in deck.instances):
        raise keyword.error(f"instance '{name}' is defined twice")
    translate, rotate = _placement(keyword)
    instance = Instance(name, part.upper(), translate, rotate, Scope(name), keyword)
    deck.instances.append(instance)
    return instance.own


def _placement(keyword):
    """The translation and rotation of an *INSTANCE's data lines: [x, y, z], then
    [xa, ya, za, xb, yb, zb, angle in degrees] (a right-handed turn about the axis from a to
    b)."""
    rows = [_floats(keyword, r) for r in range(len(keyword.data))]
    if len(rows) > 2 or (rows and len(rows[0]) > 3) or (len(rows) == 2 and len(rows[1]) != 7):
        raise keyword.error("expected at most two data lines: a translation x, y, z, then a "
                            "rotation xa, ya, za, xb, yb, zb, angle [deg]")
    translate = np.zeros(3)
    if rows:
        translate[:len(rows[0])] = rows[0]
    rotate = None
    if len(rows) == 2 and rows[1][6] != 0.0:
        a, b = np.array(rows[1][:3]), np.array(rows[1][3:6])
        if not np.any(a != b):
            raise keyword.error("the rotation's axis goes from a point to itself: expected "
                                "two distinct points a and b")
        rotate = (a, b, rows[1][6])
    return translate, rotate


def _floats(keyword, row):
    try:
        return [float(v) if v else 0.0 for v in keyword.data[row]]
    except ValueError:
        raise keyword.error(f"expected numbers, got {', '.join(keyword.data[row])}",
                            row) from None


def _close(deck, keyword, current):
    """The scope after an *END PART, *END INSTANCE, *ASSEMBLY or *END ASSEMBLY."""
    name = keyword.name
    inside_part = any(current is part for part in deck.parts.values())
    inside_instance = current is not deck.assembly and not inside_part
    if (name == "END PART" and not inside_part) or (
            name == "END INSTANCE" and not inside_instance) or (
            name in ("ASSEMBLY", "END ASSEMBLY") and current is not deck.assembly):
        raise keyword.error("out of place: expected *PART ... *END PART, then *ASSEMBLY "
                            "with *INSTANCE ... *END INSTANCE, then *END ASSEMBLY")
    return deck.assembly
