"""The solids of a brake corner (tools/mesh_corner.py): the disc and the two pads of
tools/brake_geometry.py, the outer pad mirrored through the disc's mid-plane, two pistons, an
opposed-piston caliper and the bracket (carrier) that holds the pads' ends. Each solid is built
in gmsh's OpenCASCADE kernel with the physical groups the corner's case names, and sampled for
the size integrals of tools/mesh_brake.py's node model.

The disc turns about z, its lower face at z = 0; the inboard side (the knuckle's) is +z. Every
face a pair ties is a plane (the package's pairs project on one contact plane and tie the
normal gap only), and the parts are shaped so that the pairs hold each of them: see Corner."""
import math
from dataclasses import dataclass

import numpy as np

from brake_geometry import GEOMETRY_TOL, Disc, Pad, Shape, polar_samples
from mesh_brake import GROWTH

BORE_ARC = 1 / 12     # the bores' edges' mesh size, a fraction of their circumference


@dataclass(frozen=True)
class Block:
    """An annular sector about the disc's axis: radii r0-r1 [m], polar angles t0-t1 [deg],
    heights z0-z1 [m]."""
    r0: float
    r1: float
    t0: float
    t1: float
    z0: float
    z1: float

    def build(self, occ):
        """The OCC volume's dimTags (a cylinder sector from the x axis, hollowed, turned)."""
        dz = self.z1 - self.z0
        sector = occ.addCylinder(0, 0, self.z0, 0, 0, dz, self.r1,
                                 angle=math.radians(self.t1 - self.t0))
        core = occ.addCylinder(0, 0, self.z0 - dz, 0, 0, 3 * dz, self.r0)
        cut, _ = occ.cut([(3, sector)], [(3, core)])
        occ.rotate(cut, 0, 0, 0, 0, 0, 1, math.radians(self.t0))
        return cut

    def samples(self, spacing):
        return polar_samples((0.0, 0.0), self.r0, self.r1, math.radians(self.t0),
                             math.radians(self.t1), [self.z0, self.z1], spacing,
                             periodic=False)

    @property
    def volume(self):
        return 0.5 * math.radians(self.t1 - self.t0) * (self.r1 ** 2 - self.r0 ** 2) * (
            self.z1 - self.z0)


