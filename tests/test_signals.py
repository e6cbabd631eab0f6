"""Load signals: the Numba kernel against the NumPy reference, pulse integral, chirp frequency."""
import numpy as np
import pytest

from transient.case.signals import SIGNAL_FIELDS, check_signal, compile_signals, evaluate
from transient.kernels.signals import signal_value, signal_values

SPECS = [
    {"kind": "constant"},
    {"kind": "step", "start": 1e-3, "amplitude": 2.5},
    {"kind": "step", "start": 1e-3, "amplitude": -3.0, "rise": 2e-3},
    {"kind": "impulse", "start": 0.5e-3, "duration": 0.2e-3, "amplitude": 4.0},
    {"kind": "sine", "frequency": 1200.0, "amplitude": 0.7, "phase": 0.3, "start": 1e-3},
    {"kind": "sine", "frequency": 800.0, "start": 1e-3, "duration": 2.5e-3},
    {"kind": "chirp", "f0": 1000.0, "f1": 16000.0, "duration": 3e-3, "start": 1e-3,
     "amplitude": 1.5},
    {"kind": "chirp", "f0": 5000.0, "f1": 500.0, "duration": 2e-3},
    {"kind": "table", "times": [1e-3, 2e-3, 2.5e-3, 4e-3], "values": [0.5, 1.0, -1.0, 0.25]},
    {"kind": "table", "times": [2e-3], "values": [3.0]},
]


def edges(spec):
    """Times where a signal changes regime, with their neighbours one ulp away."""
    s = check_signal(spec)
    start = s.get("start", 0.0)
    points = [start, start + s.get("duration", 0.0), start + s.get("rise", 0.0)]
    points += s.get("times", [])
    points += [s["times"][0] - 1e-4, s["times"][-1] + 1e-4] if "times" in s else []
    return [u for p in points for u in (np.nextafter(p, -1.0), p, np.nextafter(p, 1.0))]


def kernel_values(packed, j, t):
    return np.array([signal_value(j, ti, *packed) for ti in t])


def test_every_kind_is_covered():
    assert {s["kind"] for s in SPECS} == set(SIGNAL_FIELDS)


def test_kernel_equals_the_numpy_reference():
    packed = compile_signals(SPECS)
    for j, spec in enumerate(SPECS):
        t = np.concatenate([np.linspace(-1e-3, 6e-3, 2001), edges(spec)])
        np.testing.assert_allclose(kernel_values(packed, j, t), evaluate(spec, t), rtol=1e-12,
                                   atol=1e-12, err_msg=str(spec))


def test_edges_are_half_open():
    packed = compile_signals(SPECS)
    step, ramp, pulse, sine, chirp, table, single = 1, 2, 3, 5, 6, 8, 9
    assert signal_value(step, 1e-3, *packed) == 2.5
    assert signal_value(step, np.nextafter(1e-3, 0.0), *packed) == 0.0
    assert signal_value(ramp, 1e-3, *packed) == 0.0
    assert signal_value(ramp, 3e-3, *packed) == -3.0
    assert signal_value(pulse, 0.5e-3, *packed) == 0.0
    assert signal_value(pulse, 0.6e-3, *packed) == pytest.approx(4.0, rel=1e-12)
    assert signal_value(sine, 1e-3, *packed) == 0.0          # sin(0) at its start
    assert signal_value(sine, 1e-3 + 2.5e-3, *packed) == 0.0
    assert signal_value(chirp, 1e-3 + 3e-3, *packed) == 0.0
    assert signal_value(table, 0.999e-3, *packed) == 0.0     # before the first time
    assert signal_value(table, 1e-3, *packed) == 0.5
    assert signal_value(table, 2.25e-3, *packed) == pytest.approx(0.0, abs=1e-15)
    assert signal_value(table, 1.0, *packed) == 0.25         # holds the last value
    assert signal_value(single, 1.9e-3, *packed) == 0.0
    assert signal_value(single, 2e-3, *packed) == 3.0


