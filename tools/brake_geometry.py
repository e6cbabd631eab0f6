"""The solids tools/mesh_brake.py meshes: the disc and the pad of a brake, built in gmsh's
OpenCASCADE kernel with the physical groups a case names, and sampled for the size integrals
of its node model. A module of its own so the meshing and its command line stay short."""
import math
from dataclasses import dataclass, replace

import numpy as np

GEOMETRY_TOL = 1e-9


@dataclass(frozen=True)
class Shape:
    """What cuts the pad's lining [m], zeros for none: a radial slot at mid-arc, slot_width
    wide between parallel walls and slot_depth deep from the friction face (None: the lining's
    thickness, down to the backplate, which stays whole); and at both ends a chamfer whose
    plane runs parallel to the end, chamfer_length from it on the friction face (the arc to it
    at radius r, r asin(length / r), is longer by a fraction (length / r)^2 / 6) and
    chamfer_depth up the end face."""
    slot_width: float = 0.0
    slot_depth: float = None
    chamfer_length: float = 0.0
    chamfer_depth: float = 0.0


class Disc:
    """The annulus of an `annular_disc` mesh spec; its contact face is the pad's footprint on
    its top face."""

    def __init__(self, params, pad):
        self.inner, self.outer = params["inner_radius"], params["outer_radius"]
        self.thickness = params["thickness"]
        self.center = tuple(params["center"])
        self.pad = pad

    def build(self, gmsh):
        """The OCC solid and its physical groups: name -> (dim, entity tags)."""
        occ = gmsh.model.occ
        cx, cy, cz = self.center
        outer = occ.addCylinder(cx, cy, cz, 0, 0, self.thickness, self.outer)
        inner = occ.addCylinder(cx, cy, cz, 0, 0, self.thickness, self.inner)
        occ.cut([(3, outer)], [(3, inner)])
        occ.synchronize()
        levels = {"zmin": cz, "zmax": cz + self.thickness}
        radii = {"hub": self.inner, "outer": self.outer}
        names = classify(gmsh, self.center, levels, radii, other=None)
        check_surfaces(names, ("hub", "outer", "zmin", "zmax"), "disc")
        groups = {"all": (3, [v for _, v in gmsh.model.getEntities(3)])}
        groups.update({k: (2, v) for k, v in names.items()})
        return groups

    def distance(self, x, y, z):
        """Distance to the pad's friction face as it lies on the disc's top face."""
        return self.pad.footprint_distance(x, y, z)

    def outside(self, x, y, z):
        """Distance from a point to the annulus (0 inside or on it)."""
        r = math.hypot(x - self.center[0], y - self.center[1])
        plane = max(self.inner - r, r - self.outer, 0.0)
        height = max(self.center[2] - z, z - self.center[2] - self.thickness, 0.0)
        return math.hypot(plane, height)

    def samples(self, spacing):
        cz = self.center[2]
        return polar_samples(self.center[:2], self.inner, self.outer, 0.0, 2 * math.pi,
                             [cz, cz + self.thickness], spacing, periodic=True)


