"""Two pads on a disc, the outboard one the inboard one's mesh mirrored through the disc's
mid-plane (parts.NAME.transform.mirror): its contact pair and guides find their faces, and the
tied modes are those of the same geometry built without a transform, by the box generator
(hex20) or by gmsh's own mirror of the mesh (tet10)."""
import numpy as np
import pytest

import transient
from transient.case.loading import parse

CASE = """
[materials.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
[materials.lining]
E = 2.0e9
nu = 0.25
rho = 2500.0

[parts.disc]
material = "steel"
[parts.disc.mesh]
kind = "box"
size = [0.06, 0.05, 0.01]
origin = [-0.01, -0.01, 0.0]
divisions = [6, 5, 2]

[parts.pad_in]
material = "lining"
[parts.pad_in.mesh]
{pad_in}

[parts.pad_out]
material = "lining"
[parts.pad_out.mesh]
{pad_out}

[constraints.hub]
set = "disc.xmin"
# the pads slide freely on penalty springs normal to the disc: guides hold them in plane
[constraints.guide_in]
set = "pad_in.{back_in}"
dofs = ["x", "y"]
[constraints.guide_out]
set = "pad_out.{back_out}"
dofs = ["x", "y"]

[contact.inboard]
surface1 = "pad_in.{friction_in}"
surface2 = "disc.zmax"
[contact.outboard]
surface1 = "pad_out.{friction_out}"
surface2 = "disc.zmin"

[solver.modes]
count = 8
"""
BOX = ('kind = "box"\nsize = [0.04, 0.03, 0.008]\norigin = [0.0, 0.0, {z}]\n'
       'divisions = [4, 3, 2]\nelement = "hex20"')
FILE = 'kind = "file"\npath = "{path}"'
# the disc's mid-plane
MIRROR = """
[parts.pad_out.transform.mirror]
point = [0.0, 0.0, 0.005]
normal = [0.0, 0.0, 1.0]
"""


def _gmsh_pads(directory):
    """A tet10 pad above the disc (pad.msh) and gmsh's mirror of that mesh through the disc's
    mid-plane, its elements reversed by gmsh (pad_ref.msh)."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("pad")
        volume = gmsh.model.occ.addBox(0.0, 0.0, 0.01, 0.04, 0.03, 0.008)
        gmsh.model.occ.synchronize()
        faces = gmsh.model.getBoundary([(3, volume)], oriented=False)

        def at_z(z):
            return [t for _, t in faces
                    if abs(gmsh.model.occ.getCenterOfMass(2, t)[2] - z) < 1e-9]
        gmsh.model.addPhysicalGroup(2, at_z(0.01), name="friction")
        gmsh.model.addPhysicalGroup(2, at_z(0.018), name="back")
        gmsh.model.addPhysicalGroup(3, [volume], name="pad")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.01)
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(directory / "pad.msh"))
        gmsh.model.mesh.affineTransform([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0.01])
        gmsh.model.mesh.reverse()
        gmsh.write(str(directory / "pad_ref.msh"))
    finally:
        gmsh.finalize()


def _frequencies(directory, name, text):
    case = parse(text, directory / f"{name}.toml")
    found = transient.modes(case)
    assert [pair["area"] for pair in found.contact] == pytest.approx([0.0012, 0.0012])
    return found.frequencies


@pytest.mark.parametrize("mesh", ["hex20 boxes", "tet10 gmsh"])
def test_a_mirrored_outboard_pad_has_the_modes_of_one_built_in_place(tmp_path, mesh):
    if mesh == "hex20 boxes":
        pad = BOX.format(z=0.01)
        mirrored = CASE.format(pad_in=pad, pad_out=pad, back_in="zmax", back_out="zmax",
                               friction_in="zmin", friction_out="zmin") + MIRROR
        # built below the disc: its friction face is the box's top
        built = CASE.format(pad_in=pad, pad_out=BOX.format(z=-0.008), back_in="zmax",
                            back_out="zmin", friction_in="zmin", friction_out="zmax")
    else:
        _gmsh_pads(tmp_path)
        pad = FILE.format(path="pad.msh")
        sets = dict(back_in="back", back_out="back", friction_in="friction",
                    friction_out="friction")
        mirrored = CASE.format(pad_in=pad, pad_out=pad, **sets) + MIRROR
        built = CASE.format(pad_in=pad, pad_out=FILE.format(path="pad_ref.msh"), **sets)
    reference = _frequencies(tmp_path, "built", built)
    assert reference[0] > 1000.0          # clamped and guided: no rigid mode
    np.testing.assert_allclose(_frequencies(tmp_path, "mirrored", mirrored), reference,
                               rtol=1e-6)