def test_signal_values_fills_every_signal():
    packed = compile_signals(SPECS)
    out = np.full(len(SPECS), np.nan)
    for t in (0.0, 1.7e-3, 3.1e-3):
        signal_values(t, *packed, out)
        np.testing.assert_allclose(out, [evaluate(s, [t])[0] for s in SPECS], atol=1e-12)


def test_no_signal_packs_to_empty_arrays():
    codes, params, table_t, table_v, table_n = compile_signals([])
    assert codes.shape == (0,) and params.shape == (0, 8) and table_t.shape == (0, 1)
    signal_values(0.0, codes, params, table_t, table_v, table_n, np.empty(0))


def test_impulse_integral():
    d, a = 0.2e-3, 4.0
    packed = compile_signals([{"kind": "impulse", "start": 0.5e-3, "duration": d,
                               "amplitude": a}])
    t = np.linspace(0.0, 1e-3, 100001)
    assert np.trapezoid(kernel_values(packed, 0, t), t) == pytest.approx(a * 2 * d / np.pi,
                                                                         rel=1e-8)


def test_chirp_instantaneous_frequency_from_zero_crossings():
    f0, f1, d, start = 1000.0, 16000.0, 10e-3, 2e-3
    packed = compile_signals([{"kind": "chirp", "f0": f0, "f1": f1, "duration": d,
                               "start": start}])
    t = np.linspace(start, start + d, 200001)[:-1]
    s = kernel_values(packed, 0, t)
    i = np.nonzero(np.sign(s[1:]) * np.sign(s[:-1]) < 0)[0]
    crossings = t[i] - s[i] * (t[i + 1] - t[i]) / (s[i + 1] - s[i])
    measured = 0.5 / np.diff(crossings)
    middle = 0.5 * (crossings[1:] + crossings[:-1]) - start
    np.testing.assert_allclose(measured, f0 + (f1 - f0) * middle / d, rtol=1e-2)
    # phase continuity: as many half periods as the phase 2 pi (f0 + f1) d / 2 holds
    assert len(crossings) == pytest.approx((f0 + f1) * d, abs=2)


@pytest.mark.parametrize("spec, key", [
    ({"kind": "table", "times": [0.0, 2e-3, 1e-3], "values": [0, 1, 2]}, "times"),
    ({"kind": "table", "times": [0.0, 0.0], "values": [0, 1]}, "times"),
    ({"kind": "table", "times": [0.0, 1.0], "values": [0.0]}, "values"),
    ({"kind": "table", "times": [], "values": []}, "times"),
    ({"kind": "chirp", "f0": -1.0, "f1": 100.0, "duration": 1e-3}, "f0"),
    ({"kind": "chirp", "f0": 1.0, "f1": 100.0, "duration": 0.0}, "duration"),
    ({"kind": "impulse", "duration": -1e-3}, "duration"),
    ({"kind": "impulse"}, "duration"),
    ({"kind": "sine", "frequency": 100.0, "duration": -1.0}, "duration"),
    ({"kind": "step", "rise": -1.0}, "rise"),
    ({"kind": "step", "amplitude": "big"}, "amplitude"),
    ({"kind": "step", "amplitude": float("nan")}, "amplitude"),
    ({"kind": "step", "length": 1.0}, "length"),
    ({"kind": "ramp"}, "kind"),
])
def test_bad_specs_name_the_key(spec, key):
    with pytest.raises(ValueError) as info:
        compile_signals([spec], keys=["loads.brake.signal"])
    message = str(info.value)
    assert message.startswith(f"loads.brake.signal.{key}: ") and "\n" not in message


def test_defaults_fill_optional_keys():
    assert check_signal({"kind": "sine", "frequency": 50}) == {
        "kind": "sine", "frequency": 50.0, "amplitude": 1.0, "phase": 0.0, "start": 0.0,
        "duration": 0.0}
    for kind, fields in SIGNAL_FIELDS.items():
        for name, (vtype, default, unit, doc) in fields.items():
            assert vtype in ("float", "floats") and unit and doc.isascii()
