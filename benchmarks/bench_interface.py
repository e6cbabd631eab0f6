"""Time of the fine rule on Gamma (clipping, then points) and of the compatibility eigensolve.

(a) Two boxes, one on the other, whose facing surfaces have incommensurate grids and an offset of
a fraction of a cell, so that every face straddles several: the upper box's 'zmin' (surface 1)
against the lower box's 'zmax' (surface 2), for about each count of overlapping face pairs in
--pairs. Clipping should grow linearly: its time per pair should stay about constant.
(b) A case's contact interface, by default pad.friction against disc.zmax of pad_disc: the fine
rule plus the eigendecomposition of its gap energy (target: under 10 s for thousands of points
and over 1000 interface dofs N1 + N2).

A tiny interface of each element type is built first, so that numba compilation is not timed.
On a machine loaded by other processes, multithreaded OpenBLAS can stall in the eigensolver (seen:
0.12 s becoming 8 s for N1 + N2 = 1194); OPENBLAS_NUM_THREADS=1 gives steady figures.

    python benchmarks/bench_interface.py [--pairs 1e3,1e4,1e5] [--case cases/pad_disc.toml]
        [--set parts.pad.mesh.divisions=[9,22,2,1] ...] [--json]
"""
import argparse
import json
import time

import numpy as np

from transient.case.loading import load
from transient.contact.compatibility import compatibility
from transient.mesh.elements import ALIASES
from transient.mesh.generators import box
from transient.contact.interface import build_interface
from transient.model.model import build_model, resolve_set
from transient.mesh.selections import set_faces

GOLDEN = 0.5 * (1 + 5 ** 0.5)   # ratio of the two grids: far from any ratio of small integers
TARGET_S = 10.0                 # fine rule plus eigendecomposition [s]
TARGET_DOFS = 1000              # interface dofs N1 + N2 the target applies to


def stacked_boxes(n_lower, n_upper, element):
    """Lower box [0, 1]^2 x [0, 0.1] [m] (n_lower^2 cells in plan) and an upper box on it (n_upper^2
    cells), shifted in plan by a fraction of an upper cell so that no grid lines coincide."""
    lower = box((1.0, 1.0, 0.1), (n_lower, n_lower, 1), element=element)
    shift = np.array([0.31, 0.17]) / n_upper
    upper = box((1.0, 1.0, 0.1), (n_upper, n_upper, 1), origin=(*shift, 0.1), element=element)
    return lower, upper


def box_interface(n_lower, n_upper, element, degree):
    """Fine rule between the stacked boxes; returns it and the wall time of the build [s]."""
    lower, upper = stacked_boxes(n_lower, n_upper, element)
    t0 = time.perf_counter()
    interface = build_interface("boxes", upper.points, upper.face_sets["zmin"], lower.n_nodes,
                                lower.points, lower.face_sets["zmax"], 0, degree)
    return interface, time.perf_counter() - t0


def grids_for(pairs):
    """Divisions (n_lower, n_upper) of about that many overlapping face pairs.

    Grids of n and m cells per side with no common interior line overlap in (n + m - 1)^2 pairs.
    """
    n_lower = max(2, round((pairs ** 0.5 + 1) / (1 + GOLDEN)))
    return n_lower, round(GOLDEN * n_lower)


def warm_up(elements, degree):
    """Compile the numba kernels of the interface for these element types."""
    for element in elements:
        box_interface(2, 3, element, degree)


def bench_boxes(targets, element, degree):
    """One row per target pair count: sizes, seconds and microseconds per pair."""
    rows = []
    for target in targets:
        n_lower, n_upper = grids_for(target)
        interface, total = box_interface(n_lower, n_upper, element, degree)
        pairs = len(interface.pairs)
        clipping = interface.timings["clipping"]
        rows.append({"target": target, "divisions": [n_lower, n_upper], "pairs": pairs,
                     "points": interface.fine.n_points, "clipping_s": clipping,
                     "build_s": total, "clipping_us_per_pair": 1e6 * clipping / pairs,
                     "build_us_per_pair": 1e6 * total / pairs})
    return rows


def growth_exponents(rows, key):
    """Exponents a of time ~ pairs^a between consecutive rows (1: linear)."""
    return [float(np.log(b[key] / a[key]) / np.log(b["pairs"] / a["pairs"]))
            for a, b in zip(rows, rows[1:])]


def surface(case, model, ref, key):
    part, name = resolve_set(case, model.parts, ref, key)
    return part, set_faces(part.mesh, name)


