"""Pictures of a sweep (transient sweep's DIR): the stability map of a cea sweep, a run
sweep's summaries against a parameter, both for a sweep of both kinds.

The other parameters of a grid split the variants into groups: one map per group (cea), one
line per group (run).
"""
import json
from pathlib import Path
from types import SimpleNamespace

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
    x = x or parameters[0]
    if x not in parameters:
        raise CaseError(directory / "sweep.json", "--x", f"not a parameter of the sweep "
                        f"(its parameters: {', '.join(parameters)})")
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


def _maps(directory, parts, x, base):
    """One stability map per group of the other parameters' values."""
    from .cea import map_figure
    paths = []
    for k, (label, members) in enumerate(parts.items()):
        modes = []
        for row in members:
            table = json.loads((directory / row.get("modes_output", row["output"]))
                               .read_text())["modes"]
            modes.append(SimpleNamespace(**{key: np.array([m[key] for m in table])
                                            for key in ("frequency_hz", "real", "unstable")}))
        path = base if len(parts) == 1 else base.with_name(f"{base.stem}_{k}{base.suffix}")
        map_figure([r[x] for r in members], modes, path,
                   "complex modes" + (f" ({label})" if label else ""), x)
        paths.append(path)
    return paths


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
