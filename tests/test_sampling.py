"""The sampled rule: NNLS in Gram form against scipy's, the Gram matrix against explicit
features, and a small pad on a disc whose sampled points reproduce the fine rule's dynamics."""
import numpy as np
import pytest
from scipy.optimize import nnls

from transient.studies.bench import Variant, compare, run_variant
from transient.cli import main
from transient.reduce.sampling import (features, friction_terms, gram_column, gram_target,
                                       nnls_gram, sample)

from test_bench import CASES, SMALL


def _explicit(c, cb, kt, ps):
    """The feature columns z_i written out: k_t,i c_i c_iJ^T and p_i c_i / s."""
    return np.stack([np.r_[kt[i] * np.outer(c[i], cb[i]).ravel(), ps[i] * c[i]]
                     for i in range(len(c))], axis=1)


def _random_system(rng, m=40, n=7, band=3):
    omega2 = np.sort(rng.uniform(1.0, 50.0, n))
    Cr = rng.normal(size=(m, n))
    p = rng.uniform(0.0, 2.0, m)
    return omega2, Cr, p, 3.0 * p, rng.normal(size=n), band


def test_gram_matrix_is_the_features_gram():
    rng = np.random.default_rng(0)
    omega2, Cr, p, kt, q0, band = _random_system(rng)
    feats = features(omega2, Cr, p, kt, q0, band)
    Z = _explicit(*feats)
    G = Z.T @ Z
    for j in (0, 5, 39):
        assert np.allclose(gram_column(feats, j), G[:, j], rtol=1e-12, atol=1e-12 * abs(G).max())
    w = rng.uniform(0.5, 1.5, len(p))
    assert np.allclose(gram_target(feats, w), G @ w, rtol=1e-11)


def test_friction_features_gram_is_the_explicit_one():
    """With friction, each point's features gain the friction stiffness's band columns
    m k_t ct_i c_iJ^T, the friction preload m p ct_i / s (y = Omega q) and the damping along and
    across p m' ct'_i ct'_iJ^T, p (m / V) cc'_i cc'_iJ^T (y = Omega^1/2 q), written out here
    from Omega and the rows, not from the terms."""
    rng = np.random.default_rng(3)
    omega2, Cr, p, kt, q0, band = _random_system(rng)
    m_pts = len(p)
    Ct, Cc = rng.normal(size=(m_pts, len(omega2))), rng.normal(size=(m_pts, len(omega2)))
    m, dm, turn = rng.uniform(0.2, 0.5, m_pts), rng.normal(size=m_pts), rng.uniform(0, 1, m_pts)
    feats = features(omega2, Cr, p, kt, q0, band)
    terms = friction_terms(feats, omega2, Ct, Cc, m, dm, turn, p)
    omega = np.sqrt(omega2)
    s = np.linalg.norm(omega * q0)
    c, ct, r = Cr / omega, Ct / omega, np.sqrt(omega)
    extra = np.stack([np.r_[m[i] * kt[i] * np.outer(ct[i], c[i, :band]).ravel(),
                            m[i] * p[i] / s * ct[i],
                            p[i] * dm[i] * np.outer(Ct[i] / r, (Ct[i] / r)[:band]).ravel(),
                            p[i] * turn[i] * np.outer(Cc[i] / r, (Cc[i] / r)[:band]).ravel()]
                      for i in range(m_pts)], axis=1)
    Z = np.vstack([_explicit(*feats), extra])
    G = Z.T @ Z
    for j in (0, 11, 39):
        assert np.allclose(gram_column(feats, j, terms), G[:, j], rtol=1e-12,
                           atol=1e-12 * abs(G).max())
    w = rng.uniform(0.5, 1.5, m_pts)
    assert np.allclose(gram_target(feats, w, terms), G @ w, rtol=1e-11)
    # each feature's product with row j made once (ct and the band's rows are shared by
    # terms): the same arithmetic as every product made where it appears
    c, cb, kt_, ps = feats
    for j in (0, 11, 39):
        g = (c @ c[j]) * (kt_ * kt_[j] * (cb @ cb[j]) + ps * ps[j])
        for t, L, R in terms:
            g += (t * t[j]) * (L @ L[j]) * (R @ R[j])
        assert np.array_equal(gram_column(feats, j, terms), g)


def _nnls_against_scipy(seed, rows, n, share, noise):
    """nnls_gram on a random least-squares problem with every candidate allowed, against
    SciPy's NNLS: (G, h, bb, x_ref, indices taken, residual)."""
    rng = np.random.default_rng(seed)
    Z = rng.normal(size=(rows, n))
    b = Z @ np.where(rng.uniform(size=n) < share, rng.uniform(size=n), 0.0) \
        + noise * rng.normal(size=rows)
    G, h, bb = Z.T @ Z, Z.T @ b, b @ b
    x_ref, r_ref = nnls(Z, b)
    idx, x, res = nnls_gram(lambda j: G[:, j], h, bb, 0.0, n)
    assert np.all(x > 0) and 0 < len(idx) < n
    assert res == pytest.approx(r_ref / np.sqrt(bb), rel=1e-8)
    full = np.zeros(n)
    full[idx] = x
    assert np.allclose(full, x_ref, atol=1e-8)
    return G, h, bb, x_ref, idx, res


