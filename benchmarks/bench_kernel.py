"""Reduced contact kernels: time per step against a BLAS roofline, and time to accuracy.

A synthetic reduced system, seeded: n mass-normalized modes with 1 % modal damping, m contact
points on one exponential law (p0 = 1e4 Pa, lambda = 5e5 1/m, p_lin = 1e9 Pa) preloaded at 1 MPa
over 1e-3 m^2 (w = area / m, k_t* = lambda p at the preload gap g0), C (m, n) Gaussian with
column k scaled by omega_k so that the contact's part of the linearized stiffness,
C^T diag(w k_t*) C, stays below half of diag(omega^2) (the structure alone stays positive). A
constant load holds q = 0 in equilibrium, as the preload does in a run; the motion starts from
modal velocities decaying as f^-1/2 (a tap), scaled to a given RMS gap swing.

roofline: for each (n, m) of --sizes, interleaved and best of --repeat, per step: the least a
step needs with NumPy/BLAS (C @ q, np.exp on m values, C.T @ p, timed in a Python loop, so
about 1 us of call overhead per product is part of the roofline; BLAS threads as configured);
explicit_reduced on one row block and one Numba thread, and on one block per Numba thread
(dynamics.chunks.threaded_blocks); exponential_reduced with 0 and 1 corrections (1 and 2 contact passes per step),
on whichever blocks run faster. The threads run as in `transient run`: the OpenMP runtime is
the one its setup leaves serving Numba (MKL's libiomp5 when PARDISO factorized first), and two
threads spin between the steps' contact passes (`jit.spinning`). Issue target: explicit at or below the roofline at n = 300,
m = 1000, within 1.2x at every size.

accuracy: 40 modes 100 Hz - 5 kHz plus 4 at 20 - 80 kHz, m = 200, gap swing 0.5 / lambda, over
--t-end; explicit_reduced, newmark_reduced (tolerance 1e-10), exponential_reduced as PE
(corrections 0), PECE (corrections 1) and PEC (corrections 0, corrector propagated), each at a
sweep of steps, and solve_ivp (RK45, DOP853) at a sweep of rtol. Error: relative RMS of the gap
changes of 8 points at every --dt-out, against exponential_reduced (2 corrections) at
dt_out / --ref-k, itself compared with dt_out / (2 ref-k) (the self-error). Kernels run on one
row block and one Numba thread (threads do not pay at m = 200); explicit steps start at
2 / omega_max. solve_ivp integrates y = (q, v) with a NumPy right-hand side (two BLAS products
and an exp per call) and returns the outputs from its dense output (t_eval). Run time: wall
time of a call after a warm-up, setup included (exponential coefficients, Newmark's Z and G);
the best of up to --repeat calls within 1 s. On a machine loaded by other processes, multithreaded
OpenBLAS stalls in small LAPACK calls (seen: scipy's expm of the 4 x 4 exponential coefficients,
8 ms each instead of 10 us, and the Woodbury solves inside Newmark's iterations):
OPENBLAS_NUM_THREADS=1 gives steady figures there, and runs solve_ivp's BLAS on one thread as the
kernels are.

    python benchmarks/bench_kernel.py roofline [--sizes 100x300,300x1000] [--repeat 3] [--json]
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_kernel.py accuracy [--t-end 0.02 --dt-out 1e-4]
        [--json] [--png FILE]
"""
import argparse
import json
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numba
import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from transient.case.signals import compile_signals
from transient.case.specs import LawSpec, NewtonSpec
from transient.contact.contactset import ContactSet
from transient.contact.laws import law_params
from transient.dynamics import schemes
from transient.dynamics.chunks import threaded_blocks
from transient.dynamics.state import Rows, State
from transient.dynamics.system import ReducedSystem
from transient.kernels.codes import OK

