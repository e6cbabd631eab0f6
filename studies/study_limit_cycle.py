"""The limit cycle of cases/pad_disc_squeal.toml at dt and dt/2: the sensors' RMS and
frequency, whether they are stationary, and the energy balance cycle by cycle (the issue's
"RMS changes by less than 1% when dt is halved" and "over a cycle the friction input balances
the dissipation within 1%").

Each step is run by `transient run` in a child process, one after the other, with output.every
= 1, output.field = true and output.contact = true: every step is a row, so the row trapezoids
below are the kernel's own step sums, and the state q of each row gives the loads' and the
friction's work as the scheme books them. The histories stay in --out (dt_<dt>.h5) and are
reused for the same case text and overrides when complete (under any drift tolerance: it only
stops a run) or aborted (a rerun would abort again); other overrides rerun over them, so give
each set of --set its own --out.

The window is [--cycle-from, t_end], cut where the shortest run stops (an aborted one), the
same for every dt. The growth must have saturated by its start: the --sensor's envelope (RMS
in 0.5 ms blocks) grows there at less than a tenth of its peak rate and has reached 90% of the
window's RMS, or a warning line says so; its trend over the window is printed too.

- RMS: of each sensor's motion about its mean over the window, and over consecutive --sub
  windows (each about its own mean), whose spread (max - min) / mean says how stationary the
  limit cycle is. The change from dt to dt/2, on the window and each sub-window, is the first
  acceptance point.
- frequency: the peak of the window's spectrum (Hann, zero-padded 16x, a parabola through the
  log magnitudes) of each sensor.
- cycles: from one up-crossing of the --sensor's motion about its running mean (over one
  period of its frequency: the pad's mean position wanders) to the next, with a hysteresis of
  a quarter of its RMS so that harmonics do not cut a period; the balance below holds over
  any interval, the cycles only make dE small. Per cycle [J]:
    input    the sliding's input, integral of sum w p c s_t V (contact.friction.friction_powers
             on the stored pressures and slips, trapezoid on the rows);
    slip     the slip's dissipation, integral of sum w p c |s|^2 (the same);
    net      input - slip: the friction's work on the structure, what feeds the vibration;
    damping  the modal damping's dissipation. energy/dissipated holds damping + the friction's
             dissipation as the scheme books it (kernels.friction.friction_energy: its input
             less sum 1/2 (ff0 + ff) . dq), energy/external_work the loads' work + the
             friction's input; with ff from the stored tractions and rows Ct, Cc, and the
             loads' work from F(t) and the stored q: damping = d dissipated - d external_work
             + loads + friction work, exact for every = 1 (the kernel's own sums);
    loads    the loads' work, sum 1/2 (F0 + F) . dq: the piston's 1 MPa on the pad's motion,
             several mJ either way over a cycle that is not exactly periodic;
    dE       the change of kinetic + strain + contact energy;
    E        2 x the mean kinetic energy over the cycle: the vibration's energy.
  The balance residual R = input + loads - slip - damping - dE, against three scales:
    input          the second acceptance point read literally. The steady sliding's ~1 kW
                   goes in and out through the slip on both sides, so this holds even with no
                   vibration; it is the weak reading;
    mean net       the window's mean net friction work per cycle, the energy flow that
                   sustains the limit cycle (a cycle's own net passes near 0 at times): the
                   reading that tests the vibration's balance, the one that matters;
    2 pi E         an error on the cycle's loss factor.
  R = friction_error + K: friction_error = net - friction work, the continuous slip power
  against the scheme's friction work (a time discretization error), and K = d external_work -
  d dissipated - dE, the kernel's own balance error (the drift the run checks), reported per
  cycle and over the window.
- kernel: us/step of each run (timings/kernel over its steps; the median per thread count that
  dynamics.chunks.ThreadChoice keeps), slowed by anything else on the machine.

    python studies/study_limit_cycle.py [CASE] [--t-end 0.106] [--dt 3.125e-6 1.5625e-6]
        [--cycle-from 0.1] [--sub 0.002] [--sensor pad_back] [--drift-tolerance X]
        [--out /tmp/limit_cycle] [--set key=value ...] [--cycles] [--json]
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PAIR = "pad_disc"
ENVELOPE = 5e-4          # [s] blocks of the envelope for the saturation check


TOLERANCE = "solver.drift_tolerance="


def overrides(t_end, dt, every, tolerance, sets):
    """The run's --set list: ours first, so that the user's passthrough ones win."""
    ours = [f"solver.t_end={t_end!r}", f"solver.dt={dt!r}", f"output.every={every}",
            "output.field=true", "output.contact=true"]
    return ours + ([] if tolerance is None else [f"{TOLERANCE}{tolerance!r}"]) + sets


def cached(path, case, sets):
    """The stored status if the history at path is a finished run of this case text with
    these overrides, else None (missing, running or killed, interrupted, another case)."""
    from transient.io.attributes import CASE_TEXT, read_attrs
    if not path.exists():
        return None
    try:
        with h5py.File(path, "r", locking=False) as f:
            meta = read_attrs(f.attrs)
    except (OSError, ValueError, KeyError):
        return None
    status = str(meta.get("status", ""))
    stored = list(meta.get("overrides") or [])
    if meta.get(CASE_TEXT) != Path(case).read_text():
        return None
    # the drift tolerance only decides whether a run stops: a complete run is the same run
    # under any; an abort repeats on a rerun with the same overrides (deterministic), a
    # Ctrl-C or a kill does not
    if status == "complete":
        def strip(o):
            return [x for x in o if not x.startswith(TOLERANCE)]
        return status if strip(stored) == strip(sets) else None
    if status.startswith("aborted: ") and "interrupt" not in status and stored == sets:
        return status
    return None


def run(case, path, sets):
    """`transient run` of case into path in a child process; its stderr's last line if it
    failed (an aborted run keeps its rows and says why in its status)."""
    args = [sys.executable, "-m", "transient", "run", str(case), "-o", str(path), "--quiet"]
    for s in sets:
        args += ["--set", s]
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    return None if done.returncode == 0 else (lines[-1] if lines else f"rc {done.returncode}")


def rms(x):
    return float(np.sqrt(np.mean((x - x.mean()) ** 2)))


def peak_frequency(x, h, pad=16):
    """The spectrum peak [Hz] of x sampled at h: Hann window, zero-padded, a parabola through
    the log magnitudes of the largest bin and its neighbours."""
    n = len(x)
    nfft = pad * (1 << int(np.ceil(np.log2(n))))
    mag = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(n), nfft))
    k = 1 + int(np.argmax(mag[1:-1]))
    a, b, c = np.log(mag[k - 1:k + 2] + 1e-300)
    shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
    return float((k + shift) / (nfft * h))


def up_crossings(x, level):
    """Rows where x crosses 0 upwards, counted only after it has been below -level since the
    last one (harmonics and noise near 0 do not cut a cycle)."""
    rows, armed = [], False
    for r in range(1, len(x)):
        if x[r] < -level:
            armed = True
        elif armed and x[r - 1] < 0.0 <= x[r]:
            rows.append(r)
            armed = False
    return np.array(rows, dtype=int)


def step_works(f, rows):
    """Per step r -> r+1 of the stored rows: the loads' work 1/2 (F_r + F_r+1) . dq and the
    friction's 1/2 (ff_r + ff_r+1) . dq (kernels.friction.friction_energy), and the rows'
    sliding input and slip dissipation powers [W]."""
    from transient.contact.friction import friction_powers, traction_factor
    from transient.io.systems import read_friction_law, read_system
    from transient.kernels.signals import signal_values
    system = read_system(f)
    law = read_friction_law(f, PAIR)
    s = system.contacts.slices[PAIR]
    weights = f[f"geometry/contact/{PAIR}/weights"][()]
    q = f["field/q"][:rows]
    press = f[f"contact/{PAIR}/pressure"][:rows]
    slip = f[f"contact/{PAIR}/slip"][:rows]
    t = f["time"][:rows]
    p_in, p_slip = friction_powers(law, weights, press, slip)
    dq = np.diff(q, axis=0)
    # the loads F(t) = patterns^T s(t), as the kernels evaluate them
    sig, values = system.signals, np.empty(len(system.patterns))
    F = np.empty((rows, system.n))
    for r in range(rows):
        signal_values(t[r], *sig, values)
        F[r] = values @ system.patterns
    loads = 0.5 * np.einsum("ij,ij->i", F[1:] + F[:-1], dq)
    # ff . dq = tau_t . (Ct dq) + tau_c . (Cc dq), tau = w p c s (the kernel's traction)
    code, v_eps, table, tables, _ = law
    c = traction_factor(code, v_eps, table, tables, np.hypot(slip[:, 0], slip[:, 1]))
    wpc = weights * np.maximum(press, 0.0) * c
    tau_t, tau_c = wpc * slip[:, 0], wpc * slip[:, 1]
    along = dq @ system.Ct[s].T
    across = dq @ system.Cc[s].T
    friction = 0.5 * (np.einsum("ij,ij->i", tau_t[1:] + tau_t[:-1], along)
                      + np.einsum("ij,ij->i", tau_c[1:] + tau_c[:-1], across))
    return loads, friction, p_in, p_slip


def analyse(path, args, t_stop):
    """The limit cycle of one stored run over [cycle_from, t_stop] (see the module
    docstring)."""
    from transient.contact.friction import STATUS_NAMES, contact_status
    from transient.io.reading import summary
    info = summary(path)
    meta = info["meta"]
    out = {"file": str(path), "status": info["status"], "dt": meta["dt"],
           "every": meta["every"], "t_reached": info["t_end"]}
    steps = (info["steps"] - 1) * meta["every"]
    timings = info["timings"]
    out["steps"] = steps
    out["kernel_s"] = timings.get("kernel")
    out["us_per_step"] = (1e6 * timings["kernel"] / steps if timings.get("kernel") and steps
                          else None)
    # thread count -> [steps, median us/step] (dynamics.chunks.ThreadChoice)
    out["kernel_threads"] = timings.get("kernel_threads")
    out["energy_drift"] = info["energy_drift"]
    with h5py.File(path, "r", locking=False) as f:
        t = f["time"][:info["steps"]]
        h = float(np.median(np.diff(t)))
        if t_stop < args.cycle_from + args.sub:
            out["error"] = (f"the window [{args.cycle_from:g}, {t_stop:.4g}] s is shorter "
                            "than a sub-window")
            return out
        w0 = int(np.searchsorted(t, args.cycle_from - 0.25 * h))
        rows = int(np.searchsorted(t, t_stop + 0.25 * h))
        t = t[:rows]
        sensors = {name: f[f"sensors/{name}"][:rows] for name in f["sensors"]}
        energy = {name: f[f"energy/{name}"][:rows] for name in f["energy"]}
        gap = f[f"contact/{PAIR}/gap"][w0:rows]
        slip = f[f"contact/{PAIR}/slip"][w0:rows]
        weights = f[f"geometry/contact/{PAIR}/weights"][()]
        v_eps = f["system/contacts/friction/v_eps"][()]
        loads, friction, p_in, p_slip = step_works(f, rows)
    tw = t[w0:]
    out["window"] = [float(tw[0]), float(tw[-1])]

    # the sensors: RMS over the window and its sub-windows, the spectrum peak
    out["sensors"] = {}
    n_sub = int(np.floor((tw[-1] - tw[0] + 0.5 * h) / args.sub))
    for name, x in sensors.items():
        xw = x[w0:]
        parts = [xw[(tw >= tw[0] + k * args.sub - 0.5 * h)
                    & (tw < tw[0] + (k + 1) * args.sub - 0.5 * h)] for k in range(n_sub)]
        subs = [rms(p) for p in parts]
        out["sensors"][name] = {
            "rms": rms(xw), "mean": float(xw.mean()), "sub_rms": subs,
            "sub_spread": float((max(subs) - min(subs)) / np.mean(subs)),
            "frequency_hz": peak_frequency(xw, h),
            "sub_frequency_hz": [peak_frequency(p, h) for p in parts]}
    # saturation: the main sensor's envelope (RMS in blocks) over the whole run
    x = sensors[args.sensor]
    blocks = int(round(ENVELOPE / h))
    nb = len(x) // blocks
    env = np.array([rms(x[k * blocks:(k + 1) * blocks]) for k in range(nb)])
    t_env = (np.arange(nb) + 0.5) * blocks * h + t[0]
    log_env = np.log(np.maximum(env, 1e-300))
    rate = np.diff(log_env) / (blocks * h)
    t_rate = 0.5 * (t_env[1:] + t_env[:-1])
    near = int(np.argmin(np.abs(t_rate - args.cycle_from)))
    level = out["sensors"][args.sensor]["rms"]
    reached = np.flatnonzero(env >= 0.9 * level)
    out["saturation"] = {"peak_rate": float(rate.max()), "rate_at_window": float(rate[near]),
                         "t_90": float(t_env[reached[0]]) if len(reached) else None}
    # the envelope's trend over the window (a limit cycle: 0), from a line through its log
    on = t_env >= tw[0]
    out["saturation"]["trend_in_window"] = (float(np.polyfit(t_env[on], log_env[on], 1)[0])
                                            if on.sum() > 1 else None)
    out["saturated"] = bool(abs(rate[near]) < 0.1 * rate.max() and len(reached)
                            and t_env[reached[0]] <= args.cycle_from)
    # what the contact does in the window: area shares open, sticking, slipping
    status = contact_status(gap, slip, v_eps)
    out["contact_shares"] = {name: float((weights * (status == k)).sum(axis=1).mean()
                                         / weights.sum())
                             for k, name in enumerate(STATUS_NAMES)}

    # the cycles and their energies
    # the motion about its running mean over a period (the pad's mean position wanders, and
    # a fixed mean misses crossings where it does), where a whole period fits in the window
    n = int(round(1.0 / (out["sensors"][args.sensor]["frequency_hz"] * h)))
    xw = x[w0:] - np.convolve(x[w0:], np.ones(n) / n, mode="same")
    edge = n // 2 + 1
    cuts = w0 + edge + up_crossings(xw[edge:-edge], 0.25 * level)
    mech = energy["kinetic"] + energy["strain"] + energy["contact"]
    work, diss = energy["external_work"], energy["dissipated"]
    cum = {"loads": np.concatenate([[0.0], np.cumsum(loads)]),
           "friction": np.concatenate([[0.0], np.cumsum(friction)])}
    dt_rows = np.diff(t)
    cum["input"] = np.concatenate([[0.0], np.cumsum(0.5 * dt_rows * (p_in[1:] + p_in[:-1]))])
    cum["slip"] = np.concatenate([[0.0], np.cumsum(0.5 * dt_rows * (p_slip[1:] + p_slip[:-1]))])
    cycles = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        d = {k: float(v[b] - v[a]) for k, v in cum.items()}
        d_work, d_diss, d_mech = (float(s[b] - s[a]) for s in (work, diss, mech))
        kernel_input = d_work - d["loads"]
        damping = d_diss - kernel_input + d["friction"]
        net = d["input"] - d["slip"]
        resid = d["input"] + d["loads"] - d["slip"] - damping - d_mech
        check = d_work - d_diss - d_mech
        e_vib = 2.0 * float(np.mean(energy["kinetic"][a:b + 1]))
        cycles.append({
            "t0": float(t[a]), "period": float(t[b] - t[a]), "input": d["input"],
            "slip": d["slip"], "net": net, "damping": damping, "loads": d["loads"],
            "dE": d_mech, "friction_work": d["friction"], "friction_error": net - d["friction"],
            "E_vib": e_vib,
            "residual": resid, "kernel_check": check,
            "input_vs_kernel": abs(d["input"] - kernel_input) / abs(kernel_input),
            "R_input": abs(resid) / d["input"], "R_energy": abs(resid) / (2 * np.pi * e_vib),
            "K_input": abs(check) / d["input"]})
    # against the mean net work of a cycle: a cycle's own net passes through 0 at times
    flow = abs(np.mean([c["net"] for c in cycles]))
    for c in cycles:
        c["R_net"], c["K_net"] = abs(c["residual"]) / flow, abs(c["kernel_check"]) / flow
    out["cycles"] = cycles
    a, b = w0, rows - 1
    d_in = float(cum["input"][b] - cum["input"][a])
    d_net = d_in - float(cum["slip"][b] - cum["slip"][a])
    check = float((work[b] - work[a]) - (diss[b] - diss[a]) - (mech[b] - mech[a]))
    # the run's own drift measure (dynamics.energy) at the window's start and end
    total = mech - work + diss
    peak = float(np.max(np.abs(energy["kinetic"][:rows]) + np.abs(energy["strain"][:rows])
                        + np.abs(energy["contact"][:rows])))
    out["window_balance"] = {"input": d_in, "net": d_net, "kernel_check": check,
                             "K_input": abs(check) / d_in, "K_net": abs(check) / abs(d_net),
                             "drift_start": float(abs(total[a] - total[0]) / peak),
                             "drift_end": float(abs(total[b] - total[0]) / peak)}
    return out


def stats(cycles, key):
    v = np.array([c[key] for c in cycles])
    return {"mean": float(v.mean()), "max": float(np.abs(v).max()), "min": float(v.min())}


def compare(runs):
    """The relative changes of each later run from the first (dt -> dt/2 ...)."""
    ref = runs[0]
    out = []
    for r in runs[1:]:
        if "error" in r or "error" in ref:
            continue
        row = {"dt": r["dt"], "ref_dt": ref["dt"], "sensors": {}}
        for name, s in r["sensors"].items():
            s0 = ref["sensors"][name]
            n = min(len(s["sub_rms"]), len(s0["sub_rms"]))
            row["sensors"][name] = {
                "rms_change": s["rms"] / s0["rms"] - 1,
                "sub_rms_change": [s["sub_rms"][k] / s0["sub_rms"][k] - 1 for k in range(n)],
                "frequency_change": s["frequency_hz"] / s0["frequency_hz"] - 1}
        out.append(row)
    return out


def print_report(args, runs, changes):
    stop = min(r.get("window", [0, args.t_end])[1] for r in runs)
    cut = "" if stop > args.t_end - 1e-9 else f" (cut from {args.t_end:g} s: a run stopped)"
    print(f"{Path(args.case).name}: window [{args.cycle_from:g}, {stop:.4g}] s{cut}, cycles "
          f"on {args.sensor}'s up-crossings, sub-windows of {args.sub * 1e3:g} ms")
    for r in runs:
        dt = f"dt {r['dt']:.5g} s"
        threads = r.get("kernel_threads") or {}
        med = ", ".join(f"{k} thread(s) {v[1]:.0f}" for k, v in sorted(threads.items()))
        us = "n/a" if r["us_per_step"] is None else f"{r['us_per_step']:.0f}"
        print(f"\n{dt}: {r['status']}, {r['steps']} steps to t = {r['t_reached']:.5g} s, kernel "
              f"{us} us/step (median {med}), energy drift {r['energy_drift']:.2e}")
        if "error" in r:
            print(f"  {r['error']}")
            continue
        sat = r["saturation"]
        t90 = "never" if sat["t_90"] is None else f"from t = {sat['t_90'] * 1e3:.2f} ms"
        print(f"  envelope of {args.sensor}: peak growth {sat['peak_rate']:.0f} 1/s, "
              f"{sat['rate_at_window']:.0f} 1/s at {args.cycle_from:g} s, 90% of the window "
              f"RMS {t90}, trend in the window {sat['trend_in_window']:.1f} 1/s")
        if not r["saturated"]:
            print(f"  WARNING: the growth has not saturated by {args.cycle_from:g} s")
        sh = r["contact_shares"]
        print("  contact area in the window: " + ", ".join(f"{k} {100 * v:.1f}%"
                                                         for k, v in sh.items()))
        print(f"  {'sensor':>10} {'RMS [m]':>11} {'mean [m]':>11} {'f [Hz]':>9} "
              f"{'spread':>7}  sub-window RMS [m]")
        for name, s in r["sensors"].items():
            print(f"  {name:>10} {s['rms']:11.4e} {s['mean']:11.3e} {s['frequency_hz']:9.1f} "
                  f"{100 * s['sub_spread']:6.2f}%  "
                  + " ".join(f"{v:.4e}" for v in s["sub_rms"]))
            print(f"  {'':>10} {'':>11} {'':>11} {'':>9} {'':>7}  f [Hz]    "
                  + " ".join(f"{v:10.1f}" for v in s["sub_frequency_hz"]))
        cyc = r["cycles"]
        period = stats(cyc, "period")
        print(f"  {len(cyc)} cycles, period {1e6 * period['mean']:.2f} us ({1e6 * period['min']:.1f}"
              f" .. {1e6 * period['max']:.1f}); per cycle [mJ] mean (min .. max):")
        for key in ("input", "slip", "net", "damping", "loads", "dE", "E_vib", "residual",
                    "friction_error", "kernel_check"):
            s = stats(cyc, key)
            print(f"    {key:>13} {1e3 * s['mean']:12.5g} ({1e3 * s['min']:.5g} .. "
                  f"{1e3 * np.max([c[key] for c in cyc]):.5g})")
        print("  balance errors per cycle, mean / max:")
        for key, what in (("R_input", "|R| / input"), ("R_net", "|R| / mean net"),
                          ("R_energy", "|R| / (2 pi E)"), ("K_input", "|K| / input"),
                          ("K_net", "|K| / mean net"), ("input_vs_kernel",
                                                     "stored input vs kernel's")):
            s = stats(cyc, key)
            print(f"    {what:>24} {s['mean']:.2e} / {s['max']:.2e}")
        wb = r["window_balance"]
        print(f"  window: input {wb['input']:.4g} J, net {1e3 * wb['net']:.4g} mJ, kernel "
              f"check {wb['kernel_check']:.3e} J ({wb['K_input']:.2e} of input, "
              f"{wb['K_net']:.2e} of |net|); the run's drift {wb['drift_start']:.2e} at the "
              f"window's start, {wb['drift_end']:.2e} at its end")
        if args.cycles:
            print(f"    {'t0 [ms]':>8} {'input':>10} {'slip':>10} {'net':>9} {'damping':>9} "
                  f"{'loads':>9} {'dE':>9} {'R/in':>8} {'R/mnet':>8} {'R/2piE':>8}  [mJ]")
            for c in cyc:
                print(f"    {1e3 * c['t0']:8.4f} {1e3 * c['input']:10.4f} "
                      f"{1e3 * c['slip']:10.4f} {1e3 * c['net']:9.5f} {1e3 * c['damping']:9.5f} "
                      f"{1e3 * c['loads']:9.5f} {1e3 * c['dE']:9.5f} {c['R_input']:8.1e} "
                      f"{c['R_net']:8.1e} {c['R_energy']:8.1e}")
    for row in changes:
        print(f"\ndt {row['ref_dt']:.5g} -> {row['dt']:.5g} s:")
        for name, s in row["sensors"].items():
            print(f"  {name:>10}: RMS {100 * s['rms_change']:+.2f}%, frequency "
                  f"{100 * s['frequency_change']:+.3f}%; sub-windows "
                  + " ".join(f"{100 * v:+.2f}%" for v in s["sub_rms_change"]))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases" / "pad_disc_squeal.toml"))
    parser.add_argument("--t-end", type=float, default=0.106)
    parser.add_argument("--dt", type=float, nargs="+", default=[3.125e-6, 1.5625e-6])
    parser.add_argument("--cycle-from", type=float, default=0.1,
                        help="start of the limit-cycle window [s]")
    parser.add_argument("--sub", type=float, default=0.002, help="sub-window length [s]")
    parser.add_argument("--sensor", default="pad_back", help="the sensor whose up-crossings "
                        "cut the cycles, and whose envelope shows the saturation")
    parser.add_argument("--drift-tolerance", type=float, help="solver.drift_tolerance of the "
                        "runs (the case's by default: 0.05 of the largest energy held or "
                        "exchanged)")
    parser.add_argument("--every", type=int, default=1, help="steps per stored row (1: the "
                        "row sums are the kernel's; more makes the damping approximate)")
    parser.add_argument("--out", default="/tmp/limit_cycle", help="directory of the histories")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--cycles", action="store_true", help="print every cycle")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for dt in args.dt:
        path = out_dir / f"dt_{dt!r}.h5"
        sets = overrides(args.t_end, dt, args.every, args.drift_tolerance, args.set)
        if cached(path, args.case, sets) is None:
            print(f"running dt = {dt!r} s into {path}", file=sys.stderr, flush=True)
            failed = run(args.case, path, sets)
            if failed and cached(path, args.case, sets) is None:
                sys.exit(f"transient run failed at dt = {dt!r}: {failed}")
        paths.append(path)
    from transient.io.reading import summary
    # one window for every run: up to where the shortest (an aborted one) stops
    t_stop = min([args.t_end] + [summary(p)["t_end"] for p in paths])
    runs = [analyse(p, args, t_stop) for p in paths]
    changes = compare(runs)
    if args.json:
        print(json.dumps({"case": str(args.case), "cycle_from": args.cycle_from,
                          "t_end": args.t_end, "runs": runs, "changes": changes}))
        return
    print_report(args, runs, changes)


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
