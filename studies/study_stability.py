"""Stability study of `transient run`: every outcome is stable, refused or aborted, never a crash.

Each scenario runs the real command line in a child process (`python -m transient run CASE -o
FILE --quiet --json --set ...`), so a crash, a signal or a traceback is seen as such, then the
history file is opened with h5py and every dataset read. An outcome is exactly one of:

  stable    exit 0, status complete, every value of every dataset finite, energy drift finite
            and within solver.drift_tolerance (reported with the steps);
  refused   exit 2, stderr one line starting with 'error:', no traceback, no history file (or
            one without rows);
  aborted   exit 3, status 'aborted: <reason>', every stored value finite (series and
            checkpoint), rows stored (or a reason saying why none);
  FAILED    anything else (a traceback, another exit code or a signal, a NaN in a complete
            file, a refusal of more than one line, a timeout...), with the evidence.

Axes (the issue's): the exponential law's lambda over 4 decades and p0 over 3 on the small pad
on a disc (exponential scheme; cases/pad_disc.toml shrunk to a ~1 s setup), on the bar hitting
a wall (cases/bar_impact.toml, explicit, exponential wall law) and on two bars; dt from 0.1 to
1.2 times the critical step of the explicit bar (from a first run's JSON), with and without
solver.force_dt; a bar started penetrating the wall by 1, 10 and 100 / lambda (and the linear
law by the same depths); impact speeds 1, 10 and 50 m/s; a fully open start (wall out of
reach) and scenes without any [contact] table; eps from 1e-12 to 1 on the regularized pad (fine,
greedy and sampled rules); greedy m from 1 to the rank (0) and above the fine rule's points; the
sampled rule's tolerance from 1 (one point) to 1e-8, and capped at one point; taps of 4 and
8 kN on the pad (pressed by 4.4 kN) with the evaluated and the implicit corrector; the implicit
scheme on the full bar and the reduced pad. Case variants go to a temporary directory
(--keep DIR keeps them with the histories, so each row's command reruns as printed).

--quick runs a few scenarios per axis (tests/test_stability.py pins their outcomes). The exit
code is 1 when any outcome is FAILED.

    python studies/study_stability.py [--quick] [--only TEXT] [--keep DIR] [--json]
"""
import argparse
import json
import math
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))      # transient.history and transient.case, run from anywhere
CASES = ROOT / "cases"
TIMEOUT_S = 300.0
DEFAULT_DRIFT_TOLERANCE = 0.05     # solver.drift_tolerance's default (transient/schema.py)

# cases/pad_disc.toml at a ~1 s setup (582 fine contact points, 16 reduced dofs)
SMALL_PAD = ["parts.disc.mesh.divisions=[2,36,1]", 'parts.disc.mesh.element="hex8"',
             "parts.pad.mesh.divisions=[3,8,1,1]", 'parts.pad.mesh.element="hex8"',
             "solver.reduction.fmax=6000.0", "solver.modes.fmax=6000.0"]
PAD_FINE_POINTS = 582              # the small pad's fine rule (`transient compat`)
BAR_LENGTH = 0.1                   # cases/bar_impact.toml: the bar's end at x = 0.1 m
LAMBDA_BAR = 1e6                   # the bar's exponential wall law when lambda is not swept
EXP = 'contact.wall.law.kind="exponential"'


def without_tables(text, prefix):
    """TOML text without the tables [prefix] and [prefix.*] (a scene without contact)."""
    out, skipping = [], False
    for line in text.splitlines():
        header = re.match(r"\s*\[\[?\s*([^\]]+?)\s*\]", line)
        if header:
            name = header.group(1)
            skipping = name == prefix or name.startswith(prefix + ".")
        if not skipping:
            out.append(line)
    return "\n".join(out) + "\n"


