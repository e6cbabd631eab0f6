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
With friction (a squeal: growth, then a limit cycle), each run's oscillation is summed up too
(`oscillation`) and compared: growth_rate [1/s], fitted on the amplitude (over a period) of the
largest sensor motion over the later half of its linear phase; in the limit cycle's window (the run's last quarter, or from
cycle_from), cycle_rms, the norm of the sensors' RMS about their means, and cycle_frequency, the
dominant frequency of the largest sensor; their relative errors growth_error, cycle_rms_error
(on the vector of RMS) and cycle_frequency_error.

The reference is the fine rule, or (reference "case") the case's own rule at half its step,
followed by the case's own rule at its step: the fine rule's points are too many for a
saturated squeal's implicit steps (each point's three terms exact), and the limit cycle is then
measured against dt / 2 (its own error) and the sweep against that.
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
from ..case.loading import literal, load
from ..errors import CaseError
from ..plots.signals import EDGE, SATURATION, growth_rate, running_amplitude
from ..stages import choose_dt, prepare, simulate

N_FREQUENCIES = 30
COLUMNS = ("rule", "label", "regularized", "eps", "points", "kept", "reduced_dofs", "steps",
           "setup_s", "kernel_s", "total_s", "steps_per_s", "error_rms", "preload_error",
           "pressure_max_error", "frequency_error", "growth_rate", "growth_error", "cycle_rms",
           "cycle_rms_error", "cycle_frequency", "cycle_frequency_error", "status")
CYCLE = 0.25             # the limit cycle's window by default: the run's last quarter
ROWS = 2000              # rows a run keeps at most...
PER_PERIOD = 10          # ...unless a period of the highest frequency would get fewer samples
REFERENCES = ("fine", "case")
GROWING = 1.5            # a run still grows at its end if each quarter after it reached a tenth
#                          of its peak grew by this factor (growth_window)


@dataclass(frozen=True)
class Variant:
    rule: str          # "fine" for the reference row, as the bench's JSON names it; "case"
    #                    the case's own rule
    label: str         # what the plot and the table call it
    settings: dict     # contact.<pair>.<key> -> value
    dt_factor: float = 1.0   # of the case's step


def variants(eps_list, points_list, tolerances=(), reference="fine"):
    """The sweep: reference first. points 0 means the rank of the kept shapes."""
    if reference == "case":
        rows = [Variant("case", "case dt/2", {}, 0.5), Variant("case", "case", {})]
    else:
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
    sets = [f"contact.{pair}.{k}={literal(v)}" for k, v in variant.settings.items()]
    case = load(path, list(overrides) + sets + ["output.contact=true"]
                + ([f"solver.t_end={t_end!r}"] if t_end else []))
    check_transient(case)
    t0 = time.perf_counter()
    setup = prepare(case)
    dt = choose_dt(case, setup) * variant.dt_factor
    setup_s = time.perf_counter() - t0
    steps = int(round(case.solver.t_end / dt))
    series, status, kernel = simulate(case, setup, dt, steps, every(case, dt, steps))
    meta = setup.meta["pairs"][pair]
    row = {"rule": variant.rule, "label": variant.label, "regularized": meta["regularized"],
           "eps": meta["eps"] if meta["regularized"] else None, "points": meta["points"],
           "kept": meta["kept"], "reduced_dofs": setup.meta.get("reduced_dofs"),
           "steps": steps, "setup_s": setup_s, "kernel_s": kernel, "total_s": setup_s + kernel,
           "steps_per_s": steps / max(kernel, 1e-12), "status": status}
    return row, series, _frequencies(setup.system)


