"""Complex eigenvalue analysis with friction on a small pad and disc: the sliding field, the
steady sliding preload, the linearization against finite differences of a plain NumPy friction
law, the reduced analysis against the full model's shift-invert Arnoldi, and mu = 0 against the
tied modes of `transient modes`."""
import json
from pathlib import Path

import numpy as np
import pytest

from transient.case.loading import load
from transient.stability.compare import pair_modes
from transient.stability.linearize import linearized, preload_pressure
from transient.stability.stage import analyse, analysed_case
from transient.cli import main
from transient.contact.friction import coefficient, regularized_sign, steady
from transient.kernels.codes import ATAN, TANH
from transient.stages import prepare

from small_cases import PAD_DISC

PAD = Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml"
OMEGA = 50.0
SMALL = PAD_DISC + [f"motion.disc.omega={OMEGA}", "solver.damping.residual=0.0"]


def small(*more):
    return load(PAD, SMALL + list(more))


@pytest.fixture(scope="module")
def full_setup():
    case = small("contact.pad_disc.friction.mu=0.4", "solver.reduction.enabled=false")
    return case, prepare(analysed_case(case))


def test_sliding_is_circumferential_at_omega_r(full_setup):
    _, setup = full_setup
    contacts = setup.system.contacts
    case = small("contact.pad_disc.friction.mu=0.4")
    from transient.contact.pair import build_contact
    from transient.model import build_model
    pair = build_contact(case, build_model(case))[0]
    x = pair.rule.points
    r = np.hypot(x[:, 0], x[:, 1])
    np.testing.assert_allclose(pair.sliding.speed, OMEGA * r, rtol=1e-12)
    # node directions: unit, tangent to the surface (z normal), along e_theta of the rotation
    side = pair.interface.side2
    xn = side.points[side.nodes]
    e_theta = np.stack([-xn[:, 1], xn[:, 0], 0 * xn[:, 0]], axis=1) / np.hypot(
        xn[:, 0], xn[:, 1])[:, None]
    np.testing.assert_allclose(pair.sliding.along2, e_theta, atol=1e-12)
    # on the pad (surface 1) the disc slides the same way: V = v_disc - v_pad
    xp = pair.interface.side1.points[pair.interface.side1.nodes]
    np.testing.assert_allclose(np.einsum("ij,ij->i", pair.sliding.along1, xp), 0.0, atol=1e-12)
    assert contacts.friction.speed.min() > 0


def test_steady_sliding_preload_is_in_equilibrium_with_mu_p(full_setup):
    case, setup = full_setup
    system, state = setup.system, setup.state
    p, _ = preload_pressure(system, state)
    contacts, f = system.contacts, system.contacts.friction
    assert setup.meta["preload_residual"] < 1e-9
    # V >> v_eps: the traction is mu p along t exactly (tanh(V / v_eps) = 1 to round-off)
    np.testing.assert_allclose(f.m, 0.4, rtol=1e-15)
    # the friction force of the preload is along the sliding: its work rate on the sliding
    # velocity field is mu times the normal force times the speed, point by point
    np.testing.assert_allclose((contacts.weights * p * f.m).sum(),
                               0.4 * (contacts.weights * p).sum(), rtol=1e-14)
    # it changes the pressures of the frictionless preload (the lining tilts at its ends)
    setup0 = prepare(analysed_case(small("solver.reduction.enabled=false")))
    p0, _ = preload_pressure(setup0.system, setup0.state)
    assert 1e-4 < np.abs(p - p0).max() / p0.max() < 0.5
    np.testing.assert_allclose((contacts.weights * p).sum(),
                               (contacts.weights * p0).sum(), rtol=0.05)


