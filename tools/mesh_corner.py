"""A brake corner at a chosen size: the disc, an inner and an outer pad, their two pistons, an
opposed-piston caliper and the bracket, each part a tet10 mesh of its own built by gmsh
(OpenCASCADE), so every interface is non-conforming (issue 45's test model).

    python tools/mesh_corner.py OUTDIR [--dofs N] [--size H] [--interface H] [--growth G]
                                [--tolerance F] [--slot W[,D]] [--chamfer L,D]
                                [--high-order-optimize K] [--case-out PATH|none]

writes OUTDIR/NAME.msh for the parts disc, pad_in, pad_out, piston_in, piston_out, caliper and
bracket (Gmsh 4.1 binary), and OUTDIR/corner.toml: cases/brake_corner.toml with its meshes
replaced by these (--case-out: elsewhere, or 'none'). The parts, their sets and the load paths
are tools/corner_geometry.py's (Corner); the disc and the pads are cases/pad_disc.toml's.

Sizes are tools/mesh_brake.py's: --dofs N (the total, default 4e4) sets one element size h
through its node model, the meshes made again while off by more than --tolerance; --size
gives h; --interface H meshes the friction faces (the pads' linings, the disc's faces under
them) at H < h, growing away from them by --growth per unit distance. --slot and --chamfer cut
both pads' linings as mesh_brake's do. The meshes are deterministic (one thread, a fixed seed).
"""
import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import corner_geometry  # noqa: E402  (a sibling of tools/)
import mesh_brake  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "brake_corner.toml"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--dofs", type=float, default=4e4,
                        help="target dofs, every part (default 4e4)")
    parser.add_argument("--size", type=float, help="element size h [m] (overrides --dofs)")
    parser.add_argument("--interface", type=float,
                        help="element size on the friction faces [m] (default: h)")
    parser.add_argument("--growth", type=float, default=mesh_brake.GROWTH,
                        help="size growth per unit distance from the friction faces "
                        f"({mesh_brake.GROWTH})")
    parser.add_argument("--tolerance", type=float, default=0.1,
                        help="mesh again when the dofs are off the target by more (0.1)")
    parser.add_argument("--case-out", default=None, help="the case written (default "
                        "OUTDIR/corner.toml; 'none': the meshes only, as for "
                        "cases/brake_corner.toml's own)")
    parser.add_argument("--high-order-optimize", type=int, default=0, choices=(0, 1, 2, 3, 4),
                        help="gmsh Mesh.HighOrderOptimize (0: none, the default; the others "
                        "move nodes differently from run to run)")
    parser.add_argument("--slot", metavar="WIDTH[,DEPTH]", help="a radial slot at mid-arc "
                        "through both linings [m], as tools/mesh_brake.py's")
    parser.add_argument("--chamfer", metavar="LENGTH,DEPTH", help="a chamfer at both ends of "
                        "both linings [m], as tools/mesh_brake.py's")
    mesh_brake.run_tool(build, parser.parse_args(argv))


def build(args):
    """The meshes (and the case) main's arguments ask for."""
    from transient.errors import CaseError
    shape = mesh_brake.shape_of(args)
    parts = corner_geometry.corner_parts(corner_geometry.Corner(), shape)
    wrong = parts["pad_in"].shape_error()
    if wrong:
        raise CaseError("command line", wrong[0], f"expected {wrong[1]}")
    for option in ("dofs", "size", "interface", "growth", "tolerance"):
        value = getattr(args, option)
        if value is not None and not 0 < value < float("inf"):
            raise CaseError("command line", f"--{option}", f"expected a positive number, "
                            f"got {value:g}")
    args.outdir.mkdir(parents=True, exist_ok=True)
    files, total, h, refined = mesh_brake.mesh_parts(parts, args)
    if args.case_out != "none":
        target = Path(args.case_out) if args.case_out else args.outdir / "corner.toml"
        mesh_brake.write_case(CASE, [], target, files, f"{total} dofs, h = {h:.4g} m"
                              f"{refined}{mesh_brake.shape_summary(shape)}",
                              tool="tools/mesh_corner.py")
        print(f"wrote {target}")


if __name__ == "__main__":
    main()