@dataclass(frozen=True)
class Corner:
    """The corner's dimensions [m, deg]. The disc and the pads are cases/pad_disc.toml's; a
    piston of radius piston_radius has a quarter of a pad's area, so a line pressure of 4 MPa
    presses the pads at 1 MPa on average, as pad_disc's piston load.

    Load paths, each pair a tie of the normal gap on a plane. The hydraulic pressure pushes
    each piston onto its pad and the caliper's bore bottoms away from the disc (the bridge in
    tension): a piston is a part of its own, free along its axis in its bore, so the pressure
    is the preload whatever the parts' stiffness (a piston of the caliper's body would carry the
    clamp through the bridge instead of the disc). A bore is a cylinder, which no pair can tie:
    the pistons are held in the disc's plane by the case's constraints. Each pad's backplate
    ends tie to the bracket's abutments (the radial planes at the pads' ends): the friction
    drag goes to the bracket. The caliper sits on the bracket's arms (its ears on their
    inboard faces: the guide pins' seat) and its inner jaw's ends tie to the same abutments:
    three planes of three directions hold its six rigid motions. The bracket is clamped on the
    knuckle (its crossbeam's inboard face), the disc at its hub."""
    disc_inner: float = 0.055
    disc_outer: float = 0.14
    disc_thickness: float = 0.02
    pad_inner: float = 0.09
    pad_outer: float = 0.135
    pad_angle: float = 50.0
    pad_center: float = 90.0
    lining: float = 0.01
    backplate: float = 0.005
    piston_radius: float = 0.01875
    piston_length: float = 0.016
    jaw_gap: float = 0.002          # between a pad's back and the caliper's jaw
    jaw_thickness: float = 0.028    # along z, the bore's depth included
    jaw_inner: float = 0.088        # the jaws' radii
    rim_gap: float = 0.005          # between the disc's rim and the bridges
    bridge: float = 0.02            # the caliper's bridge, radially
    ear_thickness: float = 0.015    # the caliper's ears, along z
    ear_angle: float = 15.0         # past the pads' ends, as the bracket's arms
    clearance: float = 3.0          # [deg] between the caliper's outer parts and the arms
    arm_top: float = 0.015          # the arms' inboard faces above the backplates
    arm_depth: float = 0.02         # the arms' blocks along z
    bracket_bridge: float = 0.015
    crossbeam_inner: float = 0.07
    crossbeam_outer: float = 0.085
    crossbeam_z: tuple = (0.035, 0.045)

    @property
    def mid(self):
        """The disc's mid-plane z: the mirror of the inboard parts."""
        return 0.5 * self.disc_thickness

    def flip(self, z):
        return 2 * self.mid - z

    @property
    def back(self):
        """The inner pad's back, z."""
        return self.disc_thickness + self.lining + self.backplate

    @property
    def ends(self):
        """The pads' ends, polar angles [deg]."""
        return (self.pad_center - 0.5 * self.pad_angle, self.pad_center + 0.5 * self.pad_angle)

    @property
    def axis(self):
        """The pistons' axis (x, y): over the pad's mid-radius at its centre angle."""
        r, t = 0.5 * (self.pad_inner + self.pad_outer), math.radians(self.pad_center)
        return (r * math.cos(t), r * math.sin(t))

    @property
    def bore_bottom(self):
        """The inner bore's bottom (the inner piston's back), z."""
        return self.back + self.piston_length

    @property
    def seat(self):
        """The arms' inboard faces and the caliper's ears' lower ones, z."""
        return self.back + self.arm_top

    def pad_params(self):
        """The inner pad as a `brake_pad` mesh spec's parameters."""
        return dict(inner_radius=self.pad_inner, outer_radius=self.pad_outer,
                    angle=self.pad_angle, center_angle=self.pad_center,
                    lining_thickness=self.lining, backplate_thickness=self.backplate,
                    z0=self.disc_thickness, center=[0.0, 0.0])

    def disc_params(self):
        return dict(inner_radius=self.disc_inner, outer_radius=self.disc_outer,
                    thickness=self.disc_thickness, center=[0.0, 0.0, 0.0])

    def caliper_blocks(self):
        """The caliper's housing, in pieces that do not overlap: the inner jaw between the
        pads' ends, the ears over the arms above it, the bridge past the rim, the outer jaw."""
        lo, hi = self.ends
        c, e = self.clearance, self.ear_angle
        jaw0, top = self.back + self.jaw_gap, self.back + self.jaw_gap + self.jaw_thickness
        r1 = self.disc_outer + self.rim_gap
        inner = Block(self.jaw_inner, r1, lo, hi, jaw0, self.seat)
        ears = Block(self.jaw_inner, r1, lo - e, hi + e, self.seat, top)
        bridge = Block(r1, r1 + self.bridge, lo + c, hi - c, self.flip(top), top)
        outer = Block(self.jaw_inner, r1, lo + c, hi - c, self.flip(top), self.flip(jaw0))
        return [inner, ears, bridge, outer]

    def bracket_blocks(self):
        """The bracket: at each pad end an arm (a block beside each backplate, joined by a
        bridge past the rim), and the crossbeam between the arms on the knuckle's side."""
        lo, hi = self.ends
        e = self.ear_angle
        r1 = self.disc_outer + self.rim_gap
        z0 = self.disc_thickness + self.lining
        blocks = []
        for t0, t1 in ((lo - e, lo), (hi, hi + e)):
            blocks += [Block(self.crossbeam_inner, r1, t0, t1, z0, self.seat),
                       Block(self.jaw_inner, r1, t0, t1, self.flip(z0 + self.arm_depth),
                             self.flip(z0)),
                       Block(r1, r1 + self.bracket_bridge, t0, t1,
                             self.flip(z0 + self.arm_depth), self.seat)]
        blocks.append(Block(self.crossbeam_inner, self.crossbeam_outer, lo, hi,
                            *self.crossbeam_z))
        return blocks


def surfaces(gmsh, name_of):
    """Surface tags by name: name_of(kind, point, normal) of each face (a point and the normal
    at the middle of its parameter box) gives its name, None for none."""
    names = {}
    for _, tag in gmsh.model.getEntities(2):
        lo, hi = gmsh.model.getParametrizationBounds(2, tag)
        uv = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
        point = gmsh.model.getValue(2, tag, uv)
        name = name_of(gmsh.model.getType(2, tag), point, gmsh.model.getNormal(tag, uv))
        if name is not None:
            names.setdefault(name, []).append(tag)
    return names


