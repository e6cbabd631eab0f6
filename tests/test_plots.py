"""`transient plot compat`: three PNG pictures per contact pair, and the data drawn in them."""
from pathlib import Path

import numpy as np
import pytest

from transient.plots import compat as plots
from transient.plots.views import gamma_triangles
from transient.case.loading import load
from transient.cli import main
from transient.contact.pair import build_contact
from transient.model.model import build_model

CASE = Path(__file__).resolve().parent.parent / "cases" / "drilled_cube.toml"
# a smaller drilled cube: the 4 x 4 upper grid stays nested in the 8 x 8 lower one (the fine
# rule keeps its default degree: degree 2 under-integrates the gap of the tri6 faces and adds
# spurious zero-energy shapes)
SMALL = ["parts.lower.mesh.divisions=[8,8,2]", "parts.upper.mesh.divisions=[4,4,1]"]
KINDS = ("shapes", "singular_values", "observation")


def _args(*extra):
    args = ["plot", "compat", str(CASE)]
    for o in SMALL:
        args += ["--set", o]
    return args + list(extra)


@pytest.fixture(scope="module")
def pair():
    case = load(CASE, SMALL)
    return build_contact(case, build_model(case), need_compatibility=True)[0]


def _png_size(path):
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n", f"{path.name} is not a PNG"
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


@pytest.mark.slow
def test_writes_three_pictures_per_pair(tmp_path, capsys):
    out = tmp_path / "pictures"
    assert main(_args("--out", str(out), "--shapes", "1,5,30")) == 0
    printed = capsys.readouterr().out.split()
    expected = [out / f"interface_{kind}.png" for kind in KINDS]
    assert printed == [str(p) for p in expected]
    from matplotlib.image import imread
    for path in expected:
        width, height = _png_size(path)
        assert width >= 600 and height >= 300 and path.stat().st_size > 20_000, path.name
        rgb = imread(path)[..., :3]
        # something was drawn: not blank, and the colour maps show (not only grey and black)
        assert (rgb.min(axis=2) < 0.9).mean() > 0.05, f"{path.name} is nearly blank"
        assert (np.ptp(rgb, axis=2) > 0.3).mean() > 0.002, f"{path.name} has no colour"


@pytest.mark.parametrize("value, reason", [("1,x", "separated by commas"),
                                           ("0", "start at 1"),
                                           ("100000", "out of range")])
def test_bad_shapes_is_one_line_error(tmp_path, capsys, value, reason):
    assert main(_args("--out", str(tmp_path), "--shapes", value)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and "--shapes" in err
    assert reason in err
    assert not list(tmp_path.iterdir())


def test_unknown_pair_is_one_line_error(tmp_path, capsys):
    assert main(_args("--out", str(tmp_path), "--pair", "nope")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no pair 'nope'" in err


def test_default_shapes_straddle_the_cut(pair):
    numbers = plots.default_shapes(pair.compat, pair.eps)
    r = pair.compat.kept(pair.eps)
    assert numbers[0] == 1 and r in numbers and r + 1 in numbers and max(numbers) > r + 1


def test_compatible_shapes_open_no_gap(pair):
    """Drawn gap of a kept shape is round-off; past the cut it is not."""
    r = pair.compat.kept(pair.eps)
    for number, small in ((1, True), (r, True), (r + 1, False)):
        u1, u2, gap = plots.shape_fields(pair, number)
        size = max(np.abs(u1).max(), np.abs(u2).max())
        assert (np.abs(gap).max() < 1e-6 * size) == small, number


def test_gamma_triangulation_leaves_the_hole_open(pair):
    interface = pair.interface
    tri = gamma_triangles(interface, interface.fine)
    q = interface.fine.points[:, :2]
    centroids = q[tri].mean(axis=1)
    # the hole (a polygon inscribed in the circle of radius 0.015 about the centre) stays
    # empty: a triangle across it would have its centroid well inside
    assert np.linalg.norm(centroids - [0.05, 0.05], axis=1).min() > 0.95 * 0.015
    # and the triangles cover nearly all of Gamma (the points stop short of its edges)
    ab, ac = q[tri[:, 1]] - q[tri[:, 0]], q[tri[:, 2]] - q[tri[:, 0]]
    area = 0.5 * np.abs(ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]).sum()
    assert 0.85 * interface.fine.area < area <= interface.fine.area


def test_observation_rows_spread(pair):
    """The raw row lives on the nodes of one face; the regularized one on many more."""
    point = plots.centre_point(pair.interface.fine)
    side = plots.observation_side(pair)
    raw, reg = plots.observation_rows(pair, point, side)
    face_nodes = 6        # tri6 faces of the drilled (finer) cube
    assert side == 2 and np.count_nonzero(raw) <= face_nodes
    assert np.count_nonzero(np.abs(reg) > 1e-3 * np.abs(reg).max()) > 4 * face_nodes
    # both observe a rigid normal translation of the surface alike (partition of unity)
    assert raw.sum() == pytest.approx(1.0) and reg.sum() == pytest.approx(1.0)
