"""complex_modes against the closed forms of a two-dof mode-coupling (flutter) model.

The model (N. Hoffmann, M. Fischer, R. Allgaier, L. Gaul, "A minimal model for studying
properties of the mode-coupling type instability in friction induced oscillations", Mech. Res.
Commun. 29 (2002) 197-205): a point mass m with displacements x (tangential, along a belt that
slides at constant speed in +x) and y (normal to the belt, positive away from it). Two linear
springs k1, k2 in the (x, y) plane at angles alpha1, alpha2 to the x axis; a contact spring k3
along y presses the mass on the belt. Damping c_x, c_y may act on x and y.

Stiffness. A spring k along the unit vector e = (cos alpha, sin alpha) gives k e e^T, so

    Ks = sum_i k_i [[cos^2 a_i, cos a_i sin a_i], [cos a_i sin a_i, sin^2 a_i]] + [[0, 0], [0, k3]]
       = [[a, b], [b, d]],
    a = sum k_i cos^2 a_i,  b = sum k_i cos a_i sin a_i,  d = sum k_i sin^2 a_i + k3.

Friction (sign convention of this file). The normal contact force is N = N0 - k3 y (lifting
the mass off the belt unloads the contact spring); the belt always slides in +x, so the
friction force on the mass is +mu N = mu N0 - mu k3 y along x. The constant mu N0 only shifts
the equilibrium; the perturbation equations are M a + D v + K(mu) q = 0 with

    M = m I,  D = diag(c_x, c_y),  K(mu) = Ks + [[0, s mu k3], [0, 0]],  s = +1,
    K(mu) = [[a, b + mu k3], [b, d]].

(The brief's [[0, s mu k3], [0, k3]] is the same thing with k3 counted outside Ks.)

1. Undamped. det(K - w^2 M) = 0 is the quadratic in W = w^2

    m^2 W^2 - m (a + d) W + det K = 0,  det K = a d - b^2 - b k3 mu,
    W = ((a + d) -+ sqrt(Delta)) / (2 m),
    Delta = (a + d)^2 - 4 det K = (a - d)^2 + 4 b^2 + 4 b k3 mu.

Two real positive roots (stable, frequencies sqrt(W)) while Delta > 0 and det K > 0; the two
modes coalesce at Delta = 0 and flutter for Delta < 0. Delta falls with mu only for b mu < 0:
with b < 0 (the geometry below) the instability needs mu > 0 (belt in +x) and sets in at

    mu_c = ((a - d)^2 + 4 b^2) / (4 |b| k3).

Above it the roots of det(lambda^2 M + K) = 0, L = lambda^2 = -W, are the complex pair
L = (-(a + d) +- i sqrt(-Delta)) / (2 m); lambda = sqrt(L) (principal branch, L with
+i) has a positive real part and a positive imaginary part: the growing mode. The other root
with imag > 0 is -conj(lambda), the decaying partner.

2. Equal damping, D = c I = gamma M, gamma = c / m. With q = v e^{lambda t} and M^-1 K v =
-s v, lambda^2 + gamma lambda - s = 0: lambda = -gamma/2 +- sqrt(gamma^2/4 + s), s the
eigenvalues of -M^-1 K. Below mu_c the s are real negative and every Re lambda < 0. Above,
s = -A +- i B with A = (a + d) / (2 m) > 0 and B = sqrt(-Delta) / (2 m) > 0. Write
z = gamma^2/4 - A + i B = x + i y and sqrt(z) = u + i v, u >= 0; then u^2 = (x + |z|) / 2, and

    Re lambda = -gamma/2 + u > 0  iff  u^2 > gamma^2/4  iff  |z| > gamma^2/2 - x = gamma^2/4 + A
              iff  (gamma^2/4 - A)^2 + B^2 > (gamma^2/4 + A)^2  iff  B^2 > gamma^2 A.

With B^2 = -Delta / (4 m^2): -Delta > 2 c^2 (a + d) / m, i.e. (b < 0)

    mu_c(c) = ((a - d)^2 + 4 b^2 + 2 c^2 (a + d) / m) / (4 |b| k3)  >  mu_c(0).

3. Damping distributed unequally, D = diag(c1, c2). The characteristic quartic is

    det(lambda^2 M + lambda D + K) = (m L^2 + c1 L + a)(m L^2 + c2 L + d) - b (b + mu k3)
        = a4 L^4 + a3 L^3 + a2 L^2 + a1 L + a0      (L = lambda),
    a4 = m^2,  a3 = m (c1 + c2),  a2 = m (a + d) + c1 c2,  a1 = c1 d + c2 a,  a0 = det K.

Routh-Hurwitz for a quartic: stable iff all a_i > 0 and the third Hurwitz determinant

    H3 = det [[a3, a1, 0], [a4, a2, a0], [0, a3, a1]] = a3 a2 a1 - a1^2 a4 - a3^2 a0 > 0

(H2 = a3 a2 - a4 a1 > 0 follows, as H3 = a1 H2 - a3^2 a0). Only a0 holds mu, and linearly
(a0 = a d - b^2 + |b| k3 mu), so H3 is affine in mu (the quadratic degenerates) with the one root

    a0* = a1 (a3 a2 - a4 a1) / a3^2,   mu_c(c1, c2) = (a0* - a d + b^2) / (|b| k3),

stable below, unstable above. Checks: c1 = c2 = c gives a0* = (a + d)^2/4 + c^2 (a + d)/(2 m),
which is case 2. One direction only, c2 = 0: a3 = m c1, a1 = c1 d, H3 = m^2 c1^2 (a d - a0), so
a0* = a d and mu_c = |b| / k3 for every c1 > 0; c1 = 0 gives the same (a0* = a d).

The damping paradox (N. Hoffmann, L. Gaul, "Effects of damping on mode-coupling instability in
friction induced oscillations", ZAMM 83 (2003) 524-534). With c1 = c r1, c2 = c r2 and c -> 0
at a fixed ratio, a0* -> p (a + d - p), p = (r1 d + r2 a) / (r1 + r2), so

    lim mu_c = (b^2 - (p - a)(p - d)) / (|b| k3),

which for p between a and d lies in [|b| / k3, mu_c(0)], equal to the undamped mu_c(0) only for
p = (a + d)/2, i.e. r1 = r2 (when a != d). Any unequal distribution of vanishing damping lowers
the threshold; damping on one direction only lowers it the most, to |b| / k3 (here 0.4746
against 0.6032): a system that is stable without damping flutters once a little damping acts
on x (or on y) alone.

Numbers: m = 2 kg, k1 = 2400 N/m at 140 deg, k2 = 1000 N/m at 35 deg, k3 = 1500 N/m. Then
a = 2079.39, b = -711.92, d = 2820.61 N/m, mu_c(0) = 0.603237, |b|/k3 = 0.474615, and the two
frequencies near 5 Hz.
"""
import numpy as np
import pytest

