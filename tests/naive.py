"""Plain NumPy twins of the stepping kernels (transient.kernels), for the tests.

Written from the kernels' docstrings, not from their loops: a Python loop over the steps, NumPy
within a step, dense linear algebra where the kernels use triangular factors or the Woodbury
identity. Each twin takes the kernel's positional arguments and has its in-place semantics: the
state and acc (the rows and slots transient.kernels.layout names), gmin and fprev are updated,
the out_* rows filled, and (status, steps done) returned.

The implicit twins iterate as their kernels' docstrings say (the fixed operator plus the
exact corrections of the rows in active_rows, their Jacobian J_A solved densely), not by plain
Newton: the iterates are then the same and the converged steps agree to round-off, not merely
to the Newton tolerance.

The system (stepping.py): M a + c v + K_lin q = F(t) + C^T [w (p(g) + k_t* (g - g0))],
g = C q + g0, F(t) = patterns^T s(t); energies per output row: kinetic, strain (1/2 q^T K q with
K = K_lin - C^T diag(w k_t*) C), contact (sum w Phi(g)), external work, dissipated.
"""
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from transient.kernels.codes import NO_CONVERGENCE, NOT_FINITE, OK
from transient.kernels.exponential import IMPLICIT_TOL
from transient.kernels.layout import (A_ROW, DAMPING_ACC, DISSIPATED_ACC, FRICTION_ROW, Q_ROW,
                                      SLIDING_ACC, TIME_ROW, V_ROW, WORK_ACC)
from transient.kernels.woodbury import ARMIJO, FIXED_POINT_RATE, MIN_STEP, WOODBURY_REST

# contact laws: the codes and parameter rows (4,) of kernels/laws.py
EXPONENTIAL, LINEAR, BILATERAL = 0, 1, 2

# signal kinds and the columns of their parameter rows (8,)
CONSTANT, STEP, IMPULSE, SINE, CHIRP, TABLE = range(6)
START, AMPLITUDE, DURATION, RISE, FREQUENCY, F1, PHASE = range(7)
N_PARAMS = 8


# ----------------------------------------------------------------------------- contact laws

def exponential_params(p0, lam, p_lin):
    """Row of the exponential law p0 exp(-lambda g), linear below the gap where p = p_lin."""
    return np.array([p0, lam, -np.log(p_lin / p0) / lam, 0.0])


def penalty_params(k):
    """Row of the linear (unilateral) or bilateral penalty of stiffness k [Pa/m]."""
    return np.array([k, 0.0, 0.0, 0.0])


def pressure_potential(code, params, g):
    """(p, k_t, Phi) at the gaps g (m,) of points with laws code (m,) and params (m, 4).

    Exponential: p = p0 exp(-lambda g) for g >= g_lin, below g_lin the straight line with the
    same value and slope; Phi the integral of p from g to infinity. Linear: p = k max(-g, 0),
    Phi = 1/2 k min(g, 0)^2. Bilateral: p = -k g, Phi = 1/2 k g^2. k_t = -dp/dg.
    """
    g = np.asarray(g, dtype=float)
    p = np.zeros_like(g)
    kt = np.zeros_like(g)
    phi = np.zeros_like(g)
    ex = code == EXPONENTIAL
    p0, lam, g_lin = params[ex, 0], params[ex, 1], params[ex, 2]
    # the exponential taken at max(g, g_lin): its value and slope where the line starts
    pe = p0 * np.exp(-lam * np.maximum(g[ex], g_lin))
    d = np.maximum(g_lin - g[ex], 0.0)
    p[ex] = pe + lam * pe * d
    kt[ex] = lam * pe
    phi[ex] = pe / lam + pe * d + 0.5 * lam * pe * d * d
    k = params[:, 0]
    closed = (code == LINEAR) & (g < 0.0)
    tied = code == BILATERAL
    pen = closed | tied
    p[pen] = -k[pen] * g[pen]
    kt[pen] = k[pen]
    phi[pen] = 0.5 * k[pen] * g[pen] ** 2
    return p, kt, phi


# ----------------------------------------------------------------------------- signals

def signal_values(t, codes, params, table_t, table_v, table_n):
    """Values (J,) of the packed signals at time t.

    Windows are half-open, start <= t < start + duration; every kind but constant and table is
    0 before its start. Step: linear rise over RISE to AMPLITUDE. Impulse: half sine of length
    DURATION. Sine: AMPLITUDE sin(2 pi FREQUENCY tau + PHASE), DURATION 0 meaning no end. Chirp:
    phase 2 pi (f0 tau + (f1 - f0) tau^2 / (2 DURATION)). Table: 0 before its first time,
    linear between, its last value after.
    """
    out = np.zeros(len(codes))
    for j, code in enumerate(codes):
        if code == CONSTANT:
            out[j] = 1.0
            continue
        if code == TABLE:
            n = table_n[j]
            times, values = table_t[j, :n], table_v[j, :n]
            out[j] = 0.0 if t < times[0] else np.interp(t, times, values)
            continue
        tau = t - params[j, START]
        a, d = params[j, AMPLITUDE], params[j, DURATION]
        if tau < 0.0:
            out[j] = 0.0
        elif code == STEP:
            rise = params[j, RISE]
            out[j] = a * min(tau / rise, 1.0) if rise > 0.0 else a
        elif code == IMPULSE:
            out[j] = a * np.sin(np.pi * tau / d) if tau < d else 0.0
        elif code == SINE:
            ended = d > 0.0 and tau >= d
            out[j] = 0.0 if ended else a * np.sin(2 * np.pi * params[j, FREQUENCY] * tau
                                                   + params[j, PHASE])
        elif code == CHIRP:
            f0, f1 = params[j, FREQUENCY], params[j, F1]
            out[j] = a * np.sin(2 * np.pi * (f0 * tau + (f1 - f0) * tau ** 2 / (2 * d))) \
                if tau < d else 0.0
    return out


