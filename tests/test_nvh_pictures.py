"""The pictures a squeal engineer reads (issue 48): a sensor drawn about its preload, frequency
axes to the model's band, titles inside the figure, the receptance from a tap against the
reduced model's own, and a mode coloured by its signed out-of-plane motion with a stated warp.

The run is a steel rod along x on a single line of hex8 (y and z held everywhere, nu = 0: a
one-dimensional rod), clamped at x = 0, pressed at x = L by a constant pressure (its preload)
and tapped there by a half-sine force; reduced, modal damping 2%, the exponential scheme,
which integrates each mode exactly under a force linear over a step.
"""
import shutil
from pathlib import Path

import numpy as np
import pytest

from transient.case import parse
from transient.cli import main
from transient.integration import run
from transient.io.stored import open_history
from transient.plots import cea as shapes
from transient.plots.frf import LOADS, OVERSAMPLE, frf_figure, transfer_data
from transient.plots.history import history_figure, spectrum_figure, spectrogram_figure
from transient.plots.signals import derived
from transient.stages import prepare

from small_cases import PAD_DISC

E, RHO, L, AREA = 2.1e11, 7800.0, 0.5, 1e-4
PRESSURE = 2.0e7            # the preload on the end face [Pa]: x(L) = -p L / E
TAP, DURATION = 200.0, 1.0e-4     # the tap's peak [N] and length [s]
FMAX = 10000.0              # the case's band [Hz]
SEGMENT = 8192              # rows of the FRF's segment: 41 ms, 13 decay times of mode 1

CASE = f"""
[materials.steel]
E = {E}
nu = 0.0
rho = {RHO}
[parts.rod]
material = "steel"
[parts.rod.mesh]
kind = "box"
size = [{L}, 0.01, 0.01]
divisions = [50, 1, 1]
[parts.rod.sets.every]
kind = "box"
min = [-1.0, -1.0, -1.0]
max = [1.0, 1.0, 1.0]
[constraints.axial]
set = "rod.every"
dofs = ["y", "z"]
[constraints.clamp]
set = "rod.xmin"
dofs = ["x"]
[loads.press]
kind = "pressure"
set = "rod.xmax"
value = {PRESSURE}
[loads.tap]
kind = "force"
part = "rod"
point = [{L}, 0.0, 0.0]
vector = [{TAP}, 0.0, 0.0]
[loads.tap.signal]
kind = "impulse"
duration = {DURATION}
[sensors.tip]
part = "rod"
point = [{L}, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
[sensors.middle]
part = "rod"
point = [{L / 2}, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
[solver]
scheme = "exponential"
t_end = 0.128
[solver.damping]
modal = 0.02
[solver.reduction]
enabled = true
fmax = {FMAX}
"""