from transient.stability.modes import ComplexModes, complex_modes

MASS = 2.0
K1, ALPHA1 = 2400.0, np.radians(140.0)
K2, ALPHA2 = 1000.0, np.radians(35.0)
K3 = 1500.0

# the entries of Ks (k3 included): K(mu) = [[A_XX, B_XY + mu K3], [B_XY, D_YY]]
A_XX = K1 * np.cos(ALPHA1) ** 2 + K2 * np.cos(ALPHA2) ** 2
B_XY = K1 * np.cos(ALPHA1) * np.sin(ALPHA1) + K2 * np.cos(ALPHA2) * np.sin(ALPHA2)
D_YY = K1 * np.sin(ALPHA1) ** 2 + K2 * np.sin(ALPHA2) ** 2 + K3

BRACKET = (0.05, 1.5)   # stable at 0.05, unstable at 1.5 for every damping tested here
REL_BRACKET = 1e-12


def system(mu, cx=0.0, cy=0.0):
    """(M, D, K) of the Hoffmann-Gaul model at friction coefficient mu, damping cx, cy."""
    ca, sa = np.cos([ALPHA1, ALPHA2]), np.sin([ALPHA1, ALPHA2])
    k = np.array([K1, K2])
    Ks = np.array([[np.sum(k * ca * ca), np.sum(k * ca * sa)],
                   [np.sum(k * ca * sa), np.sum(k * sa * sa) + K3]])
    K = Ks + np.array([[0.0, mu * K3], [0.0, 0.0]])
    return MASS * np.eye(2), np.diag([float(cx), float(cy)]), K