class Pad:
    """The lining and backplate of a `brake_pad` mesh spec: an annular sector, two layers;
    with `mirror` (a height [m]), its image through the plane z = mirror: the outer pad of a
    caliper, whose lining faces up onto the disc's lower face."""

    def __init__(self, params, shape=Shape(), mirror=None):
        self.inner, self.outer = params["inner_radius"], params["outer_radius"]
        self.angle = math.radians(params["angle"])
        self.mid = math.radians(params["center_angle"])
        self.lining, self.backplate = params["lining_thickness"], params["backplate_thickness"]
        self.z0 = params["z0"]
        self.center = tuple(params["center"]) + (0.0,)
        self.thickness = self.lining + self.backplate
        if shape.slot_width and shape.slot_depth is None:
            shape = replace(shape, slot_depth=self.lining)
        self.shape = shape
        self.mirror = mirror

    def flip(self, z):
        """The height z of the unmirrored pad where the pad has a point at z, and back."""
        return z if self.mirror is None else 2 * self.mirror - z

    def shape_error(self):
        """(option, what was expected) when the shape does not fit the pad, else None."""
        s = self.shape
        if s.slot_width and not 0 < s.slot_depth <= self.lining:
            return "--slot", (f"a depth in (0, {self.lining:g}] m (the lining's thickness), "
                              f"got {s.slot_depth:g}")
        if s.chamfer_length and not 0 < s.chamfer_depth < self.lining:
            return "--chamfer", (f"a depth in (0, {self.lining:g}) m (below the lining's "
                                 f"thickness), got {s.chamfer_depth:g}")
        # the friction face's pieces reach from the inner arc to the outer one: a slot wall
        # and the chamfer's line on the face (or the two chamfers' lines) meet inside the
        # core, at the radius where they cross
        half = 0.5 * self.angle
        x = (s.chamfer_length + 0.5 * s.slot_width * math.cos(half)) / math.sin(half)
        if math.hypot(x, 0.5 * s.slot_width) >= self.inner:
            return "--slot, --chamfer", (
                f"a slot and chamfers that leave the friction face whole from the inner arc "
                f"to the outer one: they meet at radius {math.hypot(x, 0.5 * s.slot_width):.4g} "
                f"m, the pad's inner radius is {self.inner:g} m")
        return None

    def build(self, gmsh):
        occ = gmsh.model.occ
        cx, cy, _ = self.center
        layers = []
        for z, dz in ((self.z0, self.lining), (self.z0 + self.lining, self.backplate)):
            # a cylinder sector from the x axis, hollowed, then turned to its centre angle
            sector = occ.addCylinder(cx, cy, z, 0, 0, dz, self.outer, angle=self.angle)
            core = occ.addCylinder(cx, cy, z - dz, 0, 0, 3 * dz, self.inner)
            cut, _ = occ.cut([(3, sector)], [(3, core)])
            if z == self.z0 and self.shape != Shape():
                cut = self.cut_lining(occ, cut)
            occ.rotate(cut, cx, cy, 0, 0, 0, 1, self.mid - 0.5 * self.angle)
            if self.mirror is not None:
                # the pad, its slot and its chamfers are symmetric about its mid-arc radius:
                # the half turn about that radius in the plane z = mirror is its mirror image
                # (OpenCASCADE's mirror turns the planes and cylinders into B-splines)
                occ.rotate(cut, cx, cy, self.mirror, math.cos(self.mid), math.sin(self.mid),
                           0, math.pi)
            layers.append(cut)
        # fragment: one conforming mesh, the layers share the nodes of their common face
        _, children = occ.fragment(layers[0], layers[1])
        occ.synchronize()
        # one list of children per volume given, the lining's first (a slot down to the
        # backplate parts the lining in two)
        n = len(layers[0])
        lining = [t for c in children[:n] for _, t in c]
        backplate = [t for c in children[n:] for _, t in c]
        # the internal face (z0 + lining) is in no group; the radial end faces are 'ends'
        levels = {"friction": self.z0, None: self.z0 + self.lining,
                  "back": self.z0 + self.lining + self.backplate}
        if self.shape.slot_width and self.shape.slot_depth < self.lining:
            levels["slot"] = self.z0 + self.shape.slot_depth
        levels = {name: self.flip(z) for name, z in levels.items()}
        radii = {"inner": self.inner, "outer": self.outer}
        names = classify(gmsh, self.center, levels, radii, other=self.side_name)
        # a slot down to the backplate bares a strip of its face: a face of one volume only
        bared = [t for t in names.get(None, []) if len(gmsh.model.getAdjacencies(2, t)[0]) == 1]
        if bared:
            names[None] = [t for t in names[None] if t not in bared]
            names.setdefault("slot", []).extend(bared)
        expected = ["friction", "back", "ends", "inner", "outer"]
        expected += ["slot"] * bool(self.shape.slot_width)
        expected += ["chamfer"] * bool(self.shape.chamfer_length)
        check_surfaces(names, expected, "pad")
        unexpected = set(names) - set(expected)
        if unexpected:
            raise RuntimeError(f"pad: surfaces classified as {', '.join(sorted(unexpected))}")
        if len(names["ends"]) != 4:
            raise RuntimeError(f"pad: {len(names['ends'])} end faces, expected 4 (2 per layer)")
        groups = {"lining": (3, lining), "backplate": (3, backplate),
                  "all": (3, lining + backplate)}
        groups.update({k: (2, v) for k, v in names.items()})
        return groups

    def cut_lining(self, occ, lining):
        """The lining (a sector from the x axis, before its turn) less its slot and chamfers:
        its volumes' tags."""
        cx, cy, _ = self.center
        s, half = self.shape, 0.5 * self.angle
        # every tool spans the radii from inside the core to past the outer arc
        x0, length = 0.5 * self.inner, 2 * self.outer
        tools = []
        if s.slot_width:
            # past the lining's top when the slot goes down to the backplate: no face of the
            # box coincides with the lining's, so OpenCASCADE cuts it cleanly
            top = s.slot_depth if s.slot_depth < self.lining else 2 * self.lining
            box = occ.addBox(cx + x0, cy - 0.5 * s.slot_width, self.z0 - self.lining, length,
                             s.slot_width, top + self.lining)
            occ.rotate([(3, box)], cx, cy, 0, 0, 0, 1, half)
            tools.append((3, box))
        if s.chamfer_length:
            # a wedge at each end: a triangle in (y, z) whose long side is the chamfer's plane,
            # through (L, z0) and (0, z0 + D), the others outside the lining; y points into
            # the pad from the end on the x axis, away from it at the other end (a mirror
            # image would make the planes B-splines: the second wedge is built, then turned)
            L, D = s.chamfer_length, s.chamfer_depth
            for side, turn in ((1, 0.0), (-1, self.angle)):
                corners = [(2 * L, self.z0 - D), (-L, self.z0 + 2 * D), (-L, self.z0 - D)]
                points = [occ.addPoint(cx + x0, cy + side * y, z) for y, z in corners]
                lines = [occ.addLine(a, b) for a, b in zip(points, points[1:] + points[:1])]
                face = occ.addPlaneSurface([occ.addCurveLoop(lines)])
                wedge = [d for d in occ.extrude([(2, face)], length, 0, 0) if d[0] == 3]
                occ.rotate(wedge, cx, cy, 0, 0, 0, 1, turn)
                tools += wedge
        cut, _ = occ.cut(lining, tools)
        return cut

    def side_name(self, kind, point, normal):
        """The name of a face neither flat nor cylindrical: a plane through the axis is an
        end, a vertical plane off it a slot wall, a sloping one a chamfer."""
        if kind != "Plane":
            return kind
        if abs(normal[2]) > GEOMETRY_TOL:
            return "chamfer"
        offset = (point[0] - self.center[0]) * normal[0] + (point[1] - self.center[1]) * normal[1]
        return "ends" if abs(offset) < GEOMETRY_TOL else "slot"

    def distance(self, x, y, z):
        """Distance to the friction face, for a point of the pad (above it, unmirrored)."""
        return max(self.flip(z) - self.z0, 0.0)

    def footprint_distance(self, x, y, z):
        """Distance to the friction face from a point below it (in the disc): the in-plane
        distance to the sector, exact inside its angular range and to the nearer end segment
        outside it, combined with the depth below z0 (above it, mirrored)."""
        dx, dy = x - self.center[0], y - self.center[1]
        r = math.hypot(dx, dy)
        dtheta = (math.atan2(dy, dx) - self.mid + math.pi) % (2 * math.pi) - math.pi
        half = 0.5 * self.angle
        if abs(dtheta) <= half:
            plane = max(self.inner - r, r - self.outer, 0.0)
        else:
            end = self.mid + math.copysign(half, dtheta)
            ux, uy = math.cos(end), math.sin(end)
            along = min(max(dx * ux + dy * uy, self.inner), self.outer)
            plane = math.hypot(dx - along * ux, dy - along * uy)
        return math.hypot(plane, max(self.z0 - self.flip(z), 0.0))

    def outside(self, x, y, z):
        """Distance from a point to the pad's two layers, uncut (0 inside or on them)."""
        z = self.flip(z)
        height = max(self.z0 - z, z - self.z0 - self.thickness, 0.0)
        return math.hypot(self.footprint_distance(x, y, self.flip(self.z0)), height)

    def samples(self, spacing):
        half = 0.5 * self.angle
        levels = sorted(self.flip(z) for z in (self.z0, self.z0 + self.lining,
                                                 self.z0 + self.lining + self.backplate))
        return polar_samples(self.center[:2], self.inner, self.outer, self.mid - half,
                             self.mid + half, levels, spacing, periodic=False)


