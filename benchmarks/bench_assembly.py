"""Benchmark: our K and M assembly against scikit-fem on a distorted hex20 box, single-threaded.

Each assembler runs in its own child process (``--only ours|skfem|vector``) so that peak memory
(ru_maxrss) belongs to one assembler only; the parent collects the children's JSON lines.

* ours: ``transient.assembly.assemble`` after a warm-up on a one-cell mesh (the warm-up time is
  the Numba compile time, from an empty cache unless --warm-cache);
* skfem: scikit-fem used well for this problem: the six scalar derivative-product matrices
  A_ij = int dphi_a/dx_i dphi_b/dx_j (i <= j) and the scalar mass matrix on the scalar
  ElementHexS2 basis, combined with scipy into 3 x 3 blocks (dof = 3 node + component):
  block (i, j) = lam A_ij + mu A_ji + mu delta_ij (A_00 + A_11 + A_22). The same child then
  assembles ours and checks that both K and M agree, so the timings compare equal work;
* vector: scikit-fem's ElementVector with linear_elasticity and a vector mass form, run only when
  a pilot on about 1/8 of the cells extrapolates to under --vector-limit seconds.

Both use the 3x3x3 Gauss rule (our degree 5, scikit-fem intorder=5) and the same trilinear
geometry (midside nodes at the midpoints of straight edges).

Usage: python benchmarks/bench_assembly.py [--dofs 300000] [--json] [--no-vector] [--repeat 3]
(timings are the fastest of --repeat assemblies; peaks are of one assembly)
"""
import os

# Single-threaded before numpy / numba are imported: the comparison is per core.
for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

# Run from anywhere: the package is the parent directory of tools/.
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

E, NU, RHO = 2.1e11, 0.3, 7850.0
CELL = "hexahedron20"
PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def n_nodes(div):
    """Nodes of a hex20 box with divisions (nx, ny, nz): corners plus one per edge."""
    nx, ny, nz = div
    return ((nx + 1) * (ny + 1) * (nz + 1) + nx * (ny + 1) * (nz + 1)
            + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz)


def divisions_for(dofs):
    """Near-cubic divisions whose hex20 box has the dof count closest to dofs."""
    n = max(1, round((dofs / 12.0) ** (1.0 / 3.0)))
    best = None
    for base in range(max(1, n - 2), n + 3):
        for extra in range(4):
            div = tuple(base + (k < extra) for k in range(3))
            err = abs(3 * n_nodes(div) - dofs)
            if best is None or err < best[0]:
                best = (err, div)
    return best[1]


def distorted_box(div, seed=0):
    """Hex20 box with corners moved by up to 10 % of the cell size, midside nodes re-centred."""
    from transient.mesh import generators
    from transient.mesh.elements import ELEMENTS
    size = np.array(div, float) / max(div)
    mesh = generators.box(size, div, element=CELL)
    conn = mesh.cells[CELL]
    el = ELEMENTS[CELL]
    points = mesh.points.copy()
    corners = np.unique(conn[:, :8])
    h = size / np.array(div)
    points[corners] += np.random.default_rng(seed).uniform(-0.1, 0.1, (len(corners), 3)) * h
    for k, (a, b) in enumerate(el.edges):
        points[conn[:, 8 + k]] = 0.5 * (points[conn[:, a]] + points[conn[:, b]])
    return points, conn


def peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0   # kB on Linux


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


# --- ours -------------------------------------------------------------------------------------

def assemble_ours(points, conn):
    from transient.model.assembly import CellBlock, assemble
    ne = len(conn)
    return assemble(points, [CellBlock(CELL, conn, np.full(ne, E), np.full(ne, NU),
                                       np.full(ne, RHO))])


def warm_up():
    """Compile (or load) the kernels on a one-cell mesh; returns seconds."""
    import numba
    numba.set_num_threads(1)
    t = time.perf_counter()
    assemble_ours(*distorted_box((1, 1, 1)))
    return time.perf_counter() - t


def run_ours(div, repeat):
    compile_s = warm_up()
    points, conn = distorted_box(div)
    base = rss_mb()
    seconds = []
    for _ in range(repeat):
        ops = None      # free the previous result first: the peak is that of one assembly
        t = time.perf_counter()
        ops = assemble_ours(points, conn)
        seconds.append(time.perf_counter() - t)
    return {"dofs": 3 * len(points), "cells": len(conn), "nnz": int(ops.K.nnz),
            "ours_s": min(seconds), "ours_all_s": seconds, "compile_s": compile_s,
            "ours_peak_mb": peak_mb(), "ours_base_mb": base}


