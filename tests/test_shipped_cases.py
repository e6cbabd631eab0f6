"""Every shipped case runs through the command line and gives one physical number right."""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.case.loading import load
from transient.cli import main
from transient.dynamics.chunks import buffer
from transient.io.reading import summary
from transient.model.model import build_model
from transient.stages import prepare, stepper
from transient.studies.modal import compare

CASES = Path(__file__).resolve().parent.parent / "cases"


def run_modes(capsys, name, *overrides):
    args = ["modes", str(CASES / name), "--json"]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


def total_mass(model):
    return model.lumped_mass.sum() / 3


def test_every_case_is_tested():
    # bar_impact.toml: tests/test_transient.py::test_bar_on_a_rigid_wall (contact duration 2 L / c)
    # pad_disc_long.toml: test_pad_disc_schemes_agree_below_5khz (its scheme settings) and
    # benchmarks/bench_long.py (the whole second)
    # two_bars.toml: tests/test_transient.py::test_two_identical_bars_exchange_velocities
    # pad_disc_squeal.toml: test_pad_disc_squeal_grows_as_its_complex_modes (the growth; its
    # second of squeal: benchmarks/bench_squeal.py and docs/performance.md)
    assert sorted(p.name for p in CASES.glob("*.toml")) == [
        "bar_impact.toml", "brake_corner.toml", "drilled_cube.toml", "pad_disc.toml",
        "pad_disc_long.toml", "pad_disc_squeal.toml", "pad_disc_tet10.toml", "slotted_pad.toml",
        "two_bars.toml"]


@pytest.mark.slow
def test_pad_disc_tet10_locks_tied_exactly_with_the_rich_rule_only():
    """The paper's figure 11 on the pad and disc meshed in tet10, each part on its own: tied
    exactly (the gap held at zero on the rule's rows), the fine rule raises the first 50
    frequencies of the (1-eps) regularized centre rule by up to 10.9% mode by mode (mean
    3.0%; 10.9% as well over the MAC partners alike, MAC >= 0.5); tied by springs at the
    exponential law's tangent at 1 MPa (k = lambda p = 5e11), by 0.36% at most: the nearly
    compatible shapes stay soft under any stiffness short of some 1e21 Pa/m
    (studies/study_locking.py)."""
    path = CASES / "pad_disc_tet10.toml"
    rich = ["contact.pad_disc.rule=fine", "contact.pad_disc.regularized=false"]
    exact = compare(load(path), load(path, rich), "disc_rim", "pad_back", 0.01)
    order = exact.by_order[:50]
    alike = exact.shifts[:50][exact.mac[:50] >= 0.5]
    assert len(order) == 50 and exact.ties[0].held == 371 and exact.ties[1].held == 1653
    assert 9 < order.max() < 13 and 2.5 < order.mean() < 3.5 and order.min() > -1.0
    assert len(alike) >= 40 and 9 < alike.max() < 13 and alike.min() > -1.0
    penalty = ["solver.modes.tie=penalty"]
    soft = compare(load(path, penalty), load(path, penalty + rich), "disc_rim", "pad_back",
                   0.01)
    assert np.abs(soft.by_order[:50]).max() < 0.5 and np.abs(soft.shifts[:50]).max() < 0.5


# cases/slotted_pad.toml's own meshes, and the same tool arguments at a coarser size
# (tests/data/slotted_pad: --size 0.03 --interface 0.012): the small model for the tests
SLOTTED_SMALL = ['parts.disc.mesh.path="../tests/data/slotted_pad/disc.msh"',
                 'parts.pad.mesh.path="../tests/data/slotted_pad/pad.msh"']