def classify(gmsh, center, levels, radii, other):
    """Surface tags by name: faces of constant z at a level of `levels` (name -> z), cylinders
    about the axis through center of a radius of `radii`, the rest under `other`: a name, or
    a function of the face's kind, a point of it and its normal there that gives one."""
    names = {}
    for _, tag in gmsh.model.getEntities(2):
        lo, hi = gmsh.model.getParametrizationBounds(2, tag)
        uv = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
        x, y, z = gmsh.model.getValue(2, tag, uv)
        kind = gmsh.model.getType(2, tag)
        # (OpenCASCADE pads bounding boxes by its tolerance: the normal tells a flat face)
        if kind == "Plane" and abs(abs(gmsh.model.getNormal(tag, uv)[2]) - 1) < GEOMETRY_TOL:
            name = [n for n, level in levels.items() if abs(z - level) < GEOMETRY_TOL]
        elif kind == "Cylinder":
            r = math.hypot(x - center[0], y - center[1])
            name = [n for n, radius in radii.items() if abs(r - radius) < GEOMETRY_TOL]
        elif callable(other):
            name = [other(kind, (x, y, z), gmsh.model.getNormal(tag, uv))]
        else:
            name = [other]
        if len(name) != 1:
            raise RuntimeError(f"surface {tag} ({kind} through {x:.4g}, {y:.4g}, {z:.4g}) is "
                               "none of the expected faces")
        names.setdefault(name[0], []).append(tag)
    return names