def bases(directory):
    """Case files of the scenarios: the shipped ones as they are, the variants written out."""
    bar = (CASES / "bar_impact.toml").read_text()
    pad = (CASES / "pad_disc.toml").read_text()
    written = {"bar_free.toml": without_tables(bar, "contact"),
               "pad_free.toml": without_tables(pad, "contact"),
               "two_bars.toml": (CASES / "two_bars.toml").read_text()
               + "\n[output]\ncontact = true\n"}
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    for name, text in written.items():
        (directory / name).write_text(text)
    return {"bar": CASES / "bar_impact.toml", "pad": CASES / "pad_disc.toml",
            "bar_free": directory / "bar_free.toml", "pad_free": directory / "pad_free.toml",
            "two_bars": directory / "two_bars.toml"}


@dataclass
class Scenario:
    axis: str
    name: str                    # unique within the axis; the row's id is axis/name
    base: str                    # a key of bases()
    settings: list               # --set assignments after the base's own
    quick: bool = False          # part of the --quick subset
    dt_factor: float = None      # solver.dt = dt_factor x the bar's critical step
    probe: bool = False          # the run that gives the critical step

    @property
    def id(self):
        return f"{self.axis}/{self.name}"

    def base_settings(self):
        return list(SMALL_PAD) if self.base in ("pad", "pad_free") else []


def _g(x):
    return f"{x:.0e}".replace("e+0", "e").replace("e-0", "e-")


