"""Time signals s_j(t) [-] multiplying load patterns: f(t) = sum_j pattern_j s_j(t).

A signal is a dict with a `kind` and that kind's keys (`SIGNAL_FIELDS`). `compile_signals` packs
a list of them into plain arrays; the jitted `kernels.signals.signal_value` evaluates them inside
time-stepping kernels by branching on an integer code (no allocation, no exception).
`evaluate` is a plain NumPy reference used by the tests. Nothing here imports Numba: a case
loads without it.

Active windows are half-open: a signal with a `duration` is nonzero for start <= t <
start + duration and 0 from start + duration on; every signal but `constant` and `table` is 0
before `start`.
"""
import math

import numpy as np

from ..kernels.codes import (AMPLITUDE, CHIRP, CONSTANT, DURATION, F1, FREQUENCY,
                             IMPULSE, N_PARAMS, PHASE, RISE, SINE, START, STEP, TABLE)

SIGNAL_DOC = "time signal multiplying the load"

# kind -> {key: (type, default, unit, doc)}; default None: the key is required
SIGNAL_FIELDS = {
    "constant": {},
    "step": {
        "start": ("float", 0.0, "s", "time of the step"),
        "amplitude": ("float", 1.0, "-", "value after the rise"),
        "rise": ("float", 0.0, "s", "duration of the linear rise from 0 (0: a jump), >= 0"),
    },
    "impulse": {
        "start": ("float", 0.0, "s", "start of the half-sine pulse"),
        "duration": ("float", None, "s", "length of the pulse, > 0 (integral: amplitude 2 "
                     "duration / pi)"),
        "amplitude": ("float", 1.0, "-", "peak value"),
    },
    "sine": {
        "frequency": ("float", None, "Hz", "frequency, >= 0"),
        "amplitude": ("float", 1.0, "-", "amplitude"),
        "phase": ("float", 0.0, "rad", "phase at `start`: amplitude sin(2 pi frequency (t - "
                  "start) + phase)"),
        "start": ("float", 0.0, "s", "time the sine begins (0 before)"),
        "duration": ("float", 0.0, "s", "length after `start`, 0 from then on (0: no end), >= 0"),
    },
    "chirp": {
        "f0": ("float", None, "Hz", "frequency at `start`, >= 0"),
        "f1": ("float", None, "Hz", "frequency at `start` + `duration`, >= 0"),
        "duration": ("float", None, "s", "length of the linear sweep, > 0 (0 after it)"),
        "start": ("float", 0.0, "s", "start of the sweep (0 before)"),
        "amplitude": ("float", 1.0, "-", "amplitude"),
    },
    "table": {
        "times": ("floats", None, "s", "strictly increasing times; the signal is 0 before the "
                  "first and holds the last value after the last"),
        "values": ("floats", None, "-", "values at `times`, linearly interpolated between"),
    },
}

CODES = {"constant": CONSTANT, "step": STEP, "impulse": IMPULSE, "sine": SINE, "chirp": CHIRP,
         "table": TABLE}


def check_signal(spec, key="signal"):
    """A signal spec with its defaults filled in; ValueError naming the key on bad input.

    Parameters
    ----------
    spec : dict
        'kind' and that kind's keys (`SIGNAL_FIELDS`); absent optional keys take defaults.
    key : str
        Path of the spec in the case, used in messages (e.g. 'loads.brake.signal').
    """
    if not isinstance(spec, dict):
        raise ValueError(f"{key}: expected a table with a 'kind'")
    kind = spec.get("kind")
    if kind not in SIGNAL_FIELDS:
        raise ValueError(f"{key}.kind: unknown kind {kind!r} (expected one of: "
                         f"{', '.join(SIGNAL_FIELDS)})")
    fields = SIGNAL_FIELDS[kind]
    for name in spec:
        if name != "kind" and name not in fields:
            raise ValueError(f"{key}.{name}: unknown key for a {kind} signal (expected one of: "
                             f"{', '.join(fields) or 'none'})")
    out = {"kind": kind}
    for name, (vtype, default, _, _) in fields.items():
        if name not in spec and default is None:
            raise ValueError(f"{key}.{name}: missing key for a {kind} signal")
        value = spec.get(name, default)
        out[name] = (_number_list(value, f"{key}.{name}") if vtype == "floats"
                     else _number(value, f"{key}.{name}"))
    _check_bounds(out, key)
    return out


