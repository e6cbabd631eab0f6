"""How far the reduced basis' modes must reach for the reduced CEA to hold across its band: the
complex modes of the full model (shift-invert Arnoldi) against the reduced model's with its
normal modes to several cutoffs (solver.reduction.cutoff = factor x fmax), mode by mode
(transient.stability.compare: each real part against its own size, 5 1/s floor).

    python studies/study_cea_band.py CASE --mu 0.3,0.5 [--factors 1,1.5,2] [--set KEY=VALUE ...]
                                  [--reduced-set KEY=VALUE ...] [--out DIR] [--spans]
                                  [--markdown FILE]

--reduced-set applies to the reduced analyses only (solver.reduction.method="components"),
so that they are compared with the same cached full model.

The full model's modes are cached in DIR (default /tmp/study_cea_band) by case, overrides and
mu. --spans also gives, for each unstable mode of the full model, the part of its right and
left shapes outside each reduced basis (M-norm, relative): which directions the basis lacks.
The full model is analysed past cea's own size bound (FULL_DOFS): one complex factorization per
shift, PARDISO's when installed.
"""
import argparse
import hashlib
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from tables import publish, table  # noqa: E402  (benchmarks/tables.py)
from transient.case.loading import load
from transient.stability.compare import pair_modes
from transient.stability.linearize import linearized
from transient.stability.modes import ComplexModes
from transient.stability.reference import full_complex_modes
from transient.stability.stage import analyse, analysed_case
from transient.stages import prepare


def full_reference(case_path, overrides, fmax, out):
    """(ComplexModes, setup) of the full model, the modes cached in out."""
    overrides = list(overrides) + ["solver.reduction.enabled=false",
                                   f"solver.modes.fmax={fmax}"]
    key = hashlib.sha1(repr((str(Path(case_path).resolve()), overrides)).encode())
    cache = Path(out) / f"full_{key.hexdigest()[:16]}.npz"
    case = load(case_path, overrides)
    setup = None
    if cache.exists():
        data = np.load(cache)
        return ComplexModes(data["eigenvalues"], data["vectors"]), case, setup, 0.0
    t0 = time.perf_counter()
    setup = prepare(analysed_case(case), analysis=True)
    modes = full_complex_modes(*linearized(setup.system, setup.state), fmax)
    seconds = time.perf_counter() - t0
    np.savez(cache, eigenvalues=modes.eigenvalues, vectors=modes.vectors)
    return modes, case, setup, seconds


def left_vectors(setup, modes, which):
    """The left eigenvectors y (y^H (K + lam D + lam^2 M) = 0) of the full model's modes
    `which`, by inverse iteration on the transposed pencil at each eigenvalue."""
    from scipy.sparse import csr_matrix
    from transient.solve.linsolve import factorize_complex
    M, D, K = linearized(setup.system, setup.state)
    out = {}
    for j in which:
        lam = modes.eigenvalues[j]
        solve = factorize_complex(csr_matrix((K + lam * D + lam ** 2 * M).T, dtype=complex))
        y = np.random.default_rng(1).standard_normal(K.shape[0]) + 0j
        for _ in range(3):
            y = solve(y)
            y /= np.linalg.norm(y)
        out[j] = y
    return out, M


def outside(T, M, x):
    """||x - P x||_M / ||x||_M, P the M-orthogonal projector on the columns of T."""
    G = T.T @ (M @ T)
    L = np.linalg.cholesky(0.5 * (G + G.T))
    Q = sla.solve_triangular(L, T.T, lower=True).T
    r = x - Q @ (Q.T @ (M @ x))
    return float(np.sqrt(abs(np.vdot(r, M @ r)) / abs(np.vdot(x, M @ x))))


