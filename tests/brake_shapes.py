"""Closed forms of a slotted, chamfered brake pad (tools/mesh_brake.py --slot, --chamfer) and
of the brake corner's parts (tools/mesh_corner.py): the areas and volumes their meshes must
have, written from the geometry, not from the tools' code.

The pad is the annular sector ri < r < ro over `angle` radians. The slot's walls are parallel to
the radius at mid-arc, half a width a from it; a chamfer's line on the friction face is parallel
to its end, L from it. Both cut the annulus along a strip of constant width: in the frame of
the strip's edge, the part of the annulus with 0 < y < a."""
import math


def under_circle(a, R):
    """The integral of sqrt(R^2 - y^2) over 0 < y < a."""
    return 0.5 * (a * math.sqrt(R * R - a * a) + R * R * math.asin(a / R))


def moment_under_circle(a, R):
    """The integral of y sqrt(R^2 - y^2) over 0 < y < a."""
    return (R ** 3 - (R * R - a * a) ** 1.5) / 3.0


def strip(a, ri, ro):
    """Area of the annulus' part 0 < y < a, x > 0 (a < ri)."""
    return under_circle(a, ro) - under_circle(a, ri)


def pad_geometry(ri, ro, angle, lining, slot_width, slot_depth, chamfer_length,
                 chamfer_depth):
    """{name: area [m^2] or volume [m^3]} of the pad's faces and layers (lengths in m, angle in
    radians); a slot down to the backplate (depth = lining) bares a strip of its face."""
    a, L, D = 0.5 * slot_width, chamfer_length, chamfer_depth
    sector = 0.5 * angle * (ro * ro - ri * ri)
    slot_plan = 2 * strip(a, ri, ro)
    # a chamfer's section at y is D (1 - y / L) high, its plan the strip 0 < y < L
    chamfer_plan = strip(L, ri, ro)
    chamfer_volume = D * (chamfer_plan - (moment_under_circle(L, ro)
                                          - moment_under_circle(L, ri)) / L)
    wall = math.sqrt(ro * ro - a * a) - math.sqrt(ri * ri - a * a)
    return {
        "sector": sector,
        "friction": sector - slot_plan - 2 * chamfer_plan,
        "slot": 2 * slot_depth * wall + slot_plan,
        "chamfer": 2 * chamfer_plan * math.hypot(L, D) / L,
        "lining": sector * lining - slot_depth * slot_plan - 2 * chamfer_volume,
    }


def sector(r0, r1, degrees, dz):
    """Volume of an annular sector: radii r0-r1 [m], an angle [deg], a height dz [m]."""
    return 0.5 * math.radians(degrees) * (r1 ** 2 - r0 ** 2) * dz


# The volumes [m^3] of cases/brake_corner.toml's parts (tools/mesh_corner.py), from the
# dimensions [m, deg] of its comments: the disc 0.055-0.14 m, 20 mm thick from z = 0; the pads
# 0.09-0.135 m over 65-115 degrees, a 10 mm lining on a 5 mm backplate; the pistons 18.75 mm
# in radius and 16 mm long; the caliper's bores 14 mm deep
CORNER_LINING = sector(0.09, 0.135, 50.0, 0.01)
CORNER_BACKPLATE = sector(0.09, 0.135, 50.0, 0.005)
CORNER_PISTON = math.pi * 0.01875 ** 2 * 0.016
CORNER_VOLUMES = {
    "disc": math.pi * (0.14 ** 2 - 0.055 ** 2) * 0.02,
    "pad_in": CORNER_LINING + CORNER_BACKPLATE, "pad_out": CORNER_LINING + CORNER_BACKPLATE,
    "piston_in": CORNER_PISTON, "piston_out": CORNER_PISTON,
    # the inner jaw, the ears over the arms, the bridge past the rim, the outer jaw, less the
    # two bores
    "caliper": (sector(0.088, 0.145, 50.0, 0.013) + sector(0.088, 0.145, 80.0, 0.015)
                + sector(0.145, 0.165, 44.0, 0.11) + sector(0.088, 0.145, 44.0, 0.028)
                - 2 * math.pi * 0.01875 ** 2 * 0.014),
    # at each end of the pads an arm above (with the crossbeam's root) and below the disc and
    # its bridge past the rim; the crossbeam between the arms
    "bracket": 2 * (sector(0.07, 0.145, 15.0, 0.02) + sector(0.088, 0.145, 15.0, 0.02)
                    + sector(0.145, 0.16, 15.0, 0.08)) + sector(0.07, 0.085, 50.0, 0.01),
}
