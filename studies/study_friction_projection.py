"""How the (1-eps)-compatible projection should apply to the tangential field: the complex modes
of pad_disc with friction for three observations of the friction, against the fine rule's.

- fine: the fine rule, unregularized, gap and tangential displacement (the reference);
- projected: the regularized gap and the tangential displacement through the same projection
  (what the package does: the friction traction is mu times the normal one, one traction field,
  observed by one operator);
- raw: the regularized gap, the tangential displacement observed unprojected.

For each, the frequencies and real parts of the unstable modes below fmax against the fine
rule's (the nearest eigenvalue), and how many are unstable.

    python studies/study_friction_projection.py [CASE] [--mu 0.4] [--set key=value ...] [--json]
"""
import argparse
import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parent.parent


def _raw_rows(pair, sliding, ndof):
    """The tangential rows of the pair's fine rule, unprojected (the study's variant)."""
    s1, s2 = pair.interface.side1, pair.interface.side2
    fine = pair.interface.fine
    out = []
    for d1, d2 in ((sliding.along1, sliding.along2), (sliding.across1, sliding.across2)):
        out.append(sp.csr_matrix(fine.C1 @ s1.direction_map(d1, ndof)
                                 - fine.C2 @ s2.direction_map(d2, ndof)))
    return tuple(out)


def analyse(case_path, overrides, variant):
    from transient.case.loading import load
    from transient.stability.stage import analyse as run
    import transient.contact.contactset as cs
    import transient.contact.pair as pair_module
    case = load(case_path, overrides)
    saved = cs.tangential_rows, pair_module.row_factors
    try:
        if variant == "raw":
            # the rows held explicitly (not as factors, whose L is the projected gap's)
            pair_module.row_factors = lambda *a, **k: None
            cs.tangential_rows = _raw_rows
        return run(case).modes
    finally:
        cs.tangential_rows, pair_module.row_factors = saved


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc.toml"))
    parser.add_argument("--mu", type=float, default=0.4)
    parser.add_argument("--pair", default="pad_disc")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    base = args.set + [f"contact.{args.pair}.friction.mu={args.mu}"]
    fine = analyse(args.case, base + [f"contact.{args.pair}.rule=\"fine\"",
                                      f"contact.{args.pair}.regularized=false"], "fine")
    ref = fine.below(0.98 * fine.frequency_hz.max())
    big = np.abs(ref.real[ref.unstable]).max() if ref.unstable.any() else 1.0
    rows = []
    for variant in ("projected", "raw"):
        modes = analyse(args.case, base, variant)
        near = np.array([np.argmin(np.abs(modes.eigenvalues - lam))
                         for lam in ref.eigenvalues[ref.unstable]])
        rows.append({"variant": variant, "unstable": int(modes.unstable.sum()),
                     "reference_unstable": int(ref.unstable.sum()),
                     "frequency_error": float(np.max(np.abs(
                         modes.frequency_hz[near] / ref.frequency_hz[ref.unstable] - 1))),
                     "real_error": float(np.max(np.abs(modes.real[near]
                                                       - ref.real[ref.unstable])) / big),
                     "unstable_hz": modes.frequency_hz[modes.unstable].round(1).tolist()})
    out = {"reference_unstable_hz": ref.frequency_hz[ref.unstable].round(1).tolist(),
           "reference_real": ref.real[ref.unstable].round(2).tolist(), "rows": rows}
    if args.json:
        print(json.dumps(out))
        return
    print(f"fine rule: unstable at {out['reference_unstable_hz']} Hz, real parts "
          f"{out['reference_real']} 1/s")
    for r in rows:
        print(f"{r['variant']:>9}: {r['unstable']} unstable; on the fine rule's unstable modes "
              f"frequency within {r['frequency_error']:.2e}, real parts within "
              f"{100 * r['real_error']:.1f}% of the largest; unstable at {r['unstable_hz']}")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