def modes(mu, cx=0.0, cy=0.0) -> ComplexModes:
    return complex_modes(*system(mu, cx, cy))


# --- closed forms (scalars only: no eigen-solver) -------------------------------------------

def delta(mu):
    """Discriminant of m^2 W^2 - m (a + d) W + det K = 0 (W = omega^2)."""
    return (A_XX - D_YY) ** 2 + 4 * B_XY ** 2 + 4 * B_XY * K3 * mu


def mu_c_undamped():
    return ((A_XX - D_YY) ** 2 + 4 * B_XY ** 2) / (4 * abs(B_XY) * K3)


def omegas_undamped(mu):
    """The two circular frequencies [rad/s] below threshold, ascending."""
    root = np.sqrt(delta(mu))
    return np.sqrt(np.array([A_XX + D_YY - root, A_XX + D_YY + root]) / (2 * MASS))


def lambda_growing_undamped(mu):
    """The root of det(lambda^2 M + K) with Re > 0 and Im > 0, above threshold."""
    L = (-(A_XX + D_YY) + 1j * np.sqrt(-delta(mu))) / (2 * MASS)
    return np.sqrt(L)


def mu_c_equal(c):
    """Threshold with D = c I (= (c/m) M): B^2 = gamma^2 A."""
    return ((A_XX - D_YY) ** 2 + 4 * B_XY ** 2 + 2 * c ** 2 * (A_XX + D_YY) / MASS) \
        / (4 * abs(B_XY) * K3)


def hurwitz_coefficients(mu, c1, c2):
    """(a4, a3, a2, a1, a0) of det(lambda^2 M + lambda diag(c1, c2) + K(mu))."""
    m, a, b, d = MASS, A_XX, B_XY, D_YY
    return (m * m, m * (c1 + c2), m * (a + d) + c1 * c2, c1 * d + c2 * a,
            a * d - b * (b + mu * K3))


def mu_c_hurwitz(c1, c2):
    """Root of H3 = a3 a2 a1 - a1^2 a4 - a3^2 a0 (affine in mu through a0)."""
    a4, a3, a2, a1, _ = hurwitz_coefficients(0.0, c1, c2)
    a0_star = a1 * (a3 * a2 - a4 * a1) / a3 ** 2
    return (a0_star - A_XX * D_YY + B_XY ** 2) / (abs(B_XY) * K3)


def mu_c_limit(r1, r2):
    """lim_{c -> 0} of the threshold with D = c diag(r1, r2)."""
    p = (r1 * D_YY + r2 * A_XX) / (r1 + r2)
    return (B_XY ** 2 - (p - A_XX) * (p - D_YY)) / (abs(B_XY) * K3)


# --- thresholds from complex_modes alone ------------------------------------------------------

def bisect(unstable_at, lo=BRACKET[0], hi=BRACKET[1]):
    """The stability boundary in mu between a stable lo and an unstable hi, to REL_BRACKET."""
    assert not unstable_at(lo) and unstable_at(hi), "bracket does not straddle the threshold"
    while hi - lo > REL_BRACKET * hi:
        mid = 0.5 * (lo + hi)
        if unstable_at(mid):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def flags_unstable(cx=0.0, cy=0.0):
    """Undamped: below threshold the real parts are round-off, so ask `unstable`
    (UNSTABLE_RTOL |lambda|)."""
    return lambda mu: bool(modes(mu, cx, cy).unstable.any())


def grows(cx, cy):
    """Damped: below threshold every real part is clearly negative, so its sign decides."""
    return lambda mu: bool(np.max(modes(mu, cx, cy).real) > 0.0)


def rel(x, ref):
    return abs(x - ref) / abs(ref)


def assert_mode_shapes(cm, M, D, K):
    """Each vector solves (lambda^2 M + lambda D + K) v = 0 and has unit largest entry."""
    for lam, v in zip(cm.eigenvalues, cm.vectors.T):
        assert abs(np.max(np.abs(v)) - 1.0) < 1e-12
        r = (lam ** 2 * M + lam * D + K) @ v
        assert np.linalg.norm(r) <= 1e-10 * np.linalg.norm(K)