def _number(value, key):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{key}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{key}: expected a finite number, got {value!r}")
    return float(value)


def _number_list(value, key):
    if not isinstance(value, (list, tuple, np.ndarray)):
        raise ValueError(f"{key}: expected a list of numbers, got {value!r}")
    return [_number(v, key) for v in value]


def _check_bounds(s, key):
    def require(ok, name, message):
        if not ok:
            raise ValueError(f"{key}.{name}: {message}")

    for name in ("rise", "frequency", "f0", "f1"):
        if name in s:
            require(s[name] >= 0.0, name, f"expected >= 0, got {s[name]!r}")
    if "duration" in s:
        if s["kind"] == "sine":
            require(s["duration"] >= 0.0, "duration",
                    f"expected >= 0 (0: no end), got {s['duration']!r}")
        else:
            require(s["duration"] > 0.0, "duration", f"expected > 0, got {s['duration']!r}")
    if s["kind"] == "table":
        times, values = s["times"], s["values"]
        require(len(times) >= 1, "times", "expected at least one time")
        require(len(values) == len(times), "values",
                f"expected {len(times)} values (one per time), got {len(values)}")
        require(all(b > a for a, b in zip(times, times[1:])), "times",
                "expected strictly increasing times")


def compile_signals(specs, keys=None):
    """Pack signals into arrays for `signal_value` and `signal_values`.

    Parameters
    ----------
    specs : list of dict
        J signal specs (validated or not: `check_signal` is applied to each).
    keys : list of str, optional
        Their paths in the case, for error messages (default 'signals[j]').

    Returns
    -------
    codes : int64 (J,)
        Kind of each signal (`CODES`).
    params : float64 (J, N_PARAMS)
        Parameters in the columns START, AMPLITUDE, DURATION, RISE, FREQUENCY, F1, PHASE [SI].
    table_t, table_v : float64 (J, T)
        Times [s] and values [-] of table signals, T the longest table (at least 1).
    table_n : int64 (J,)
        Number of points of each table (0 for other kinds).
    """
    keys = keys if keys is not None else [f"signals[{j}]" for j in range(len(specs))]
    checked = [check_signal(spec, key) for spec, key in zip(specs, keys)]
    J = len(checked)
    T = max([len(s["times"]) for s in checked if s["kind"] == "table"], default=1)
    codes = np.zeros(J, np.int64)
    params = np.zeros((J, N_PARAMS))
    table_t = np.zeros((J, T))
    table_v = np.zeros((J, T))
    table_n = np.zeros(J, np.int64)
    columns = {"start": START, "amplitude": AMPLITUDE, "duration": DURATION, "rise": RISE,
               "frequency": FREQUENCY, "f0": FREQUENCY, "f1": F1, "phase": PHASE}
    for j, s in enumerate(checked):
        codes[j] = CODES[s["kind"]]
        for name, column in columns.items():
            if name in s:
                params[j, column] = s[name]
        if s["kind"] == "table":
            n = len(s["times"])
            table_t[j, :n] = s["times"]
            table_v[j, :n] = s["values"]
            table_n[j] = n
    return codes, params, table_t, table_v, table_n


def evaluate(spec, t):
    """Reference NumPy evaluation of one signal at the times t [s]: the tests check the
    kernels against it, and a history's pictures rebuild the load a run applied with it."""
    s = check_signal(spec)
    t = np.asarray(t, dtype=float)
    kind = s["kind"]
    if kind == "constant":
        return np.ones_like(t)
    if kind == "table":
        times, values = np.array(s["times"]), np.array(s["values"])
        return np.where(t < times[0], 0.0, np.interp(t, times, values))
    tau = t - s["start"]
    a = s["amplitude"]
    if kind == "step":
        ramp = np.minimum(tau / s["rise"], 1.0) if s["rise"] > 0 else np.ones_like(t)
        return np.where(tau < 0.0, 0.0, a * ramp)
    active = (tau >= 0.0) & ((tau < s["duration"]) | (kind == "sine" and s["duration"] == 0.0))
    if kind == "impulse":
        value = a * np.sin(np.pi * tau / s["duration"])
    elif kind == "sine":
        value = a * np.sin(2 * np.pi * s["frequency"] * tau + s["phase"])
    else:
        f0, f1, d = s["f0"], s["f1"], s["duration"]
        value = a * np.sin(2 * np.pi * (f0 * tau + (f1 - f0) * tau ** 2 / (2 * d)))
    return np.where(active, value, 0.0)