# --- scikit-fem -------------------------------------------------------------------------------

def skfem_mesh(points, conn):
    """MeshHex1 of the corners; scikit-fem's local vertex i is our VTK corner LOCAL[i]."""
    from skfem import MeshHex1
    corners, compact = np.unique(conn[:, :8], return_inverse=True)
    compact = compact.reshape(len(conn), 8)
    return MeshHex1(points[corners].T.copy(), compact[:, LOCAL[:8]].T.copy())


# Our local node at the reference point of ElementHexS2's local dof s (xi = 2 X - 1).
LOCAL = np.array([6, 2, 5, 7, 1, 3, 4, 0, 18, 13, 14, 9, 10, 17, 12, 19, 15, 8, 11, 16])


def scalar_forms():
    from skfem import BilinearForm

    def derivative_product(i, j):
        # rows are test (v) dofs: entry (a, b) = int dphi_a/dx_i dphi_b/dx_j
        @BilinearForm
        def form(u, v, w):
            return v.grad[i] * u.grad[j]
        return form

    @BilinearForm
    def mass(u, v, w):
        return u * v

    return [derivative_product(i, j) for i, j in PAIRS], mass


def to_csr(coo):
    """CSR of scikit-fem COO data, explicit zeros kept so every form has the same pattern."""
    import scipy.sparse as sp
    A = sp.csr_matrix((coo.data, (coo.indices[0], coo.indices[1])), shape=coo.shape)
    A.sort_indices()
    return A


def assemble_skfem_scalar(points, conn):
    """Vector K and M (dof = 3 scikit-fem node + component) and timings [s]."""
    import scipy.sparse as sp
    from skfem import Basis, ElementHexS2
    times = {}
    t = time.perf_counter()
    basis = Basis(skfem_mesh(points, conn), ElementHexS2(), intorder=5)
    times["skfem_setup_s"] = time.perf_counter() - t
    t = time.perf_counter()
    # Form.elemental + scipy rather than Form.assemble: the latter drops exact zeros, which would
    # give the seven matrices different patterns; the work is the same.
    forms, mass = scalar_forms()
    A = {pair: to_csr(form.elemental(basis)) for pair, form in zip(PAIRS, forms)}
    Ms = to_csr(mass.elemental(basis))
    times["skfem_forms_s"] = time.perf_counter() - t
    t = time.perf_counter()
    P = A[0, 0]
    for a in A.values():
        assert np.array_equal(a.indptr, P.indptr) and np.array_equal(a.indices, P.indices)
    d = {pair: a.data for pair, a in A.items()}
    for i, j in PAIRS[3:]:
        d[j, i] = A[i, j].T.tocsr().data    # transpose of a symmetric pattern: same pattern
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    trace = d[0, 0] + d[1, 1] + d[2, 2]
    blocks = np.empty((len(P.data), 3, 3))
    for i in range(3):
        for j in range(3):
            blocks[:, i, j] = lam * d[i, j] + mu * d[j, i] + (mu * trace if i == j else 0.0)
    n = P.shape[0]
    K = sp.bsr_matrix((blocks, P.indices, P.indptr), shape=(3 * n, 3 * n)).tocsr()
    del blocks
    M = sp.kron(RHO * Ms, sp.identity(3), format="csr")
    times["skfem_combine_s"] = time.perf_counter() - t
    times["skfem_s"] = sum(times.values())
    return K, M, basis, times


def node_permutation(basis, conn):
    """perm[our node] = scikit-fem scalar dof."""
    perm = np.full(conn.max() + 1, -1)
    perm[conn[:, LOCAL]] = basis.element_dofs.T
    assert np.array_equal(perm[conn[:, LOCAL]], basis.element_dofs.T) and perm.min() >= 0
    return perm


def relative_difference(A, B):
    return float(abs(A - B).max() / abs(B).max())


def run_skfem(div, repeat):
    points, conn = distorted_box(div)
    base = rss_mb()
    runs = []
    for _ in range(repeat):
        K = M = basis = None
        K, M, basis, times = assemble_skfem_scalar(points, conn)
        runs.append(times)
    times = min(runs, key=lambda r: r["skfem_s"])
    out = dict(times, skfem_all_s=[r["skfem_s"] for r in runs], skfem_peak_mb=peak_mb(),
               skfem_base_mb=base, skfem_nnz=int(K.nnz))
    # Equal work: our K and M must be the same matrices (after this child's peak was taken).
    dof = (3 * node_permutation(basis, conn)[:, None] + np.arange(3)).ravel()
    K, M = K[dof][:, dof], M[dof][:, dof]
    warm_up()
    ops = assemble_ours(points, conn)
    out["rel_diff_K"] = relative_difference(ops.K, K)
    out["rel_diff_M"] = relative_difference(ops.M, M)
    return out