def pack_signals(specs):
    """(codes, params, table_t, table_v, table_n) of signals given as (code, {column: value})
    pairs, a table as (TABLE, (times, values))."""
    T = max([len(p[0]) for c, p in specs if c == TABLE], default=1)
    codes = np.array([c for c, _ in specs], dtype=np.int64)
    params = np.zeros((len(specs), N_PARAMS))
    table_t = np.zeros((len(specs), T))
    table_v = np.zeros((len(specs), T))
    table_n = np.zeros(len(specs), dtype=np.int64)
    for j, (code, p) in enumerate(specs):
        if code == TABLE:
            table_n[j] = len(p[0])
            table_t[j, :table_n[j]], table_v[j, :table_n[j]] = p
        else:
            for column, value in p.items():
                params[j, column] = value
    return codes, params, table_t, table_v, table_n


def external(t, patterns, sig):
    """F(t) = patterns^T s(t)."""
    return patterns.T @ signal_values(t, *sig)


# ----------------------------------------------------------------------------- coefficients

def exponential_coefficients(omega2, damp, dt):
    """(n, 8) per mode of x'' + c x' + omega^2 x = F, F linear over the step:
    [E11, E12, E21, E22, G0x, G0v, G1x, G1v] with
    (x, v)(dt) = E (x, v)(0) + G0 F(0) + G1 (F(dt) - F(0)).

    The force is carried as two more states, F itself and its ramp r = F(dt) - F(0) with
    F' = r / dt, so one matrix exponential of the 4 x 4 system gives E, G0 and G1 at once.
    """
    n = len(omega2)
    A = np.zeros((n, 4, 4))
    A[:, 0, 1] = 1.0
    A[:, 1, 0] = -omega2
    A[:, 1, 1] = -damp
    A[:, 1, 2] = 1.0
    A[:, 2, 3] = 1.0 / dt
    X = sla.expm(A * dt)
    return np.stack([X[:, 0, 0], X[:, 0, 1], X[:, 1, 0], X[:, 1, 1],
                     X[:, 0, 2], X[:, 1, 2], X[:, 0, 3], X[:, 1, 3]], axis=1)


def propagate(coef, q0, v0, f0, f1):
    """(q, v) at the end of a step from (q0, v0), forces f0 and f1 at its ends."""
    df = f1 - f0
    q = coef[:, 0] * q0 + coef[:, 1] * v0 + coef[:, 4] * f0 + coef[:, 6] * df
    v = coef[:, 2] * q0 + coef[:, 3] * v0 + coef[:, 5] * f0 + coef[:, 7] * df
    return q, v


# ----------------------------------------------------------------------------- contact pass

def _contact(s, g0, w, kt0, code, params):
    """Per-point force w (p + k_t* s), gap and pressure, and (contact potential,
    1/2 sum w k_t* s^2), for the motion s = C q of the rows."""
    g = g0 + s
    p, _, phi = pressure_potential(code, params, g)
    return w * (p + kt0 * s), g, p, (np.sum(w * phi), 0.5 * np.sum(w * kt0 * s * s))


def remainder_dense(C, g0, w, kt0, code, params, q, f, gap, press, blocks, fbuf):
    """f = C^T [w (p(g) + k_t* (g - g0))]; fills gap and press. With more than one block,
    fbuf[b] holds the part of f from rows blocks[b]:blocks[b + 1]. Returns (contact
    potential, 1/2 sum w k_t* (g - g0)^2)."""
    r, gap[:], press[:], energies = _contact(C @ q, g0, w, kt0, code, params)
    if len(blocks) == 2:
        f[:] = C.T @ r
    else:
        for b in range(len(blocks) - 1):
            rows = slice(blocks[b], blocks[b + 1])
            fbuf[b] = C[rows].T @ r[rows]
        f[:] = fbuf.sum(axis=0)
    return energies


def csr(triplet, n_cols):
    """scipy CSR matrix of an (indptr, indices, data) triplet."""
    indptr, indices, data = triplet
    return sp.csr_matrix((data, indices, indptr), shape=(len(indptr) - 1, n_cols))


