"""The case keys of a part's geometry: its mesh (a generator's parameters, or a file read by
meshio), the named selections made from its coordinates and its placement (case.schema's
PART)."""
from .nodes import REQUIRED, Table, Value, Variant


def positive(doc, unit="", default=REQUIRED):
    return Value("float", doc, default, unit, open_min=0.0)


def vector3(doc, unit="m", default=REQUIRED):
    return Value("floats", doc, default, unit, length=3)


ELEMENT = Value("choice", "element type of the generated mesh", "hex8",
                choices=("hex8", "hex20", "tet4", "tet10", "wedge6", "wedge15"))

MESH = Variant("mesh of the part: a generator or a file", {
    "box": {
        "size": Value("floats", "edge lengths along x, y, z", unit="m", length=3, open_min=0.0),
        "divisions": Value("ints", "cells along x, y, z", length=3, minimum=1),
        "origin": vector3("corner with the smallest coordinates", default=[0.0, 0.0, 0.0]),
        "element": ELEMENT,
    },
    "drilled_box": {
        "size": Value("floats", "edge lengths along x, y, z", unit="m", length=3, open_min=0.0),
        "divisions": Value("ints", "background cells along x, y, z", length=3, minimum=1),
        "origin": vector3("corner with the smallest coordinates", default=[0.0, 0.0, 0.0]),
        "hole_center": Value("floats", "x, y of the axis of the hole (along z)", unit="m",
                             length=2),
        "hole_radius": positive("radius of the hole", "m"),
        "ogrid_cells": Value("int", "half-width in background cells of the square meshed as an "
                             "O-grid around the hole (0: smallest that fits 1.5 radius)", 0,
                             minimum=0),
        "filled": Value("bool", "mesh the hole too (a plain block with the drilled block's plan)",
                        False),
        "element": ELEMENT,
    },
    "annular_disc": {
        "inner_radius": positive("radius of the hub (inner) face", "m"),
        "outer_radius": positive("outer radius", "m"),
        "thickness": positive("thickness along z", "m"),
        "divisions": Value("ints", "cells along radius, circumference, thickness", length=3,
                           minimum=1),
        "center": vector3("centre of the lower face", default=[0.0, 0.0, 0.0]),
        "element": ELEMENT,
    },
    "brake_pad": {
        "inner_radius": positive("inner radius of the annular sector", "m"),
        "outer_radius": positive("outer radius of the annular sector", "m"),
        "angle": Value("float", "opening angle of the sector", unit="deg", open_min=0.0,
                       maximum=360.0),
        "center_angle": Value("float", "polar angle of the sector's middle", 90.0, "deg"),
        "lining_thickness": positive("thickness of the friction lining", "m"),
        "backplate_thickness": positive("thickness of the steel backplate", "m"),
        "divisions": Value("ints", "cells along radius, angle, lining thickness, backplate "
                           "thickness", length=4, minimum=1),
        "z0": Value("float", "height of the friction face (bottom of the lining)", 0.0, "m"),
        "center": Value("floats", "x, y of the axis of the sector", [0.0, 0.0], "m", length=2),
        "element": ELEMENT,
    },
    "file": {
        "path": Value("str", "mesh file, relative to the case file: an Abaqus or CalculiX "
                      "deck (.inp), or any file meshio reads (Gmsh .msh, VTU...)"),
        "scale": positive("factor applied to the coordinates (1e-3 for a file in mm)", "-", 1.0),
        "translate": vector3("translation applied after scaling", default=[0.0, 0.0, 0.0]),
        "body": Value("str", "the file's cell set whose cells alone make the part: an "
                      "instance of a deck's assembly, an element set, a physical volume "
                      "(empty: every cell of the file)", ""),
    },
})

SELECTION = Variant("named selection from geometry: nodes within tol, and the boundary faces "
                    "whose nodes are all selected", {
                        "plane": {
                            "point": vector3("a point of the plane"),
                            "normal": Value("floats", "normal of the plane", length=3),
                        },
                        "box": {
                            "min": vector3("smallest corner"),
                            "max": vector3("largest corner"),
                        },
                        "cylinder": {
                            "point": vector3("a point of the axis"),
                            "axis": Value("floats", "direction of the axis", length=3),
                            "radius": positive("radius of the cylindrical surface", "m"),
                        },
                    }, common={
                        "tol": Value("float", "distance tolerance", 1e-9, "m", minimum=0.0),
                    })

TRANSFORM = Table("placement of the part, applied after its mesh's own scale and translate "
                  "and after its sets are selected: translate, then rotate, then mirror; the "
                  "node, face and cell sets follow the mesh", {
    "translate": vector3("translation of the part, the first step of its placement (after "
                         "the mesh's own scale and translate; its sets follow it)",
                         default=[0.0, 0.0, 0.0]),
    "rotate": Table("rotation about an axis through a point, after the translation", {
        "axis": Value("floats", "direction of the axis, right-handed with the angle (needed "
                      "when the angle is not 0)", [], length=3),
        "angle": Value("float", "angle of the rotation, after the translation", 0.0, "deg",
                       minimum=-360.0, maximum=360.0),
        "point": vector3("a point of the axis", default=[0.0, 0.0, 0.0]),
    }, optional=True),
    "mirror": Table("reflection through a plane, after the rotation", {
        "point": vector3("a point of the plane", default=[0.0, 0.0, 0.0]),
        "normal": Value("floats", "normal of the mirror plane, the last step ([]: no mirror; "
                        "each cell's nodes are reordered so its volume stays positive)", [],
                        length=3),
    }, optional=True),
}, optional=True)