# --- 1. undamped ------------------------------------------------------------------------------

def test_geometry_has_flutter_for_positive_mu():
    """b < 0 so Delta falls with mu > 0; mu_c in (0.1, 1); det K > 0 (no divergence) up to 1.5."""
    assert B_XY < 0
    assert 0.1 < mu_c_undamped() < 1.0
    assert abs(A_XX - D_YY) > 0.2 * A_XX          # a != d: the paradox below is not degenerate
    assert A_XX * D_YY - B_XY * (B_XY + BRACKET[1] * K3) > 0
    assert delta(mu_c_undamped()) == pytest.approx(0.0, abs=1e-9 * A_XX ** 2)


def test_undamped_threshold_from_bisection_matches_closed_form():
    """mu_c = ((a - d)^2 + 4 b^2) / (4 |b| k3), found from `unstable` alone."""
    mu_cea = bisect(flags_unstable())
    assert rel(mu_cea, mu_c_undamped()) < 1e-8


@pytest.mark.parametrize("frac", [-1.0, 0.0, 0.5, 0.9, 0.99])
def test_undamped_below_threshold_stable_with_closed_form_frequencies(frac):
    """Below mu_c: two modes, real parts at round-off, omega = sqrt(((a+d) -+ sqrt(Delta))/(2m)).

    frac = -1 is the belt reversed (mu < 0, b mu > 0): Delta only grows, no flutter.
    """
    mu = frac * mu_c_undamped()
    cm = modes(mu)
    lam = cm.eigenvalues
    assert lam.shape == (2,)
    assert not cm.unstable.any()
    assert np.all(np.abs(lam.real) <= 1e-11 * np.abs(lam))
    w = omegas_undamped(mu)
    assert np.all(np.abs(lam.imag - w) <= 1e-10 * w)
    assert np.all(np.abs(cm.frequency_hz - w / (2 * np.pi)) <= 1e-10 * w / (2 * np.pi))
    assert np.all(np.abs(cm.damping_ratio) <= 1e-11)


def test_undamped_above_threshold_growing_root_is_the_biquadratic_root():
    """At 1.2 mu_c: lambda^2 = (-(a+d) + i sqrt(-Delta)) / (2m), lambda its principal sqrt.

    The two returned roots (imag >= 0) are lambda and -conj(lambda); `unstable` marks lambda.
    """
    mu = 1.2 * mu_c_undamped()
    cm = modes(mu)
    lam = cm.eigenvalues
    assert lam.shape == (2,)
    expect = lambda_growing_undamped(mu)
    assert expect.real > 0 and expect.imag > 0
    i = int(np.argmax(lam.real))
    assert abs(lam[i] - expect) <= 1e-10 * abs(expect)
    assert abs(lam[1 - i] + np.conj(expect)) <= 1e-10 * abs(expect)
    assert cm.unstable.tolist() == [k == i for k in range(2)]
    assert cm.damping_ratio[i] < 0 < cm.damping_ratio[1 - i]
    assert_mode_shapes(cm, *system(mu))


# --- 2. equal damping -------------------------------------------------------------------------

@pytest.mark.parametrize("c", [0.5, 2.0, 8.0])
def test_equal_damping_threshold_rises_as_closed_form(c):
    """D = c I: mu_c(c) = ((a-d)^2 + 4 b^2 + 2 c^2 (a+d)/m) / (4 |b| k3) > mu_c(0)."""
    mu_cea = bisect(grows(c, c))
    assert rel(mu_cea, mu_c_equal(c)) < 1e-8
    assert mu_cea > mu_c_undamped() * (1 + 1e-6)
    # the Hurwitz form with c1 = c2 is the same closed form (two derivations agree)
    assert rel(mu_c_hurwitz(c, c), mu_c_equal(c)) < 1e-13