LAW = LawSpec("exponential", p0=1e4, lam=5e5, p_lin=1e9)
PRELOAD = 1e6          # [Pa]
AREA = 1e-3            # [m^2]
ZETA = 0.01            # modal damping ratio
SHARE = 0.5            # largest share of a mode's stiffness carried by the contact
SENSORS = 8            # observed points
NEWTON_TOL, MAX_ITER = 1e-10, 50
TARGET_RATIO = 1.2     # explicit / roofline at every size
THRESHOLDS = (1e-2, 3e-3)
# exponential variants of the accuracy mode: (corrections, propagate)
EXPONENTIAL = {"exp c0 PE": (0, False), "exp c1 PECE": (1, False), "exp c0 PEC": (0, True)}
SIZES = [(n, m) for n in (100, 300, 600) for m in (300, 1000, 3000)]
BLAS_THREADS = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
ACCURACY_FREQS = np.r_[np.geomspace(100.0, 5e3, 40), np.geomspace(20e3, 80e3, 4)]


@dataclass
class System:
    omega2: np.ndarray
    damp: np.ndarray
    C: np.ndarray
    g0: np.ndarray
    w: np.ndarray
    kt0: np.ndarray
    code: np.ndarray
    params: np.ndarray
    P: np.ndarray          # (1, n) the preload's load pattern, on a constant signal
    sig: tuple
    S: np.ndarray          # (SENSORS, n) rows of C: outputs are gap changes
    state: np.ndarray      # (6, n) initial state, in the layout of dynamics.state.State


def contact_system(freqs, m, swing, seed):
    """The synthetic system at rest at the preload, with a tap giving an RMS gap swing of
    swing / lambda."""
    rng = np.random.default_rng(seed)
    n = len(freqs)
    omega = 2 * np.pi * np.asarray(freqs, float)
    code, law = law_params(LAW, 0.0)
    lam = LAW.lam
    w = np.full(m, AREA / m)
    kt0 = np.full(m, lam * PRELOAD)
    # Marchenko-Pastur: the Gram matrix of the Gaussian rows stays below (1 + sqrt(n/m))^2
    scale = omega * np.sqrt(SHARE / (AREA * kt0[0])) / (1 + np.sqrt(n / m))
    C = np.ascontiguousarray(rng.standard_normal((m, n)) * scale)
    v0 = rng.standard_normal(n) * np.sqrt(omega[0] / omega)
    v0 *= swing / lam / np.sqrt(np.mean(((C * (v0 / omega)) ** 2).sum(axis=1)))
    s = System(omega ** 2, 2 * ZETA * omega, C, np.full(m, -np.log(PRELOAD / LAW.p0) / lam),
               w, kt0, np.full(m, code, np.int64), np.tile(law, (m, 1)),
               np.ascontiguousarray(-(C.T @ (w * PRELOAD))[None, :]),
               compile_signals([{"kind": "constant"}]),
               np.ascontiguousarray(C[np.linspace(0, m - 1, SENSORS).astype(int)]), None)
    s.state = np.zeros((6, n))
    s.state[1] = v0
    forces = s.P[0] + remainder(s, s.state[0])
    s.state[2] = forces - s.damp * v0
    s.state[4] = s.state[5] = forces
    return s


def remainder(s, q):
    """C^T [w (p(g) + k_t* (g - g0))] with NumPy: two BLAS products and an exp."""
    p0, lam, g_lin = s.params[0, :3]
    d = s.C @ q
    g = s.g0 + d
    gl = np.maximum(g, g_lin)
    p = p0 * np.exp(-lam * gl) * (1.0 + lam * (gl - g))
    return s.C.T @ (s.w * (p + s.kt0 * d))


def reduced(s):
    """The synthetic system as the dynamics stage holds a reduced one."""
    contacts = ContactSet(sp.csr_matrix(s.C), s.g0, s.w, s.code, s.params,
                          {"bench": slice(0, len(s.g0))})
    return ReducedSystem(contacts, s.kt0, s.P, s.sig, s.S, (), 0, None, omega2=s.omega2,
                         damp=s.damp, C=s.C)