def remainder_sparse(Cp, Ci, Cd, g0, w, kt0, code, params, q, f, gap, press):
    """remainder_dense for the rows of a CSR matrix C (no blocks)."""
    C = csr((Cp, Ci, Cd), len(q))
    r, gap[:], press[:], energies = _contact(C @ q, g0, w, kt0, code, params)
    f[:] = C.T @ r
    return energies


# ----------------------------------------------------------------------------- common parts

def _energies(acc, kinetic, strain, contact, work, dissipated):
    """The output row of energies, after adding the step's work and dissipation to acc."""
    acc[WORK_ACC] += work
    acc[DISSIPATED_ACC] += dissipated
    return np.array([kinetic, strain, contact, acc[WORK_ACC], acc[DISSIPATED_ACC]])


def _modal_energies(acc, q, v, q0, v0, fext0, fext, damp, omega2, lin, phi, dt):
    """Energies after a modal step from (q0, v0) to (q, v): work and dissipation by the
    trapezoid rule, kinetic and structural strain at the end."""
    work = 0.5 * np.dot(fext0 + fext, q - q0)
    dissipated = 0.5 * dt * np.dot(damp, v0 * v0 + v * v)
    return _energies(acc, 0.5 * np.dot(v, v), 0.5 * np.dot(omega2, q * q) - lin, phi, work,
                     dissipated)


def _finite(*arrays):
    return all(np.all(np.isfinite(x)) for x in arrays)


def _store(outs, row, t, observed, gap, press, energy, slip=None):
    """An output row; the slip velocities (2, m) too where their rows have columns."""
    out_t, out_s, out_g, out_p, out_v, out_e = outs
    out_t[row] = t
    out_s[row] = observed
    if out_g.shape[1] > 0:
        out_g[row] = gap
        out_p[row] = press
    if out_v.shape[2] > 0:
        out_v[row] = slip
    out_e[row] = energy


def active_rows(code, params, gap, w, kt0, scale, Gd):
    """(e, rows A) of the exact contact corrections: e_i = scale w_i (k_t,i - k_t*,i); A the
    rows of largest |e_i| G_ii, taken until the sum over the others is at most WOODBURY_REST."""
    _, kt, _ = pressure_potential(code, params, gap)
    e = scale * w * (kt - kt0)
    size = np.abs(e) * Gd
    order = np.argsort(-size)
    rest = size.sum() - np.concatenate([[0.0], np.cumsum(size[order])])
    return e, order[:np.argmax(rest <= WOODBURY_REST)]


def _newton_step(S, U, C, e, rows, r):
    """J_A^-1 r for J_A = S + diag(U) C_A^T diag(e_A) C_A, S a dense (n, n) operator: what the
    kernels obtain from S^-1 and the Woodbury identity."""
    CA = C[rows]
    return np.linalg.solve(S + U[:, None] * (CA.T @ (e[rows, None] * CA)), r)


TANH, ATAN, NONE = 0, 1, -1
SMALL = 1e-6


def no_friction(n):
    """The friction arrays of a system without friction (as dynamics.schemes makes them)."""
    return (np.zeros((0, n)), np.zeros((0, n)), np.zeros(0), np.zeros(0, np.int64),
            np.zeros(0), np.zeros(0, np.int64), np.zeros((1, 1)), np.zeros((1, 1)),
            np.ones(1, np.int64))


def slips(fr, v):
    """The points' slip velocities (2, m) at v: (V - Ct v, -Cc v), and (V, 0) where a point
    has no friction law."""
    Ct, Cc, V, code = fr[:4]
    s = np.array([V - Ct @ v, -(Cc @ v)])
    s[:, code == NONE] = np.array([V, 0.0 * V])[:, code == NONE]
    return s


def friction_force(fr, w, press, v):
    """(force on the coordinates, the sliding's input power) of the regularized Coulomb
    tractions w p mu(|s|) sgn_reg(|s|) s / |s|, s = (V - Ct v, -Cc v); None without
    friction."""
    Ct, Cc, V, code, v_eps, table, tab_v, tab_mu, tab_n = fr
    if len(Ct) == 0:
        return None, 0.0
    st, sc = V - Ct @ v, -(Cc @ v)
    s = np.hypot(st, sc)
    mu = np.array([np.interp(x, tab_v[k, :tab_n[k]], tab_mu[k, :tab_n[k]])
                   for x, k in zip(s, table)])
    x = s / v_eps
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(code == TANH, np.tanh(x), (2 / np.pi) * np.arctan(x)) / s
    series = np.where(code == TANH, 1.0, 2 / np.pi) * (1.0 - x * x / 3.0) / v_eps
    ratio = np.where(x < SMALL, series, ratio)
    c = np.where((code == NONE) | (press <= 0.0), 0.0, w * press * mu * ratio)
    return Ct.T @ (c * st) + Cc.T @ (c * sc), float((c * st) @ V)


