"""`transient info`'s table: a history's summary (io.reading.summary) as text."""
import json


def format_summary(d):
    """`summary` as a human-readable table."""
    drift = "n/a" if d["energy_drift"] is None else f"{d['energy_drift']:.3g}"
    t_end = "n/a" if d["t_end"] is None else f"{d['t_end']:.6g} s"
    timings = ", ".join(f"{k} {v:.3g} s" if isinstance(v, (int, float)) else f"{k} {v}"
                        for k, v in d["timings"].items())
    lines = [("file", f"{d['path']} ({_size(d['file_size'])})"), ("status", d["status"]),
             ("rows", str(d["steps"])), ("t_end", t_end), ("energy drift", drift),
             ("timings", timings or "n/a")] + _steps(d["meta"])
    lines += [("series" if i == 0 else "", f"{name} {tuple(shape)}")
              for i, (name, shape) in enumerate(d["series"].items())]
    lines += [("meta" if i == 0 else "", f"{key} = {_show(value)}")
              for i, (key, value) in enumerate(d["meta"].items())]
    width = max(len(label) for label, _ in lines)
    return "\n".join(f"{label:<{width}}  {text}" for label, text in lines)


def _size(n):
    for unit in ("bytes", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1000


def _show(value):
    return value if isinstance(value, str) else json.dumps(value)


def _steps(meta):
    """The step a run took and, where it was subdivided, when, to what and why."""
    if "dt" not in meta:
        return []
    why = f": {meta['dt_reason']}" if meta.get("dt_reason") else ""
    lines = [("step", f"{meta['dt']:.4g} s{why}")]
    lines += [("", f"subdivided at t = {s['t']:.6g} s to {s['dt']:.4g} s: {s['why']}")
              for s in meta.get("subdivisions") or ()]
    return lines