@pytest.mark.parametrize("overrides, ndof", [([], 27678), (SLOTTED_SMALL, 7287)])
def test_slotted_pad_sets_and_mass(overrides, ndof):
    """The slotted pad's sets as its case names them, at both sizes: the friction face is the
    lining's face less the slot and the chamfers, and the parts weigh their volumes at their
    materials' densities (the lining's 2500, the backplate's and the disc's 7850)."""
    from brake_shapes import pad_geometry
    from transient.mesh.selections import set_faces
    from transient.model.loads import face_area
    case = load(CASES / "slotted_pad.toml", overrides)
    model = build_model(case)
    assert model.ndof == ndof
    pad = model.parts["pad"].mesh
    shape = pad_geometry(0.0675, 0.1125, np.radians(52.0), 0.01, 0.004, 0.01, 0.005, 0.003)
    assert {"friction", "slot", "chamfer", "ends", "back"} <= set(pad.face_sets)
    assert face_area(pad.points, set_faces(pad, "friction")) == pytest.approx(
        shape["friction"], rel=1e-4)
    assert face_area(pad.points, set_faces(pad, "back")) == pytest.approx(shape["sector"],
                                                                           rel=1e-4)
    disc = np.pi * (0.12 ** 2 - 0.06 ** 2) * 0.011 * 7850.0
    lining = shape["lining"] * 2500.0
    backplate = shape["sector"] * 0.005 * 7850.0
    assert total_mass(model) == pytest.approx(disc + lining + backplate, rel=1e-4)


@pytest.mark.slow
def test_slotted_pad_contact_carries_the_piston(tmp_path):
    """A short run of the small slotted pad: the pad is held in its plane only, so at the
    preload the contact carries the whole piston force, 1 MPa on the backplate's whole back
    (the slot and the chamfers cut the lining only)."""
    out = tmp_path / "slotted.h5"
    assert main(["run", str(CASES / "slotted_pad.toml"), "-o", str(out), "--quiet",
                 "--set", "solver.t_end=2e-4"]
                + [a for o in SLOTTED_SMALL for a in ("--set", o)]) == 0
    assert summary(out)["status"] == "complete"
    with h5py.File(out, "r") as f:
        force = json.loads(f.attrs["preload_contact_force"])["pad_disc"]
    sector = 0.5 * (0.1125 ** 2 - 0.0675 ** 2) * np.radians(52.0)
    assert force == pytest.approx(1.0e6 * sector, rel=1e-4)


CORNER_DOFS = {"disc": 13578, "pad_in": 2928, "pad_out": 2952, "piston_in": 1281,
               "piston_out": 1260, "caliper": 11823, "bracket": 7884}


def test_brake_corner_parts_and_mass():
    """The corner's seven meshes (tools/mesh_corner.py --size 0.016), each part's dofs, and
    their mass: the parts' volumes at steel's density, the linings' at the lining's."""
    from brake_shapes import CORNER_LINING, CORNER_VOLUMES
    model = build_model(load(CASES / "brake_corner.toml"))
    assert {name: 3 * part.mesh.n_nodes for name, part in model.parts.items()} == CORNER_DOFS
    mass = 7850.0 * sum(CORNER_VOLUMES.values()) - 2 * (7850.0 - 2500.0) * CORNER_LINING
    assert total_mass(model) == pytest.approx(mass, rel=1e-4)


@pytest.mark.slow
def test_brake_corner_preload_with_friction():
    """The corner's preload at mu = 0.4 on both linings, the disc turning about +z: each
    friction pair carries its piston's force, the line pressure on the piston's area (the
    pistons are free along their axes, the pads' other ties hold the tangential plane only);
    the friction drags both pads along the disc's motion at their centres (-x), the mirrored
    outer pad as the inner one, by mu times that force less the spread of its directions over
    the pads' arc; the abutments hold it, the trailing one in compression, the leading one in
    tension. The setup's stages up to the preload only (no reduction)."""
    from transient.contact.contactset import first_tangent, stack
    from transient.contact.pair import build_contact
    from transient.model import constant_load
    from transient.shared import factorization
    from transient.solve.preload import solve_preload
    case = load(CASES / "brake_corner.toml", ["contact.pad_in_disc.friction.mu=0.4",
                                              "contact.pad_out_disc.friction.mu=0.4"])
    model = build_model(case)
    pairs = build_contact(case, model)
    contacts = stack(pairs, model.ndof)
    preload = solve_preload(model.K, model.fixed, constant_load(case, model), contacts,
                            factorization(case, model, contacts), case.solver.newton.tolerance,
                            case.solver.newton.max_iter, first_tangent(pairs, contacts))
    force = {name: float((contacts.weights * preload.pressure)[s].sum())
             for name, s in contacts.slices.items()}
    piston = 4.0e6 * np.pi * 0.01875 ** 2
    friction = contacts.friction_force(preload.pressure)
    for side in ("in", "out"):
        # (the piston's face a circle of 12 quadratic arcs: 1.6e-4 short of its area)
        assert force[f"pad_{side}_disc"] == pytest.approx(piston, rel=3e-4)
        assert force[f"piston_{side}"] == pytest.approx(force[f"pad_{side}_disc"], rel=1e-8)
        drag = friction[model.part_dofs(f"pad_{side}")].reshape(-1, 3).sum(axis=0)
        assert -0.4 * piston < drag[0] < -0.95 * 0.4 * piston
        assert abs(drag[2]) < 1e-9 * piston
        assert force[f"abutment_{side}_hi"] > 0.1 * piston
        assert force[f"abutment_{side}_lo"] < -0.1 * piston


