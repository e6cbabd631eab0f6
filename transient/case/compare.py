"""What differs between two cases, key by key: a resumed run must integrate the case it was
started with, so anything that changes results is refused by name."""
from dataclasses import fields, is_dataclass

# what a resumed run may change: how long it runs and how it is watched, not what it computes
RESUMABLE = ("title", "solver.t_end", "solver.chunk", "solver.drift_tolerance",
             "solver.force_dt", "output.file", "output.vtu", "limits.memory", "limits.steps")
CASE_FIELDS = ("title", "materials", "parts", "constraints", "loads", "contact", "sensors",
               "initial", "solver", "output", "limits")


def flatten(case):
    """Dotted case key -> value of every leaf of a case's specs."""
    out = {}
    for name in CASE_FIELDS:
        _walk(getattr(case, name), name, out)
    return out


def _walk(value, key, out):
    if is_dataclass(value):
        for f in fields(value):
            # the kind-dependent fields (mesh and selection parameters) sit under their table
            sub = key if f.name == "params" else f"{key}.{'lambda' if f.name == 'lam' else f.name}"
            _walk(getattr(value, f.name), sub, out)
    elif isinstance(value, dict):
        for k, v in value.items():
            _walk(v, f"{key}.{k}", out)
    else:
        out[key] = value


def changed(old, new, allowed=RESUMABLE):
    """Sorted keys whose values differ between two cases (present in one only included),
    leaving out the allowed ones."""
    a, b = flatten(old), flatten(new)
    keys = set(a) | set(b)
    return sorted(k for k in keys if k not in allowed and (k not in a or k not in b
                                                              or a[k] != b[k]))