def scenarios():
    """Every scenario of the study, the --quick ones flagged."""
    S = []

    def add(*args, **kwargs):
        S.append(Scenario(*args, **kwargs))
    # the explicit bar at its automatic step (0.9 x critical, or less where the penalty's own
    # oscillator asks: dynamics.critical.CONTACT_OMEGA_DT): gives the critical step. The
    # shipped bar's contact step is 0.56 x critical: 0.9x is refused unless forced
    add("dt", "auto", "bar", [], quick=True, probe=True)
    for f in (0.1, 0.5, 0.9, 1.0, 1.1, 1.2):
        add("dt", f"{f}x", "bar", [], quick=f in (0.5, 0.9, 1.2), dt_factor=f)
        add("dt", f"{f}x forced", "bar", ["solver.force_dt=true"], quick=f in (0.9, 1.2),
            dt_factor=f)
    for lam in (1e4, 1e5, 1e6, 1e7, 1e8):
        add("lambda", f"bar lambda={_g(lam)}", "bar",
            [EXP, f"contact.wall.law.lambda={lam!r}"], quick=lam in (1e4, 1e8))
        add("lambda", f"pad lambda={_g(lam)}", "pad",
            [f"contact.pad_disc.law.lambda={lam!r}"], quick=lam == 1e8)
    for lam in (1e4, 1e8):
        add("lambda", f"two bars lambda={_g(lam)}", "two_bars",
            ['contact.impact.law.kind="exponential"', f"contact.impact.law.lambda={lam!r}"])
    for p0 in (1e3, 1e4, 1e5, 1e6):
        add("p0", f"bar p0={_g(p0)}", "bar",
            [EXP, f"contact.wall.law.lambda={LAMBDA_BAR!r}", f"contact.wall.law.p0={p0!r}"],
            quick=p0 == 1e6)
        add("p0", f"pad p0={_g(p0)}", "pad", [f"contact.pad_disc.law.p0={p0!r}"],
            quick=p0 == 1e3)
    # the bar at rest, started penetrating the wall by n / lambda (or the same depth, linear)
    for n in (1, 10, 100):
        depth = n / LAMBDA_BAR
        wall = [f"contact.wall.wall_point=[{BAR_LENGTH - depth!r}, 0.0, 0.0]",
                "initial.impact.velocity=[0.0, 0.0, 0.0]"]
        add("penetration", f"exponential {n}/lambda", "bar",
            [EXP, f"contact.wall.law.lambda={LAMBDA_BAR!r}"] + wall, quick=n == 100)
        add("penetration", f"linear {_g(depth)} m", "bar", wall, quick=n == 100)
    add("penetration", "exponential 100/lambda, lambda=1e4", "bar",
        [EXP, "contact.wall.law.lambda=1e4",
         f"contact.wall.wall_point=[{BAR_LENGTH - 1e-2!r}, 0.0, 0.0]",
         "initial.impact.velocity=[0.0, 0.0, 0.0]"])
    for v in (1.0, 10.0, 50.0):
        add("speed", f"linear {v:g} m/s", "bar", [f"initial.impact.velocity=[{v!r}, 0.0, 0.0]"],
            quick=v == 50.0)
    add("speed", "exponential 50 m/s", "bar",
        [EXP, f"contact.wall.law.lambda={LAMBDA_BAR!r}",
         "initial.impact.velocity=[50.0, 0.0, 0.0]"])
    # a fully open start: the wall 0.1 m away, out of reach during the run
    far = "contact.wall.wall_point=[0.2, 0.0, 0.0]"
    add("open", "bar linear", "bar", [far], quick=True)
    add("open", "bar exponential", "bar", [EXP, f"contact.wall.law.lambda={LAMBDA_BAR!r}", far])
    # the pad 1 mm above the disc: without the piston nothing closes the gap (the tap moves
    # the pad by tens of um); with it, the preload presses the pad down to contact first
    lifted = ["parts.pad.mesh.z0=0.021", "solver.t_end=2e-3"]
    add("open", "pad 1 mm above, no piston", "pad", lifted + ["loads.piston.value=0.0"])
    add("open", "pad 1 mm above, no piston, implicit", "pad",
        lifted + ["loads.piston.value=0.0", 'solver.scheme="implicit"'])
    add("open", "pad 1 mm above, the piston closes it", "pad", lifted)
    # no [contact] table at all
    add("no contact", "bar explicit", "bar_free", [], quick=True)
    add("no contact", "bar implicit", "bar_free", ['solver.scheme="implicit"'], dt_factor=2.0)
    add("no contact", "pad exponential", "pad_free", ["solver.t_end=2e-3"])
    for rule in ("fine", "greedy", "sampled"):
        for eps in (1e-12, 1e-8, 1e-4, 1e-2, 1.0):
            add("eps", f"{rule} eps={_g(eps)}", "pad",
                [f'contact.pad_disc.rule="{rule}"', "contact.pad_disc.regularized=true",
                 f"contact.pad_disc.eps={eps!r}"], quick=eps == 1e-12)
    for m in (1, 2, 10, 0, 1000):
        label = "rank" if m == 0 else f"{m} (> {PAD_FINE_POINTS} fine points)" if m > \
            PAD_FINE_POINTS else str(m)
        add("m", f"greedy m={label}", "pad",
            ['contact.pad_disc.rule="greedy"', f"contact.pad_disc.points={m}"],
            quick=m in (1, 1000))
    # the sampled rule from one point (tolerance 1: the first point meets it) to all of them
    for tol in (1.0, 1e-1, 1e-3, 1e-8):
        add("sampling", f"sampled tol={_g(tol)}", "pad",
            ['contact.pad_disc.rule="sampled"', f"contact.pad_disc.sampling_tolerance={tol!r}"],
            quick=tol == 1.0)
    add("sampling", "sampled at most 1 point", "pad",
        ['contact.pad_disc.rule="sampled"', "contact.pad_disc.points=1"])
    # a tap of several times the preload: the exponential scheme's explicit remainder against
    # its implicit corrector, at the step set by accuracy
    for force in (4e3, 8e3):
        for corrector in ("evaluated", "implicit"):
            add("tap", f"pad {force / 1e3:g} kN tap, {corrector}", "pad",
                [f"loads.tap.vector=[0.0, 0.0, {-force!r}]",
                 f'solver.corrector="{corrector}"', "solver.t_end=2e-3"],
                quick=force == 8e3 and corrector == "implicit")
    implicit = 'solver.scheme="implicit"'
    add("implicit", "bar dt=0.9x", "bar", [implicit], dt_factor=0.9)
    add("implicit", "bar dt=5x", "bar", [implicit], quick=True, dt_factor=5.0)
    add("implicit", "bar no dt", "bar", [implicit])
    add("implicit", "bar exponential law dt=2x", "bar",
        [implicit, EXP, f"contact.wall.law.lambda={LAMBDA_BAR!r}"], dt_factor=2.0)
    add("implicit", "two bars dt=2x", "two_bars", [implicit], dt_factor=2.0)
    add("implicit", "pad", "pad", [implicit], quick=True)
    add("implicit", "pad lambda=1e8", "pad", [implicit, "contact.pad_disc.law.lambda=1e8"])
    add("implicit", "pad fine eps=1", "pad",
        [implicit, 'contact.pad_disc.rule="fine"', "contact.pad_disc.eps=1.0"])
    add("scheme", "exponential on the full bar", "bar", ['solver.scheme="exponential"'],
        quick=True)
    return S


