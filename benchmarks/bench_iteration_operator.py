"""What Newmark's iteration operator costs on a full model, by factorization: the alternatives
behind the run's 'factorizations:' line.

The full-model kernel solves S x = r with S = (1 + dt/2 alpha) M + (dt/2 beta + dt^2/4) K_lin
inside Numba, once per Newton iteration, so it needs explicit triangular factors: CHOLMOD's
L L^T (scikit-sparse, not on the registry: no wheel nor sdist reaches this machine) or SuperLU's
L U, which is what runs here. PARDISO factorizes faster and leaner but keeps its factors: a
kernel could only use it by returning to Python for every solve (per step, not per chunk).
This script measures, on a case's full model at its solver.dt: SuperLU's explicit factors
(time, nonzeros) and one solve through them in Numba, PARDISO's factorization and one
single right-hand-side solve from Python.

    python benchmarks/bench_iteration_operator.py CASE [--set key=value ...] [--repeat 20]
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from transient.case.loading import load                     # noqa: E402
from transient.kernels.sparse import factor_solve           # noqa: E402
from transient.solve.linsolve import factorize, triangular_factors   # noqa: E402
from transient.stages import prepare                        # noqa: E402


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args(argv)
    case = load(args.case, args.overrides + ["solver.reduction.enabled=false",
                                             'solver.scheme="implicit"'])
    if not case.solver.dt:
        sys.exit("give solver.dt (the implicit step)")
    system = prepare(case).system
    dt, n = case.solver.dt, system.K.shape[0]
    h = 0.5 * dt
    S = ((1.0 + h * system.alpha) * system.M + (h * system.beta + h * h) * system.K).tocsr()
    print(f"{Path(args.case).name}: {n} free dofs, S {S.nnz} nonzeros, dt {dt:.3g} s")
    t0 = time.perf_counter()
    p_in, L, U, p_out, name = triangular_factors(S)
    t_lu = time.perf_counter() - t0
    b = np.random.default_rng(0).standard_normal(n)
    x, work = np.empty(n), np.empty(n)
    factor_solve(p_in, L, U, p_out, b, x, work)           # compiles
    t_solve = best(lambda: factor_solve(p_in, L, U, p_out, b, x, work), args.repeat)
    print(f"  {name} explicit factors: {t_lu:.2f} s, {len(L[2]) + len(U[2])} nonzeros; "
          f"one solve in Numba {1e3 * t_solve:.3f} ms (residual "
          f"{np.linalg.norm(S @ x - b) / np.linalg.norm(b):.1e})")
    t0 = time.perf_counter()
    solve = factorize(S, "pardiso")
    t_par = time.perf_counter() - t0
    solve(b)
    t_psolve = best(lambda: solve(b), args.repeat)
    print(f"  pardiso: factorization {t_par:.2f} s; one solve from Python "
          f"{1e3 * t_psolve:.3f} ms (factors kept inside MKL)")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