def bench_case(path, overrides, surface1, surface2, k, degree):
    """Sizes and seconds of a case's interface: model, fine rule and compatibility."""
    case = load(path, overrides)
    t0 = time.perf_counter()
    model = build_model(case)
    t_model = time.perf_counter() - t0
    p1, faces1 = surface(case, model, surface1, "--surface1")
    p2, faces2 = surface(case, model, surface2, "--surface2")
    warm_up(sorted({ctype for p in (p1, p2) for ctype in p.mesh.cells}), degree)
    t0 = time.perf_counter()
    interface = build_interface("bench", p1.mesh.points, faces1, p1.offset, p2.mesh.points,
                                faces2, p2.offset, degree)
    t_fine = time.perf_counter() - t0
    t0 = time.perf_counter()
    comp = compatibility(interface.fine, k)
    t_comp = time.perf_counter() - t0
    n1, n2 = interface.side1.n, interface.side2.n
    return {"case": str(path), "overrides": list(overrides), "surfaces": [surface1, surface2],
            "model_dofs": model.ndof, "pairs": len(interface.pairs),
            "points": interface.fine.n_points, "n1": n1, "n2": n2, "interface_dofs": n1 + n2,
            "model_s": t_model, "clipping_s": interface.timings["clipping"],
            "fine_rule_s": interface.timings["fine_rule"], "interface_s": t_fine,
            "gap_energy_s": comp.timings["gap_energy"],
            "eigendecomposition_s": comp.timings["eigendecomposition"],
            "compatibility_s": t_comp, "fine_plus_eig_s": t_fine + t_comp,
            "large_enough": n1 + n2 >= TARGET_DOFS, "under_target": t_fine + t_comp < TARGET_S}


def print_boxes(rows, element, degree):
    print(f"(a) stacked boxes, {element}, triangle rule of degree {degree}")
    print(f"{'divisions':>11} {'pairs':>8} {'points':>9} {'clipping s':>11} {'build s':>9} "
          f"{'clip us/pair':>13} {'build us/pair':>14}")
    for r in rows:
        print(f"{'%d/%d' % tuple(r['divisions']):>11} {r['pairs']:8d} {r['points']:9d} "
              f"{r['clipping_s']:11.4f} {r['build_s']:9.3f} {r['clipping_us_per_pair']:13.2f} "
              f"{r['build_us_per_pair']:14.2f}")
    for key in ("clipping_s", "build_s"):
        exponents = ", ".join(f"{a:.2f}" for a in growth_exponents(rows, key))
        print(f"growth exponent of {key[:-2]} time vs pairs (1 = linear): {exponents}")


def print_case(r):
    print(f"(b) {' '.join([r['case']] + r['overrides'])}: {r['surfaces'][0]} vs "
          f"{r['surfaces'][1]}, model {r['model_dofs']} dofs built in {r['model_s']:.2f} s")
    print(f"pairs {r['pairs']}, points {r['points']}, interface dofs N1 + N2 = {r['n1']} + "
          f"{r['n2']} = {r['interface_dofs']}")
    for key in ("clipping_s", "fine_rule_s", "interface_s", "gap_energy_s",
                "eigendecomposition_s", "compatibility_s", "fine_plus_eig_s"):
        print(f"  {key[:-2]:<20} {r[key]:8.3f} s")
    if not r["large_enough"]:
        print(f"  interface smaller than the target's {TARGET_DOFS} dofs: refine the case")
    print(f"  fine rule + eigendecomposition {'under' if r['under_target'] else 'OVER'} "
          f"{TARGET_S:g} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", default="1e3,1e4,1e5",
                        help="target pair counts of (a), comma-separated; empty to skip")
    parser.add_argument("--element", default="hex8", choices=sorted(ALIASES),
                        help="element of the boxes of (a)")
    parser.add_argument("--degree", type=int, default=4, help="degree of the triangle rule")
    parser.add_argument("--case", default="cases/pad_disc.toml", help="case of (b); empty to skip")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY.PATH=VALUE", help="override a case value (repeatable)")
    parser.add_argument("--surface1", default="pad.friction")
    parser.add_argument("--surface2", default="disc.zmax")
    parser.add_argument("--k", type=float, default=5e11, help="gap stiffness density [Pa/m]")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = {}
    if args.pairs:
        element = ALIASES[args.element]
        warm_up([element], args.degree)
        targets = [int(float(p)) for p in args.pairs.split(",")]
        result["boxes"] = bench_boxes(targets, element, args.degree)
        if not args.json:
            print_boxes(result["boxes"], element, args.degree)
    if args.case:
        result["case"] = bench_case(args.case, args.overrides, args.surface1, args.surface2,
                                    args.k, args.degree)
        if not args.json:
            print_case(result["case"])
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
