"""The paper's locking in dynamics (section 4.2, figure 11) on the pad and disc: how far a rich
contact rule raises the tied modes above the (1-eps) regularized centre rule, by tie and by
stiffness, on the tet10 meshes made each on its own (cases/pad_disc_tet10.toml) and on the
structured hex20 ones (cases/pad_disc.toml).

    python studies/study_locking.py [--case tet10|hex20|both] [--modes 50] [--k K ...]
                                  [--sizes 0.004 0.008] [--mesh-dir DIR] [--json PATH]

1. The interface's compatibility (singular values of the gap energy on the fine rule): its
   shapes, those compatible to round-off, the share above eps = 1e-4 (the paper: over 70%) and
   C(1e-3), the share kept at 1e-3 (the paper: 42%); both shares over min(N1, N2) as C(eps).
2. For each tie (solver.modes.tie: penalty springs of density k = 5e11, the law's tangent at
   1 MPa, 1e13, 1e15, 1e17 on every rule; preload, the law's tangents at the preload; exact,
   the gap held at zero on the rule's rows) the first modes of the reference rule (centre,
   regularized at eps = 1e-3: the paper's "(1-eps) 6 to 1") and of the rich rules (fine and
   gauss, unregularized; fine regularized at 1e-3) and, as a control, the centre rule
   unregularized; each one's shifts over the reference at the same tie: each reference mode
   against its partner by mass MAC (one to one, among the rule's first modes + MARGIN), and by
   mode order as the paper plots them.
3. --sizes: the tet10 meshes again (tools/mesh_brake.py, bulk 12 mm) at other interface sizes,
   tied exactly, fine against the reference: how the locking changes with the interface's
   element size against the bulk's.
Prints progress and a markdown table; --json writes every number (frequencies, partners, MAC).

Found on 2026-12-04 (2 cores shared with another developer, load average 1.8-2.0; 599 s for
both cases, 49 s more for --sizes 0.004 0.008; 151 s for --case tet10 --k 1e19 1e21 1e23),
first 50 modes, shifts over the reference at the same tie, by MAC (by order):
- compatibility: tet10 1658 shapes (798 + 860 normal dofs), 5 compatible to round-off
  (< 1e-13), 79% above 1e-4, 278 kept at 1e-3 (C = 35%); hex20 1194, 13, 65%, 306 (57%).
- tet10 exact: fine 16.4% (10.9%), mean 3.0%, 32 modes above 1%, 11 above 5%, 1653 of 1658
  directions held; but the 16.4% pair has MAC 0.16: over the 43 pairs with MAC >= 0.5 the
  largest is 10.9%. gauss (2226 points) 7.8% (6.9%), mean 1.7%; fine regularized 16.3% (9.2%),
  mean 2.5%, holding 551; centre unregularized 0.3% softer on average, at most 0.04% stiffer:
  the coarse rule, not the regularization, keeps the exact tie free.
- tet10 penalty: every rule within 0.46% at k = 5e11, 1e13, 1e15, 1e17 (fine 0.36, 0.45, 0.13,
  0.03%: not monotone; the reference is within 0.2% of its exact tie by 1e15, 12% below it at
  5e11, while the fine rule's nearly compatible shapes, 1e-13 to 1e-4 of the largest gap
  energy, stay soft); --k 1e19 1e21 1e23: fine 0.26%, 4.1%, 7.7% by order: the exact tie is
  the limit only past k ~ 1e23 (a probe at 1e25 overshot it by 1% on average: round-off).
  preload: 0.33%.
- hex20: exact fine 2.1% (1.8%), mean 0.5%, 9 modes above 1%, none above 5%; gauss 1.5%, fine
  regularized 1.9%; penalty 1.1-1.5% at every k, preload 1.2%.
- --sizes (tet10, bulk 12 mm, exact, fine): interface 4 mm (33408 points) 7.7% (7.0%), mean
  1.7%; 5.5 mm 16.4% (10.9%), 3.0%; 8 mm 33% on a MAC 0.04 pair (12.2%), 3.4%: the coarser
  the interface the more it locks; above 1e-4 83%, 79%, 78%.
The MAC max is the one-to-one assignment's, which pairs every reference mode, a locked mode
whose shape changed too: read it with "MAC>=0.5: n, max". MACs of 0.5-0.75 under springs are
the disc's doublets, split differently.
"""
import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from transient.case.loading import load                      # noqa: E402
from transient.contact.compatibility import ROUND_OFF        # noqa: E402
from transient.contact.pair import build_contact             # noqa: E402
from transient.model import build_model                      # noqa: E402
from transient.solve.modes import mac_pairs                  # noqa: E402
from transient.solve.tied import contact_modes               # noqa: E402

CASES = {"tet10": ROOT / "cases" / "pad_disc_tet10.toml",
         "hex20": ROOT / "cases" / "pad_disc.toml"}
