"""Closed forms of a slotted, chamfered brake pad (tools/mesh_brake.py --slot, --chamfer): the
areas and volumes its meshes must have, written from the geometry, not from the tool's code.

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