def test_nnls_in_gram_form_matches_scipy():
    G, h, bb, x_ref, idx, _ = _nnls_against_scipy(1, 60, 40, 0.3, 0.3)
    # a looser tolerance stops early, with fewer points, at a residual within it
    idx2, x2, res2 = nnls_gram(lambda j: G[:, j], h, bb, 0.9, 40)
    assert res2 <= 0.9 and len(idx2) < len(idx)
    # the residual in Gram form loses half the digits: a reachable b stops near sqrt(eps)
    _, _, res3 = nnls_gram(lambda j: G[:, j], G @ np.abs(x_ref), np.abs(x_ref) @ G
                           @ np.abs(x_ref), 0.0, 40)
    assert res3 < 1e-6


@pytest.mark.slow
def test_nnls_in_gram_form_grows_its_buffers_past_the_first_256_points():
    # every candidate may be taken (max_points = N): the buffers double as points are taken
    _, _, _, _, idx, _ = _nnls_against_scipy(3, 700, 600, 0.8, 0.1)
    assert len(idx) > 256


def test_a_rule_that_is_its_own_sample_is_reproduced_exactly():
    rng = np.random.default_rng(2)
    omega2, Cr, p, kt, q0, band = _random_system(rng, m=12, n=4, band=2)
    w = rng.uniform(0.5, 1.5, 12)
    s = sample(omega2, Cr, w, p, kt, q0, band, 1e-12, 12)
    assert s.residual < 1e-9
    feats = features(omega2, Cr, p, kt, q0, band)
    Z = _explicit(*feats)
    assert np.allclose(Z[:, s.chosen] @ s.weights, Z @ w, atol=1e-9 * abs(Z @ w).max())


@pytest.fixture(scope="module")
def small_pad():
    """The fine rule of a small pad on a disc (the reference) and its sampled rules."""
    path, pair = CASES / "pad_disc.toml", "pad_disc"
    ref = run_variant(path, SMALL, pair, Variant("fine", "fine", {"rule": "fine"}), 2e-3)
    out = {}
    for tol in (1e-1, 1e-2, 1e-3):
        out[tol] = run_variant(path, SMALL, pair, Variant(
            "sampled", "sampled", {"rule": "sampled", "sampling_tolerance": tol}), 2e-3)
    return ref, out


def test_sampled_points_reproduce_the_fine_rule_and_converge(small_pad):
    (ref, ref_series, ref_freq), runs = small_pad
    errors = {}
    for tol, (row, series, freq) in runs.items():
        assert row["status"] == "complete"
        assert row["points"] < ref["points"]
        assert row["reduced_dofs"] == ref["reduced_dofs"]
        errors[tol] = compare(ref_series, series, ref_freq, freq)
    points = [runs[t][0]["points"] for t in (1e-1, 1e-2, 1e-3)]
    assert points[0] <= points[1] <= points[2] < ref["points"] / 10
    assert errors[1e-2]["error_rms"] < 0.01
    assert errors[1e-3]["error_rms"] < errors[1e-1]["error_rms"] / 3
    # the band (below fmax, 6 kHz here) is what the points are fitted to
    band = ref_freq < 6000.0
    for tol, bound in ((1e-2, 1e-4), (1e-3, 1e-5)):
        freq = runs[tol][2]
        assert np.max(np.abs(freq[band] / ref_freq[band] - 1)) < bound


def test_sampled_rule_needs_a_reduced_model(tmp_path, capsys):
    args = ["run", str(CASES / "pad_disc.toml"), "-o", str(tmp_path / "x.h5"),
            "--set", 'contact.pad_disc.rule="sampled"', "--set", "solver.reduction.enabled=false",
            "--set", 'solver.scheme="explicit"']
    for o in SMALL:
        args += ["--set", o]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "contact.pad_disc.rule" in err and "reduction" in err and "Traceback" not in err


@pytest.mark.parametrize("corrector", ["evaluated", "implicit"])
@pytest.mark.slow
def test_a_resumed_sampled_run_equals_an_uninterrupted_one(tmp_path, corrector):
    """Resuming prepares again: the sampling must pick the same points and weights, and the
    kernel restart from the state stored (its end forces recomputed there) bit for bit."""
    import h5py
    from transient.case.loading import load
    from transient.integration import run
    base = SMALL + ['contact.pad_disc.rule="sampled"', "solver.chunk=50", "output.contact=true",
                    f'solver.corrector="{corrector}"']
    whole = run(load(CASES / "pad_disc.toml", base + ["solver.t_end=1e-3"]), tmp_path / "w.h5")
    part = run(load(CASES / "pad_disc.toml", base + ["solver.t_end=5e-4"]), tmp_path / "p.h5")
    assert part.steps < whole.steps
    resumed = run(load(CASES / "pad_disc.toml", base + ["solver.t_end=1e-3"]), tmp_path / "p.h5",
                  resume=True)
    assert resumed.status == "complete" and resumed.steps == whole.steps
    with h5py.File(tmp_path / "w.h5", "r") as a, h5py.File(tmp_path / "p.h5", "r") as b:
        for name in ("time", "sensors/pad_back", "contact/pad_disc/pressure",
                     "geometry/contact/pad_disc/weights"):
            np.testing.assert_array_equal(a[name][()], b[name][()], err_msg=name)
