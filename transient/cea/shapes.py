"""What a complex mode looks like on a brake: the nodal diameter of the rotating part and the
share of the motion each part carries (which disc mode and how much of the pad couple)."""
import numpy as np

from ..mesh.mesh import unit


def nodal_diameter(model, motion, u):
    """(n, share): the circumferential order n of the axial displacement of the part that a
    rotation turns, and the share of that order in its axial motion (|c_n|^2 / sum |c_k|^2).
    u: (ndof,) complex displacement."""
    part = model.parts[motion.part]
    dofs = model.part_dofs(motion.part).reshape(-1, 3)
    axis = unit(motion.axis)
    x = part.mesh.points - np.asarray(motion.point, float)
    e1 = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    theta = np.arctan2(x @ np.cross(axis, e1), x @ e1)
    w = u[dofs] @ axis
    # up to half the distinct angles of the nodes: beyond, orders alias (N - n is n again)
    angles = len(np.unique(np.round(theta, 6)))
    orders = np.arange(0, max(angles // 2, 1) + 1)
    c = np.abs(np.exp(-1j * np.outer(orders, theta)) @ w) ** 2
    # an order n and its mirror -n are one nodal diameter: a standing or travelling wave
    c = c + np.abs(np.exp(1j * np.outer(orders, theta)) @ w) ** 2 * (orders > 0)
    n = int(np.argmax(c))
    return n, float(c[n] / max(c.sum(), 1e-300))


def part_shares(model, M, u):
    """{part: share of the mode's kinetic energy u^H M u}."""
    Mu = M @ u
    total = float(np.real(np.vdot(u, Mu)))
    return {name: float(np.real(np.vdot(u[d], Mu[d]))) / max(total, 1e-300)
            for name in model.parts for d in [model.part_dofs(name)]}


def describe(case, model, T, modes, which):
    """One dict per mode index in which: frequency, real part, the rotating parts' nodal
    diameter and the parts' energy shares."""
    rotations = [m for m in case.motion.values() if m.kind == "rotation"]
    out = []
    for j in which:
        u = T @ modes.vectors[:, j]
        row = {"mode": int(j + 1), "frequency_hz": float(modes.frequency_hz[j]),
               "real": float(modes.real[j]), "shares": part_shares(model, model.M, u)}
        for m in rotations:
            n, share = nodal_diameter(model, m, u)
            row.setdefault("nodal_diameters", {})[m.part] = {"order": n, "share": share}
        out.append(row)
    return out