@pytest.fixture(scope="module")
def rod(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rod")
    path = folder / "rod.toml"
    path.write_text(CASE)
    case = parse(CASE, path)
    run(case, folder / "rod.h5")
    return case, open_history(folder / "rod.h5")


def test_sensors_are_drawn_about_their_preload(rod, tmp_path):
    """The run starts at its preload, the rod's static shortening under the pressure: each
    sensor's first row is that (p x / E, exact on a one-dimensional rod of linear elements),
    and the line drawn is the series less it, from 0; --keep-preload draws the series."""
    _, stored = rod
    fig = history_figure(stored, ["sensors/tip", "sensors/middle"], tmp_path / "h.png")
    ax = fig.axes[0]
    assert "about the preload" in ax.get_ylabel()
    for line, name, x in zip(ax.lines, ("tip", "middle"), (L, L / 2)):
        raw = stored.read(f"sensors/{name}")
        assert raw[0] == pytest.approx(-PRESSURE * x / E, rel=1e-9)
        drawn = line.get_ydata()
        assert drawn[0] == 0.0
        np.testing.assert_array_equal(drawn, raw - raw[0])
        # the tap's vibration, drawn on its own scale, smaller than the preload
        assert 0 < np.abs(drawn).max() < abs(raw[0])
    kept = history_figure(stored, ["sensors/tip"], tmp_path / "k.png", keep_preload=True)
    np.testing.assert_array_equal(kept.axes[0].lines[0].get_ydata(), stored.read("sensors/tip"))
    assert "preload" not in kept.axes[0].get_ylabel()


def test_frequency_axes_end_at_the_model_band(rod, tmp_path):
    """spectrum, spectrogram and frf end at the case's solver.reduction.fmax, not at the rows'
    Nyquist frequency (100 kHz here); --fmax overrides it, inf gives the Nyquist frequency."""
    _, stored = rod
    nyquist = 0.5 / float(np.diff(stored.time()[:2])[0])
    assert nyquist > 5 * FMAX
    tops = [spectrum_figure(stored, ["sensors/tip"], tmp_path / "s.png").axes[-1].get_xlim()[1],
            spectrogram_figure(stored, "sensors/tip", tmp_path / "g.png").axes[0].get_ylim()[1],
            frf_figure(stored, "loads/tap", "sensors/tip", tmp_path / "f.png").axes[-1]
            .get_xlim()[1]]
    np.testing.assert_allclose(tops, FMAX / 1e3, rtol=1e-12)
    asked = frf_figure(stored, "loads/tap", "sensors/tip", tmp_path / "f.png", fmax=4000.0)
    assert asked.axes[-1].get_xlim()[1] == pytest.approx(4.0)
    whole = spectrum_figure(stored, ["sensors/tip"], tmp_path / "s.png", fmax=np.inf)
    assert whole.axes[-1].get_xlim()[1] == pytest.approx(nyquist / 1e3, rel=1e-6)


def test_a_full_models_axes_run_to_the_nyquist_frequency(tmp_path):
    """A full model holds every mode its mesh resolves: with no solver.modes.fmax its run has
    no band, and the axes run to the rows' Nyquist frequency (the unused default
    solver.reduction.fmax is none of its, above which bar_impact's first mode lies)."""
    text = (CASE.replace("enabled = true", "enabled = false")
            .replace("t_end = 0.128", "t_end = 2e-4\ndt = 2e-6")
            .replace('scheme = "exponential"', 'scheme = "implicit"')
            .replace("modal = 0.02", "beta = 1e-7"))
    path = tmp_path / "full.toml"
    path.write_text(text)
    run(parse(text, path), tmp_path / "full.h5")
    stored = open_history(tmp_path / "full.h5")
    nyquist = 0.5 / float(np.diff(stored.time()[:2])[0])
    top = spectrum_figure(stored, ["sensors/tip"], tmp_path / "s.png").axes[-1].get_xlim()[1]
    assert top == pytest.approx(nyquist / 1e3, rel=1e-6)
    with_band = text.replace("[solver.reduction]", "[solver.modes]\nfmax = 4000.0\n"
                             "[solver.reduction]")
    path.write_text(with_band)
    run(parse(with_band, path), tmp_path / "band.h5")
    banded = spectrum_figure(open_history(tmp_path / "band.h5"), ["sensors/tip"],
                             tmp_path / "b.png")
    assert banded.axes[-1].get_xlim()[1] == pytest.approx(4.0)


def test_titles_lie_inside_the_figure(rod, tmp_path):
    """A history with a long name: its frf title, one line, would run past both edges of the
    picture; wrapped, every title's extent lies inside the figure."""
    _, stored = rod
    long = tmp_path / ("a_squeal_run_of_the_slotted_pad_at_mu_0.5_with_its_tet10_disc_" * 2
                       + ".h5")
    shutil.copy(stored.path, long)
    stored = open_history(long)
    figures = [frf_figure(stored, "loads/tap", "sensors/middle", tmp_path / "f.png"),
               history_figure(stored, ["sensors/tip"], tmp_path / "h.png"),
               spectrum_figure(stored, ["sensors/tip"], tmp_path / "s.png"),
               spectrogram_figure(stored, "sensors/tip", tmp_path / "g.png")]
    for fig in figures:
        renderer = fig.canvas.get_renderer()
        title = fig._suptitle
        box = title.get_window_extent(renderer)
        assert 0 <= box.x0 and box.x1 <= fig.bbox.width, title.get_text()
        assert 0 <= box.y0 and box.y1 <= fig.bbox.height, title.get_text()
        wrapped = title.get_text()
        assert wrapped.count("\n") >= 1
        # the test can fail: the title on one line is wider than the figure
        title.set_text(wrapped.replace("\n", " "))
        assert title.get_window_extent(renderer).width > fig.bbox.width


def _half_sine(f):
    """Fourier transform of sin(pi t / D) on [0, D) at f [Hz] (per unit peak) [s]."""
    w, a = 2 * np.pi * np.asarray(f, float), np.pi / DURATION
    return a * (1 + np.exp(-1j * w * DURATION)) / (a ** 2 - w ** 2)


def _samples(f, step):
    """h sum_k sin(pi t_k / D) exp(-i w t_k), t_k = k h on [0, D]: the transform of the tap's
    samples at step h, the continuous one plus its images at multiples of 1 / h [s]."""
    t = step * np.arange(int(round(DURATION / step)) + 1)
    return np.exp(-2j * np.pi * np.asarray(f)[:, None] * t) @ np.sin(np.pi * t / DURATION) * step


def _poles(system):
    """The two poles of each vector, x'' + c x' + omega^2 x: (-c +- i (4 omega^2 - c^2)^1/2) / 2."""
    root = 0.5j * np.sqrt(4 * system.omega2 - system.damp ** 2 + 0j)
    return -0.5 * system.damp + root, -0.5 * system.damp - root


def _hat_transfer(system, f, h):
    """(k, n): each vector's response at the rows, q_k, to a unit force that rises linearly
    from 0 at row -1 to 1 at row 0 and falls to 0 at row 1 (the first-order hold's hat), as
    sum_k q_k exp(-i w k h). With g(t) = (e^(l1 t) - e^(l2 t)) / (l1 - l2) the impulse
    response, q_0 = int_0^h g (1 - u / h) du and q_k = e^(l k h) (e^(l h) - 2 + e^(-l h)) /
    (l^2 h) per pole for k >= 1: geometric series, exact, the sum over the rows' images
    sum_q H(f + q / h) sinc^2(f h + q) in closed form."""
    l1, l2 = _poles(system)
    z = np.exp(2j * np.pi * np.asarray(f)[:, None] * h)
    total = 0.0
    for pole, sign in ((l1, 1.0), (l2, -1.0)):
        x = pole * h
        ratio = np.exp(x) / z
        total = total + sign * ((np.expm1(x) - x) + (np.expm1(x) + np.expm1(-x))
                                * ratio / (1 - ratio)) / (pole ** 2 * h)
    return total / (l1 - l2)


def _free_transfer(system, f, h):
    """(k, n): h sum_k x_k exp(-i w k h), x the free motion of each vector from a unit
    displacement at rest, (l1 e^(l2 t) - l2 e^(l1 t)) / (l1 - l2) [s]."""
    l1, l2 = _poles(system)
    z = np.exp(2j * np.pi * np.asarray(f)[:, None] * h)
    return h * (l1 / (1 - np.exp(l2 * h) / z) - l2 / (1 - np.exp(l1 * h) / z)) / (l1 - l2)


@pytest.mark.parametrize("segment", [SEGMENT, None])
@pytest.mark.parametrize("sensor", ["tip", "middle"])
def test_receptance_from_the_tap_is_the_reduced_model_s(rod, sensor, segment):
    """The receptance from the tap, by H1 over rectangular segments from the tap (SEGMENT
    rows, or one of every row), against the closed form of the reduced model under the
    exponential scheme. The model's own is H(f) = sum_j s_j p_j / (w_j^2 - w^2 + i w c_j)
    per newton. The scheme integrates each vector exactly under the force linear between its
    steps (here the rows): the rows' response is S(f) R(f), S the transform of the tap's
    samples at the steps, R = sum_j s_j p_j R_j the hat's response summed over the rows
    (_hat_transfer), which is sum_q H(f + q / dt) sinc^2(f dt + q) with the rows' images in
    closed form (a sum cut at a few images is short of it by their tail, where the bound is
    tight); the estimate divides by the continuous half-sine's transform F. So it is
    S(f) / F(f) R(f).

    What separates the estimate from that closed form, each bound from the problem:
    - the segment's end: the response left at T = segment dt (the frequency resolution's
      inverse) is exp(-sigma_1 T) of mode 1's, the slowest to decay (sigma = c / 2), counted
      twice for the mode's two exponentials;
    - the input's transform, a sum over OVERSAMPLE points a row: X = S_fine, the transform of
      the samples at dt / OVERSAMPLE, whose images fold back: the estimate is the closed form
      times F / X, off by |e| / (1 - |e|) of it at most, e = X / F - 1 (8e-6 at 0 Hz; 0 at
      1 / (2 D) = 5 kHz, where every image shares the half-sine's zero 1 + exp(-i w D));
    - free vibrations, the response to no force of the tap: the preload's, from its first
      row's reduced residual r = P - Omega^2 q0 (the rows relax from q0 to Omega^-2 P: a
      displacement |r_j| / w_j^2), and the rounding of each step's state, at most gamma_4 =
      4 eps of |q0_j| (1 + w_j dt) in displacement and velocity, in phase at every one of the
      segment's N steps: sum_j |s_j| |Free_j(f)| d_j / |X(f)| (_free_transfer).
    A segment of every row holds no ringing at its end (exp(-41)): the bound is then the
    input's and the free vibrations', which the first term alone hid at SEGMENT rows.
    """
    case, stored = rod
    setup = prepare(case)
    system = setup.system
    k, j = system.sensor_names.index(sensor), list(case.loads).index("tap")
    rows = int(np.sum(stored.time() >= 0.0))
    segment = segment or rows
    data = transfer_data(stored, "loads/tap", f"sensors/{sensor}", segment=segment)
    dt = float(stored.meta["dt"])
    assert not stored.meta.get("subdivisions") and data.dt == dt and data.segment == segment
    assert data.window == "rectangular" and data.what == "receptance" and data.unit == "m/N"
    f = data.f[(data.f > 0) & (data.f <= FMAX)]
    band = np.isin(data.f, f)
    samples, F = _samples(f, dt), _half_sine(f)
    expected = (_hat_transfer(system, f, dt) @ (system.sensors[k] * system.patterns[j] / TAP)
                * samples / F)
    sigma = 0.5 * system.damp[np.argmin(system.omega2)]
    X = _samples(f, dt / OVERSAMPLE)
    e = np.abs(X / F - 1)
    q0 = setup.state.q
    residual = system.patterns[list(case.loads).index("press")] - system.omega2 * q0
    displacement = (np.abs(residual) / system.omega2 + segment * 4 * np.finfo(float).eps
                    * np.abs(q0) * (1 + np.sqrt(system.omega2) * dt))
    free = (np.abs(_free_transfer(system, f, dt)) @ (np.abs(system.sensors[k]) * displacement)
            / np.abs(TAP * X))
    bound = (2 * np.exp(-sigma * segment * dt) * np.abs(expected).max()
             + e / (1 - e) * np.abs(expected) + free)
    error = np.abs(data.H[band] - expected)
    assert np.all(error <= bound), (error / bound).max()
    # sharp enough to see the scheme's own hold of the tap (S / F - 1) at mode 1's peak
    peak = np.argmax(np.abs(expected))
    assert bound[peak] < 0.1 * abs(samples[peak] / F[peak] - 1) * abs(expected[peak])
    # the response is the tap's: coherent over the band; one segment has no coherence
    if data.averages > 1:
        assert data.coherence[band].min() > 0.99
    else:
        assert np.isnan(data.coherence).all()
    # mobility and accelerance are its time derivatives
    for kind, power in (("mobility", 1), ("accelerance", 2)):
        other = transfer_data(stored, "loads/tap", f"sensors/{sensor}", segment, kind)
        np.testing.assert_allclose(other.H[band], data.H[band] * (2j * np.pi * f) ** power,
                                   rtol=1e-12)
        np.testing.assert_array_equal(derived(data.f, data.H, kind), other.H)
    assert other.unit == "(m/s^2)/N"


def test_a_tap_s_frf_takes_every_row_from_it_by_default(rod, tmp_path):
    """Rectangular segments after the tap's first hold no input and add nothing to H1: by
    default the tap's FRF is one segment of every row from it, which resolves mode 1's peak
    (104 Hz wide at 2%) in 7.8 Hz bins where the quarter-record default cut it at 48.8 Hz
    and 20 ms. The coherence of one segment, 1 by construction, is not given; what the
    segment's end cuts is: the tip's largest motion over its last tenth against its largest,
    mode 1's exp(-sigma 0.9 T), the slowest to decay, carrying most of the tip's motion."""
    case, stored = rod
    rows = int(np.sum(stored.time() >= 0.0))
    data = transfer_data(stored, "loads/tap", "sensors/tip")
    assert (data.segment, data.averages, data.window) == (rows, 1, "rectangular")
    assert np.isnan(data.coherence).all()
    # the whole record rings down to the preload's relaxation (1e-15 m of 3e-6 m)
    assert data.left < 1e-9
    system = prepare(case).system
    sigma = 0.5 * system.damp[np.argmin(system.omega2)]
    for segment in (SEGMENT, SEGMENT // 2):
        cut = np.exp(-sigma * 0.9 * segment * data.dt)
        left = transfer_data(stored, "loads/tap", "sensors/tip", segment).left
        assert 0.5 * cut < left < 2 * cut
    fig = frf_figure(stored, "loads/tap", "sensors/tip", tmp_path / "f.png")
    title = fig._suptitle.get_text().replace("\n", " ")
    assert f"one rectangular segment of {rows} samples" in title
    assert "no coherence" in fig.axes[-1].texts[0].get_text()
    hann = transfer_data(stored, "loads/tap", "sensors/tip", window="hann")
    assert hann.segment == 4096 and hann.averages > 1


def test_frf_draws_the_load_s_receptance(rod, tmp_path, capsys):
    """The figure draws transfer_data's |H| in dB; without --input the one load varying in
    time is the input; a constant load, or a kind from a sensor, is a one-line error."""
    _, stored = rod
    fig = frf_figure(stored, "loads/tap", "sensors/tip", tmp_path / "f.png")
    data = transfer_data(stored, "loads/tap", "sensors/tip")
    shown = data.f <= FMAX
    with np.errstate(divide="ignore"):
        np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(),
                                   20 * np.log10(np.abs(data.H[shown])), rtol=1e-12)
    assert "receptance" in fig.axes[0].get_ylabel() and "m/N" in fig.axes[0].get_ylabel()
    png = tmp_path / "default.png"
    assert main(["plot", "frf", str(stored.path), "--output", "sensors/tip", "-o",
                 str(png)]) == 0
    assert png.exists() and "from loads/tap " in fig._suptitle.get_text()
    capsys.readouterr()
    for args, key in ((["--input", LOADS + "press"], "does not vary in time"),
                      (["--input", "sensors/middle", "--kind", "mobility"], "--kind")):
        assert main(["plot", "frf", str(stored.path), "--output", "sensors/tip"] + args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and key in err, err


def _pad_disc():
    from transient.case.loading import load
    from transient.model import build_model
    case = load(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml", PAD_DISC)
    return case, build_model(case)


def _wave(points):
    """A complex displacement (3 n,): out of the plane cos 2 theta (real) and sin 2 theta / 2
    (imaginary), two nodal diameters, with an in-plane part of its own."""
    theta = np.arctan2(points[:, 1], points[:, 0])
    u = np.stack([0.3 * np.sin(theta), 0.2j * np.cos(3 * theta),
                  np.cos(2 * theta) + 0.5j * np.sin(2 * theta)], axis=1)
    return 1e-3 * u.ravel()


def test_a_mode_is_coloured_by_its_signed_out_of_plane_motion():
    """The colours are the displacement along the disc's axis over the largest, of each part,
    both signs present (the nodal lines between); |u| by option; the warp draws the largest
    displacement as WARP of the model's size, the caption says the scale."""
    case, model = _pad_disc()
    direction, along = shapes.out_of_plane(case, model)
    np.testing.assert_allclose(direction, [0.0, 0.0, 1.0], atol=1e-15)
    assert "rotation" in along
    u = _wave(model.points)
    drawn = shapes.mode_panels(model.points, u, direction)
    U = u.reshape(-1, 3)
    largest = np.sqrt((np.abs(U) ** 2).sum(axis=1)).max()
    real, imag = drawn["panels"]
    np.testing.assert_allclose(real["colour"], U.real[:, 2] / largest, rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(imag["colour"], U.imag[:, 2] / largest, rtol=1e-14, atol=1e-16)
    assert real["colour"].min() < -0.5 and real["colour"].max() > 0.5
    size = np.ptp(model.points, axis=0).max()
    assert drawn["scale"] == pytest.approx(shapes.WARP * size / largest, rel=1e-14)
    np.testing.assert_allclose(real["warp"], drawn["scale"] * U.real, rtol=1e-14)
    assert f"warp x {drawn['scale']:.3g}" in drawn["caption"] and "5%" in drawn["caption"]
    magnitude = shapes.mode_panels(model.points, u, direction, "magnitude")["panels"][0]
    np.testing.assert_allclose(magnitude["colour"],
                               np.linalg.norm(U.real, axis=1) / largest, rtol=1e-14)


def test_without_a_rotation_out_of_plane_is_the_thinnest_direction():
    from transient.model import build_model
    text = CASE.replace(f"size = [{L}, 0.01, 0.01]", f"size = [{L}, 0.01, 0.1]")
    case = parse(text, Path("plate.toml"))
    direction, along = shapes.out_of_plane(case, build_model(case))
    np.testing.assert_allclose(direction, [0.0, 1.0, 0.0], atol=1e-12)
    assert "thinnest" in along


def test_the_mode_picture_states_its_warp(tmp_path):
    """Rendered: the picture holds the caption, read back from its own text."""
    from PIL import Image
    from transient.plots.render import RenderingUnavailable
    case, model = _pad_disc()
    direction, along = shapes.out_of_plane(case, model)
    path = tmp_path / "mode.png"
    try:
        drawn = shapes.mode_figure(model, _wave(model.points), path, "a wave", direction,
                                   along=along)
    except RenderingUnavailable as exc:
        pytest.skip(str(exc))
    assert drawn["caption"] in drawn["texts"] and drawn["caption"].startswith("warp x")
    with Image.open(path) as image:
        assert np.asarray(image.convert("L")).std() > 5
