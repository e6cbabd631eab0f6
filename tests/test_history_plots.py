"""`transient plot history|spectrum|frf|pressure`: pictures of a history and the numbers in them."""
from pathlib import Path

import h5py
import numpy as np
import pytest
from matplotlib.image import imread

from transient.case.loading import load
from transient.cli import main
from transient.io.history import History
from transient.plots.pressure import contact_force, plane_frame, pressure_panels
from transient.plots.signals import amplitude_spectrum, sample_step, transfer_function
from transient.integration import run
from transient.io.stored import open_history

CASE = Path(__file__).resolve().parent.parent / "cases" / "bar_impact.toml"
SHORT = ["solver.t_end=3e-5"]      # contact from 10 us: 190 rows, a third of them in contact


@pytest.fixture(scope="module")
def history(tmp_path_factory):
    path = tmp_path_factory.mktemp("plots") / "bar.h5"
    run(load(CASE, SHORT), path)
    return path


def _synthetic(path, time, values):
    """A history holding one sensor 's' (values [m] at times [s])."""
    with History.create(path, {}, {"time": (), "sensors/s": ()}) as h:
        h.append({"time": time, "sensors/s": values})
    return path


def _check_picture(path, min_width=500):
    rgb = imread(path)[..., :3]
    height, width = rgb.shape[:2]
    assert width >= min_width and height >= 300, path.name
    # something was drawn: neither blank nor one colour, and some colour shows
    assert (rgb.min(axis=2) < 0.9).mean() > 0.01, f"{path.name} is nearly blank"
    assert rgb.reshape(-1, 3).std(axis=0).max() > 0.05, f"{path.name} is uniform"
    return width, height


def _one_line_error(capsys, *names):
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    for name in names:
        assert name in err, err
    return err


@pytest.mark.parametrize("args, suffix", [
    (["history"], "history"),
    (["history", "--series", "energy", "sensors/tip"], "history"),
    (["spectrum", "--fmax", "1e6"], "spectrum"),
    (["frf", "--input", "sensors/tip", "--output", "sensors/tail", "--segment", "64"], "frf"),
])
def test_pictures_of_a_history(history, capsys, args, suffix):
    assert main(["plot", args[0], str(history)] + args[1:]) == 0
    path = history.with_name(f"bar_{suffix}.png")
    assert capsys.readouterr().out.split() == [str(path)]
    _check_picture(path)


def test_spectrum_of_a_sine_peaks_at_its_frequency(tmp_path, capsys):
    dt, n, f0, a = 1e-6, 1000, 12e3, 2e-6       # 1 kHz bins: f0 on the 12th
    t = dt * np.arange(n)
    path = _synthetic(tmp_path / "sine.h5", t, 0.5e-6 + a * np.sin(2 * np.pi * f0 * t))
    stored = open_history(path)
    f, amplitude = amplitude_spectrum(stored.read("sensors/s"), sample_step(stored, t))
    assert f[np.argmax(amplitude)] == pytest.approx(f0)
    assert amplitude.max() == pytest.approx(a, rel=1e-9)
    assert amplitude[0] < 1e-9 * a                  # the offset is removed
    png = tmp_path / "sine.png"
    assert main(["plot", "spectrum", str(path), "-o", str(png)]) == 0
    assert capsys.readouterr().out.strip() == str(png)
    _check_picture(png)


@pytest.mark.parametrize("gap", [2e-6, np.nan])
def test_spectrum_needs_evenly_spaced_rows(tmp_path, capsys, gap):
    t = np.cumsum(np.r_[0.0, np.full(50, 1e-6), np.full(50, gap)])
    path = _synthetic(tmp_path / "uneven.h5", t, np.sin(1e5 * t))
    assert main(["plot", "spectrum", str(path)]) == 2
    _one_line_error(capsys, str(path), "not evenly spaced")