def stepper(s, scheme, dt, blocks, corrections=0, propagate=False, threads=0):
    """run(n_steps, every) integrating from the initial state -> (status, steps done, sensor
    outputs, kernel seconds); scheme: explicit, newmark or exponential (with its corrections
    and corrector, as solver.corrections and solver.corrector = propagated). The steppers are
    those of `transient run` (dynamics.schemes), called as it calls them on `threads` Numba
    threads (with more than one, spinning between the steps' parallel regions)."""
    system = reduced(s)
    if scheme == "explicit":
        step = schemes.explicit(system, dt, blocks)
    elif scheme == "newmark":
        step = schemes.implicit(system, dt, NewtonSpec(NEWTON_TOL, MAX_ITER), blocks=blocks)
    else:
        step = schemes.exponential(system, dt, corrections,
                                   "propagated" if propagate else "evaluated", None, blocks)
    step = replace(step, threads=threads)

    def run(n_steps, every):
        # the smallest gaps (explicit) and the previous forces (exponential) start afresh
        state = State(s.state.copy(), np.zeros(3), s.g0.copy())
        out = Rows.empty(n_steps // every, len(s.S), 0)
        t0 = time.perf_counter()
        status, done = step(state, n_steps, every, out)
        return status, done, out.sensors, time.perf_counter() - t0
    return run


# ---------------------------------------------------------------------------- roofline

def blas_step(s, steps):
    """Seconds per step of the NumPy minimum: C @ q, exp on m values, C.T @ p."""
    C, q = s.C, s.state[1].copy()
    g, p, f = np.empty(C.shape[0]), np.empty(C.shape[0]), np.empty(C.shape[1])
    t0 = time.perf_counter()
    for _ in range(steps):
        np.dot(C, q, out=g)
        np.exp(g, out=p)
        np.dot(C.T, p, out=f)
    return (time.perf_counter() - t0) / steps


@contextmanager
def numba_threads(k):
    before = numba.get_num_threads()
    numba.set_num_threads(k)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def kernel_step(run):
    def timer(steps):
        status, done, _, seconds = run(steps, steps)
        if status != OK or done != steps:
            raise RuntimeError(f"kernel stopped with status {status} after {done} steps")
        return seconds / steps
    return timer


def roofline_row(n, m, repeat, target_s, seed):
    s = contact_system(np.geomspace(100.0, 16e3, n), m, 0.1, seed)
    dt = 0.8 * 2.0 / np.sqrt(s.omega2.max())       # stable for the explicit scheme
    # one block on one thread (with more, the pool's threads take part even in one block)
    threaded = threaded_blocks(m)
    blocks = {"1": (np.array([0, m], np.int64), 1)}
    if len(threaded) > 2:
        blocks["threads"] = (threaded, numba.get_num_threads())
    timers = {"roofline": lambda steps: blas_step(s, steps)}
    for label, (b, threads) in blocks.items():
        timers[f"explicit_{label}"] = kernel_step(stepper(s, "explicit", dt, b,
                                                          threads=threads))
        for c in (0, 1):
            timers[f"exponential{c}_{label}"] = kernel_step(
                stepper(s, "exponential", dt, b, c, threads=threads))
    for timer in timers.values():
        timer(20)                                     # compilation, caches
    # steps per measurement: about target_s each (threads stalled by a busy machine run slow)
    steps = {key: int(np.clip(target_s / timer(20), 20, 2000)) for key, timer in timers.items()}
    best = dict.fromkeys(timers, np.inf)
    for _ in range(repeat):
        for key, timer in timers.items():
            best[key] = min(best[key], timer(steps[key]))
    us = {f"{key}_us": t * 1e6 for key, t in best.items()}
    explicit = min(us["explicit_1_us"], us.get("explicit_threads_us", np.inf))
    row = {"n": n, "m": m, "steps": steps, "blocks": len(threaded) - 1, **us,
           "ratio": explicit / us["roofline_us"]}
    for c in (0, 1):
        row[f"exponential{c}_us"] = min(us[f"exponential{c}_1_us"],
                                        us.get(f"exponential{c}_threads_us", np.inf))
    row["exponential1_pass_us"] = row["exponential1_us"] / 2
    return row


def roofline(sizes, repeat=3, target_s=0.1, seed=0):
    rows = [roofline_row(n, m, repeat, target_s, seed) for n, m in sizes]
    return {"cpu_count": os.cpu_count(), "numba_threads": numba.get_num_threads(),
            "openblas_num_threads": BLAS_THREADS, "load_average": os.getloadavg()[0],
            "rows": rows}


def print_roofline(result):
    print(f"os.cpu_count() = {result['cpu_count']}, numba threads = {result['numba_threads']}, "
          f"OPENBLAS_NUM_THREADS = {result['openblas_num_threads']} (BLAS threads not controlled "
          f"otherwise); 1-min load average at the end, this run included: "
          f"{result['load_average']:.2f}")
    rows = result["rows"]
    print(f"{'n':>4s} {'m':>5s} {'roof':>8s} {'expl 1':>8s} {'expl thr':>8s} {'ratio':>6s} "
          f"{'exp c0':>8s} {'exp c1':>8s} {'c1/pass':>8s}   [us per step]")
    for r in rows:
        threads = r.get("explicit_threads_us")
        print(f"{r['n']:4d} {r['m']:5d} {r['roofline_us']:8.1f} {r['explicit_1_us']:8.1f} "
              f"{threads if threads else float('nan'):8.1f} {r['ratio']:6.2f} "
              f"{r['exponential0_us']:8.1f} {r['exponential1_us']:8.1f} "
              f"{r['exponential1_pass_us']:8.1f}")
    above = [f"{r['n']}x{r['m']} ({r['ratio']:.2f})" for r in rows if r["ratio"] > TARGET_RATIO]
    print(f"ratio: best explicit / roofline; target <= 1 at 300x1000, <= {TARGET_RATIO} "
          f"everywhere; above {TARGET_RATIO}: {', '.join(above) or 'none'}")


# ---------------------------------------------------------------------------- accuracy

def rel_error(Y, ref):
    return float(np.sqrt(np.sum((Y - ref) ** 2) / np.sum(ref ** 2)))


def kernel_run(s, scheme, k, dt_out, N, corrections=0, propagate=False):
    """Outputs at every dt_out with dt = dt_out / k, wall time with the setup, steps, status."""
    t0 = time.perf_counter()
    run = stepper(s, scheme, dt_out / k, np.array([0, len(s.g0)], np.int64), corrections,
                  propagate)
    status, done, Y, _ = run(N * k, k)
    return Y, time.perf_counter() - t0, done, status


def ivp_run(s, method, rtol, dt_out, N):
    """solve_ivp on y = (q, v): outputs at every dt_out, wall time, nfev, status."""
    n = len(s.omega2)
    fext = s.P[0]

    def rhs(t, y):
        q, v = y[:n], y[n:]
        return np.concatenate((v, fext + remainder(s, q) - s.damp * v - s.omega2 * q))

    vmax = np.abs(s.state[1]).max()
    atol = rtol * np.r_[np.full(n, vmax / np.sqrt(s.omega2[0])), np.full(n, vmax)]
    times = dt_out * np.arange(1, N + 1)
    t0 = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, times[-1]), np.r_[s.state[0], s.state[1]], method=method,
                    t_eval=times, rtol=rtol, atol=atol)
    seconds = time.perf_counter() - t0
    return (s.S @ sol.y[:n]).T, seconds, sol.nfev, sol.status