@pytest.mark.parametrize("code", [TANH, ATAN])
def test_law_slopes_against_finite_differences(code):
    class Spec:
        mu, speeds, values, v_eps = 0.0, (0.0, 1.0, 3.0), (0.5, 0.4, 0.35), 2e-3
        regularization = "tanh" if code == TANH else "atan"
    s = np.array([-2.0, -0.5, -1e-3, 1e-4, 3e-3, 0.7, 2.0, 5.0])
    h = 1e-7
    law = steady(Spec, s)

    def m(x):
        mu, _ = coefficient(Spec, x)
        return mu * regularized_sign(code, x, Spec.v_eps)[0]
    np.testing.assert_allclose(law.m, m(s), rtol=1e-15)
    np.testing.assert_allclose(law.dm, (m(s + h) - m(s - h)) / (2 * h), rtol=1e-5, atol=1e-6)


def _numpy_friction(system, q, v, mu, v_eps):
    """The friction force on the system's dofs in plain NumPy: the 2D regularized Coulomb
    traction mu(|s|) p tanh(|s| / v_eps) s / |s| of the sliding velocity s = (V - Ct v, -Cc v);
    mu a number or a table (speeds, values)."""
    c = system.contacts
    g = system.C @ q + c.gap0
    p, _, _ = c.laws(np.asarray(g))
    s_t, s_c = c.friction.speed - system.Ct @ v, -(system.Cc @ v)
    norm = np.hypot(s_t, s_c)
    coef = np.interp(norm, *mu) if isinstance(mu, tuple) else mu
    traction = coef * c.weights * p * np.tanh(norm / v_eps) / norm
    return system.Ct.T @ (traction * s_t) + system.Cc.T @ (traction * s_c)


FALLING = ((0.0, 2.0, 10.0), (0.5, 0.4, 0.3))     # mu(v), falling through the sliding speeds


@pytest.fixture(scope="module")
def falling_setup():
    case = small("contact.pad_disc.friction.speeds=[0.0,2.0,10.0]",
                 "contact.pad_disc.friction.values=[0.5,0.4,0.3]",
                 "solver.reduction.enabled=false")
    return case, prepare(analysed_case(case))


@pytest.mark.parametrize("law", ["constant", "falling"])
def test_linearization_against_finite_differences(full_setup, falling_setup, law):
    """K and D of the linearization are the derivatives of a plain NumPy friction law (plus
    K_lin and the contact tangent): -dF/dq and -dF/dv by central differences. A falling mu(v)
    makes the damping along the sliding negative."""
    _, setup = full_setup if law == "constant" else falling_setup
    mu = 0.4 if law == "constant" else FALLING
    system, state = setup.system, setup.state
    M, D, K = linearized(system, state)
    rng = np.random.default_rng(1)
    q0, v0 = state.q, np.zeros(system.n)
    from transient.stability.linearize import _friction_terms
    p, kt = preload_pressure(system, state)
    Kf, Df = _friction_terms(system, p, kt)
    for _ in range(3):
        dq = rng.standard_normal(system.n) * 1e-9
        dv = rng.standard_normal(system.n) * 1e-2      # 1e-5 m/s: above round-off
        h = 1e-3
        fq = (_numpy_friction(system, q0 + h * dq, v0, mu, 1e-3)
              - _numpy_friction(system, q0 - h * dq, v0, mu, 1e-3)) / (2 * h)
        fv = (_numpy_friction(system, q0, v0 + h * dv, mu, 1e-3)
              - _numpy_friction(system, q0, v0 - h * dv, mu, 1e-3)) / (2 * h)
        np.testing.assert_allclose(Kf @ dq, -fq, rtol=1e-5, atol=1e-6 * np.abs(fq).max())
        np.testing.assert_allclose(Df @ dv, -fv, rtol=1e-5, atol=1e-6 * np.abs(fv).max())
    # the friction stiffness is what makes K non-symmetric
    Kd = K.toarray()
    assert np.abs(Kd - Kd.T).max() > 1e-3 * np.abs(Kf.toarray()).max()
    f = system.contacts.friction
    assert (f.dm < 0).all() if law == "falling" else (f.dm == 0).all()