@pytest.mark.parametrize("dt, every", [(5e-6, 1), (2.5e-6, 2)])
def test_the_sample_step_is_the_run_s_not_the_rounded_time_differences(tmp_path, dt, every):
    """A run's row times are sums of its steps, each rounded at the time reached: their
    median difference is off the step by about 1e-12 over 0.128 s; the step is the run's
    (attributes dt and every), which the rows' spacing agrees with."""
    t = np.cumsum(np.r_[0.0, np.full(25600 * every, dt)])[::every]
    path = _synthetic(tmp_path / "rows.h5", t, np.zeros_like(t))
    with h5py.File(path, "a") as f:
        f.attrs["dt"], f.attrs["every"] = dt, every
    stored = open_history(path)
    assert abs(np.median(np.diff(t)) / (dt * every) - 1) > 1e-13
    assert sample_step(stored, stored.time()) == dt * every
    with h5py.File(path, "a") as f:
        f.attrs["dt"] = 3 * dt          # not this history's step: its rows' spacing is taken
    stored = open_history(path)
    assert sample_step(stored, stored.time()) == np.median(np.diff(t))


def test_transfer_function_of_a_sensor_with_itself_is_one(history, capsys):
    stored = open_history(history).uniform()
    x = stored.read("sensors/tip")
    dt = sample_step(stored, stored.time())
    f, H, coherence = transfer_function(x, x, dt, 64)
    assert len(f) == 33 and np.all(np.isfinite(H))
    assert np.allclose(H, 1.0, rtol=0, atol=1e-12) and np.allclose(coherence, 1.0, atol=1e-12)
    # a gain of -3 reads as 9.5 dB and half a turn of phase
    _, H, coherence = transfer_function(x, -3.0 * x, dt, 64)
    assert np.allclose(H, -3.0, atol=1e-12) and np.allclose(coherence, 1.0, atol=1e-12)
    png = history.with_name("self_frf.png")
    assert main(["plot", "frf", str(history), "--input", "sensors/tip", "--output",
                 "sensors/tip", "-o", str(png)]) == 0
    _check_picture(png)


def test_frf_refuses_a_segment_longer_than_the_history(history, capsys):
    assert main(["plot", "frf", str(history), "--input", "sensors/tip", "--output",
                 "sensors/tail", "--segment", "4096"]) == 2
    # 308 rows, the last the run's end off the rows' grid: no sample of a spectrum
    _one_line_error(capsys, str(history), "--segment", "307 rows, fewer than the segment")


@pytest.mark.slow
def test_pressure_maps_side_by_side(history, tmp_path, capsys):
    finer = tmp_path / "finer.h5"
    run(load(CASE, SHORT + ["parts.bar.mesh.divisions=[100,3,3]"]), finer)   # 108 points
    png = tmp_path / "pressure.png"
    assert main(["plot", "pressure", str(history), str(finer), "--labels", "1 x 1 faces",
                 "3 x 3 faces", "-o", str(png)]) == 0
    assert capsys.readouterr().out.strip() == str(png)
    width, height = _check_picture(png, min_width=900)
    assert width > 1.5 * height                      # two panels side by side
    # the default time is that of the largest force; the bar pushes the wall while in contact
    stored = open_history(history)
    force = contact_force(stored, "wall")
    t = stored.time()
    assert force.max() > 0 and np.all(force[t < 9.9e-6] == 0)
    panels = pressure_panels([stored, open_history(finer)])
    assert [len(p["points"]) for p in panels] == [12, 108]
    assert panels[0]["force"] == force.max() and panels[0]["time"] == t[np.argmax(force)] > 1e-5
    assert abs(panels[1]["time"] - panels[0]["time"]) < 1e-6
    assert panels[0]["rule"] == "fine rule" and panels[0]["label"] == "bar"
    # Gamma is the end face x = 0.1: its plane's axes lie in y, z
    centre, axes = plane_frame(stored.geometry("contact/wall/points"),
                               stored.geometry("contact/wall/normals"))
    assert centre[0] == pytest.approx(0.1) and np.allclose(axes[:, 0], 0.0)
    assert np.allclose(axes @ axes.T, np.eye(2))