# ---------------------------------------------------------------------------------------------
# one run and its classification

@dataclass
class Result:
    """What a child `transient run` left: exit code, output streams and the history path."""
    returncode: int
    stdout: str
    stderr: str
    path: Path
    seconds: float = 0.0
    timed_out: bool = False


def command(case, out, settings):
    args = [sys.executable, "-m", "transient", "run", str(case), "-o", str(out), "--quiet",
            "--json"]
    for s in settings:
        args += ["--set", s]
    return args


def execute(args, out, timeout=TIMEOUT_S):
    t0 = time.perf_counter()
    try:
        done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        return Result(None, _text(exc.stdout), _text(exc.stderr), Path(out),
                      time.perf_counter() - t0, timed_out=True)
    return Result(done.returncode, done.stdout, done.stderr, Path(out),
                  time.perf_counter() - t0)


def _text(stream):
    return stream.decode(errors="replace") if isinstance(stream, bytes) else (stream or "")


def _nonfinite(f):
    """'dataset[index] = value' of the first non-finite value of each float dataset."""
    bad = []

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "fc":
            a = np.asarray(obj[()])
            ok = np.isfinite(a)
            if not ok.all():
                idx = tuple(int(i) for i in np.argwhere(~ok)[0])
                bad.append(f"{name}{list(idx)} = {a[idx]} ({int((~ok).sum())} values)")

    f.visititems(visit)
    return bad


def inspect(path):
    """The history as the classification needs it: status, rows, drift, non-finite values,
    series whose length differs from the rows attribute. None when there is no file."""
    path = Path(path)
    if not path.exists():
        return None
    from transient.io.reading import summary
    with h5py.File(path, "r", locking=False) as f:
        status = f.attrs.get("status")
        status = status.decode() if isinstance(status, bytes) else status
        rows = int(f.attrs.get("rows", -1))
        bad = _nonfinite(f)
        ragged = []

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and not name.startswith(("checkpoint",
                                                                       "geometry/",
                                                                       "system/")):
                if obj.shape[0] != rows:
                    ragged.append(f"{name}: {obj.shape[0]} rows, attribute rows = {rows}")
        f.visititems(visit)
        dt_critical = f.attrs.get("dt_critical")
        points = f.attrs.get("n_points")
    try:
        with np.errstate(all="ignore"):        # inf - inf in a file that kept an Inf
            drift = summary(path)["energy_drift"]
    except Exception as exc:          # noqa: BLE001  (evidence, not a crash of the study)
        drift = f"summary failed: {type(exc).__name__}: {exc}"
    return {"status": status, "rows": rows, "nonfinite": bad, "ragged": ragged,
            "energy_drift": drift, "points": None if points is None else int(points),
            "dt_critical": None if dt_critical is None else float(dt_critical)}


def _json(stdout):
    for line in reversed(stdout.strip().splitlines()):
        try:
            value = json.loads(line)
        except ValueError:
            continue
        if isinstance(value, dict):
            return value
    return None


def _finite(x):
    return isinstance(x, (int, float)) and math.isfinite(x)