# the pad and disc: the small model's divisions with the shipped case's hex20
HEX20 = [o for o in SMALL if "element" not in o]


@pytest.mark.slow
def test_reduced_complex_modes_match_the_full_model_mode_by_mode():
    """Every mode below fmax that is unstable in the full model's shift-invert Arnoldi or in
    the reduced analysis: the frequency within 0.1% and the real part within 5% of its own
    (or 5 1/s), and the same stability (stability.compare). The default basis reaches 2 fmax; with
    its modes cut at fmax the weak modes of the band's upper half miss (the issue's figures:
    -37% to +155%), which the same comparison catches. The components path, each part's
    modes to 2 fmax and its interface responses, holds them too."""
    fmax = 16000.0
    overrides = HEX20 + ["contact.pad_disc.friction.mu=0.4"]
    full = analyse(load(PAD, overrides + ["solver.reduction.enabled=false"]))
    reduced = analyse(load(PAD, overrides))
    assert full.reduced == 0 and 0 < reduced.reduced < full.ndof
    assert reduced.meta["modes_fmax_hz"] == 2 * fmax
    pairs = pair_modes(full.modes, reduced.modes, fmax)
    assert sum(p.unstable for p in pairs) >= 6, "the scene must squeal across its band"
    assert max(p.frequency_hz for p in pairs if p.unstable) > 0.9 * fmax
    assert [p for p in pairs if not p.within()] == []
    cut = analyse(load(PAD, overrides + [f"solver.reduction.cutoff={fmax}"]))
    assert [p for p in pair_modes(full.modes, cut.modes, fmax) if not p.within()] != []
    # each part reduced on its own (reduce.components) holds the same modes
    parts = analyse(load(PAD, overrides + ['solver.reduction.method="components"']))
    assert "factorization" not in parts.stages
    # its --json says each part's stages; the assembled path's has none to say
    stages = parts.summary()["part_stages"]
    assert set(stages) == {"disc", "pad"} and all(stages.values())
    assert "part_stages" not in reduced.summary()
    pairs = pair_modes(full.modes, parts.modes, fmax)
    assert sum(p.unstable for p in pairs) >= 6
    assert [p for p in pairs if not p.within()] == []
    # the shapes a mu map links its values by (stability.branches): X (A z) at a sample of
    # the model's dofs, from each kind of basis (the full model's injection, the assembled
    # path's, the parts' synthesis), and alike across them for a mode the analyses share
    from transient.stability.branches import observed
    from transient.solve.mac import mac
    unstable = np.flatnonzero(full.modes.unstable & (full.modes.frequency_hz <= fmax))
    for analysis in (full, reduced, parts):
        dofs, shapes = observed(analysis)
        j = np.flatnonzero(analysis.modes.unstable)[:3]
        assert np.allclose(shapes[:, j], np.stack([analysis.displacement(k)[dofs] for k in j],
                                                  axis=1), rtol=0, atol=1e-12)
        if analysis is not full:
            nearest = [int(np.argmin(np.abs(analysis.modes.eigenvalues - lam)))
                       for lam in full.modes.eigenvalues[unstable]]
            alike = mac(observed(full)[1][:, unstable], shapes[:, nearest])
            assert np.diag(alike).min() > 0.9


@pytest.mark.parametrize("reduced", [True, False])
def test_an_analysis_setup_is_the_runs_without_its_critical_step(reduced):
    """prepare(analysis=True), the cea's: the same system as a run's setup, bit for bit, but
    no critical step (its eigenvalues were 0.3 s of pad_disc's cea) and no initial row."""
    case = analysed_case(small("contact.pad_disc.friction.mu=0.4",
                               f"solver.reduction.enabled={str(reduced).lower()}"))
    run, analysis = prepare(case), prepare(case, analysis=True)
    assert run.system.critical is not None and run.rows0 is not None
    assert analysis.system.critical is None and analysis.rows0 is None
    for name in ("C", "Ct", "Cc") + (("omega2", "damp") if reduced else ("K", "M")):
        a, b = getattr(run.system, name), getattr(analysis.system, name)
        a, b = (a.toarray(), b.toarray()) if hasattr(a, "toarray") else (a, b)
        assert np.array_equal(a, b), name
    assert np.array_equal(run.state.q, analysis.state.q)