def test_equal_damping_eigenvalues_are_shifted_undamped_ones():
    """D = gamma M: lambda = -gamma/2 +- sqrt(gamma^2/4 + s), s = -A + i B (above mu_c(0))."""
    c = 2.0
    gamma = c / MASS
    mu = 1.3 * mu_c_undamped()
    s = (-(A_XX + D_YY) + 1j * np.sqrt(-delta(mu))) / (2 * MASS)
    root = np.sqrt(gamma ** 2 / 4 + s)
    # the two with imag > 0: -gamma/2 + u + i v and -gamma/2 - u + i v
    expect = np.array([-gamma / 2 - root.real + 1j * root.imag, -gamma / 2 + root])
    cm = modes(mu, c, c)
    lam = cm.eigenvalues[np.argsort(cm.eigenvalues.real)]
    assert np.all(np.abs(lam - expect) <= 1e-10 * np.abs(expect))
    assert cm.unstable.sum() == 1 and lam[1].real > 0
    assert_mode_shapes(cm, *system(mu, c, c))


# --- 3. unequal damping: Routh-Hurwitz and the paradox ----------------------------------------

@pytest.mark.parametrize("c1, c2", [(2.0, 0.0), (0.0, 2.0), (20.0, 0.0), (0.0, 0.05),
                                    (2.0, 0.5), (0.5, 3.0), (6.0, 1.0)])
def test_unequal_damping_threshold_matches_hurwitz(c1, c2):
    """D = diag(c1, c2): the root of H3 = a3 a2 a1 - a1^2 a4 - a3^2 a0 against bisection."""
    coeffs = hurwitz_coefficients(mu_c_hurwitz(c1, c2), c1, c2)
    assert all(x > 0 for x in coeffs)     # at the threshold only H3 changes sign
    mu_cea = bisect(grows(c1, c2))
    assert rel(mu_cea, mu_c_hurwitz(c1, c2)) < 1e-8


@pytest.mark.parametrize("c1, c2", [(1e-2, 0.0), (0.0, 1e-2), (1.0, 0.0), (30.0, 0.0)])
def test_one_direction_damping_threshold_is_b_over_k3_for_any_c(c1, c2):
    """c2 = 0 (or c1 = 0): H3 = m^2 c^2 (a d - a0), threshold |b| / k3 whatever c."""
    assert rel(mu_c_hurwitz(c1, c2), abs(B_XY) / K3) < 1e-13
    assert rel(bisect(grows(c1, c2)), abs(B_XY) / K3) < 1e-8


def test_damping_paradox():
    """Vanishing damping on one direction flutters below the undamped threshold.

    lim_{c->0} mu_c(c diag(1, 0)) = lim mu_c(c diag(0, 1)) = |b|/k3 < mu_c(0), while equal
    damping tends to mu_c(0) from above; an unequal ratio lands in between.
    """
    mu0 = mu_c_undamped()
    lim_x, lim_y = mu_c_limit(1.0, 0.0), mu_c_limit(0.0, 1.0)
    assert rel(lim_x, abs(B_XY) / K3) < 1e-13 and rel(lim_y, abs(B_XY) / K3) < 1e-13
    assert lim_x < 0.8 * mu0
    assert rel(mu_c_limit(1.0, 1.0), mu0) < 1e-13
    lim_ratio = mu_c_limit(1.0, 3.0)
    assert lim_x < lim_ratio < mu0
    # the limit from the CEA itself: a tiny damping at the fixed ratio
    c = 1e-3
    assert rel(bisect(grows(c, 3 * c)), lim_ratio) < 1e-6
    assert rel(bisect(grows(c, 0.0)), lim_x) < 1e-8
    assert rel(bisect(grows(c, c)), mu0) < 1e-6 and bisect(grows(c, c)) > mu0
    # directly: halfway between, the undamped system is stable, adding damping on x destabilizes
    mu = 0.5 * (lim_x + mu0)
    assert not modes(mu).unstable.any()
    for cx, cy in [(c, 0.0), (0.0, c), (1.0, 0.0), (0.0, 1.0)]:
        cm = modes(mu, cx, cy)
        assert np.max(cm.real) > 0 and cm.unstable.sum() == 1
    assert np.max(modes(mu, 1.0, 1.0).real) < 0


# --- the same model through the package's contact set and linearization ----------------------