@pytest.mark.slow
def test_drilled_cube_mass_and_modes(capsys):
    case = load(CASES / "drilled_cube.toml")
    model = build_model(case)
    lower = case.parts["lower"].mesh.params
    # the hole is a polygon inscribed in the circle, one vertex in the direction of each node of
    # the O-grid square (half-width 3 background cells of 0.1/12 here)
    r, t = lower["hole_radius"], np.linspace(-1.0, 1.0, 7)[:-1]
    square = np.concatenate([np.c_[t, -np.ones(6)], np.c_[np.ones(6), t],
                             np.c_[-t, np.ones(6)], np.c_[-np.ones(6), -t]])
    angles = np.arctan2(square[:, 1], square[:, 0])
    polygon = 0.5 * r ** 2 * np.sin(np.diff(np.r_[angles, angles[0] + 2 * np.pi])).sum()
    volume = 2 * 0.1 ** 3 - polygon * 0.1
    assert total_mass(model) == pytest.approx(7800.0 * volume, rel=1e-10)
    out = run_modes(capsys, "drilled_cube.toml")
    f = np.array(out["frequencies_hz"])
    # tied contact and rollers hold the upper cube: no rigid mode left; without the contact the
    # upper cube would keep its vertical translation
    assert f[0] > 1000 and out["contact"][0]["points"] > 0
    free = run_modes(capsys, "drilled_cube.toml", "contact.interface.k=1e-3")
    assert abs(free["frequencies_hz"][0]) < 1e-3 * f[0]


@pytest.mark.slow
def test_pad_disc_mass_and_modes_to_16khz(capsys):
    case = load(CASES / "pad_disc.toml")
    model = build_model(case)
    d, p = case.parts["disc"].mesh.params, case.parts["pad"].mesh.params
    disc = np.pi * (d["outer_radius"] ** 2 - d["inner_radius"] ** 2) * d["thickness"] * 7850
    sector = np.radians(p["angle"]) / 2 * (p["outer_radius"] ** 2 - p["inner_radius"] ** 2)
    pad = sector * (p["lining_thickness"] * 2500 + p["backplate_thickness"] * 7850)
    assert total_mass(model) == pytest.approx(disc + pad, rel=1e-4)   # curved hex20 edges
    out = run_modes(capsys, "pad_disc.toml")
    assert 20_000 <= out["ndof"] <= 100_000
    f = np.array(out["frequencies_hz"])
    assert f[-1] <= 16000 and len(f) > 30


@pytest.mark.slow
def test_pad_disc_transient_preload_and_energy_over_1e5_steps(tmp_path, capsys):
    out = tmp_path / "pad_disc.h5"
    assert main(["run", str(CASES / "pad_disc.toml"), "-o", str(out), "--quiet",
                 "--set", "solver.t_end=0.3125", "--set", "output.every=50",
                 "--set", "output.contact=false"]) == 0
    info = summary(out)
    assert info["status"] == "complete" and info["steps"] == 100_000 // 50 + 1
    assert info["energy_drift"] < 1e-3
    import h5py
    with h5py.File(out, "r") as f:
        force = json.loads(f.attrs["preload_contact_force"])["pad_disc"]
        assert f.attrs["reduced"]
    case = load(CASES / "pad_disc.toml")
    piston = -build_model(case).load_patterns["piston"].reshape(-1, 3)[:, 2].sum()
    # the pad is held in its plane only: the contact carries the whole piston force
    assert force == pytest.approx(piston, rel=1e-8)
    p = case.parts["pad"].mesh.params
    sector = 0.5 * (p["outer_radius"] ** 2 - p["inner_radius"] ** 2) * np.radians(p["angle"])
    assert force == pytest.approx(1.0e6 * sector, rel=1e-4)     # quadratic arcs