def check_surfaces(names, expected, part):
    """Every expected surface found; the unnamed ones (the pad's internal face) dropped."""
    missing = [n for n in expected if not names.get(n)]
    if missing:
        raise RuntimeError(f"{part}: no surface classified as {', '.join(missing)}")
    names.pop(None, None)


def polar_samples(center, r0, r1, t0, t1, levels, spacing, periodic):
    """Midpoint samples of a polar box (r0-r1, t0-t1, z between levels) and of its faces and
    edges, cells about `spacing` wide: {3: (points, volumes), 2: (points, areas), 1: (points,
    lengths)}. The faces are the z-faces at every level (the internal ones too: they are
    meshed), the cylinders r0 and r1, and the two radial ends unless periodic; the edges are
    their intersections. The weights sum to the exact volume, area and length."""
    def cuts(a, b, length):
        """Midpoints and width of the cells of [a, b], `length` long in metres."""
        n = max(1, math.ceil(length / spacing))
        return a + (np.arange(n) + 0.5) * (b - a) / n, (b - a) / n

    r, dr = cuts(r0, r1, r1 - r0)
    t, dt = cuts(t0, t1, 0.5 * (r0 + r1) * (t1 - t0))
    zs = [cuts(a, b, b - a) for a, b in zip(levels[:-1], levels[1:])]
    z = np.concatenate([c for c, _ in zs])
    dz = np.concatenate([np.full(len(c), d) for c, d in zs])

    def polar(R, T, Z, W):
        R, T, Z, W = np.broadcast_arrays(R, T, Z, W)
        pts = np.stack([center[0] + R * np.cos(T), center[1] + R * np.sin(T), Z], axis=-1)
        return pts.reshape(-1, 3), W.ravel()

    def join(pieces):
        return (np.vstack([p for p, _ in pieces]), np.concatenate([w for _, w in pieces]))

    ends = [] if periodic else [t0, t1]
    R, T, Z = np.meshgrid(r, t, z, indexing="ij")
    volume = polar(R, T, Z, R * dr * dt * np.broadcast_to(dz, Z.shape))
    faces = [polar(*np.meshgrid(r, t, [lv], indexing="ij"),
                   np.meshgrid(r, t, [lv], indexing="ij")[0] * dr * dt) for lv in levels]
    faces += [polar(rr, *np.meshgrid(t, z, indexing="ij"), rr * dt * dz[None, :])
              for rr in (r0, r1)]
    faces += [polar(*np.meshgrid(r, [te], z, indexing="ij"), dr * dz[None, None, :])
              for te in ends]
    edges = [polar(rr, t, lv, rr * dt) for lv in levels for rr in (r0, r1)]
    edges += [polar(r, te, lv, dr) for lv in levels for te in ends]
    edges += [polar(rr, te, z, dz) for rr in (r0, r1) for te in ends]
    return {3: volume, 2: join(faces), 1: join(edges)}