def friction_energy(state, acc, energy, ff, dq, p_in, dt):
    """The friction's energies of a step (kernels.friction.friction_energy): its work on the
    structure 1/2 (ff0 + ff) . dq, the sliding's input by the trapezoid; ff0 in the state's
    FRICTION_ROW."""
    onto = 0.5 * np.dot(state[FRICTION_ROW] + ff, dq)
    inflow = 0.5 * dt * (acc[SLIDING_ACC] + p_in)
    acc[WORK_ACC] += inflow
    acc[DISSIPATED_ACC] += inflow - onto
    acc[SLIDING_ACC] = p_in
    state[FRICTION_ROW] = ff
    energy[3], energy[4] = acc[WORK_ACC], acc[DISSIPATED_ACC]


def slip_tangent(code, v_eps, mu, dmu, st, sc):
    """(c, c' |s|) of the traction w p c(|s|) s, c = mu sgn_reg(|s|) / |s| (mu and its slope
    dmu at |s| given): c' |s| = dmu sgn_reg + mu (sgn_reg' - sgn_reg / |s|), the last
    difference -(2/3) x^2 / v_eps (times 2 / pi for atan) to leading order where it would
    cancel (x = |s| / v_eps < 1e-4)."""
    s = np.hypot(st, sc)
    x = s / v_eps
    k = 1.0 if code == TANH else 2.0 / np.pi
    g = np.tanh(x) if code == TANH else k * np.arctan(x)
    gp = (1.0 - g * g) / v_eps if code == TANH else k / (v_eps * (1.0 + x * x))
    if x < 1e-4:
        return mu * k * (1.0 - x * x / 3.0) / v_eps, dmu * g + mu * k * (-2.0 / 3.0) * x * x / v_eps
    return mu * g / s, dmu * g + mu * (gp - g / s)


def _table_slope(tab_v, tab_mu, k, s):
    """(mu, dmu/ds) of a table of k points at s (0 slope beyond its ends)."""
    xs, ys = tab_v[:k], tab_mu[:k]
    if k == 1 or s <= xs[0] or s >= xs[-1]:
        return float(np.interp(s, xs, ys)), 0.0
    j = np.searchsorted(xs, s)
    slope = (ys[j] - ys[j - 1]) / (xs[j] - xs[j - 1])
    return ys[j - 1] + slope * (s - xs[j - 1]), slope


def coupled_terms(code, params, gap, press, w, kt0, fr, v, P, Dq, Dv, C):
    """The Jacobian terms U_c V_c^T of the implicit steps (kernels.woodbury.coupled_rows:
    x moves q by Dq x and v by Dv x, J = P + sum U V^T, P a diagonal (n,) or a full
    operator (n, n)), as dense (U, V) pairs with each
    term's size, the sum of |coefficient x V_c^T P^-1 column| over the columns C_i, Ct_i,
    Cc_i it combines; per point i the gap's term, then the slip's along and across."""
    _, kt, _ = pressure_potential(code, params, gap)
    m = len(gap)
    friction = len(fr[0]) > 0
    terms = []

    def cross(a, da, b):
        if P.ndim == 1:
            return abs(float(a * da / P @ b))
        return abs(float(a * da @ np.linalg.solve(P, b)))

    for i in range(m):
        e = w[i] * (kt[i] - kt0[i])
        U, V = e * C[i], Dq * C[i]
        size = abs(e) * cross(1.0, C[i] * Dq, C[i])
        slips = []
        if friction:
            Ct, Cc, Vs, fcode, v_eps, table, tab_v, tab_mu, tab_n = fr
            slips = [(0.0, np.zeros_like(U), Dv * Ct[i]), (0.0, np.zeros_like(U), Dv * Cc[i])]
            if fcode[i] != NONE and press[i] > 0.0:
                st, sc = Vs[i] - Ct[i] @ v, -(Cc[i] @ v)
                t = table[i]
                mu, dmu = _table_slope(tab_v[t], tab_mu[t], tab_n[t], np.hypot(st, sc))
                c, d = slip_tangent(fcode[i], v_eps[i], mu, dmu, st, sc)
                g = w[i] * kt[i] * c
                U = U + g * (st * Ct[i] + sc * Cc[i])
                size += abs(g * st) * cross(1.0, C[i] * Dq, Ct[i]) + abs(g * sc) * cross(
                    1.0, C[i] * Dq, Cc[i])
                s2 = st * st + sc * sc
                H = w[i] * press[i] * (c * np.eye(2) + (d / s2 if s2 > 0 else 0.0)
                                       * np.outer([st, sc], [st, sc]))
                slips = [(abs(H[0, 0]) * cross(1.0, Ct[i] * Dv, Ct[i])
                          + abs(H[1, 0]) * cross(1.0, Ct[i] * Dv, Cc[i]),
                          H[0, 0] * Ct[i] + H[1, 0] * Cc[i], Dv * Ct[i]),
                         (abs(H[1, 1]) * cross(1.0, Cc[i] * Dv, Cc[i])
                          + abs(H[0, 1]) * cross(1.0, Cc[i] * Dv, Ct[i]),
                          H[0, 1] * Ct[i] + H[1, 1] * Cc[i], Dv * Cc[i])]
        terms.append((size, U, V))
        terms.extend(slips)
    return terms