def flat_level(kind, normal):
    """True for a plane of constant z."""
    return kind == "Plane" and abs(abs(normal[2]) - 1) < GEOMETRY_TOL


def radial_angle(kind, point, normal):
    """The polar angle [deg, 0-180) of a plane through the disc's axis, else None."""
    if kind != "Plane" or abs(normal[2]) > GEOMETRY_TOL:
        return None
    if abs(point[0] * normal[0] + point[1] * normal[1]) > GEOMETRY_TOL:
        return None
    return math.degrees(math.atan2(-normal[0], normal[1])) % 180.0


def near(value, target):
    return abs(value - target) < 1e-6


def expect(names, wanted, part):
    missing = [n for n in wanted if not names.get(n)]
    if missing:
        raise RuntimeError(f"{part}: no surface classified as {', '.join(missing)}")


class Housing:
    """A solid fused from Blocks, less cylindrical bores, its faces named by `name_of`. The
    bores' edges are meshed at most BORE_ARC of their circumference apart: coarser, gmsh leaves
    slivers on their walls that turn inside out once their midside nodes go onto the cylinder
    (the caliper at h = 16 mm and above, det J -4e-8)."""
    thickness = 0.02

    def __init__(self, blocks, bores, name_of, wanted, label):
        self.blocks, self.bores = blocks, bores
        self.name_of, self.wanted, self.label = name_of, wanted, label

    def build(self, gmsh):
        occ = gmsh.model.occ
        pieces = [v for b in self.blocks for v in b.build(occ)]
        solid, _ = occ.fuse(pieces[:1], pieces[1:])
        if self.bores:
            holes = [(3, occ.addCylinder(x, y, z0, 0, 0, z1 - z0, r))
                     for x, y, z0, z1, r in self.bores]
            solid, _ = occ.cut(solid, holes)
        occ.synchronize()
        volumes = [t for _, t in gmsh.model.getEntities(3)]
        if len(volumes) != 1:
            raise RuntimeError(f"{self.label}: {len(volumes)} volumes, expected one")
        names = surfaces(gmsh, self.name_of)
        expect(names, self.wanted, self.label)
        return {"all": (3, volumes), **{k: (2, v) for k, v in names.items()}}

    def distance(self, x, y, z):
        # no friction face: the size away from the contact everywhere
        return math.inf

    def local_size(self, x, y, z):
        """The bores' size on their walls, growing away from them as the contact's does
        (tools/mesh_brake.py's size_at caps h with it)."""
        size = math.inf
        for bx, by, z0, z1, r in self.bores:
            wall = math.hypot(math.hypot(x - bx, y - by) - r, max(z0 - z, z - z1, 0.0))
            size = min(size, BORE_ARC * 2 * math.pi * r + GROWTH * wall)
        return size

    def samples(self, spacing):
        pieces = [b.samples(spacing) for b in self.blocks]
        return {k: (np.vstack([p[k][0] for p in pieces]),
                    np.concatenate([p[k][1] for p in pieces])) for k in (3, 2, 1)}


def caliper(corner):
    """The housing: sets `bores` (the bottoms the line pressure pushes), `seat` (the ears'
    faces on the arms), `end_lo` and `end_hi` (the inner jaw's ends on the abutments)."""
    lo, hi = corner.ends
    x, y = corner.axis
    bottoms = (corner.bore_bottom, corner.flip(corner.bore_bottom))
    jaw = corner.back + corner.jaw_gap

    def name_of(kind, point, normal):
        if flat_level(kind, normal):
            z = point[2]
            return ("bores" if any(near(z, b) for b in bottoms)
                    else "seat" if near(z, corner.seat) else None)
        angle = radial_angle(kind, point, normal)
        # the inner jaw's ends only: the outer parts stand clear of the arms
        if angle is not None and jaw < point[2] < corner.seat + 1e-6:
            return "end_lo" if near(angle, lo) else "end_hi" if near(angle, hi) else None
        return None
    bores = [(x, y, jaw - 0.001, corner.bore_bottom, corner.piston_radius),
             (x, y, corner.flip(corner.bore_bottom), corner.flip(jaw) + 0.001,
              corner.piston_radius)]
    return Housing(corner.caliper_blocks(), bores, name_of,
                   ("bores", "seat", "end_lo", "end_hi"), "caliper")