def every(case, dt, steps):
    """Steps between kept rows: ROWS over the run, but PER_PERIOD samples at least in a period
    of the case's highest frequency (its modes' fmax): a squeal's limit cycle is read from its
    spectrum, which a coarse sampling would alias."""
    fmax = case.solver.modes.fmax
    cap = int(1.0 / (PER_PERIOD * fmax * dt)) if fmax > 0 else steps
    return max(1, min(steps // ROWS, cap))


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


def oscillation(series, cycle_from=None):
    """growth_rate, cycle_rms, the vector of the sensors' RMS in the window (for the error) and
    cycle_frequency of a run (see the module's docstring); NaN where there is no motion."""
    t = series["time"]
    names = [k for k in series if k.startswith("sensors/")]
    nan = {"growth_rate": np.nan, "cycle_rms": np.nan, "cycle_frequency": np.nan}
    if not names or len(t) < 16:
        return nan, np.full(len(names), np.nan)
    dt = t[1] - t[0]
    motion = np.stack([series[k] - series[k][0] for k in names])
    start = cycle_from if cycle_from is not None else t[0] + (1 - CYCLE) * (t[-1] - t[0])
    window = t >= start
    if window.sum() < 16 and cycle_from is None:
        return nan, np.full(len(names), np.nan)          # too short a run to sum up
    if window.sum() < 16:
        raise CaseError("command line", "--cycle-from", f"{start:g} s leaves "
                        f"{window.sum()} rows of the run (to {t[-1]:g} s) for its limit cycle")
    part = motion[:, window]
    rms = np.sqrt(np.mean((part - part.mean(axis=1, keepdims=True)) ** 2, axis=1))
    if not np.all(np.isfinite(motion)) or rms.max() == 0:
        return nan, np.full(len(names), np.nan)
    main = int(np.argmax(rms))
    # the spectrum's peak, zero-padded eightfold, refined on the parabola through its log
    # neighbours (a Hann window's peak is near-Gaussian: a small fraction of a bin)
    x = part[main] - part[main].mean()
    pad = np.concatenate([x * np.hanning(len(x)), np.zeros(7 * len(x))])
    a = np.abs(np.fft.rfft(pad))
    k = 1 + int(np.argmax(a[1:-1]))
    la, lb, lc = np.log(a[k - 1:k + 2] + 1e-300)
    shift = 0.5 * (la - lc) / (la - 2 * lb + lc) if la - 2 * lb + lc < 0 else 0.0
    frequency = (k + shift) / (len(pad) * dt)
    # the growth on the amplitude over a period of that frequency: pad_disc_squeal at mu = 0.4
    # grows 1973 1/s so (CEA 1991), 360 on the Hilbert envelope, which the saturated end's
    # leakage and the limit cycle's offset swamp
    env = running_amplitude(motion[main], round(1.0 / (frequency * dt)))
    try:
        sigma = growth_rate(t, env, growth_window(t, env))[0]
    except ValueError:
        sigma = np.nan
    return ({"growth_rate": float(sigma), "cycle_rms": float(np.linalg.norm(rms)),
             "cycle_frequency": float(frequency)}, rms)


def growth_window(t, env):
    """The growth's window: the later half of its linear phase, where the fastest mode has
    outgrown the others the tap excited too. The phase ends where growth_rate's automatic
    window does, at SATURATION of the peak, or at the run's end (less its edge) when the
    amplitude still grew by GROWING over the last tenth (a limit cycle's wanders by less);
    a run that decays has no growth and gets growth_rate's own window."""
    n = len(t)
    lo, hi = int(EDGE * n), n - int(EDGE * n)
    if hi - lo < 8:
        return None
    inner = env[lo:hi]
    peak = int(np.argmax(inner))
    if inner[0] >= SATURATION * inner[peak] and peak < 0.5 * (hi - lo):
        return None                                   # a decay
    arrival = int(np.argmax(inner >= SATURATION * inner[peak]))
    # still growing at its end: from its arrival at SATURATION of its peak on, each quarter's
    # largest amplitude is GROWING times the last's. A limit cycle wanders by a third long
    # after it saturated, and its last tenth may grow 1.6x (pad_disc_squeal's 20 ms at mu =
    # 0.4, saturated by 7 ms, fitted as a growth of -13 1/s on that tenth's test)
    after = inner[arrival:]
    q = len(after) // 4
    growing = q > 0 and all(after[(k + 1) * q:(k + 2) * q].max()
                            >= GROWING * after[k * q:(k + 1) * q].max() for k in range(3))
    end = hi - 1 if growing else lo + arrival
    return 0.5 * (t[lo] + t[end]), t[end]


def compare_oscillation(ref, ref_rms, run, rms):
    """The relative errors of a run's oscillation against the reference's."""
    def rel(a, b):
        return float(abs(a - b) / abs(b)) if np.isfinite(a) and np.isfinite(b) and b else np.nan
    return {"growth_error": rel(run["growth_rate"], ref["growth_rate"]),
            "cycle_rms_error": float(np.linalg.norm(rms - ref_rms) / np.linalg.norm(ref_rms))
            if np.all(np.isfinite(rms)) and np.linalg.norm(ref_rms) > 0 else np.nan,
            "cycle_frequency_error": rel(run["cycle_frequency"], ref["cycle_frequency"])}


def bench(path, overrides=(), pair=None, eps_list=(1e-6, 1e-4, 1e-3, 1e-2),
          points_list=None, t_end=None, progress=None, tolerances=(3e-2, 1e-2, 3e-3),
          reference="fine", cycle_from=None):
    """Rows of the sweep, reference first (rule 'fine', or with reference 'case' the case's rule
    at dt / 2). points_list None: the greedy rule's own count r (m = 0), then r / 2, r / 4, 4 r
    and 10 r (those below the fine rule's); tolerances: the sampled rule's. With friction, the
    oscillation's numbers too, the limit cycle from cycle_from [s] (default: the last
    quarter)."""
    case = load(path, list(overrides))
    pair = checked_pair(case, pair, reference, cycle_from, t_end)
    squeal = any(c.friction.active for c in case.contact.values())
    rows = []
    ref = ref_freq = ref_osc = None
    todo = variants(eps_list, points_list if points_list is not None else [0], tolerances,
                    reference)
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
        if squeal:
            osc, rms = oscillation(series, cycle_from)
            if ref_osc is None:
                ref_osc = osc, rms
            row.update(osc)
            row.update(compare_oscillation(*ref_osc, osc, rms))
        rows.append(row)
        if progress:
            progress(row)
        if points_list is None and variant.settings.get("points") == 0:
            # below the rank the error grows fast; above it the rule converges to the fine
            # one (pad_disc: 1% needs about 10 r), so the sweep reaches both ways
            r = row["points"]
            fine = rows[0]["points"] if reference == "fine" else np.inf
            todo += [Variant("greedy", f"greedy m={m}", dict(variant.settings, points=m))
                     for m in (r // 2, r // 4, 4 * r, 10 * r) if 0 < m < fine]
    return rows


def checked_pair(case, pair=None, reference="fine", cycle_from=None, t_end=None):
    """The pair a bench of case sweeps, the bench's options checked (CaseError) before any
    stage."""
    if reference not in REFERENCES:
        raise CaseError("command line", "--reference", f"expected one of "
                        f"{', '.join(REFERENCES)}, got '{reference}'")
    pair = _pair_name(case, pair)
    end = t_end or case.solver.t_end
    if cycle_from is not None and not 0 <= cycle_from < end:
        raise CaseError("command line", "--cycle-from", f"expected a time in [0, {end:g}) s "
                        f"(the run's), got {cycle_from:g}")
    return pair


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
    good = [r for r in rows[1:] if r["regularized"] and r["rule"] not in ("fine", "case")
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
    # with friction a third panel: the limit cycle's RMS error, which a phase drift over a
    # long run leaves meaningful where error_rms saturates near 1 (a squeal's 20 ms)
    panels = [("error_rms", "kernel_s", "kernel"), ("error_rms", "total_s", "setup + kernel")]
    if any(np.isfinite(r.get("cycle_rms_error") or np.nan) for r in rows[1:]):
        panels.append(("cycle_rms_error", "kernel_s", "kernel"))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4.5))
    floor = 1e-6     # the reference's own error is 0: drawn at the floor
    markers = {"fine": "o", "centre": "s", "greedy": "^", "sampled": "D", "case": "*"}
    for ax, (metric, key, name) in zip(axes, panels):
        for row in rows:
            value = row.get(metric)
            if value is None or not np.isfinite(value):
                continue           # refused, or no motion to compare
            err = max(value, floor)
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
        ax.set_ylabel(f"{metric} vs {rows[0]['label']}")
        ax.grid(True, which="both", alpha=0.3)
    ref = rows[0]["label"]
    axes[0].set_ylabel(f"error_rms of the sensor histories vs {ref}")
    axes[1].set_ylim(axes[0].get_ylim())
    fig.suptitle("Contact rules: error against run time (open markers: not regularized; "
                 f"{ref} drawn at 1e-6)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