class LineSearch:
    """The friction's iteration of a step: fixed-point steps while the residual falls by
    FIXED_POINT_RATE, then Newton steps, halved while the squared residual does not fall by
    ARMIJO times the step's fraction (down to MIN_STEP of it): kernels.woodbury.backtrack."""

    def __init__(self, fixed_point=False):
        self.start, self.step, self.r2, self.alpha = None, None, np.inf, 1.0
        self.fixed_point, self.last = fixed_point, np.inf

    def newton_started(self, r2):
        """Whether the iteration is (now) Newton's, given the residual r2 just evaluated."""
        if self.fixed_point and r2 <= FIXED_POINT_RATE ** 2 * self.last:
            self.last = r2
            return False
        self.fixed_point = False
        return True

    def newton(self, x, step, r2):
        """The full Newton step from x (residual r2 there)."""
        self.start, self.step, self.r2, self.alpha = x.copy(), step, r2, 1.0
        return x - step

    def shorter(self, r2):
        """Whether the point just evaluated (residual r2) is to be replaced by a shorter step."""
        if self.alpha > MIN_STEP and r2 > (1.0 - ARMIJO * self.alpha) ** 2 * self.r2:
            self.alpha *= 0.5
            return True
        return False

    def point(self):
        return self.start - self.alpha * self.step


def coupled_newton(terms, P, R):
    """J_A^-1 R, J_A = P (its diagonal, or in full) + the terms of largest size, taken until
    the others sum to at most WOODBURY_REST, solved densely."""
    sizes = np.array([t[0] for t in terms])
    order = np.argsort(-sizes)
    rest = sizes.sum() - np.concatenate([[0.0], np.cumsum(sizes[order])])
    J = np.diag(P) if P.ndim == 1 else P.copy()
    for c in order[:np.argmax(rest <= WOODBURY_REST)]:
        J += np.outer(terms[c][1], terms[c][2])
    return np.linalg.solve(J, R)


# ----------------------------------------------------------------------------- explicit

def explicit_reduced(state, acc, n_steps, every, dt, omega2, damp, contact, fr, signals, blocks,
                     gmin, out):
    """Velocity Verlet on the modal system, the diagonal damping taken implicitly at the end
    of the step: v_{n+1} = (v_{n+1/2} + dt/2 f_{n+1}) / (1 + dt/2 c); friction at the
    half-step velocity."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    out_t, out_s, out_g, out_p, out_v, out_e = out
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    m, n = C.shape
    f, gap, press = np.empty(n), np.empty(m), np.empty(m)
    fbuf = np.empty((len(blocks) - 1, n))
    outs = (out_t, out_s, out_g, out_p, out_v, out_e)
    fext_old = external(t, patterns, sig)
    row = 0
    for step in range(1, n_steps + 1):
        power_old = np.dot(damp, v * v)
        v_half = v + 0.5 * dt * a
        dq = dt * v_half
        q += dq
        t += dt
        fext = external(t, patterns, sig)
        phi, lin = remainder_dense(C, g0, w, kt0, code, params, q, f, gap, press, blocks, fbuf)
        ff, p_in = friction_force(fr, w, press, v_half)
        slip = slips(fr, v_half)
        if ff is not None:
            f += ff
        gmin[:] = np.fmin(gmin, gap)
        force = fext + f - omega2 * q
        v[:] = (v_half + 0.5 * dt * force) / (1.0 + 0.5 * dt * damp)
        a[:] = force - damp * v
        energy = _energies(acc, 0.5 * np.dot(v, v), 0.5 * np.dot(omega2, q * q) - lin, phi,
                           0.5 * np.dot(fext_old + fext, dq),
                           0.5 * dt * (power_old + np.dot(damp, v * v)))
        if ff is not None:
            friction_energy(state, acc, energy, ff, dq, p_in, dt)
        fext_old = fext
        if not _finite(q, v, energy):
            state[TIME_ROW, 0] = t
            return NOT_FINITE, step
        if step % every == 0:
            _store(outs, row, t, S @ q, gap, press, energy, slip)
            row += 1
    state[TIME_ROW, 0] = t
    return OK, n_steps


def explicit_full(state, acc, n_steps, every, dt, K, mass, alpha, beta, contact, fr, signals, gmin,
                  out):
    """Central differences with a lumped mass: alpha M implicit at the end of the step, beta K
    on the half-step velocity. The dissipation is the trapezoid of the damping power
    v . (alpha M v + beta K v_half) at the steps' ends, carried between calls in acc[DAMPING_ACC].
    Friction (fr with CSR rows) at the half-step velocity, as explicit_reduced takes it."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    out_t, out_s, out_g, out_p, out_v, out_e = out
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    n, m = len(q), len(g0)
    Km, Sm = csr(K, n), csr(S, n)
    fr = (csr(fr[0], n).toarray(), csr(fr[1], n).toarray()) + tuple(fr[2:])
    slip = None
    f, gap, press = np.empty(n), np.empty(m), np.empty(m)
    outs = (out_t, out_s, out_g, out_p, out_v, out_e)
    fext_old = external(t, patterns, sig)
    power_old = acc[DAMPING_ACC]                  # the damping power the last call ended with
    row = 0
    for step in range(1, n_steps + 1):
        v_half = v + 0.5 * dt * a
        dq = dt * v_half
        q += dq
        t += dt
        fext = external(t, patterns, sig)
        phi, lin = remainder_sparse(*C, g0, w, kt0, code, params, q, f, gap, press)
        ff, p_in = friction_force(fr, w, press, v_half)
        if ff is not None:
            f = f + ff
            slip = slips(fr, v_half)
        gmin[:] = np.fmin(gmin, gap)
        ku = Km @ q
        kv = Km @ v_half
        force = fext + f - ku - beta * kv
        v[:] = (v_half + 0.5 * dt * force / mass) / (1.0 + 0.5 * dt * alpha)
        a[:] = force / mass - alpha * v
        power = np.dot(alpha * mass * v + beta * kv, v)     # v . the damping force
        energy = _energies(acc, 0.5 * np.dot(mass * v, v), 0.5 * np.dot(q, ku) - lin, phi,
                           0.5 * np.dot(fext_old + fext, dq), 0.5 * dt * (power_old + power))
        power_old = acc[DAMPING_ACC] = power
        if ff is not None:
            friction_energy(state, acc, energy, ff, dq, p_in, dt)
        fext_old = fext
        if not _finite(q, v, energy):
            state[TIME_ROW, 0] = t
            return NOT_FINITE, step
        if step % every == 0:
            _store(outs, row, t, Sm @ q, gap, press, energy, slip)
            row += 1
    state[TIME_ROW, 0] = t
    return OK, n_steps


