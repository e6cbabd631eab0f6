"""Pictures of a sweep (transient sweep's DIR): the stability map of a cea sweep (its complex
modes linked into branches, with the tables of its unstable modes and coupling points), a run
sweep's summaries against a parameter, both for a sweep of both kinds.

The other parameters of a grid split the variants into groups: one map per group (cea), one
line per group (run).
"""
import json
from pathlib import Path

import numpy as np

from ..errors import CaseError

SUMMARIES = (("growth_rate", "growth rate [1/s]"), ("cycle_rms", "limit cycle RMS"),
             ("cycle_frequency", "dominant frequency [Hz]"))


def read_sweep(directory):
    """(kind, parameters, rows) of sweep.json in directory."""
    path = Path(directory) / "sweep.json"
    try:
        data = json.loads(path.read_text())
        return data["kind"], data["parameters"], data["rows"]
    except FileNotFoundError:
        raise CaseError(path, "", "no sweep here: expected the sweep.json that transient "
                        "sweep --out DIR writes") from None
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CaseError(path, "", f"not a sweep's summary: {exc}") from None


def groups(rows, parameters, x):
    """{label of the other parameters' values: rows}, complete rows only, in order of x."""
    others = [k for k in parameters if k != x]
    out = {}
    for row in sorted((r for r in rows if r["status"] == "complete"), key=lambda r: r[x]):
        label = ", ".join(f"{k}={row[k]}" for k in others)
        out.setdefault(label, []).append(row)
    return out


def sweep_figures(directory, x=None, png=None):
    """The sweep's pictures, written next to sweep.json (or at png, suffixed per group);
    returns their paths."""
    directory = Path(directory)
    kind, parameters, rows = read_sweep(directory)
    x = _checked_x(directory, parameters, x)
    parts = groups(rows, parameters, x)
    if not parts:
        raise CaseError(directory / "sweep.json", "", "no complete variant to draw")
    base = Path(png) if png else directory / f"sweep_{kind}.png"
    if kind == "both":
        return (_maps(directory, parts, x, base.with_name(f"{base.stem}_cea{base.suffix}"))
                + _summaries(parts, x, base.with_name(f"{base.stem}_run{base.suffix}")))
    if kind == "cea":
        return _maps(directory, parts, x, base)
    return _summaries(parts, x, base)


def _checked_x(directory, parameters, x):
    """x, or the sweep's first parameter; CaseError if not one of them."""
    x = x or parameters[0]
    if x not in parameters:
        raise CaseError(directory / "sweep.json", "--x", f"not a parameter of the sweep "
                        f"(its parameters: {', '.join(parameters)})")
    return x


def _maps(directory, parts, x, base):
    """One map of the branches per group of the other parameters' values, with its tables of
    unstable modes and coupling points beside it (base's name, suffixed)."""
    from .branches import branches_figure
    paths = []
    for k, (label, members) in enumerate(parts.items()):
        found = track_rows(directory, members, x)
        path = base if len(parts) == 1 else base.with_name(f"{base.stem}_{k}{base.suffix}")
        branches_figure(found, path, "complex modes" + (f" ({label})" if label else ""), x)
        paths += [path] + found.write(path.with_name(f"{path.stem}_unstable.csv"),
                                      path.with_name(f"{path.stem}_coupling.csv"))
    return paths


def track_rows(directory, members, x):
    """The Branches (stability.branches) of a group's variants against the parameter x: each
    variant's complex modes read back from its modes file, linked by their stored shapes, or by
    the eigenvalue alone where a file holds none (written before they were stored)."""
    from ..stability.branches import Step, read_shapes, track
    steps = []
    for row in members:
        if not isinstance(row[x], (int, float)):
            raise CaseError(directory / "sweep.json", "--x", f"branches are drawn against a "
                            f"parameter of numbers, got {row[x]!r}")
        stored = json.loads((directory / row.get("modes_output", row["output"])).read_text())
        table = stored["modes"]
        dofs, shapes = (read_shapes(stored["shapes"]) if "shapes" in stored else (None, None))
        lam = np.array([m["real"] + 2j * np.pi * m["frequency_hz"] for m in table], complex)
        steps.append(Step(float(row[x]), lam, np.array([m["unstable"] for m in table], bool),
                          float(stored.get("growth_rate_threshold", 0.0)), shapes, dofs))
    return track(x, steps)


def branch_groups(directory, x=None):
    """{label of the other parameters' values: Branches} of a cea sweep's folder, as
    `plot sweep` draws them."""
    directory = Path(directory)
    kind, parameters, rows = read_sweep(directory)
    if kind == "run":
        raise CaseError(directory / "sweep.json", "", "a run sweep holds no complex modes: "
                        "expected a sweep of kind cea or both")
    x = _checked_x(directory, parameters, x)
    return {label: track_rows(directory, members, x)
            for label, members in groups(rows, parameters, x).items()}


def _summaries(parts, x, base):
    """The run's summaries against x, one line per group of the other parameters' values."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(SUMMARIES), figsize=(5 * len(SUMMARIES), 4.2))
    for ax, (key, name) in zip(axes, SUMMARIES):
        for label, members in parts.items():
            xs = [r[x] for r in members if r.get(key) is not None]
            ys = [r[key] for r in members if r.get(key) is not None]
            ax.plot(xs, ys, "o-", label=label or None)
        ax.set_xlabel(x)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    if any(parts):
        axes[0].legend(fontsize=7)
    fig.suptitle(f"sweep: {sum(len(m) for m in parts.values())} complete variants")
    fig.tight_layout()
    fig.savefig(base, dpi=120)
    plt.close(fig)
    return [base]