REFERENCE = ("centre reg", 'rule="centre"', "regularized=true", "eps=1e-3")
RULES = [("fine", 'rule="fine"', "regularized=false"),
         ("gauss", 'rule="gauss"', "regularized=false"),
         ("fine reg", 'rule="fine"', "regularized=true", "eps=1e-3"),
         # the control: as few points as the reference, none of its regularization
         ("centre", 'rule="centre"', "regularized=false")]
K = [5e11, 1e13, 1e15, 1e17]   # the penalty's k; --k replaces them
# a rule stiffer than the reference pushes modes past the first count: its partners are
# sought among count + MARGIN modes, so no reference mode is forced onto a wrong one
MARGIN = 15
# a pair below this MAC is the assignment's leftover, not the same mode (the disc's doublets,
# split apart, fall to 0.5-0.75 though): its shift is reported apart
SURE = 0.5


class Study:
    """One case file: its model built once, the contact geometry shared by the variants equal
    on it (same rule and k: build_contact(geometry=...)), the modes of each variant."""

    def __init__(self, name, path, count):
        self.name, self.path, self.count = name, path, count
        self.base = ["solver.modes.fmax=0.0", f"solver.modes.count={count + MARGIN}"]
        self.model = build_model(load(path, self.base))
        self.geometry = {}

    def contact(self, rule, tie, k):
        """(case, pairs, seconds) of a rule at a tie; the geometry reused when built already."""
        over = self.base + [f"contact.pad_disc.{r}" for r in rule[1:]]
        over += [f'solver.modes.tie="{tie}"'] + ([f"contact.pad_disc.k={k}"] if k else [])
        case = load(self.path, over)
        key = (rule[0], case.contact["pad_disc"].k)
        t0 = time.perf_counter()
        pairs = self.geometry[key] = build_contact(case, self.model,
                                                   geometry=self.geometry.get(key))
        return case, pairs, time.perf_counter() - t0

    def modes(self, rule, tie, k):
        """(Modes, Tie, rule points, contact seconds, modes seconds) of a rule at a tie."""
        case, pairs, contact_s = self.contact(rule, tie, k)
        t0 = time.perf_counter()
        m, t = contact_modes(case, self.model, pairs)
        return m, t, pairs[0].rule.n_points, contact_s, time.perf_counter() - t0

    def compatibility(self):
        comp = self.contact(REFERENCE, "exact", None)[1][0].compat
        n = min(comp.n1, comp.n2)   # C(eps) counts over the smaller side, as the paper
        return {"case": self.name, "dofs": self.model.ndof, "shapes": len(comp.normalized),
                "n1": comp.n1, "n2": comp.n2,
                "round_off": int(np.sum(comp.normalized < ROUND_OFF)),
                "above_1e-4": 1 - comp.kept(1e-4) / n, "kept_1e-3": comp.kept(1e-3),
                "C_1e-3": comp.kept(1e-3) / n}


def row(study, tie, k, label, ref, res):
    """A table row: the rule's shifts over the reference [%], by MAC and by order."""
    (m, t, points, contact_s, modes_s), n = res, study.count
    out = {"case": study.name, "tie": tie, "k": k, "rule": label, "points": points,
           "held": t.held if tie == "exact" else None,
           "held_of": t.dofs if tie == "exact" else None,
           "seconds": contact_s + modes_s, "contact_s": contact_s, "modes_s": modes_s,
           "frequencies": m.frequencies[:n + MARGIN].tolist()}
    if ref is None:
        return out
    fa, fb = ref[0].frequencies[:n], m.frequencies
    partner, mac = mac_pairs(ref[0].shapes[:, :n], m.shapes[:, :n + MARGIN], study.model.M)
    by_mac, by_order = 100 * (fb[partner] / fa - 1), 100 * (fb[:n] / fa - 1)
    out.update({"max_mac": by_mac.max(), "mean_mac": by_mac.mean(), "min_shift_mac": by_mac.min(),
                "max_order": by_order.max(), "mean_order": by_order.mean(),
                "above_1": int(np.sum(by_mac > 1)), "above_5": int(np.sum(by_mac > 5)),
                "above_1_order": int(np.sum(by_order > 1)),
                "above_5_order": int(np.sum(by_order > 5)),
                "sure": int(np.sum(mac >= SURE)), "max_sure": by_mac[mac >= SURE].max(),
                "mean_sure": by_mac[mac >= SURE].mean(), "min_mac": mac.min(),
                "partners": partner.tolist(), "mac": mac.tolist()})
    return {key: float(v) if isinstance(v, np.floating) else v for key, v in out.items()}


def describe(r):
    held = f"; held {r['held']} of {r['held_of']}" if r["held"] is not None else ""
    if "max_mac" not in r:
        return f"{r['points']} pts, f1 {r['frequencies'][0]:.0f} Hz{held}"
    return (f"{r['points']} pts: MAC max {r['max_mac']:.2f}% mean {r['mean_mac']:.2f}% "
            f"(min {r['min_shift_mac']:.2f}%), order max {r['max_order']:.2f}% mean "
            f"{r['mean_order']:.2f}%; MAC >= {SURE}: {r['sure']}, max {r['max_sure']:.2f}%; "
            f">1% {r['above_1']}, >5% {r['above_5']}; min MAC "
            f"{r['min_mac']:.2f}{held}")