# ----------------------------------------------------------------------------- exponential

def _finish(state, t, f0, fstart, omega2, damp):
    """The exponential twins' end of a call: the time, the start forces handed on, and the
    acceleration they give."""
    state[TIME_ROW, 0] = t
    fstart[:] = f0
    state[A_ROW] = f0 - omega2 * state[Q_ROW] - damp * state[V_ROW]


def exponential_reduced(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks,
                        corrector, carry, out):
    """Exact modal propagation under forces linear over the step. The end forces are first
    extrapolated from the step's start and fprev (the previous step's start), then evaluated
    1 + corrections times, each at the state propagated with the last ones; if
    propagate_last, a final propagation with the last forces ends the step (the gaps,
    pressures and contact energy stay those of the last evaluation). The start forces come
    in fstart and go out there for the next call; the acceleration left is theirs."""
    coef, damp, omega2 = modal
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    corrections, propagate_last = corrector
    fprev, fstart = carry
    out_t, out_s, out_g, out_p, out_v, out_e = out
    q, v = state[Q_ROW], state[V_ROW]
    t = state[TIME_ROW, 0]
    m, n = C.shape
    rem, gap, press = np.empty(n), np.empty(m), np.empty(m)
    fbuf = np.empty((len(blocks) - 1, n))
    outs = (out_t, out_s, out_g, out_p, out_v, out_e)
    fext0 = external(t, patterns, sig)
    f0 = fstart.copy()
    row = 0
    for step in range(1, n_steps + 1):
        q0, v0 = q.copy(), v.copy()
        f1 = 2.0 * f0 - fprev
        t += dt
        fext = external(t, patterns, sig)
        for _ in range(corrections + 1):
            q[:], v[:] = propagate(coef, q0, v0, f0, f1)
            phi, lin = remainder_dense(C, g0, w, kt0, code, params, q, rem, gap, press, blocks,
                                       fbuf)
            ff, p_in = friction_force(fr, w, press, v)
            slip = slips(fr, v)
            f1 = fext + rem + (ff if ff is not None else 0.0)
        if propagate_last:
            q[:], v[:] = propagate(coef, q0, v0, f0, f1)
        energy = _modal_energies(acc, q, v, q0, v0, fext0, fext, damp, omega2, lin, phi, dt)
        if ff is not None:
            friction_energy(state, acc, energy, ff, q - q0, p_in, dt)
        fprev[:] = f0
        f0, fext0 = f1, fext
        if not _finite(q, v, energy):
            _finish(state, t, f0, fstart, omega2, damp)
            return NOT_FINITE, step
        if step % every == 0:
            _store(outs, row, t, S @ q, gap, press, energy, slip)
            row += 1
    _finish(state, t, f0, fstart, omega2, damp)
    return OK, n_steps