@pytest.mark.every_core
def test_the_unstable_shapes_are_the_same_with_the_pads_modes_beside_the_qz_or_after(
        monkeypatch):
    """analysis_of makes the still parts' own modes in a thread beside the dense QZ when the
    process has two cores or more, after it on one (a campaign's worker): the same numbers."""
    from transient.stability.stage import analysis_of
    from transient.stages import prepare
    case = small("contact.pad_disc.friction.mu=0.4")
    setup = prepare(analysed_case(case), analysis=True)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    beside = analysis_of(case, setup)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    after = analysis_of(case, setup)
    assert beside.shapes and all("part_modes" in row for row in beside.shapes)
    assert beside.shapes == after.shapes
    assert np.array_equal(beside.modes.eigenvalues, after.modes.eigenvalues)


def test_frictionless_complex_modes_are_the_tied_modes(capsys):
    """mu = 0 with the disc turning: every complex mode is stable (real parts at round-off)
    and its frequency equals the tied modes of `transient modes` (a bilateral law: its tangent
    is the tied springs' k)."""
    overrides = ['contact.pad_disc.law.kind="bilateral"', 'contact.pad_disc.rule="fine"',
                 "solver.modes.fmax=16000.0"]
    args = [a for o in SMALL + overrides for a in ("--set", o)]
    assert main(["modes", str(PAD), "--json"] + args) == 0
    tied = np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])
    assert main(["cea", str(PAD), "--json"] + args) == 0
    out = json.loads(capsys.readouterr().out)
    f = np.array([m["frequency_hz"] for m in out["modes"]])
    real = np.array([m["real"] for m in out["modes"]])
    assert not any(m["unstable"] for m in out["modes"])
    assert np.abs(real).max() <= 1e-9 * 2 * np.pi * f.max()
    assert len(f) == len(tied)
    np.testing.assert_allclose(f, tied, rtol=1e-8)
    assert out["ndof"] > out["reduced"] > len(f)


def test_nodal_diameter_of_a_disc_wave():
    """A standing wave cos(3 theta) of the disc's axial motion is 3 nodal diameters, all of
    it; a travelling one exp(5 i theta) is 5; energy shares add to one."""
    from transient.stability.diameters import disc_motion
    from transient.stability.shapes import part_shares
    from transient.model import build_model
    case = small()
    model = build_model(case)
    motion = case.motion["disc"]
    x = model.parts["disc"].mesh.points
    theta = np.arctan2(x[:, 1], x[:, 0])
    dofs = model.part_dofs("disc").reshape(-1, 3)
    for wave, order in ((np.cos(3 * theta), 3), (np.exp(5j * theta), 5)):
        u = np.zeros(model.ndof, complex)
        u[dofs[:, 2]] = wave * np.hypot(x[:, 0], x[:, 1])
        found, = disc_motion(model, motion, u[:, None])
        assert found["motion"] == "out-of-plane" and found["axial_share"] == 1.0
        assert found["order"] == order and found["share"] > 0.999
        shares = part_shares(model, model.M, u[:, None])[0]
        assert shares["disc"] == pytest.approx(1.0) and shares["pad"] == 0.0


