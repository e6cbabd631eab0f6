"""stability.compare: two analyses' complex modes paired mode by mode, each real part judged against
its own size with a floor, stability compared outside the floor."""
import numpy as np

from transient.stability.compare import pair_modes
from transient.stability.modes import ComplexModes


def modes(*eigs):
    lam = np.array([complex(r, 2 * np.pi * f) for f, r in eigs])
    return ComplexModes(lam, np.eye(len(lam), dtype=complex))


def test_a_weak_mode_is_judged_against_its_own_real_part():
    ref = modes((1000.0, 2000.0), (5000.0, 100.0), (9000.0, -50.0))
    ok = modes((1000.0, 2050.0), (5000.0, 104.0), (9000.0, -40.0))
    assert all(p.within() for p in pair_modes(ref, ok, 10000.0))
    # 40 1/s is 2% of the strongest mode but 40% of this one's
    weak = modes((1000.0, 2000.0), (5000.0, 60.0), (9000.0, -50.0))
    bad = [p for p in pair_modes(ref, weak, 10000.0) if not p.within()]
    assert [p.frequency_hz for p in bad] == [5000.0]


def test_the_floor_covers_neutral_modes_but_not_a_real_instability():
    ref = modes((1000.0, 0.3), (3000.0, -20.0))
    flipped = modes((1000.0, -0.2), (3000.0, -20.0))
    assert all(p.within() for p in pair_modes(ref, flipped, 5000.0))
    spurious = modes((1000.0, 0.3), (3000.0, 12.0))
    pairs = pair_modes(ref, spurious, 5000.0)
    assert [(round(p.frequency_hz), p.within()) for p in pairs] == [(1000, True), (3000, False)]


def test_frequency_band_and_frequency_error():
    ref = modes((1000.0, 10.0), (20000.0, 500.0))
    shifted = modes((1002.0, 10.0), (20000.0, 100.0))
    pairs = pair_modes(ref, shifted, 16000.0)
    assert len(pairs) == 1 and not pairs[0].within()
    assert np.isclose(pairs[0].frequency_error, 2e-3)
    assert pairs[0].within(frequency_rtol=3e-3)


def test_an_instability_only_the_other_analysis_has_is_counted():
    ref = modes((1000.0, -30.0), (1010.0, -35.0))
    # the other's unstable mode lies nearest a stable reference mode that is already paired
    other = modes((1000.0, -30.0), (1004.0, 40.0))
    pairs = pair_modes(ref, other, 2000.0)
    assert any(p.other_unstable and not p.within() for p in pairs)