def test_pressure_needs_the_contact_output(tmp_path, capsys):
    path = tmp_path / "nocontact.h5"
    run(load(CASE, ["solver.t_end=2e-6", "output.contact=false"]), path)
    assert main(["plot", "pressure", str(path)]) == 2
    _one_line_error(capsys, str(path), "output.contact = true")


@pytest.mark.parametrize("args, expected", [
    (["history", "{missing}"], "file not found"),
    (["spectrum", "{text}"], "not a transient history"),
    (["history", "{h5}", "--series", "sensors/nowhere"], "no scalar series 'sensors/nowhere'"),
    (["frf", "{h5}", "--input", "sensors", "--output", "sensors/tail"], "--input"),
    (["spectrum", "{h5}", "--fmax", "-5"], "--fmax"),
    (["pressure", "{h5}", "--pair", "floor"], "no contact pair 'floor'"),
    (["pressure", "{h5}", "{h5}", "--labels", "one"], "one label per file"),
])
def test_bad_input_is_one_line_error(history, tmp_path, capsys, args, expected):
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5")
    names = {"missing": str(tmp_path / "missing.h5"), "text": str(text), "h5": str(history)}
    args = [a.format(**names) for a in args]
    assert main(["plot"] + args) == 2
    _one_line_error(capsys, args[1], expected)


def _growing(t, sigma=50.0, f=2000.0, limit=1e-4):
    """A sine growing at sigma [1/s] from 1e-6, saturating at `limit` (a limit cycle), plus a
    decaying 5 kHz tone."""
    a = 1e-6 * np.exp(sigma * t) / np.sqrt(1 + (1e-6 * np.exp(sigma * t) / limit) ** 2)
    return a * np.sin(2 * np.pi * f * t) + 1e-7 * np.exp(-20 * t) * np.sin(2 * np.pi * 5e3 * t)


@pytest.mark.parametrize("sigma", [30.0, -30.0])
def test_growth_rate_of_a_pure_exponential(sigma):
    from transient.plots.signals import envelope, growth_rate
    dt = 1e-5
    t = np.arange(0, 0.2, dt)
    fitted, (t0, t1), rms = growth_rate(t, envelope(np.exp(sigma * t) * np.sin(4e3 * np.pi * t),
                                                    dt))
    assert fitted == pytest.approx(sigma, rel=5e-4)
    assert t1 - t0 > 0.05 and rms < 0.05


def test_growth_rate_of_a_limit_cycle_is_fitted_on_its_linear_phase():
    """The growth until a tenth of the limit cycle's amplitude, the other tone filtered out by
    the band: within 0.5% (the saturation slows the growth by 1% at the end of the fit)."""
    from transient.plots.signals import envelope, growth_rate
    dt = 1e-5
    t = np.arange(0, 0.2, dt)
    x = _growing(t)
    sigma, (t0, t1), _ = growth_rate(t, envelope(x, dt, (1500.0, 2500.0)))
    assert sigma == pytest.approx(50.0, rel=5e-3)
    assert t1 < np.log(0.11 * 1e-4 / 1e-6) / 50.0       # before a tenth of the limit (and a bit)


def test_running_amplitude_keeps_a_growth_over_four_decades():
    """A tone growing from 1e-9 to 1e-5 on a moving offset (the limit cycle's mean shifting)
    and under a constant floor tone: over a period, the running amplitude is the tone's
    within its growth over half a period, and its growth fitted past the floor is sigma to
    0.1%; the Hilbert envelope, whose FFT leaks the large end onto the small start, is not."""
    from transient.plots.signals import envelope, growth_rate, running_amplitude
    dt, f, sigma = 1e-6, 10e3, 2000.0
    t = np.arange(0, 6e-3, dt)
    amp = 1e-9 * np.exp(sigma * np.minimum(t, 4.6e-3))
    x = amp * np.sin(2 * np.pi * f * t) + 1e-6 * np.tanh((t - 5e-3) / 2e-4) \
        + 2e-10 * np.sin(2 * np.pi * 7.3e3 * t)
    a = running_amplitude(x, round(1 / (f * dt)))
    inner = (t > 2e-3) & (t < 4.4e-3)
    assert np.allclose(a[inner], amp[inner], rtol=np.expm1(sigma * 0.5 / f) + 0.02)
    fitted, _, _ = growth_rate(t, a, (2e-3, 4.4e-3))
    assert fitted == pytest.approx(sigma, rel=1e-3)
    hilbert, _, _ = growth_rate(t, envelope(x, dt), (2e-3, 4.4e-3))
    assert abs(hilbert / sigma - 1) > 0.1