def reduced_hoffmann(mu, speeds=(), values=(), V=1.0, N0=100.0):
    """The Hoffmann-Gaul mass as the package's ReducedSystem: one contact point (weight 1, a
    linear law of k = K3) whose gap is y and whose tangential displacement along the belt's
    sliding (+x) is x, pressed by N0; its modes diagonalize K_lin (Ks with the contact's
    tangent K3). The friction enters only through the contact set (FrictionSet) and
    stability.linearize, so their conventions are what this checks against the closed forms."""
    import scipy.sparse as sp
    from transient.case.specs import FrictionSpec
    from transient.contact.contactset import ContactSet, FrictionSet
    from transient.contact.friction import steady
    from transient.dynamics.state import State
    from transient.dynamics.system import ReducedSystem
    from transient.kernels.codes import LINEAR, TANH
    M, _, K_lin = system(0.0)
    omega2, Phi = np.linalg.eigh(K_lin / MASS)
    Phi = Phi / np.sqrt(MASS)                       # Phi^T M Phi = I
    spec = FrictionSpec(mu, tuple(speeds), tuple(values), "tanh", 1e-3)
    law = steady(spec, np.array([V]))
    Cn, Ct = np.array([[0.0, 1.0]]), np.array([[1.0, 0.0]])
    table = (np.array([speeds or (0.0,)]), np.array([values or (mu,)]),
             np.array([max(len(speeds), 1)]))
    friction = FrictionSet(sp.csr_matrix(Ct), sp.csr_matrix((1, 2)), np.array([V]), law.m,
                           law.dm, law.turn, np.array([TANH]), np.array([1e-3]),
                           np.zeros(1, np.int64), table)
    contacts = ContactSet(sp.csr_matrix(Cn), np.zeros(1), np.ones(1), np.array([LINEAR]),
                          np.array([[K3, 0.0, 0.0, 0.0]]), {"belt": slice(0, 1)},
                          friction=friction)
    sys_ = ReducedSystem(contacts, np.array([K3]), np.zeros((0, 2)), (), np.zeros((0, 2)), (),
                         0, None, omega2=omega2, damp=np.zeros(2), C=Cn @ Phi, Ct=Ct @ Phi,
                         Cc=np.zeros((1, 2)))
    state = State.zeros(2, 1)
    state.q[:] = Phi.T @ M @ np.array([0.0, -N0 / K3])    # the contact spring holds N0
    return sys_, state


def package_modes(mu, **kw):
    from transient.stability.linearize import linearized
    return complex_modes(*linearized(*reduced_hoffmann(mu, **kw)))


def test_the_package_linearization_has_hoffmanns_threshold_and_eigenvalue():
    """The friction stiffness of the contact set (mu k_t along +x from the normal gap) is the
    closed form's [[0, mu K3], [0, 0]]: the threshold from the package's linearization and the
    growing eigenvalue above it match the closed forms."""
    mu_c = bisect(lambda mu: bool(package_modes(mu).unstable.any()))
    assert rel(mu_c, mu_c_undamped()) < 1e-8
    lam = package_modes(1.2 * mu_c_undamped()).eigenvalues
    grow = lam[np.argmax(lam.real)]
    assert rel(grow, lambda_growing_undamped(1.2 * mu_c_undamped())) < 1e-10


def test_a_falling_friction_law_is_negative_damping_along_the_sliding():
    """mu(v) falling by dmu/dv at the sliding speed is a damper w p dmu/dv < 0 on x: the
    eigenvalues are the roots of det(lambda^2 M + lambda diag(N0 dmu, 0) + K(mu(V)))."""
    N0, V = 100.0, 1.0
    speeds, values = (0.0, 2.0), (0.5, 0.3)          # mu(1) = 0.4, dmu/dv = -0.1 s/m
    lam = package_modes(0.0, speeds=speeds, values=values, V=V, N0=N0).eigenvalues
    c1 = N0 * (-0.1)
    roots = np.roots(hurwitz_coefficients(0.4, c1, 0.0))
    roots = roots[roots.imag >= 0]
    for r in roots:
        assert np.min(np.abs(lam - r)) < 1e-10 * abs(r)
    assert np.max(lam.real) > 0             # negative damping: unstable at mu = 0.4 < mu_c