def study(case_path, overrides, mus, factors, out, spans, reduced_overrides=()):
    rows = []
    base = load(case_path, overrides)
    fmax = base.solver.reduction.fmax
    for mu in mus:
        more = list(overrides) + [f"{key}.friction.mu={mu}" for key in
                                  (f"contact.{n}" for n in base.contact)]
        ref, _, setup, seconds = full_reference(case_path, more, fmax, out)
        unstable = np.flatnonzero(ref.unstable & (ref.frequency_hz <= fmax))
        print(f"mu = {mu}: full model, {len(unstable)} unstable modes below {fmax:g} Hz"
              + (f" ({seconds:.0f} s)" if seconds else " (cached)"), flush=True)
        if spans and setup is None:
            setup = prepare(analysed_case(load(case_path, more + [
                "solver.reduction.enabled=false"])), analysis=True)
        lefts, M = left_vectors(setup, ref, unstable) if spans else (None, None)
        for factor in factors:
            t0 = time.perf_counter()
            red = analyse(load(case_path, more + list(reduced_overrides)
                               + [f"solver.reduction.cutoff={factor * fmax}"]))
            seconds = time.perf_counter() - t0
            pairs = pair_modes(ref, red.modes, fmax)
            failing = [p for p in pairs if not p.within()]
            worst = max((abs(p.real_error) / max(0.05 * abs(p.real), 5.0) for p in pairs),
                        default=0.0)
            row = {"mu": mu, "factor": factor, "cutoff_hz": factor * fmax,
                   "method": red.meta.get("reduction_method", "assembled"),
                   "reduced": red.reduced, "seconds": seconds,
                   "unstable_full": len(unstable),
                   "unstable_reduced": int(np.sum(red.modes.unstable)),
                   "worst_frequency": max((abs(p.frequency_error) for p in pairs), default=0.0),
                   "worst_real_over_allowed": worst, "failing": len(failing),
                   "pairs": [p.__dict__ for p in pairs]}
            if spans:
                X, A = red.basis
                T = (X @ A)[setup.system.free]
                row["spans"] = [{"frequency_hz": float(ref.frequency_hz[j]),
                                 "right": outside(T, M, ref.vectors[:, j]),
                                 "left": outside(T, M, lefts[j])} for j in unstable]
            rows.append(row)
            print(f"  cutoff {factor:g} fmax: {red.reduced} dofs, {seconds:.1f} s, worst real "
                  f"error {worst:.2f} of allowed, frequency {row['worst_frequency']:.1e}, "
                  f"{len(failing)} failing", flush=True)
            for p in pairs:
                mark = "" if p.within() else "   <- out"
                print(f"    {p.frequency_hz:9.1f} Hz {p.real:9.2f} -> {p.other_real:9.2f} 1/s "
                      f"({p.real_error:+.2f}, frequency {p.frequency_error:+.1e}){mark}")
            for s in row.get("spans", []):
                print(f"    outside the basis at {s['frequency_hz']:9.1f} Hz: right "
                      f"{s['right']:.1e}, left {s['left']:.1e}")
    return rows


def markdown(case_path, rows):
    header = ["case", "mu", "cutoff", "reduced dofs", "cea [s]", "unstable (full)",
              "worst frequency error", "worst real error / allowed", "failing"]
    return table(header, [[Path(case_path).name, r["mu"], f"{r['factor']:g} fmax",
                           r["reduced"], f"{r['seconds']:.1f}", r["unstable_full"],
                           f"{r['worst_frequency']:.1e}", f"{r['worst_real_over_allowed']:.2f}",
                           r["failing"]] for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("case")
    parser.add_argument("--mu", default="0.3,0.5")
    parser.add_argument("--factors", default="1,1.5,2")
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--reduced-set", dest="reduced", action="append", default=[])
    parser.add_argument("--out", default="/tmp/study_cea_band")
    parser.add_argument("--spans", action="store_true")
    parser.add_argument("--markdown", help="append the table to this file")
    parser.add_argument("--json", help="write every row to this file")
    args = parser.parse_args(argv)
    Path(args.out).mkdir(parents=True, exist_ok=True)
    rows = study(args.case, args.overrides, [float(m) for m in args.mu.split(",")],
                 [float(f) for f in args.factors.split(",")], args.out, args.spans,
                 args.reduced)
    publish(markdown(args.case, rows), args.markdown, args.json, rows)
    return 0


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    sys.exit(main())
