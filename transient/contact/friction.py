"""Friction on a contact pair: the sliding a [motion] imposes, the tangential observation, and
the regularized Coulomb law.

Sliding. A rigid motion of a part's material (a disc rotating under its fixed mesh: the
deformation is computed in the frame where the mesh stays) gives every point of Gamma the
velocity V = v2 - v1 of surface 2 relative to surface 1, projected on the contact plane at the
point: its direction t is the sliding direction, its length the sliding speed (Omega r on a
disc). c = n x t is the direction across. The inertial (gyroscopic, convective) terms of the
motion are left out.

Tangential observation. Like the gap, through the node directions: t_a at each interface node
(V at the node, projected off its normal), so the tangential displacement of a side is a scalar
nodal field, observed by the very rows that observe the normal one. d = C1 u1_t - C2 u2_t is the
displacement of surface 1 relative to surface 2 along t. A regularized rule observes it through
the same (1-eps)-compatible projection: the friction traction is mu times the normal one, the
same traction field, so its work is observed by the same operator (and a factored rule, C = L
B^T, shares L: only B changes). Measured (studies/study_friction_projection.py, mu = 0.4), the
unstable modes with the tangential field projected or observed raw, against the fine rule
unregularized: pad_disc, 7 modes within 1.2e-6 in frequency either way; the drilled cube on a
belt (eps auto, 25 of 817 shapes kept), 2 modes within 1.6e-4, real parts within 2.0%
(projected) and 2.1% (raw) of the largest. The choice barely matters on these interfaces; the
projection keeps one operator and the factored form.

Law. The traction on surface 1 is mu(|s|) p sgn_reg(s) along t with s = V - d' the sliding
speed of 2 relative to 1, so the force on the dofs is f = C_t^T (w p m(s)), m(s) = mu(|s|)
sgn_reg(s). sgn_reg(s) = tanh(s / v_eps) (the default: exactly Coulomb to round-off once s >
20 v_eps, so steady sliding is unbiased) or (2 / pi) atan(s / v_eps) (a tail 2 v_eps / (pi s)
below Coulomb at every speed). Its slope at rest, mu / v_eps, is a viscous damper of w p mu /
v_eps per point: the bound it puts on an explicit step is the same as any damper's, dt <=
2 (sqrt(1 + zeta^2) - zeta) / omega. Across the sliding the traction turns with the velocity:
mu p w reg(V) / V per unit of velocity across, a damper (the friction's directional damping).
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from ..kernels.codes import ATAN, FRICTIONLESS, TANH
from ..mesh.mesh import unit

CODES = {"tanh": TANH, "atan": ATAN}
MAX_SPEED = 1e6     # m/s: the sliding's, as motion.NAME.velocity's bound in the schema


def rigid_velocity(motion, x):
    """Velocity (k, 3) of the rigid motion (MotionSpec) at points x (k, 3)."""
    x = np.asarray(x, float)
    if motion.kind == "rotation":
        axis = unit(motion.axis)
        return motion.omega * np.cross(axis, x - np.asarray(motion.point, float))
    return np.broadcast_to(np.asarray(motion.velocity, float), x.shape).copy()


def _part_velocity(case, part, x):
    v = np.zeros((len(x), 3))
    for name, motion in case.motion.items():
        if motion.part == part:
            _check_reach(case, name, motion, x)
            v += rigid_velocity(motion, x)
    return v


def _check_reach(case, name, motion, x):
    """A rotation's speed at x, |omega| times the largest coordinate of x's arm (within
    sqrt(3) of it), within MAX_SPEED (a translation's bound), checked before it is formed: a
    point of the axis 1e300 m away overflowed the product, then the sliding's norm."""
    if motion.kind != "rotation" or not len(x) or motion.omega == 0.0:
        return
    axis = unit(motion.axis)
    with np.errstate(over="ignore", invalid="ignore"):
        r = np.asarray(x, float) - np.asarray(motion.point, float)
        arm = float(np.abs(r - (r @ axis)[:, None] * axis).max())
    if not abs(motion.omega) <= MAX_SPEED / max(arm, 1e-300):
        raise CaseError(case.path, f"motion.{name}.point", f"{list(motion.point)} turns the "
                        f"contact of part '{motion.part}' at up to {abs(motion.omega) * arm:.3g}"
                        f" m/s (omega {motion.omega:g} rad/s, {arm:.3g} m from the axis): "
                        f"expected a point of the axis that keeps it within {MAX_SPEED:g} m/s")


def _in_plane(v, normals):
    return v - np.einsum("ij,ij->i", v, normals)[:, None] * normals


def sliding_velocity(case, spec, x, normals):
    """V = v2 - v1 at points x (k, 3), projected off the unit normals (k, 3)."""
    part1 = spec.surface1.split(".", 1)[0]
    v = -_part_velocity(case, part1, x)
    if not spec.wall:
        v += _part_velocity(case, spec.surface2.split(".", 1)[0], x)
    return _in_plane(v, normals)


def _directions(V, what, key, case):
    speed = np.linalg.norm(V, axis=1)
    scale = speed.max() if len(speed) else 0.0
    still = speed <= 1e-9 * max(scale, 1e-300)
    if np.any(still):
        raise CaseError(case.path, key, f"the motions leave {int(still.sum())} {what} of the "
                        "contact without sliding (on an axis of rotation, or no relative "
                        "motion): friction needs a sliding direction everywhere")
    return V / speed[:, None], speed


@dataclass(frozen=True)
class PairFriction:
    """The sliding of a pair: node directions of each side, speeds at the rule's points."""
    along1: np.ndarray       # (N1, 3) t at the nodes of side 1
    along2: np.ndarray       # (N2, 3)
    across1: np.ndarray      # (N1, 3) n x t
    across2: np.ndarray
    speed: np.ndarray        # (P,) sliding speed V at the rule's points [m/s]


def pair_sliding(case, pair):
    """The sliding field of a contact pair with friction (ContactPair)."""
    spec, interface = pair.spec, pair.interface
    key = f"contact.{pair.name}.friction"
    sides = []
    for side in (interface.side1, interface.side2):
        if side.n == 0:
            sides.append((np.zeros((0, 3)), np.zeros((0, 3))))
            continue
        x = side.points[side.nodes]
        t, _ = _directions(sliding_velocity(case, spec, x, side.node_normals), "nodes", key, case)
        sides.append((t, np.cross(side.node_normals, t)))
    rule = pair.rule
    _, speed = _directions(sliding_velocity(case, spec, rule.points, rule.normals), "points",
                           key, case)
    return PairFriction(sides[0][0], sides[1][0], sides[0][1], sides[1][1], speed)


def regularized_sign(code, s, v_eps):
    """sgn_reg(s) and its derivative."""
    x = s / v_eps
    if code == TANH:
        sign = np.tanh(x)
        return sign, (1.0 - sign ** 2) / v_eps
    return (2 / np.pi) * np.arctan(x), (2 / np.pi) / (v_eps * (1.0 + x ** 2))


def coefficient(spec, speed):
    """mu(|s|) and d mu / d|s| at speeds (the table linear between its points)."""
    speed = np.abs(np.asarray(speed, float))
    if not spec.speeds:
        return np.full(speed.shape, spec.mu), np.zeros(speed.shape)
    v, m = np.asarray(spec.speeds, float), np.asarray(spec.values, float)
    mu = np.interp(speed, v, m)
    if len(v) == 1:
        return mu, np.zeros(speed.shape)
    slopes = np.diff(m) / np.diff(v)
    i = np.searchsorted(v, speed, side="right") - 1
    inside = (i >= 0) & (i < len(slopes))
    return mu, np.where(inside, slopes[np.clip(i, 0, len(slopes) - 1)], 0.0)


@dataclass(frozen=True)
class SteadySliding:
    """The law linearized at steady sliding (d = 0, s = V) at every point: f = C_t^T (w p m)."""
    m: np.ndarray            # (P,) mu(V) sgn_reg(V): the traction per unit pressure
    dm: np.ndarray           # (P,) d m / d s at V: the damping along t per unit pressure
    turn: np.ndarray         # (P,) m / V: the damping across t per unit pressure [s/m]


def steady(spec, speed):
    """SteadySliding of a FrictionSpec at sliding speeds V (P,)."""
    code = CODES[spec.regularization]
    sign, dsign = regularized_sign(code, speed, spec.v_eps)
    mu, dmu = coefficient(spec, speed)
    m = mu * sign
    return SteadySliding(m, dmu * sign * np.sign(speed) + mu * dsign, m / speed)



def tangential_rows(pair, sliding, ndof):
    """The pair's observation of the tangential displacement along and across the sliding:
    (Ct, Cc) as CSR rows (P, ndof), or, for a factored rule (C = L B^T), (Bt, Bc) with Ct =
    L Bt^T: the same L as the gap's."""
    s1, s2 = pair.interface.side1, pair.interface.side2
    out = []
    for d1, d2 in ((sliding.along1, sliding.along2), (sliding.across1, sliding.across2)):
        T1, T2 = s1.direction_map(d1, ndof), s2.direction_map(d2, ndof)
        if pair.factors is not None:
            (_, Y1), (_, Y2) = pair.projections
            out.append(sp.hstack([T1.T @ sp.csr_matrix(Y1.T), T2.T @ sp.csr_matrix(Y2.T)])
                       .tocsr())
        else:
            rule = pair.rule
            out.append(sp.csr_matrix(sp.csr_matrix(rule.C1) @ T1
                                     - sp.csr_matrix(rule.C2) @ T2))
    return tuple(out)


# What a point of a stored history is doing (contact_status): apart, in the regularization's
# zone (|s| < v_eps, where sgn_reg is below tanh(1) = 0.76 of the full traction), or sliding.
OPEN, STICK, SLIP = 0, 1, 2
STATUS_NAMES = ("open", "stick", "slip")


def contact_status(gap, slip, v_eps):
    """Status codes (OPEN, STICK, SLIP) of points with gaps (..., m) [m] and slip velocities
    (..., 2, m) [m/s] along and across the sliding: open where the gap is positive (for the
    exponential law p < p0), stick where |s| < v_eps, slip otherwise."""
    speed = np.hypot(slip[..., 0, :], slip[..., 1, :])
    return np.where(gap > 0.0, OPEN, np.where(speed < v_eps, STICK, SLIP))


def traction_factor(code, v_eps, table, tables, speed):
    """c(|s|) = mu(|s|) sgn_reg(|s|) / |s| of each point (its traction per unit w p is c s),
    at slip speeds (..., m), with its limit at 0 (kernels.friction's law, in NumPy)."""
    speeds, values, counts = tables
    mu = np.empty_like(speed)
    for t in range(len(counts)):
        on = table == t
        k = counts[t]
        mu[..., on] = np.interp(speed[..., on], speeds[t, :k], values[t, :k])
    c = np.empty_like(speed)
    for code_i, scale in ((TANH, 1.0), (ATAN, 2.0 / np.pi)):
        on = code == code_i
        s, eps = speed[..., on], v_eps[on]
        x = s / eps
        with np.errstate(divide="ignore", invalid="ignore"):
            sign = np.tanh(x) if code_i == TANH else scale * np.arctan(x)
            c[..., on] = np.where(x < 1e-6, scale * (1.0 - x * x / 3.0) / eps, sign / s)
    c[..., code == FRICTIONLESS] = 0.0
    return mu * c


def friction_powers(law, weights, pressure, slip):
    """(the sliding's input, the slip's dissipation) [W] per row, from the points' pressures
    (rows, m) [Pa] and slip velocities (rows, 2, m): sum w p c s_t V and sum w p c |s|^2, with
    law = (code, v_eps, table, tables, V) of the points (kernels.friction: the structure takes
    their difference)."""
    code, v_eps, table, tables, V = law
    s_t, s_c = slip[:, 0, :], slip[:, 1, :]
    c = traction_factor(code, v_eps, table, tables, np.hypot(s_t, s_c))
    wp = weights * np.maximum(pressure, 0.0)
    return (np.sum(wp * c * s_t * V, axis=1),
            np.sum(wp * c * (s_t * s_t + s_c * s_c), axis=1))