def test_nodal_diameters_on_scattered_nodes_count_the_orders_they_sample():
    """On nodes scattered over an annulus (an unstructured mesh: every angle distinct) the
    orders summed stop at pi R / d (d their median spacing), not at half the nodes, and a
    wave cos(4 theta) is 4 nodal diameters carrying nearly all of it (half, summed over every
    order to half the nodes: the rest is the scattered sampling's leakage)."""
    from scipy.spatial import cKDTree
    from transient.stability.diameters import _order, _orders
    rng = np.random.default_rng(3)
    r, theta = np.sqrt(rng.uniform(0.05 ** 2, 0.14 ** 2, 4000)), rng.uniform(-np.pi, np.pi, 4000)
    x = np.stack([r * np.cos(theta), r * np.sin(theta), rng.uniform(0, 0.02, 4000)], axis=1)
    orders = _orders(theta, x, r)
    step = np.median(cKDTree(x).query(x, k=2)[0][:, 1])
    assert orders == int(np.ceil(np.pi * r.max() / step)) + 1
    assert 10 < orders < 4000 // 20
    n, share = _order(theta, np.full(4000, 1.0), [np.cos(4 * theta)[:, None]], orders)
    assert n[0] == 4 and share[0] > 0.9


@pytest.mark.parametrize("basis", [[], ["contact.pad_disc.friction.basis_mu=0.3"]])
def test_plot_cea_draws_the_diagram_the_unstable_shapes_and_the_mu_map(tmp_path, capsys,
                                                                      basis):
    """(With a basis_mu, the values of mu share one basis.) The map's tables beside it: no
    unstable mode without friction, the flutter pair's growing member (11-12.5 kHz) at 0.4,
    as at the case's own mu."""
    import csv
    from PIL import Image
    args = ["plot", "cea", str(PAD), "--out", str(tmp_path), "--mu", "0:0.4:2"]
    args += [a for o in SMALL + ["contact.pad_disc.friction.mu=0.4"] + basis
             for a in ("--set", o)]
    assert main(args) == 0
    paths = [Path(p) for p in capsys.readouterr().out.split()]
    names = [p.name for p in paths]
    assert names[0] == "pad_disc_stability.png" and names[-3:] == [
        "pad_disc_mu_map.png", "pad_disc_mu_map_unstable.csv", "pad_disc_mu_map_coupling.csv"]
    assert len([n for n in names if n.startswith("pad_disc_mode_")]) >= 2
    for p in paths[:-2]:
        with Image.open(p) as image:
            pixels = np.asarray(image.convert("L"))
        assert pixels.std() > 5, p           # something is drawn, not a blank canvas
    with open(paths[-2], newline="") as f:
        rows = list(csv.DictReader(f))
    assert {float(r["mu"]) for r in rows} == {0.4}
    own = [n for n in names if n.startswith("pad_disc_mode_")]
    assert len(rows) == len(own) and any(11e3 < float(r["frequency_hz"]) < 12.5e3
                                         and float(r["real"]) > 500 for r in rows)


@pytest.mark.parametrize("mu, reason", [("0:1", "START:STOP:COUNT"), ("0:0.6:0", "COUNT"),
                                        ("-0.1,0.2", ">= 0"), ("0:0.6:x", "")])
def test_plot_cea_bad_mu_is_one_line(tmp_path, capsys, mu, reason):
    code = main(["plot", "cea", str(PAD), "--out", str(tmp_path), f"--mu={mu}"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "--mu" in err and reason in err


def test_a_pad_mode_is_recognized_by_its_mac():
    """A displacement that is the pad's own third mode (alone on its abutments), plus some
    disc motion, matches that mode with MAC 1."""
    from transient.stability.shapes import matched_part_modes, part_modes
    from transient.model import build_model
    model = build_model(small())
    f, Phi, dofs, _ = part_modes(model, "pad", 20000.0)
    assert len(f) > 4 and f[3] > 1000.0
    u = np.zeros((model.ndof, 1), complex)
    u[dofs, 0] = (1 + 2j) * Phi[:, 3]
    u[model.part_dofs("disc")[2::3], 0] = 1e-3
    (index, freq, mac), = matched_part_modes(model, u, ["pad"], 20000.0).values()
    assert index[0] == 3 and freq[0] == f[3] and mac[0] == pytest.approx(1.0, abs=1e-12)