def timed(fn, budget=1.0, repeat=3):
    """fn() -> (outputs, seconds, count, status): the best of up to `repeat` calls, while their
    total stays under `budget` seconds."""
    Y, seconds, count, status = fn()
    spent = seconds
    for _ in range(repeat - 1):
        if spent > budget:
            break
        again = fn()[1]
        spent += again
        seconds = min(seconds, again)
    return Y, seconds, count, status


def plan(s, dt_out, N, rtols, exp_ks, newmark_ks, explicit_factors):
    """(method, setting, fn) of every run."""
    k_min = int(np.ceil(dt_out * np.sqrt(s.omega2.max()) / 2.0))   # dt at most 2 / omega_max
    runs = [("explicit", f"dt={dt_out / (k_min * f):.3g}",
             lambda f=f: kernel_run(s, "explicit", k_min * f, dt_out, N))
            for f in explicit_factors]
    runs += [("newmark", f"dt={dt_out / k:.3g}",
              lambda k=k: kernel_run(s, "newmark", k, dt_out, N)) for k in newmark_ks]
    for name, (c, propagate) in EXPONENTIAL.items():
        runs += [(name, f"dt={dt_out / k:.3g}",
                  lambda k=k, c=c, p=propagate: kernel_run(s, "exponential", k, dt_out, N, c,
                                                           p)) for k in exp_ks]
    for method in ("RK45", "DOP853"):
        runs += [(method, f"rtol={rtol:.0e}",
                  lambda method=method, rtol=rtol: ivp_run(s, method, rtol, dt_out, N))
                 for rtol in rtols]
    return runs