def exponential_implicit(state, acc, n_steps, every, dt, modal, contact, fr, signals, blocks,
                         iteration, carry, out):
    """The exponential step with the end forces x implicit: q = qb + D x, v = vb + Dv x
    (D, Dv = diag(G1x), diag(G1v)), R(x) = x - fext - remainder(q) - friction(q, v) = 0 solved
    by Newton from the extrapolated forces, with J = I + the terms of coupled_terms solved
    densely: GQ and GV are taken for the signature only. Converged when |D R| <= IMPLICIT_TOL
    |q - q0| (and with friction |Dv R| <= IMPLICIT_TOL |v - v0|); q stays the last state
    evaluated, v is propagated with the forces found there."""
    coef, damp, omega2 = modal
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    GQ, GV, max_iter = iteration
    fprev, fstart = carry
    out_t, out_s, out_g, out_p, out_v, out_e = out
    q, v = state[Q_ROW], state[V_ROW]
    t = state[TIME_ROW, 0]
    m, n = C.shape
    friction = len(fr[0]) > 0
    rem, gap, press = np.empty(n), np.empty(m), np.empty(m)
    fbuf = np.empty((len(blocks) - 1, n))
    outs = (out_t, out_s, out_g, out_p, out_v, out_e)
    D, Dv, ones = coef[:, 6], coef[:, 7], np.ones(n)
    fext0 = external(t, patterns, sig)
    f0 = fstart.copy()
    row = 0
    for step in range(1, n_steps + 1):
        q0, v0 = q.copy(), v.copy()
        x = 2.0 * f0 - fprev
        t += dt
        fext = external(t, patterns, sig)
        q[:], v[:] = propagate(coef, q0, v0, f0, x)
        qb, vb = q - D * x, v - Dv * x
        converged = False
        line = LineSearch(fixed_point=friction)
        for _ in range(max_iter):
            phi, lin = remainder_dense(C, g0, w, kt0, code, params, q, rem, gap, press, blocks,
                                       fbuf)
            ff, p_in = friction_force(fr, w, press, v)
            slip = slips(fr, v)
            f1 = fext + rem + (ff if ff is not None else 0.0)
            R = x - f1

            def small(r, d, d0):
                return np.dot(r, r) <= IMPLICIT_TOL ** 2 * max(np.dot(d - d0, d - d0),
                                                              1e-20 * np.dot(d, d), 1e-300)
            if small(D * R, q, q0) and (not friction or small(Dv * R, v, v0)):
                converged = True
                break
            if not line.newton_started(np.dot(R, R)):
                x = x - R                                 # the fixed point
            elif friction and line.shorter(np.dot(R, R)):
                x = line.point()
            else:
                terms = coupled_terms(code, params, gap, press, w, kt0, fr, v, ones, D, Dv, C)
                x = line.newton(x, coupled_newton(terms, ones, R), np.dot(R, R))
            q[:], v[:] = qb + D * x, vb + Dv * x
        v[:] = propagate(coef, q0, v0, f0, f1)[1]
        energy = _modal_energies(acc, q, v, q0, v0, fext0, fext, damp, omega2, lin, phi, dt)
        if ff is not None:
            friction_energy(state, acc, energy, ff, q - q0, p_in, dt)
        fprev[:] = f0
        f0, fext0 = f1, fext
        if not _finite(q, v, energy):
            _finish(state, t, f0, fstart, omega2, damp)
            return NOT_FINITE, step
        if not converged:
            _finish(state, t, f0, fstart, omega2, damp)
            return NO_CONVERGENCE, step
        if step % every == 0:
            _store(outs, row, t, S @ q, gap, press, energy, slip)
            row += 1
    _finish(state, t, f0, fstart, omega2, damp)
    return OK, n_steps


# ----------------------------------------------------------------------------- Newmark

