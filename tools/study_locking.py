"""The paper's locking in dynamics (section 4.2, figure 11) on the pad and disc: how far a rich
contact rule raises the tied modes above the (1-eps) regularized centre rule, by tie and by
stiffness, on the tet10 meshes made each on its own (cases/pad_disc_tet10.toml) and on the
structured hex20 ones (cases/pad_disc.toml).

    python tools/study_locking.py [--modes 50] [--hex20] [--json PATH]

For each tie (solver.modes.tie: penalty springs at k = 5e11, the exponential law's tangent at
1 MPa, to 1e17; the law's tangents at the preload; exact, the gap held at zero on the rule's
rows) the first modes of the reference rule (centre, regularized at eps = 1e-3: the paper's
"(1-eps) 6 to 1") and of the rich rules (fine; gauss, 6 points a face: the paper's; fine
regularized at 1e-3), and each rich rule's frequency shifts against the reference: each mode
against its MAC partner (mass MAC, one to one), and by mode order as the paper plots them.
The interface's compatibility first: its shapes, those compatible to round-off, the share
above eps = 1e-4 (the paper: over 70%) and kept at 1e-3 (the paper: 42%).

Found on 2026-12-04 (2 cores, load 0-1.1; 249 s with --hex20), first 50 modes. tet10 (38.7k
dofs, 1658 interface normal dofs, 7 shapes compatible to round-off, 1 - C(1e-4) = 79%, C(1e-3)
= 35%), shifts over the (1-eps) centre rule, by MAC (by order):
- exact: fine at most 16.4% (10.9%), mean 3.0%, 32 modes above 1%, 11 above 5%, 1653 of 1658
  directions held; gauss (6 points a face) 7.8% (6.9%), mean 1.7%; fine regularized at 1e-3
  16.3% (9.2%), mean 2.5%, though it holds only 551 directions; centre unregularized (371)
  0.3% softer on average, never stiffer: the coarse rule, not the regularization, keeps the
  exact tie from locking;
- penalty at k = 5e11, 1e13, 1e15, 1e17 and the preload's tangents: every rule within 0.46%
  (centre unregularized within -2.0%): under a finite k the shapes whose gap energy is below
  the structure's stiffness stay free, whatever the rule, so nothing locks;
- hex20 pad_disc (1 - C(1e-4) = 65%, C(1e-3) = 57%): exact fine 2.1% (1.8%), mean 0.5%, gauss
  1.5%, fine regularized 1.9%; penalty at 5e11 1.1%.
The figures of each run are printed (and written with --json); the docstring's are a run's.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from transient.case.loading import load                      # noqa: E402
from transient.contact.pair import build_contact             # noqa: E402
from transient.model import build_model                      # noqa: E402
from transient.solve.modes import mac_pairs                  # noqa: E402
from transient.solve.tied import contact_modes               # noqa: E402

REFERENCE = ("centre reg", ["rule=centre", "regularized=true", "eps=1e-3"])
# the rich rules, and the centre rule unregularized: what holds fewer directions, not the
# regularization alone, keeps the tie soft
RICH = [("fine", ["rule=fine", "regularized=false"]),
        ("gauss", ["rule=gauss", "regularized=false"]),
        ("fine reg", ["rule=fine", "regularized=true", "eps=1e-3"]),
        ("centre", ["rule=centre", "regularized=false"])]
TIES = [("penalty", 5e11), ("penalty", 1e13), ("penalty", 1e15), ("penalty", 1e17),
        ("preload", None), ("exact", None)]


def modes(path, model, base, rule, tie, k):
    over = base + [f"contact.pad_disc.{r}" for r in rule] + [f"solver.modes.tie={tie}"]
    if k is not None:
        over.append(f"contact.pad_disc.k={k}")
    case = load(path, over)
    t0 = time.perf_counter()
    pairs = build_contact(case, model)
    m, t = contact_modes(case, model, pairs)
    return m, t, pairs[0].rule.n_points, time.perf_counter() - t0


def shifts(ref, other, M, count):
    """(by MAC, by order) shifts of other over ref [%], and the MACs, on the first count."""
    partner, mac = mac_pairs(ref.shapes[:, :count], other.shapes[:, :count], M)
    fa, fb = ref.frequencies[:count], other.frequencies[:count]
    return 100 * (fb[partner] / fa - 1), 100 * (fb / fa - 1), mac


def compatibility(path, model, base):
    case = load(path, base + [f"contact.pad_disc.{r}" for r in REFERENCE[1]])
    comp = build_contact(case, model)[0].compat
    s, n = comp.normalized, min(comp.n1, comp.n2)
    # as the paper counts them: C(eps), the shapes kept over the smaller side's dofs
    return {"shapes": len(s), "round_off": int(np.sum(s < 1e-12)),
            "above_1e-4": 1 - comp.kept(1e-4) / n, "kept_1e-3": comp.kept(1e-3),
            "C_1e-3": comp.kept(1e-3) / n}


def study(name, path, count, ties):
    base = ["solver.modes.fmax=0.0", f"solver.modes.count={count}"]
    model = build_model(load(path, base))
    comp = compatibility(path, model, base)
    print(f"{name}: {3 * len(model.points)} dofs; interface shapes {comp['shapes']}, "
          f"{comp['round_off']} compatible to round-off; 1 - C(1e-4) = "
          f"{100 * comp['above_1e-4']:.0f}%; {comp['kept_1e-3']} kept at 1e-3, C(1e-3) = "
          f"{100 * comp['C_1e-3']:.0f}%", flush=True)
    rows = []
    for tie, k in ties:
        ref, _, ref_points, ref_s = modes(path, model, base, REFERENCE[1], tie, k)
        for label, rule in RICH:
            m, t, points, sec = modes(path, model, base, rule, tie, k)
            by_mac, by_order, mac = shifts(ref, m, model.M, count)
            row = {"case": name, "tie": tie, "k": k, "rule": label, "points": points,
                   "reference_points": ref_points, "held": t.held if tie == "exact" else None,
                   "held_of": t.dofs if tie == "exact" else None,
                   "max_mac": float(by_mac.max()), "mean_mac": float(by_mac.mean()),
                   "min_shift_mac": float(by_mac.min()),
                   "max_order": float(by_order.max()), "mean_order": float(by_order.mean()),
                   "above_1": int(np.sum(by_mac > 1)), "above_5": int(np.sum(by_mac > 5)),
                   "min_mac": float(mac.min()), "seconds": sec + ref_s}
            rows.append(row)
            print(f"  {tie:8s} k {k or '-':>6} {label:9s} {points:6d} pts: by MAC max "
                  f"{row['max_mac']:6.2f}% mean {row['mean_mac']:5.2f}% (min "
                  f"{row['min_shift_mac']:5.2f}%), by order max {row['max_order']:6.2f}% mean "
                  f"{row['mean_order']:5.2f}%; >1% {row['above_1']:2d}, >5% {row['above_5']:2d};"
                  f" min MAC {row['min_mac']:.2f}"
                  + (f"; held {t.held} of {t.dofs}" if tie == "exact" else ""), flush=True)
    return {"compatibility": comp, "rows": rows}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, default=50)
    parser.add_argument("--hex20", action="store_true", help="also cases/pad_disc.toml "
                        "(exact and the law's tangent only)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    t0 = time.perf_counter()
    out = {"tet10": study("pad_disc_tet10", ROOT / "cases" / "pad_disc_tet10.toml",
                          args.modes, TIES)}
    if args.hex20:
        out["hex20"] = study("pad_disc", ROOT / "cases" / "pad_disc.toml", args.modes,
                             [("penalty", 5e11), ("exact", None)])
    print(f"{time.perf_counter() - t0:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