def classify(result, drift_tolerance=DEFAULT_DRIFT_TOLERANCE):
    """(outcome, details) of one run: outcome 'stable', 'refused', 'aborted' or 'FAILED';
    details: status, steps, rows, energy_drift, dt, dt_critical, points (contact points),
    reason and evidence (why FAILED)."""
    err = result.stderr.strip()
    lines = [line for line in err.splitlines() if line.strip()]
    summary = _json(result.stdout)
    d = {"exit_code": result.returncode, "status": None, "steps": None, "rows": None,
         "energy_drift": None, "dt": None, "dt_critical": None, "points": None, "reason": "",
         "evidence": []}
    if summary:
        d.update(steps=summary.get("steps"), dt=summary.get("dt"),
                 dt_critical=summary.get("dt_critical"), status=summary.get("status"))
    failed = d["evidence"]
    if result.timed_out:
        failed.append(f"timed out after {result.seconds:.0f} s")
    elif result.returncode is not None and result.returncode < 0:
        sig = -result.returncode
        name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else sig
        failed.append(f"killed by signal {name}")
    if "Traceback" in result.stderr or "Traceback" in result.stdout:
        tail = "\n".join(err.splitlines()[-3:])
        failed.append(f"traceback: {tail}")
    try:
        h = inspect(result.path)
    except Exception as exc:          # noqa: BLE001
        failed.append(f"history unreadable: {type(exc).__name__}: {exc}")
        h = None
    if h is not None:
        d["rows"] = h["rows"]
        d["energy_drift"] = h["energy_drift"]
        d["status"] = h["status"]
        d["points"] = h["points"]
        d["dt_critical"] = d["dt_critical"] if d["dt_critical"] is not None else h["dt_critical"]
        if h["ragged"]:
            failed.append("series lengths differ from rows: " + "; ".join(h["ragged"][:3]))
    code = result.returncode
    if failed:
        return "FAILED", d
    if code == 0:
        if h is None:
            failed.append("exit 0 but no history file")
        else:
            if h["status"] != "complete":
                failed.append(f"exit 0 but status {h['status']!r}")
            if h["nonfinite"]:
                failed.append("non-finite values in a complete file: "
                              + "; ".join(h["nonfinite"][:4]))
            drift = h["energy_drift"]
            if not _finite(drift):
                failed.append(f"energy drift not a finite number: {drift!r}")
            elif drift > drift_tolerance * (1 + 1e-9):
                failed.append(f"complete with an energy drift {drift:.3g} over "
                              f"solver.drift_tolerance {drift_tolerance:g}")
            if h["rows"] < 1:
                failed.append("complete without rows")
        if summary is None:
            failed.append(f"stdout is not the JSON summary: {result.stdout.strip()[:200]!r}")
        elif summary.get("status") != "complete":
            failed.append(f"JSON status {summary.get('status')!r}")
        if lines:
            d["reason"] = f"stderr: {lines[0][:160]}"
        return ("FAILED" if failed else "stable"), d
    if code == 2:
        if len(lines) != 1:
            failed.append(f"refusal of {len(lines)} lines on stderr: {err[:400]!r}")
        elif not lines[0].startswith("error:"):
            failed.append(f"refusal not starting with 'error:': {lines[0][:300]!r}")
        if h is not None and h["rows"] > 0:
            failed.append(f"refused, yet a history with {h['rows']} rows (status "
                          f"{h['status']!r}) was written")
        d["reason"] = lines[0][len("error:"):].strip() if lines else ""
        return ("FAILED" if failed else "refused"), d
    if code == 3:
        if h is None:
            failed.append("aborted without a history file")
        else:
            status = h["status"] or ""
            if not status.startswith("aborted:"):
                failed.append(f"exit 3 but status {status!r}")
            d["reason"] = status[len("aborted:"):].strip()
            if h["nonfinite"]:
                failed.append("non-finite values kept in an aborted file: "
                              + "; ".join(h["nonfinite"][:4]))
            if h["rows"] < 1 and not re.search(r"\bt = 0\b", status):
                failed.append("aborted without rows and without saying why")
        if not any("aborted" in line for line in lines):
            failed.append(f"stderr does not say the run aborted: {err[:300]!r}")
        return ("FAILED" if failed else "aborted"), d
    if code is not None and code >= 0:
        failed.append(f"exit code {code}; stderr: {err[-400:]!r}")
    return "FAILED", d


def drift_tolerance(case, settings):
    """solver.drift_tolerance of the case with its overrides (the default if it does not load)."""
    from transient.case.loading import load
    from transient.errors import CaseError
    try:
        return load(case, settings).solver.drift_tolerance
    except CaseError:
        return DEFAULT_DRIFT_TOLERANCE


# ---------------------------------------------------------------------------------------------
# the study

