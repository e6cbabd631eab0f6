"""`transient bench`: error against run time for a sweep of contact rules on one case.

Each variant of the case's contact pair (the fine rule: the reference; the fine rule regularized
at each eps; the centre rule, plain and regularized; the greedy coarse rule at several m; the
sampled rule at several tolerances, regularized at the case's eps) is
set up (`stages.prepare`, timed) and integrated in memory (`stages.simulate`, timed) over the same
time, then compared with the reference:
- error_rms: RMS over the sensor histories of the difference of the motion about the preloaded
  state (each run's own) to the reference's (interpolated to the reference's times), relative
  to the RMS of the reference's motion; the preload itself is compared apart:
- preload_error: the largest difference of the sensors at the preload, relative to the largest
  reference value there;
- pressure_max_error: the largest contact pressure reached (over points and time), relative;
- frequency_error: the largest relative error of the first 30 contact-linearized frequencies
  (the structure with the contact tangents at the preload).
"""
import csv
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..case.checks import check_transient
from ..case.loading import load
from ..errors import CaseError
from ..stages import choose_dt, prepare, simulate

N_FREQUENCIES = 30
COLUMNS = ("rule", "label", "regularized", "eps", "points", "kept", "reduced_dofs", "steps",
           "setup_s", "kernel_s", "total_s", "steps_per_s", "error_rms", "preload_error",
           "pressure_max_error", "frequency_error", "status")


@dataclass(frozen=True)
class Variant:
    rule: str          # "fine" for the reference row, as the bench's JSON names it
    label: str         # what the plot and the table call it
    settings: dict     # contact.<pair>.<key> -> value


def variants(eps_list, points_list, tolerances=()):
    """The sweep: reference first. points 0 means the rank of the kept shapes."""
    rows = [Variant("fine", "fine", {"rule": "fine", "regularized": False})]
    rows += [Variant("fine", f"fine reg eps={e:g}",
                     {"rule": "fine", "regularized": True, "eps": e}) for e in eps_list]
    rows += [Variant("centre", "centre", {"rule": "centre", "regularized": False}),
             Variant("centre", "centre reg", {"rule": "centre", "regularized": True})]
    rows += [Variant("greedy", f"greedy m={m or 'rank'}",
                     {"rule": "greedy", "regularized": True, "points": m}) for m in points_list]
    rows += [Variant("sampled", f"sampled tol={t:g}",
                     {"rule": "sampled", "regularized": True, "sampling_tolerance": t})
             for t in tolerances]
    return rows