def warm_up(s, dt_out):
    for scheme in ("explicit", "newmark", "exponential"):
        kernel_run(s, scheme, 1, dt_out, 1)
    for method in ("RK45", "DOP853"):
        ivp_run(s, method, 1e-3, dt_out, 1)


def time_to(runs, threshold):
    """The fastest run of each method with an error at or below threshold (None: none)."""
    out = {}
    for r in runs:
        ok = r["error"] is not None and r["error"] <= threshold
        best = out.get(r["method"])
        if ok and (best is None or r["seconds"] < best["seconds"]):
            out[r["method"]] = r
        else:
            out.setdefault(r["method"], None)
    return {method: r and {"seconds": r["seconds"], "setting": r["setting"],
                           "error": r["error"]} for method, r in out.items()}


def measure(method, setting, fn, ref, repeat):
    Y, seconds, count, status = timed(fn, repeat=repeat)
    ok = status == 0 and np.all(np.isfinite(Y))
    return {"method": method, "setting": setting, "seconds": seconds, "count": int(count),
            "status": int(status), "error": rel_error(Y, ref) if ok else None}


def accuracy(freqs=ACCURACY_FREQS, m=200, t_end=0.02, dt_out=1e-4, ref_k=200,
             rtols=(1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9), exp_ks=(1, 2, 4, 8, 16, 32),
             newmark_ks=(1, 2, 4, 8, 16, 32, 64), explicit_factors=(1, 2, 4, 8), repeat=3,
             seed=0):
    s = contact_system(freqs, m, 0.5, seed)
    N = int(round(t_end / dt_out))
    with numba_threads(1):
        warm_up(s, dt_out)
        ref = kernel_run(s, "exponential", 2 * ref_k, dt_out, N, 2)[0]
        coarse = kernel_run(s, "exponential", ref_k, dt_out, N, 2)[0]
        runs = [measure(method, setting, fn, ref, repeat) for method, setting, fn in
                plan(s, dt_out, N, rtols, exp_ks, newmark_ks, explicit_factors)]
    return {"n": len(freqs), "m": m, "t_end": N * dt_out, "dt_out": dt_out,
            "reference": {"dt": dt_out / (2 * ref_k), "self_error": rel_error(coarse, ref),
                          "swing_lambda": float(LAW.lam * np.abs(ref).max())},
            "runs": runs, "time_to": {f"{t:g}": time_to(runs, t) for t in THRESHOLDS},
            "load_average": os.getloadavg()[0], "openblas_num_threads": BLAS_THREADS}