def run_scenario(sc, files, directory, dt_critical=None, timeout=TIMEOUT_S):
    """One scenario through the command line: its row (id, settings, outcome, details,
    command)."""
    settings = sc.base_settings() + list(sc.settings)
    row = {"id": sc.id, "axis": sc.axis, "scenario": sc.name, "case": sc.base,
           "settings": list(sc.settings)}
    if sc.dt_factor is not None:
        if not _finite(dt_critical):
            row.update(outcome="FAILED", exit_code=None, seconds=0.0, command="",
                       reason="", evidence=["no critical step from the probe run (dt/auto)"])
            return row
        dt = sc.dt_factor * dt_critical
        settings.append(f"solver.dt={dt!r}")
        row["settings"] = row["settings"] + [f"solver.dt={dt:.4g} ({sc.dt_factor:g}x critical)"]
    out = Path(directory) / (re.sub(r"[^A-Za-z0-9]+", "_", sc.id).strip("_") + ".h5")
    if out.exists():
        out.unlink()
    args = command(files[sc.base], out, settings)
    result = execute(args, out, timeout)
    outcome, details = classify(result, drift_tolerance(files[sc.base], settings))
    row.update(outcome=outcome, **details, seconds=result.seconds,
               command=shlex.join(["python"] + args[1:]))
    return row


def study(quick=False, only=None, directory=None, timeout=TIMEOUT_S, show=None):
    """Rows of the study (all scenarios, or the --quick ones; `only`: ids containing it).
    show(row) is called after each run."""
    chosen = [s for s in scenarios() if (s.quick or not quick)
              and (only is None or only in s.id or s.probe)]
    with tempfile.TemporaryDirectory(prefix="study_stability_") as tmp:
        work = Path(directory) if directory else Path(tmp)
        files = bases(work)
        rows, dt_critical = [], None
        for sc in sorted(chosen, key=lambda s: not s.probe):   # the probe first
            row = run_scenario(sc, files, work, dt_critical, timeout)
            if sc.probe:
                dt_critical = row.get("dt_critical")
            rows.append(row)
            if show:
                show(row)
    return rows


def note(row):
    """The table's last column: the drift and steps, the reason, or the evidence."""
    if row["outcome"] == "stable":
        text = f"drift {row['energy_drift']:.2e}, {row['steps']} steps"
        return text + (f"; {row['reason']}" if row.get("reason") else "")
    if row["outcome"] == "refused":
        return row["reason"]
    if row["outcome"] == "aborted":
        return f"{row['rows']} rows kept; {row['reason']}"
    return " | ".join(row["evidence"])


HEADER = f"{'scenario':40s} {'settings':58s} {'outcome':8s} drift or reason"


def format_row(row, width=None):
    settings = " ".join(s.replace("contact.wall.", "").replace("contact.pad_disc.", "")
                        .replace("contact.impact.", "").replace("solver.", "")
                        for s in row["settings"]) or "(case)"
    text = note(row)
    if width and len(text) > width:
        text = text[:width - 3] + "..."
    return f"{row['id']:40s} {settings[:58]:58s} {row['outcome']:8s} {text}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a few scenarios per axis")
    parser.add_argument("--only", metavar="TEXT", help="scenarios whose id contains TEXT")
    parser.add_argument("--keep", metavar="DIR", help="write case variants and histories here")
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S, help="seconds per run")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = parser.parse_args(argv)
    if not args.json:
        print(HEADER, flush=True)

    def show(row):
        if not args.json:
            print(format_row(row, 160), flush=True)
    rows = study(args.quick, args.only, args.keep, args.timeout, show)
    failed = [r for r in rows if r["outcome"] == "FAILED"]
    counts = {k: sum(r["outcome"] == k for r in rows)
              for k in ("stable", "refused", "aborted", "FAILED")}
    if args.json:
        print(json.dumps({"counts": counts, "rows": rows}, indent=1))
    else:
        print(", ".join(f"{v} {k}" for k, v in counts.items()))
        for r in failed:
            print(f"\nFAILED {r['id']}:\n  {r['command']}\n  " + "\n  ".join(r["evidence"]))
    return 1 if failed else 0


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    sys.exit(main())