def _newmark(state, acc, n_steps, every, dt, M, K, cdamp, C, contact, patterns, sig, observe,
             tol, max_iter, outs, fr=None):
    """Average-acceleration Newmark on M a + cdamp v + K q = F + remainder(q), dense M, K and
    cdamp, Newton on a with J = S + C_A^T diag(e_A) C_A (S = M + dt/2 cdamp + dt^2/4 K,
    e_i = dt^2/4 w_i (k_t,i - k_t*,i), A as in active_rows with G_ii = (C S^-1 C^T)_ii).
    Converged when |R| <= tol |(f, |K| |q|, M a, 2/dt M v)|. The dissipation is the trapezoid
    of the damping power v . cdamp v; contact = (remainder, code, params, w, kt0) with
    remainder(q) -> (force, gap, pressure, (phi, lin)). With friction (fr, dense rows), the
    friction force at v joins the remainder and the Jacobian is that of coupled_terms (x = a,
    P = S, Dq = dt^2/4, Dv = dt/2), after the fixed point a -= S^-1 R; its work and the
    sliding's input as friction_energy takes them."""
    q, v, a = state[Q_ROW], state[V_ROW], state[A_ROW]
    t = state[TIME_ROW, 0]
    remainder, code, params, w, kt0 = contact
    friction = fr is not None and len(fr[0]) > 0
    h2 = 0.25 * dt * dt
    v_scale = 2.0 / dt if dt > 0.0 else 0.0
    Sop = M + 0.5 * dt * cdamp + h2 * K
    Gd = np.sum(C.T * np.linalg.solve(Sop, C.T), axis=0)
    fext_old = external(t, patterns, sig)
    row = 0
    for step in range(1, n_steps + 1):
        q_old, v_old = q.copy(), v.copy()
        qp = q + dt * v + h2 * a
        vp = v + 0.5 * dt * a
        t += dt
        fext = external(t, patterns, sig)
        converged = False
        line = LineSearch(fixed_point=friction)
        for _ in range(max_iter):
            q[:] = qp + h2 * a
            v[:] = vp + 0.5 * dt * a
            rem, gap, press, (phi, lin) = remainder(q)
            ff, p_in = friction_force(fr, w, press, v) if friction else (None, 0.0)
            slip = slips(fr, v) if friction else None
            f = fext + rem + (ff if ff is not None else 0.0)
            ku = K @ q
            r = M @ a + cdamp @ v + ku - f
            scale = (np.dot(f, f) + np.sum((np.abs(K) @ np.abs(q)) ** 2)
                     + np.sum((M @ a) ** 2) + np.sum((v_scale * (M @ v)) ** 2))
            if np.dot(r, r) <= tol * tol * max(scale, 1e-300):
                converged = True
                break
            if friction and not line.newton_started(np.dot(r, r)):
                a -= np.linalg.solve(Sop, r)              # the fixed point
            elif friction and line.shorter(np.dot(r, r)):
                a[:] = line.point()
            elif friction:
                P = Sop
                terms = coupled_terms(code, params, gap, press, w, kt0, fr, v, P,
                                      np.full(len(q), h2), np.full(len(q), 0.5 * dt), C)
                a[:] = line.newton(a, coupled_newton(terms, P, r), np.dot(r, r))
            else:
                e, rows = active_rows(code, params, gap, w, kt0, h2, Gd)
                a -= _newton_step(Sop, np.ones(len(q)), C, e, rows, r)
        q[:] = qp + h2 * a
        v[:] = vp + 0.5 * dt * a
        energy = _energies(acc, 0.5 * np.dot(v, M @ v), 0.5 * np.dot(q, K @ q) - lin, phi,
                           0.5 * np.dot(fext_old + fext, q - q_old),
                           0.5 * dt * (np.dot(v_old, cdamp @ v_old) + np.dot(v, cdamp @ v)))
        if friction:
            friction_energy(state, acc, energy, ff, q - q_old, p_in, dt)
        fext_old = fext
        if not _finite(q, v, energy):
            state[TIME_ROW, 0] = t
            return NOT_FINITE, step
        if not converged:
            state[TIME_ROW, 0] = t
            return NO_CONVERGENCE, step
        if step % every == 0:
            _store(outs, row, t, observe(q), gap, press, energy, slip)
            row += 1
    state[TIME_ROW, 0] = t
    return OK, n_steps


def newmark_reduced(state, acc, n_steps, every, dt, damp, omega2, contact, fr, signals, blocks,
                    iteration, out):
    """Newmark on the modal system (M = I, diagonal damping and K_lin), friction included.
    GQ and GV are taken for the signature only (see _newmark)."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    GQ, GV, tol, max_iter = iteration
    out_t, out_s, out_g, out_p, out_v, out_e = out
    m, n = C.shape
    fbuf = np.empty((len(blocks) - 1, n))

    def remainder(q):
        f, gap, press = np.empty(n), np.empty(m), np.empty(m)
        energies = remainder_dense(C, g0, w, kt0, code, params, q, f, gap, press, blocks, fbuf)
        return f, gap, press, energies

    return _newmark(state, acc, n_steps, every, dt, np.eye(n), np.diag(omega2), np.diag(damp),
                    C, (remainder, code, params, w, kt0), patterns, sig, lambda q: S @ q, tol,
                    max_iter, (out_t, out_s, out_g, out_p, out_v, out_e), fr)


def newmark_full(state, acc, n_steps, every, dt, K, M, alpha, beta, contact, fr, signals,
                 iteration, out):
    """Newmark on the full model, K (K_lin), M, C and S CSR triplets, Rayleigh damping
    alpha M + beta K, friction's rows fr as CSR triplets. The iteration operator is formed and
    solved densely: factor, Z, G and GV are taken for the signature only."""
    C, g0, w, kt0, code, params = contact
    patterns, sig, S = signals
    factor, Z, G, GV, tol, max_iter = iteration
    out_t, out_s, out_g, out_p, out_v, out_e = out
    n, m = state.shape[1], len(g0)
    fr = (csr(fr[0], n).toarray(), csr(fr[1], n).toarray()) + tuple(fr[2:])
    Kd, Md = csr(K, n).toarray(), csr(M, n).toarray()
    Cs, Sm = csr(C, n), csr(S, n)
    cdamp = alpha * Md + beta * Kd

    def remainder(q):
        f, gap, press = np.empty(n), np.empty(m), np.empty(m)
        energies = remainder_sparse(*C, g0, w, kt0, code, params, q, f, gap, press)
        return f, gap, press, energies

    return _newmark(state, acc, n_steps, every, dt, Md, Kd, cdamp, Cs.toarray(),
                    (remainder, code, params, w, kt0), patterns, sig, lambda q: Sm @ q, tol,
                    max_iter, (out_t, out_s, out_g, out_p, out_v, out_e), fr)