def test_envelope_and_spectrogram_pictures(tmp_path, capsys):
    t = np.arange(0, 0.1, 1e-5)
    path = _synthetic(tmp_path / "squeal.h5", t, _growing(t))
    assert main(["plot", "envelope", str(path), "--band", "1500:2500"]) == 0
    out = capsys.readouterr().out
    picture = tmp_path / "squeal_envelope.png"
    _check_picture(picture)
    sigma = float(out.split("growth rate ")[1].split()[0])
    assert sigma == pytest.approx(50.0, rel=5e-3)
    assert main(["plot", "spectrogram", str(path), "--fmax", "8000"]) == 0
    _check_picture(tmp_path / "squeal_spectrogram.png")
    from transient.plots.signals import spectrogram
    f, tc, A = spectrogram(_growing(t), 1e-5, 512)
    assert abs(f[np.argmax(A[:, -1])] - 2000.0) <= f[1]
    # a sine on a bin reads its amplitude in every segment
    f_bin = 10 * 1e5 / 512
    f, tc, A = spectrogram(3e-5 * np.sin(2 * np.pi * f_bin * t), 1e-5, 512)
    np.testing.assert_allclose(A[10], 3e-5, rtol=1e-3)


def test_a_spectrogram_keeps_a_narrow_tone_where_its_bins_outnumber_the_pixels():
    """A tone one bin wide among 4097 bins (segments of 8192 samples) drawn on 400 rows: each
    row holds its group's peak, so every segment's row of the tone reads its amplitude (a 1 s
    squeal history's limit cycle vanished from the picture when the rows were the bins)."""
    from transient.plots.signals import peak_pooled, spectrogram
    dt = 1.25e-5
    t = np.arange(0, 0.5, dt)
    f_bin = 757 / (8192 * dt)
    f, tc, A = spectrogram(2e-6 * np.sin(2 * np.pi * f_bin * t), dt, 8192)
    fp, Ap = peak_pooled(f, A, 400)
    assert len(fp) <= 400 and Ap.shape == (len(fp), A.shape[1])
    row = int(np.argmin(np.abs(fp - f_bin)))
    np.testing.assert_allclose(Ap[row], 2e-6, rtol=1e-3)
    assert fp[0] < fp[1] and abs(fp[row] - f_bin) < fp[1] - fp[0]
    # few bins: drawn as they are
    few = A[:300]
    assert peak_pooled(f[:300], few, 400)[1] is few


@pytest.mark.parametrize("args, key", [(["envelope", "--window", "0.05"], "--window"),
                                       (["envelope", "--window", "0.05:0.01"], "--window"),
                                       (["envelope", "--band", "a:b"], "--band"),
                                       (["envelope", "--window", "0.2:0.3"], "--window"),
                                       (["spectrogram", "--segment", "4"], "--segment"),
                                       (["spectrogram", "--series", "sensors/x"], "--series")])
def test_bad_envelope_and_spectrogram_options_are_one_line(tmp_path, capsys, args, key):
    t = np.arange(0, 0.1, 1e-5)
    path = _synthetic(tmp_path / "s.h5", t, _growing(t))
    assert main(["plot", args[0], str(path)] + args[1:]) == 2
    _one_line_error(capsys, key)
