"""Coarse contact rules against the regularized fine rule: error of the first tied modes.

For one contact pair, the frequencies of the first --modes modes with the pair tied (bilateral
linear, stiffness k) under each rule are compared with those of the regularized fine rule at the
same eps: the fine rule unregularized, the centre rule (master surface1, surface2) plain and
regularized, and the greedy rule at several m (0 = the rank k; default k, 1.5k, 2k, N/5 with N
the fine points) with nearest and nnls weights, and exact weights when the interface is small
enough. The model is built once; only the pair changes. setup_s is the contact stage (the pair:
interface, compatibility, regularization, selection; and its stiffness), modes_s the eigensolver.

    python studies/study_coarse.py [--case cases/pad_disc.toml] [--pair pad_disc]
        [--points 0,900] [--modes 30] [--set KEY=VALUE ...] [--out DIR] [--json]

On a shared machine run with OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1: spinning BLAS and
OpenMP threads on busy cores make the timings (not the errors) 10-50 times worse.
"""
import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np

from transient.case.loading import load
from transient.contact.pair import build_pair, contact_stiffness
from transient.errors import CaseError
from transient.kernels.greedy import greedy_rows
from transient.model.model import build_model
from transient.solve.modes import normal_modes

CASES = Path(__file__).resolve().parent.parent / "cases"
FIELDS = ["rule", "weights", "points", "fraction", "energy_error", "max_error_pct",
          "mean_error_pct", "setup_s", "modes_s"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(CASES / "pad_disc.toml"))
    parser.add_argument("--pair", help="contact pair (default: the case's first)")
    parser.add_argument("--points", help="greedy m, comma separated (0: the rank k); "
                        "default k, 1.5k, 2k, N/5")
    parser.add_argument("--modes", type=int, default=30)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--out", help="directory for the CSV, JSON and PNG")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    greedy_rows(np.eye(3), 2, 1e-8, True)    # compile (or load) the kernel outside the timings
    case = load(args.case, args.overrides)
    name = args.pair or next(iter(case.contact))
    key = f"contact.{name}"
    t0 = time.perf_counter()
    model = build_model(case)
    # the case's other pairs, as the case defines them: tied in every run
    K_base = model.K + contact_stiffness(
        [build_pair(case, model, other) for other in case.contact if other != name],
        model.ndof)
    t_model = time.perf_counter() - t0
    log = (lambda *a: None) if args.json else print
    log(f"{case.path.name}, pair {name}: {model.ndof} dofs, model {t_model:.1f} s")

    def run(settings):
        """Frequencies and the pair with these [contact.NAME] settings."""
        c = load(args.case, args.overrides + [f"{key}.{k}={v}" for k, v in settings.items()])
        t0 = time.perf_counter()
        pair = build_pair(c, model, name)
        K = K_base + contact_stiffness([pair], model.ndof)
        t1 = time.perf_counter()
        f = normal_modes(K, model.M, model.fixed, count=args.modes).frequencies
        return f, pair, t1 - t0, time.perf_counter() - t1

    ref, ref_pair, t_setup, t_modes = run({"rule": "fine", "regularized": "true"})
    eps, N = ref_pair.eps, ref_pair.interface.fine.n_points
    log(f"reference: regularized fine rule, {N} points, eps = {eps:.3g} "
        f"({ref_pair.eps_source}), {ref_pair.compat.kept(eps)} shapes kept, "
        f"f = {ref[0]:.1f} .. {ref[-1]:.1f} Hz; setup {t_setup:.1f} s, modes {t_modes:.1f} s")
    rows, skipped = [], []

    def add(label, weights, settings):
        try:
            f, pair, t_setup, t_modes = run(settings)
        except CaseError as exc:
            skipped.append({"rule": label, "weights": weights, "reason": str(exc)})
            log(f"  skipped {label} {weights}: {exc}")
            return None
        err = np.abs(f / ref - 1) * 100
        row = {"rule": label, "weights": weights, "points": pair.rule.n_points,
               "fraction": pair.rule.n_points / N,
               "energy_error": pair.coarse.energy_error if pair.coarse else None,
               "max_error_pct": float(err.max()), "mean_error_pct": float(err.mean()),
               "setup_s": t_setup, "modes_s": t_modes,
               "rank": pair.coarse.rank if pair.coarse else None,
               "stages_s": pair.timings, "frequencies_hz": f.tolist()}
        rows.append(row)
        log(_line(row))
        return pair

    log(_header())
    reg = {"regularized": "true", "eps": repr(float(eps))}
    add("fine", "-", {"rule": "fine", "regularized": "false"})
    for master in ("surface1", "surface2"):
        add(f"centre {master}", "-", {"rule": "centre", "master": master, "regularized": "false"})
        add(f"centre {master} reg", "-", {"rule": "centre", "master": master, **reg})
    greedy = {"rule": "greedy", "candidates": "fine", **reg}
    first = add("greedy", "nearest", {**greedy, "points": 0, "weights": "nearest"})
    k = first.coarse.rank
    points = ([int(p) for p in args.points.split(",")] if args.points
              else [0, round(1.5 * k), 2 * k, N // 5])
    points = sorted({k if p == 0 else min(p, N) for p in points})
    for m in points:
        for weights in ("nearest", "nnls"):
            if not (weights == "nearest" and m == k):     # already run
                add("greedy", weights, {**greedy, "points": m, "weights": weights})
    add("greedy", "exact", {**greedy, "points": 0, "weights": "exact"})

    out = {"case": str(case.path), "overrides": args.overrides, "pair": name,
           "ndof": model.ndof, "modes": args.modes, "fine_points": N, "eps": eps,
           "eps_source": ref_pair.eps_source, "rank": k, "kept": ref_pair.compat.kept(eps),
           "reference_hz": ref.tolist(), "reference_setup_s": t_setup,
           "reference_modes_s": t_modes, "rows": rows, "skipped": skipped}
    if args.out:
        write(Path(args.out), f"{case.path.stem}_{name}", out)
    if args.json:
        print(json.dumps(out, indent=1))


def _header():
    return (f"  {'rule':22s} {'weights':8s} {'points':>6s} {'frac':>6s} {'energy_err':>10s} "
            f"{'max [%]':>9s} {'mean [%]':>9s} {'setup_s':>7s} {'modes_s':>7s}")


def _line(r):
    e = "-" if r["energy_error"] is None else f"{r['energy_error']:.2e}"
    return (f"  {r['rule']:22s} {r['weights']:8s} {r['points']:6d} {r['fraction']:6.3f} "
            f"{e:>10s} {r['max_error_pct']:9.3g} {r['mean_error_pct']:9.3g} "
            f"{r['setup_s']:7.2f} {r['modes_s']:7.2f}")


def write(directory, stem, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    directory.mkdir(parents=True, exist_ok=True)
    with open(directory / f"{stem}.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(out["rows"])
    (directory / f"{stem}.json").write_text(json.dumps(out, indent=1))
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    floor = 1e-14   # exact rules reach round-off: keep them on the log axis
    for weights, style in (("nearest", "o-"), ("nnls", "s-"), ("exact", "*")):
        rs = sorted((r for r in out["rows"] if r["rule"] == "greedy" and r["weights"] == weights),
                    key=lambda r: r["points"])
        if rs:
            ax.loglog([r["points"] for r in rs], [max(r["max_error_pct"], floor) for r in rs],
                      style, ms=8 if weights == "exact" else 5, label=f"greedy {weights}")
    for r in out["rows"]:
        if r["rule"] != "greedy":
            ax.loglog(r["points"], max(r["max_error_pct"], floor),
                      "v" if "centre" in r["rule"] else "D", label=r["rule"])
    ax.axvline(out["rank"], color="0.7", ls=":", lw=1)
    ax.set_xlabel("contact points")
    ax.set_ylabel(f"max relative error, first {out['modes']} tied modes [%]")
    ax.set_title(f"{Path(out['case']).stem}, pair {out['pair']}: against the regularized fine "
                 f"rule ({out['fine_points']} points, eps = {out['eps']:.2g})", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(directory / f"{stem}.png", dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