def print_accuracy(result):
    ref = result["reference"]
    print(f"n = {result['n']}, m = {result['m']}, T = {result['t_end']:g} s, outputs every "
          f"{result['dt_out']:g} s; reference dt = {ref['dt']:.3g} s, self-error "
          f"{ref['self_error']:.1e}; largest gap change {ref['swing_lambda']:.2f} / lambda; "
          f"OPENBLAS_NUM_THREADS = {result['openblas_num_threads']}, 1-min load average at the "
          f"end {result['load_average']:.2f}")
    print(f"{'method':15s} {'setting':14s} {'time [s]':>9s} {'error':>9s} {'steps/nfev':>10s}")
    for r in result["runs"]:
        error = (f"{r['error']:9.2e}" if r["error"] is not None
                 else f"{'status ' + str(r['status']):>9s}")
        print(f"{r['method']:15s} {r['setting']:14s} {r['seconds']:9.4f} {error} {r['count']:10d}")
    print("fastest run reaching the error [s]:")
    print(f"{'method':15s} " + " ".join(f"{'<= ' + t:>24s}" for t in result["time_to"]))
    for method in next(iter(result["time_to"].values())):
        cells = []
        for best in (result["time_to"][t][method] for t in result["time_to"]):
            cells.append(f"{best['seconds']:8.4f} ({best['setting']})" if best else "-")
        print(f"{method:15s} " + " ".join(f"{c:>24s}" for c in cells))


def plot_accuracy(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5))
    for method in dict.fromkeys(r["method"] for r in result["runs"]):
        # in the order of the sweep (step or tolerance), not of the time
        pts = [(r["seconds"], r["error"]) for r in result["runs"]
               if r["method"] == method and r["error"] is not None]
        if pts:
            ax.loglog(*zip(*pts), "o-", label=method)
    for t in THRESHOLDS:
        ax.axhline(t, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("run time [s]")
    ax.set_ylabel("relative RMS error of the gap changes")
    ax.set_title(f"n = {result['n']}, m = {result['m']}, T = {result['t_end']:g} s")
    ax.legend()
    fig.savefig(path, dpi=120, bbox_inches="tight")


def production_runtime():
    """Load the OpenMP runtime `transient run` ends up with before Numba's pool starts: its
    factorization stage runs PARDISO (MKL's libiomp5) before the kernel's first parallel
    region. Without PARDISO installed the run, like this, has libgomp."""
    from transient.solve.linsolve import available, factorize
    if "pardiso" in available():
        factorize(sp.eye(4).tocsr(), "pardiso")(np.ones(4))


def main():
    production_runtime()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="mode", required=True)
    roof = sub.add_parser("roofline")
    roof.add_argument("--sizes", default=",".join(f"{n}x{m}" for n, m in SIZES),
                      help="n x m pairs, comma separated")
    roof.add_argument("--target-s", type=float, default=0.1,
                      help="roofline time of one measurement (sets the steps, 20 to 2000)")
    acc = sub.add_parser("accuracy")
    acc.add_argument("--t-end", type=float, default=0.02)
    acc.add_argument("--dt-out", type=float, default=1e-4)
    acc.add_argument("--ref-k", type=int, default=200)
    acc.add_argument("--png")
    for p in (roof, acc):
        p.add_argument("--repeat", type=int, default=3)
        p.add_argument("--seed", type=int, default=0)
        p.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.mode == "roofline":
        sizes = [tuple(map(int, size.split("x"))) for size in args.sizes.split(",")]
        result = roofline(sizes, args.repeat, args.target_s, args.seed)
        if args.json:
            print(json.dumps(result, indent=1))
        else:
            print_roofline(result)
        return
    result = accuracy(t_end=args.t_end, dt_out=args.dt_out, ref_k=args.ref_k,
                      repeat=args.repeat, seed=args.seed)
    if args.png:
        plot_accuracy(result, args.png)
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print_accuracy(result)


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
