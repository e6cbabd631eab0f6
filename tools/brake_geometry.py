"""The solids tools/mesh_brake.py meshes: the disc and the pad of a brake, built in gmsh's
OpenCASCADE kernel with the physical groups a case names, and sampled for the size integrals
of its node model. A module of its own so the meshing and its command line stay short."""
import math

import numpy as np

GEOMETRY_TOL = 1e-9


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

    def samples(self, spacing):
        cz = self.center[2]
        return polar_samples(self.center[:2], self.inner, self.outer, 0.0, 2 * math.pi,
                             [cz, cz + self.thickness], spacing, periodic=True)


class Pad:
    """The lining and backplate of a `brake_pad` mesh spec: an annular sector, two layers."""

    def __init__(self, params):
        self.inner, self.outer = params["inner_radius"], params["outer_radius"]
        self.angle = math.radians(params["angle"])
        self.mid = math.radians(params["center_angle"])
        self.lining, self.backplate = params["lining_thickness"], params["backplate_thickness"]
        self.z0 = params["z0"]
        self.center = tuple(params["center"]) + (0.0,)
        self.thickness = self.lining + self.backplate

    def build(self, gmsh):
        occ = gmsh.model.occ
        cx, cy, _ = self.center
        layers = []
        for z, dz in ((self.z0, self.lining), (self.z0 + self.lining, self.backplate)):
            # a cylinder sector from the x axis, hollowed, then turned to its centre angle
            sector = occ.addCylinder(cx, cy, z, 0, 0, dz, self.outer, angle=self.angle)
            core = occ.addCylinder(cx, cy, z - dz, 0, 0, 3 * dz, self.inner)
            cut, _ = occ.cut([(3, sector)], [(3, core)])
            occ.rotate(cut, cx, cy, 0, 0, 0, 1, self.mid - 0.5 * self.angle)
            layers.append(cut)
        # fragment: one conforming mesh, the layers share the nodes of their common face
        _, children = occ.fragment(layers[0], layers[1])
        occ.synchronize()
        lining = [t for _, t in children[0]]
        backplate = [t for _, t in children[1]]
        # the internal face (z0 + lining) is in no group; the radial end faces are 'ends'
        levels = {"friction": self.z0, None: self.z0 + self.lining,
                  "back": self.z0 + self.lining + self.backplate}
        radii = {"inner": self.inner, "outer": self.outer}
        names = classify(gmsh, self.center, levels, radii, other="ends")
        check_surfaces(names, ("friction", "back", "ends", "inner", "outer"), "pad")
        if len(names["ends"]) != 4:
            raise RuntimeError(f"pad: {len(names['ends'])} end faces, expected 4 (2 per layer)")
        groups = {"lining": (3, lining), "backplate": (3, backplate),
                  "all": (3, lining + backplate)}
        groups.update({k: (2, v) for k, v in names.items()})
        return groups

    def distance(self, x, y, z):
        """Distance to the friction face, for a point of the pad (above it)."""
        return max(z - self.z0, 0.0)

    def footprint_distance(self, x, y, z):
        """Distance to the friction face from a point below it (in the disc): the in-plane
        distance to the sector, exact inside its angular range and to the nearer end segment
        outside it, combined with the depth below z0."""
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
        return math.hypot(plane, max(self.z0 - z, 0.0))

    def samples(self, spacing):
        half = 0.5 * self.angle
        return polar_samples(self.center[:2], self.inner, self.outer, self.mid - half,
                             self.mid + half, [self.z0, self.z0 + self.lining,
                                               self.z0 + self.lining + self.backplate],
                             spacing, periodic=False)


def classify(gmsh, center, levels, radii, other):
    """Surface tags by name: faces of constant z at a level of `levels` (name -> z), cylinders
    about the axis through center of a radius of `radii`, the rest under `other`."""
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