def run_ties(study, ties, rules):
    rows = []
    for tie, k in ties:
        ref = study.modes(REFERENCE, tie, k)
        rows.append(row(study, tie, k, REFERENCE[0], None, ref))
        for rule in rules:
            rows.append(row(study, tie, k, rule[0], ref, study.modes(rule, tie, k)))
        for r in rows[-1 - len(rules):]:
            ks = f"{r['k']:g}" if r["k"] else "-"
            print(f"  {study.name} {tie} k={ks} {r['rule']}: {describe(r)} "
                  f"({r['seconds']:.0f} s)", flush=True)
    return rows


def sizes(args, count):
    """The interface size's effect: tet10 meshes at other interface sizes, exact tie."""
    out = []
    for h in args.sizes:
        outdir = args.mesh_dir / f"interface_{1000 * h:g}mm"
        case = outdir / "brake.toml"
        if not case.exists():   # mesh_brake's meshes are deterministic: a rerun reuses them
            subprocess.run([sys.executable, str(ROOT / "tools" / "mesh_brake.py"), str(outdir),
                            "--size", "0.012", "--interface", str(h), "--case-out", str(case)],
                           check=True, stdout=subprocess.DEVNULL)
        study = Study(f"tet10 {1000 * h:g} mm", case, count)
        comp = study.compatibility()
        rows = run_ties(study, [("exact", None)], RULES[:1])
        out.append({"interface": h, "compatibility": comp, "rows": rows})
    return out


def table(compat, rows):
    lines = ["| case | dofs | interface shapes | round-off | above 1e-4 | kept 1e-3 | C(1e-3) |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {c['case']} | {c['dofs']} | {c['shapes']} ({c['n1']} + {c['n2']}) | "
              f"{c['round_off']} | {100 * c['above_1e-4']:.0f}% | {c['kept_1e-3']} | "
              f"{100 * c['C_1e-3']:.0f}% |" for c in compat]
    lines += ["", "| case | tie | k | rule | points | held | MAC max | MAC mean | "
              f"order max | order mean | MAC>={SURE}: n, max | >1% (MAC/order) | "
              ">5% (MAC/order) | min MAC | s |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        k = f"{r['k']:.0e}" if r["k"] else "-"
        held = f"{r['held']}/{r['held_of']}" if r["held"] is not None else "-"
        head = f"| {r['case']} | {r['tie']} | {k} | {r['rule']} | {r['points']} | {held} |"
        if "max_mac" not in r:
            lines.append(head + " ref | | | | | | | | " + f"{r['seconds']:.0f} |")
            continue
        lines.append(head + f" {r['max_mac']:.2f}% | {r['mean_mac']:.2f}% | "
                     f"{r['max_order']:.2f}% | {r['mean_order']:.2f}% | {r['sure']}, "
                     f"{r['max_sure']:.2f}% | {r['above_1']}/"
                     f"{r['above_1_order']} | {r['above_5']}/{r['above_5_order']} | "
                     f"{r['min_mac']:.2f} | {r['seconds']:.0f} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=("tet10", "hex20", "both"), default="both")
    parser.add_argument("--hex20", action="store_true",
                        help="both cases, the default (kept for scripts that pass it)")
    parser.add_argument("--modes", type=int, default=50, help="modes compared (50)")
    parser.add_argument("--k", type=float, nargs="*", default=K, help="the penalty ties' k")
    parser.add_argument("--sizes", type=float, nargs="*", default=[],
                        help="interface sizes [m] for the size study (e.g. 0.004 0.008)")
    parser.add_argument("--mesh-dir", type=Path, default=Path("/tmp/study_locking"),
                        help="where the size study's meshes go (reused when there)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    t0 = time.perf_counter()
    compat, rows, out = [], [], {"modes": args.modes, "margin": MARGIN}
    for name in ("tet10", "hex20") if args.case == "both" or args.hex20 else (args.case,):
        study = Study(name, CASES[name], args.modes)
        compat.append(study.compatibility())
        print(f"{name}: {study.model.ndof} dofs; {compat[-1]}", flush=True)
        rows += run_ties(study, [("penalty", k) for k in args.k] + [("preload", None),
                                                                   ("exact", None)], RULES)
    out["seconds"] = time.perf_counter() - t0
    if args.sizes:
        out["sizes"] = sizes(args, args.modes)
        for s in out["sizes"]:
            compat.append(s["compatibility"])
            rows += s["rows"]
        out["sizes_seconds"] = time.perf_counter() - t0 - out["seconds"]
    out.update({"compatibility": compat, "rows": rows})
    print(table(compat, rows))
    print(f"{out['seconds']:.0f} s" + (f", sizes {out['sizes_seconds']:.0f} s" if args.sizes
                                       else ""), flush=True)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