@pytest.mark.slow
def test_pad_disc_schemes_agree_below_5khz():
    # a 0.4 ms half-sine tap: a response mostly below 5 kHz. One setup, four integrations over
    # 5 ms: central differences at 0.9 times the critical step, Newmark at the same step, and
    # the exponential scheme at 8 times that step, with the corrector of pad_disc and with the
    # one-pass corrector of pad_disc_long
    from scipy.signal import butter, sosfiltfilt
    from transient.stages import choose_dt, prepare, simulate
    long = load(CASES / "pad_disc_long.toml")
    base = ["loads.tap.signal.duration=4e-4", "output.contact=false"]
    cases = {scheme: load(CASES / "pad_disc.toml", base + [f"solver.scheme={scheme}"])
             for scheme in ("explicit", "implicit", "exponential")}
    cases["one pass"] = load(CASES / "pad_disc.toml", base + [
        f"solver.{key}={getattr(long.solver, key)!r}".replace("'", '"')
        for key in ("scheme", "corrections", "corrector")])
    setup = prepare(cases["explicit"])
    # pad_disc_long: 1 s at 20 steps per period of 16 kHz
    assert long.solver.t_end == 1.0
    assert choose_dt(long, setup) == pytest.approx(1.0 / (20 * 16000))
    dt = 0.9 * setup.system.critical.dt
    n = int(5e-3 / dt) // 8 * 8
    runs = {}
    for name, case in cases.items():
        k = 8 if case.solver.scheme == "exponential" else 1
        series, status, _ = simulate(case, setup, k * dt, n // k)
        assert status == "complete"
        runs[name] = series
    sos = butter(4, 5000, fs=1 / dt, output="sos")
    for sensor in ("sensors/disc_rim", "sensors/pad_back"):
        ref = runs["explicit"][sensor]
        low = sosfiltfilt(sos, ref - ref[0])
        other = sosfiltfilt(sos, runs["implicit"][sensor] - ref[0])
        assert np.sqrt(np.mean((other - low) ** 2) / np.mean(low ** 2)) < 0.01
        for name in ("exponential", "one pass"):
            x, y = ref[::8], runs[name][sensor]
            assert np.sqrt(np.mean((x - y) ** 2) / np.mean((x - x[0]) ** 2)) < 0.01


@pytest.mark.slow
def test_pad_disc_squeal_grows_as_its_complex_modes():
    """The squeal case's first 28 ms, the linear growth from its 2 mN tap: the transient's
    dominant frequency (its analytic signal's phase) is the fastest-growing complex mode's
    within 1%, and its growth rate, fitted on the pad sensor's envelope and on the kinetic
    energy over 15-25 ms (where that mode dominates the other unstable one, 243 against 408
    1/s), its real part within 5% (5e-5, 0.6% and 0.5% measured at the case's step). One
    setup for both: the run's, whose unsampled rule is the analysis's (`transient cea`)."""
    from scipy.signal import hilbert
    from transient.plots.signals import envelope, growth_rate
    from transient.stability.stage import analysis_of
    from transient.stages import choose_dt, simulate
    case = load(CASES / "pad_disc_squeal.toml")
    setup = prepare(case, unsampled=True)
    modes = analysis_of(case, setup.unsampled).summary()["modes"]
    fastest = max((m for m in modes if m["unstable"]), key=lambda m: m["real"])
    assert 9e3 < fastest["frequency_hz"] < 11e3
    step = choose_dt(case, setup)
    series, status, _ = simulate(case, setup, step, int(round(0.028 / step)), case.output.every)
    assert status == "complete"
    t, x, kinetic = series["time"], series["sensors/pad_back"], series["energy/kinetic"]
    dt = t[1] - t[0]
    window = (t > 15e-3) & (t < 25e-3)
    # the frequency from the analytic signal's phase (a spectrum of 10 ms resolves 100 Hz)
    phase = np.unwrap(np.angle(hilbert(x - x.mean())))
    frequency = np.polyfit(t[window], phase[window], 1)[0] / (2 * np.pi)
    assert frequency == pytest.approx(fastest["frequency_hz"], rel=1e-2)
    sigma, _, _ = growth_rate(t, envelope(x - x.mean(), dt), (15e-3, 25e-3))
    assert sigma == pytest.approx(fastest["real"], rel=5e-2)
    rate = 0.5 * np.polyfit(t[window], np.log(kinetic[window]), 1)[0]
    assert rate == pytest.approx(fastest["real"], rel=5e-2)


def _lead(step, system, state, dt, lead):
    """Step state on by `lead` [s] with step (stages.stepper's at dt), nothing stored."""
    n = int(round(lead / dt))
    assert step(state, n, n, buffer(system, 1, False)) == (0, n)


def _cycle_run(step, system, state, dt, lead, span):
    """(pad sensor, energies, q) of the squeal case over `span` with step (at dt) after
    `lead` unstored, from state (stepped on), a row a step (the balance below is then the
    kernel's own sums)."""
    _lead(step, system, state, dt, lead)
    n = int(round(span / dt))
    out = buffer(system, n, False)
    assert step(state, n, 1, out) == (0, n)
    names = system.sensor_names
    return out.sensors[:, names.index("pad_back")], out.energy, out.sensors[:, len(names):]


@pytest.mark.slow
def test_pad_disc_squeal_limit_cycle_holds_under_half_the_step():
    """The squeal case's limit cycle (9.41 kHz with the other mode at 10.91 kHz, from 0.1 s):
    over 0.15-0.17 s the pad's RMS changes by less than 1% when dt is halved, and the energy
    balance closes within 1% of the sliding's input in every cycle: the kernel's own residual
    dW - dD - dE (work of the loads and the sliding in, damping and slip out) against the
    input, the work in less the piston's (0.27% at most measured at the case's step, 0.09% on
    average; 0.045% and 0.019% at half the step from rest). The half step starts on the cycle
    at 0.13 s, 20 ms (five times the growth's time constant) before its window: its RMS is
    0.18% from the case step's, 0.22% from a half step's from rest, and the windows of the
    two from rest differ by 0.40%. About a minute."""
    case = load(CASES / "pad_disc_squeal.toml", ["output.field=true"])
    setup = prepare(case)
    piston = setup.system.patterns[list(case.loads).index("piston")]
    dt, system = case.solver.dt, setup.system
    step, half = stepper(case, system, dt), stepper(case, system, dt / 2)
    state = setup.state.copy()
    _lead(step, system, state, dt, 0.13)
    branch = state.copy()
    runs = [_cycle_run(step, system, state, dt, 0.02, 0.02),
            _cycle_run(half, system, branch, dt / 2, 0.02, 0.02)]
    rms, balance = [], []
    for x, e, q in runs:
        rms.append(np.std(x))
        # cycles between up-crossings of the pad's motion about its mean
        up = np.flatnonzero((x[:-1] < x.mean()) & (x[1:] >= x.mean()))
        held = e[:, 0] + e[:, 1] + e[:, 2]
        work_in, out_ = e[:, 3], e[:, 4]
        a, b = up[:-1], up[1:]
        residual = (work_in[b] - work_in[a]) - (out_[b] - out_[a]) - (held[b] - held[a])
        sliding = (work_in[b] - work_in[a]) - (q[b] - q[a]) @ piston
        assert len(a) > 150 and np.all(sliding > 0)
        balance.append(np.max(np.abs(residual) / sliding))
    assert abs(rms[0] / rms[1] - 1) < 0.01
    assert balance[0] < 0.01 and balance[1] < balance[0]
