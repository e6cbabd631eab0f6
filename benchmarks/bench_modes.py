"""Time and peak memory of shift-invert modes for each sparse factorization backend.

A hex20 block clamped at one end, about --dofs dofs, --modes modes. Each backend runs in its own
child process so that peak memory (ru_maxrss) is its own.

    python benchmarks/bench_modes.py --dofs 100000 --modes 50 [--backends pardiso,superlu] [--json]
"""
import argparse
import json
import resource
import subprocess
import sys
import time


def hex20_nodes(nx, ny, nz):
    """Corner plus mid-edge nodes of an nx x ny x nz hex20 block."""
    return ((nx + 1) * (ny + 1) * (nz + 1) + nx * (ny + 1) * (nz + 1)
            + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz)


def block_divisions(dofs):
    """Divisions (4n, n, n) of a hex20 block with at least that many dofs."""
    n = 1
    while 3 * hex20_nodes(4 * n, n, n) < dofs:
        n += 1
    return 4 * n, n, n


def child(dofs, modes, backend):
    import numpy as np
    from transient.model.assembly import CellBlock, assemble
    from transient.mesh.generators import box
    from transient.solve.modes import normal_modes
    divisions = block_divisions(dofs)
    mesh = box((4.0, 1.0, 1.0), divisions, element="hexahedron20")
    conn = mesh.cells["hexahedron20"]
    ne = len(conn)
    ops = assemble(mesh.points, [CellBlock("hexahedron20", conn, np.full(ne, 2.1e11),
                                           np.full(ne, 0.3), np.full(ne, 7800.0))])
    fixed = np.zeros(ops.K.shape[0], bool)
    fixed[3 * mesh.node_sets["xmin"][:, None] + np.arange(3)] = True
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    result = normal_modes(ops.K, ops.M, fixed, count=modes, backend=backend)
    total = time.perf_counter() - t0
    return {"backend": result.backend, "dofs": int(ops.K.shape[0]), "free": int((~fixed).sum()),
            "nnz": int(ops.K.nnz), "divisions": list(divisions), "modes": modes,
            "factorization_s": result.timings["factorization"],
            "eigensolver_s": result.timings["eigensolver"], "total_s": total,
            "rss_before_gb": rss0 / 2 ** 20,
            "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20,
            "f1_hz": float(result.frequencies[0]), "flast_hz": float(result.frequencies[-1])}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dofs", type=int, default=100_000)
    parser.add_argument("--modes", type=int, default=50)
    parser.add_argument("--backends", default="auto")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.dofs, args.modes, args.child)))
        return
    from transient.solve.linsolve import available
    backends = available() if args.backends == "auto" else args.backends.split(",")
    rows = []
    for backend in backends:
        proc = subprocess.run([sys.executable, __file__, "--dofs", str(args.dofs), "--modes",
                               str(args.modes), "--child", backend], capture_output=True,
                              text=True)
        if proc.returncode != 0:
            rows.append({"backend": backend, "error": proc.stderr.strip().splitlines()[-1]})
        else:
            rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        if not args.json:
            print(rows[-1], flush=True)
    if args.json:
        print(json.dumps({"rows": rows}))


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
