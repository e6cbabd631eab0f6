"""The whole model's fields of the reduced modes formed a block of modes at a time (the band
residual, the complex modes' residuals and descriptors): the figures of the whole band at
once, each mode's its own."""
import pytest

from transient import api

from small_cases import PAD_DISC

PAD = "cases/pad_disc.toml"


def _analysis(monkeypatch, width):
    import transient.reduce.stage as stage
    import transient.stability.residual as residual
    import transient.stability.shapes as shapes
    for module in (stage, residual, shapes):
        monkeypatch.setattr(module, "block_columns", lambda n: width)
    case = api.load(PAD, PAD_DISC + ["contact.pad_disc.friction.mu=0.6", 'cea.shapes="all"'])
    return api.cea(case)


def _flat(row, prefix=""):
    for key, value in row.items():
        if isinstance(value, dict):
            yield from _flat(value, f"{prefix}{key}.")
        else:
            yield prefix + key, value


def test_blocks_of_modes_give_the_figures_of_the_whole_band(monkeypatch):
    """Blocks of 3 modes against one block of them all: the same descriptors, residuals and
    band residual, to round-off (some products' order follows the block's width)."""
    whole = _analysis(monkeypatch, 10 ** 6)
    blocks = _analysis(monkeypatch, 3)
    assert len(whole.shapes) > 6
    assert all("residual" in row for row in whole.shapes)
    for a, b in zip(blocks.shapes, whole.shapes, strict=True):
        a, b = dict(_flat(a)), dict(_flat(b))
        assert a.keys() == b.keys()
        for key, value in b.items():
            if isinstance(value, float):
                assert a[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key
            else:
                assert a[key] == value, key
    # a residual 1e-6 of its forces: their round-off, which the block's width orders, shows
    # at 1e-10 of it
    assert blocks.meta["band_residual"] == pytest.approx(whole.meta["band_residual"], rel=1e-8)
    assert whole.meta["band_residual"] > 0