def bracket(corner):
    """The carrier: sets `abutment_lo` and `abutment_hi` (the arms' faces at the pads'
    ends), `seat` (the arms' inboard faces) and `knuckle` (the crossbeam's, clamped)."""
    lo, hi = corner.ends

    def name_of(kind, point, normal):
        if flat_level(kind, normal):
            z = point[2]
            return ("seat" if near(z, corner.seat)
                    else "knuckle" if near(z, corner.crossbeam_z[1]) else None)
        angle = radial_angle(kind, point, normal)
        if angle is not None:
            return "abutment_lo" if near(angle, lo) else "abutment_hi" if near(angle, hi) \
                else None
        return None
    return Housing(corner.bracket_blocks(), [], name_of,
                   ("abutment_lo", "abutment_hi", "seat", "knuckle"), "bracket")


class Piston:
    """A solid cylinder along z: sets `front` (on the pad's back), `back` (in the bore: the
    line pressure) and `side`."""

    def __init__(self, corner, mirrored):
        self.x, self.y = corner.axis
        self.radius, self.thickness = corner.piston_radius, corner.piston_length
        z = (corner.back, corner.bore_bottom)
        self.front, self.rear = (corner.flip(v) for v in z) if mirrored else z

    def build(self, gmsh):
        occ = gmsh.model.occ
        z0 = min(self.front, self.rear)
        tag = occ.addCylinder(self.x, self.y, z0, 0, 0, self.thickness, self.radius)
        occ.synchronize()

        def name_of(kind, point, normal):
            if flat_level(kind, normal):
                return "front" if near(point[2], self.front) else "back"
            return "side" if kind == "Cylinder" else None
        names = surfaces(gmsh, name_of)
        expect(names, ("front", "back", "side"), "piston")
        return {"all": (3, [tag]), **{k: (2, v) for k, v in names.items()}}

    def distance(self, x, y, z):
        return math.inf

    def local_size(self, x, y, z):
        # the caliper's bores' size: the line pressure acts on the area of a circle, not a
        # hexagon's (-8e-4 at h = 16 mm)
        return BORE_ARC * 2 * math.pi * self.radius

    def samples(self, spacing):
        return polar_samples((self.x, self.y), 0.0, self.radius, 0.0, 2 * math.pi,
                             sorted((self.front, self.rear)), spacing, periodic=True)


class CornerPad(Pad):
    """A pad whose backplate's two end faces are sets of their own, `end_lo` and `end_hi`
    (at the smaller and the larger polar angle): the faces the abutments hold."""

    def build(self, gmsh):
        groups = super().build(gmsh)
        backplate = set(groups["backplate"][1])
        split = {}
        for tag in groups["ends"][1]:
            if not set(gmsh.model.getAdjacencies(2, tag)[0]) & backplate:
                continue
            lo, hi = gmsh.model.getParametrizationBounds(2, tag)
            uv = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
            x, y, _ = gmsh.model.getValue(2, tag, uv)
            side = "end_lo" if math.atan2(y, x) < self.mid else "end_hi"
            split.setdefault(side, []).append(tag)
        if sorted(split) != ["end_hi", "end_lo"] or any(len(v) != 1 for v in split.values()):
            raise RuntimeError(f"pad: backplate ends {split}, expected one at each end")
        return {**groups, **{k: (2, v) for k, v in split.items()}}


class CornerDisc(Disc):
    """The disc, its size graded from both pads' footprints (its upper and lower faces)."""

    def __init__(self, params, pads):
        super().__init__(params, pads[0])
        self.pads = pads

    def distance(self, x, y, z):
        return min(p.footprint_distance(x, y, z) for p in self.pads)


def corner_parts(corner, shape=Shape()):
    """{part name: solid} of the corner, the pads cut to `shape` (brake_geometry.Shape)."""
    pad_in = CornerPad(corner.pad_params(), shape)
    pad_out = CornerPad(corner.pad_params(), shape, mirror=corner.mid)
    return {"disc": CornerDisc(corner.disc_params(), (pad_in, pad_out)),
            "pad_in": pad_in, "pad_out": pad_out,
            "piston_in": Piston(corner, False), "piston_out": Piston(corner, True),
            "caliper": caliper(corner), "bracket": bracket(corner)}