def assemble_skfem_vector(points, conn):
    from skfem import Basis, BilinearForm, ElementHexS2, ElementVector
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    @BilinearForm
    def mass(u, v, w):
        return RHO * dot(u, v)

    t = time.perf_counter()
    basis = Basis(skfem_mesh(points, conn), ElementVector(ElementHexS2()), intorder=5)
    linear_elasticity(*lame_parameters(E, NU)).assemble(basis)
    mass.assemble(basis)
    return time.perf_counter() - t


def run_vector(div, limit):
    cells = div[0] * div[1] * div[2]
    pilot = tuple(max(1, d // 2) for d in div)
    pilot_s = assemble_skfem_vector(*distorted_box(pilot))
    estimate = pilot_s * cells / (pilot[0] * pilot[1] * pilot[2])
    out = {"vector_pilot_cells": pilot[0] * pilot[1] * pilot[2], "vector_pilot_s": pilot_s,
           "vector_estimate_s": estimate, "vector_s": None}
    if estimate <= limit:
        out["vector_s"] = assemble_skfem_vector(*distorted_box(div))
    out["vector_peak_mb"] = peak_mb()
    return out


# --- driver -----------------------------------------------------------------------------------

def child(args, only, env=None):
    cmd = [sys.executable, os.path.abspath(__file__), "--only", only, "--dofs", str(args.dofs),
           "--vector-limit", str(args.vector_limit), "--repeat", str(args.repeat)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        sys.exit(f"child --only {only} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def report(r):
    lines = [
        f"mesh      : hex20 box {r['divisions']}, {r['cells']} cells, {r['dofs']} dofs, "
        f"K nnz {r['nnz']} (skfem {r['skfem_nnz']})",
        f"ours      : {r['ours_s']:.2f} s (compile {r['compile_s']:.2f} s), "
        f"peak {r['ours_peak_mb']:.0f} MB (base {r['ours_base_mb']:.0f} MB)",
        f"skfem     : {r['skfem_s']:.2f} s (setup {r['skfem_setup_s']:.2f}, forms "
        f"{r['skfem_forms_s']:.2f}, combine {r['skfem_combine_s']:.2f}), "
        f"peak {r['skfem_peak_mb']:.0f} MB (base {r['skfem_base_mb']:.0f} MB)",
        f"ratio     : skfem / ours = {r['ratio']:.1f}",
        f"agreement : K {r['rel_diff_K']:.1e}, M {r['rel_diff_M']:.1e} (relative max difference)",
    ]
    if "vector_estimate_s" in r:
        if r["vector_s"] is not None:
            lines.append(f"skfem vec : {r['vector_s']:.2f} s, ratio {r['vector_ratio']:.1f}, "
                         f"peak {r['vector_peak_mb']:.0f} MB")
        else:
            lines.append(f"skfem vec : skipped, pilot ({r['vector_pilot_cells']} cells, "
                         f"{r['vector_pilot_s']:.2f} s) extrapolates to "
                         f"{r['vector_estimate_s']:.0f} s")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dofs", type=int, default=300000, help="target number of dofs")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--no-vector", action="store_true",
                   help="skip scikit-fem's vector linear_elasticity form")
    p.add_argument("--vector-limit", type=float, default=60.0,
                   help="run the vector form only if its pilot extrapolates below this [s]")
    p.add_argument("--repeat", type=int, default=3,
                   help="assemblies per assembler; the fastest is reported")
    p.add_argument("--warm-cache", action="store_true",
                   help="use the Numba cache on disk (compile time is then load time)")
    p.add_argument("--only", choices=("ours", "skfem", "vector"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    div = divisions_for(args.dofs)
    if args.only:
        run = {"ours": lambda: run_ours(div, args.repeat),
               "skfem": lambda: run_skfem(div, args.repeat),
               "vector": lambda: run_vector(div, args.vector_limit)}[args.only]
        print(json.dumps(run()))
        return
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        ours_env = env if args.warm_cache else dict(env, NUMBA_CACHE_DIR=cache)
        r = {"divisions": list(div), **child(args, "ours", ours_env)}
    r.update(child(args, "skfem", env))
    r["ratio"] = r["skfem_s"] / r["ours_s"]
    if not args.no_vector:
        r.update(child(args, "vector", env))
        if r["vector_s"] is not None:
            r["vector_ratio"] = r["vector_s"] / r["ours_s"]
    print(json.dumps(r, indent=1) if args.json else report(r))


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