def _literal(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return repr(value)


def _pair_name(case, pair):
    names = list(case.contact)
    if not names:
        raise CaseError(case.path, "contact", "the bench sweeps contact rules: the case has no "
                        "contact pair")
    if pair is None:
        return names[0]
    if pair not in names:
        raise CaseError(case.path, "contact", f"no pair '{pair}' (pairs: {', '.join(names)})")
    return pair


def run_variant(path, overrides, pair, variant, t_end):
    """Set up and integrate one variant; returns (row, series, frequencies)."""
    sets = [f"contact.{pair}.{k}={_literal(v)}" for k, v in variant.settings.items()]
    case = load(path, list(overrides) + sets + ["output.contact=true"]
                + ([f"solver.t_end={t_end!r}"] if t_end else []))
    check_transient(case)
    t0 = time.perf_counter()
    setup = prepare(case)
    dt = choose_dt(case, setup)
    setup_s = time.perf_counter() - t0
    steps = int(round(case.solver.t_end / dt))
    series, status, kernel = simulate(case, setup, dt, steps, max(1, steps // 2000))
    meta = setup.meta["pairs"][pair]
    row = {"rule": variant.rule, "label": variant.label, "regularized": meta["regularized"],
           "eps": meta["eps"] if meta["regularized"] else None, "points": meta["points"],
           "kept": meta["kept"], "reduced_dofs": setup.meta.get("reduced_dofs"),
           "steps": steps, "setup_s": setup_s, "kernel_s": kernel, "total_s": setup_s + kernel,
           "steps_per_s": steps / max(kernel, 1e-12), "status": status}
    return row, series, _frequencies(setup.system)


def _frequencies(system):
    """The first contact-linearized frequencies [Hz]: of the reduced model, or of the full
    model's K_lin with its lumped mass."""
    if system.reduced:
        omega2 = system.omega2
    else:
        K, M = system.K, sp.diags(system.mass)
        k = min(N_FREQUENCIES, K.shape[0] - 2)
        omega2 = np.sort(spla.eigsh(K, k=k, M=M, sigma=-1.0, which="LM",
                                    return_eigenvectors=False))
    return np.sqrt(np.maximum(omega2[:N_FREQUENCIES], 0.0)) / (2 * np.pi)


def compare(ref, series, ref_freq, freq):
    """error_rms, pressure_max_error and frequency_error of a run against the reference."""
    t = ref["time"]
    sensors = [k for k in ref if k.startswith("sensors/")]
    num = den = 0.0
    for name in sensors:
        x = np.interp(t, series["time"], series[name] - series[name][0])
        num += np.sum((x - (ref[name] - ref[name][0])) ** 2)
        den += np.sum((ref[name] - ref[name][0]) ** 2)
    error = np.sqrt(num / den) if den > 0 else np.nan
    x0 = np.array([series[name][0] for name in sensors])
    r0 = np.array([ref[name][0] for name in sensors])
    preload = np.abs(x0 - r0).max() / max(np.abs(r0).max(), 1e-300) if sensors else np.nan
    p_ref = ref["contact/pressure"].max() if "contact/pressure" in ref else np.nan
    p = series["contact/pressure"].max() if "contact/pressure" in series else np.nan
    n = min(len(ref_freq), len(freq))
    f_err = (np.abs(freq[:n] - ref_freq[:n]) / np.maximum(ref_freq[:n], 1e-300)).max() \
        if n else np.nan
    return {"error_rms": float(error), "preload_error": float(preload),
            "pressure_max_error": float(abs(p - p_ref) / p_ref),
            "frequency_error": float(f_err)}


def bench(path, overrides=(), pair=None, eps_list=(1e-6, 1e-4, 1e-3, 1e-2),
          points_list=None, t_end=None, progress=None, tolerances=(3e-2, 1e-2, 3e-3)):
    """Rows of the sweep, reference first (rule 'fine'). points_list None: the greedy rule's
    own count r (m = 0), then r / 2, r / 4, 4 r and 10 r (those below the fine rule's);
    tolerances: the sampled rule's."""
    case = load(path, list(overrides))
    pair = _pair_name(case, pair)
    rows = []
    ref = ref_freq = None
    todo = variants(eps_list, points_list if points_list is not None else [0], tolerances)
    k = 0
    while k < len(todo):
        variant = todo[k]
        k += 1
        try:
            row, series, freq = run_variant(path, overrides, pair, variant, t_end)
        except CaseError as exc:
            if ref is None:
                raise            # no reference, nothing to compare with
            # a rule the scene does not admit (a rigid wall has no second mesh to regularize
            # or select on): a row that says so, and the sweep goes on
            rows.append(refused(variant, exc))
            if progress:
                progress(rows[-1])
            continue
        if ref is None:
            ref, ref_freq = series, freq
        row.update(compare(ref, series, ref_freq, freq))
        rows.append(row)
        if progress:
            progress(row)
        if points_list is None and variant.settings.get("points") == 0:
            # below the rank the error grows fast; above it the rule converges to the fine
            # one (pad_disc: 1% needs about 10 r), so the sweep reaches both ways
            r, fine = row["points"], rows[0]["points"]
            todo += [Variant("greedy", f"greedy m={m}", dict(variant.settings, points=m))
                     for m in (r // 2, r // 4, 4 * r, 10 * r) if 0 < m < fine]
    return rows


def refused(variant, exc):
    """The row of a variant refused before its run: no figures, the reason as status."""
    row = {c: None for c in COLUMNS}
    row.update({"rule": variant.rule, "label": variant.label,
                "regularized": bool(variant.settings.get("regularized")),
                "status": f"refused: {exc.key}: {exc.message}"})
    return row


def target(rows):
    """The best regularized coarse row within 1% error_rms of the reference at a third or less
    of its kernel time (None if there is none)."""
    ref = rows[0]
    good = [r for r in rows[1:] if r["regularized"] and r["rule"] != "fine"
            and r["error_rms"] is not None and r["error_rms"] <= 0.01 and r["kernel_s"] <= ref["kernel_s"] / 3]
    return min(good, key=lambda r: r["kernel_s"]) if good else None


def write(rows, out):
    """bench.csv, bench.json and bench.png (error against run time, log-log) in out."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "bench.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for row in rows:
            w.writerow({k: row.get(k) for k in COLUMNS})
    (out / "bench.json").write_text(json.dumps({"rows": rows}, indent=1))
    _plot(rows, out / "bench.png")
    return [out / "bench.csv", out / "bench.json", out / "bench.png"]


def _plot(rows, path):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    floor = 1e-6     # the reference's own error is 0: drawn at the floor
    markers = {"fine": "o", "centre": "s", "greedy": "^", "sampled": "D"}
    for ax, key, name in zip(axes, ("kernel_s", "total_s"), ("kernel", "setup + kernel")):
        for row in rows:
            if row["error_rms"] is None or not np.isfinite(row["error_rms"]):
                continue           # refused, or no motion to compare
            err = max(row["error_rms"], floor)
            filled = "none" if not row["regularized"] else None
            ax.loglog(row[key], err, markers[row["rule"]], ms=8,
                      mfc=filled, label=row["label"])
            ax.annotate(row["label"], (row[key], err), fontsize=7, xytext=(4, 3),
                        textcoords="offset points")
        ax.axhline(0.01, color="0.6", lw=0.8, ls="--")
        # ticks at 1, 2, 5 per decade: a sweep's totals often span less than one decade
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: f"{x:g}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel(f"{name} time [s]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("error_rms of the sensor histories vs the fine rule")
    fig.suptitle("Contact rules: error against run time (open markers: not regularized; "
                 "the fine rule drawn at 1e-6)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def format_row(row):
    if row["setup_s"] is None:
        return f"{row['label']:<22} {row['status']}"
    kept = row["kept"] if row["kept"] is not None else "-"
    return (f"{row['label']:<22} {row['points']:>6} {kept:>5} "
            f"{row['setup_s']:8.2f} {row['kernel_s']:8.2f} {row['total_s']:8.2f} "
            f"{row['steps_per_s']:9.0f} {row['error_rms']:9.2e} {row['preload_error']:9.2e} "
            f"{row['pressure_max_error']:9.2e} "
            f"{row['frequency_error']:9.2e} {row['status']}")


HEADER = (f"{'rule':<22} {'points':>6} {'kept':>5} {'setup s':>8} {'kernel s':>8} "
          f"{'total s':>8} {'steps/s':>9} {'error_rms':>9} {'preload':>9} {'p_max err':>9} "
          f"{'freq err':>9}")
