"""What the part a rotation turns (the disc) does in a mode: whether its motion is out of its
plane (axial), in its plane (radial and tangential) or mixed, and the nodal diameters of the
motion that carries the mode.

Each node's displacement is split along the rotation's axis, the radius through the node and
the circumference. Their shares of the part's kinetic energy (lumped mass) name the motion:
out-of-plane when the axial motion carries at least AXIAL_SHARE of it, in-plane when it carries
at most 1 - AXIAL_SHARE, mixed between. The nodal diameters are the circumferential order n of
the motion that carries the mode, from its Fourier series in the angle theta about the axis,
c_n = |sum_i m_i w_i exp(-i n theta_i)|^2 (the mass weights make the sum the integral over the
part on any mesh): the order of the largest c_n, and its share of them all. A mixed mode gets no
order: a count of the axial motion would describe a minor part of it (an in-plane mode's
Poisson motion gave "340 nodal diameters, 3% of its axial motion").
"""
import numpy as np
from scipy.spatial import cKDTree

from ..mesh.mesh import unit

# the share of the part's kinetic energy its axial motion carries in an out-of-plane mode (and
# its in-plane motion in an in-plane one): three quarters, so that the order counted is that of
# most of the motion, while a bending mode's in-plane part (the section's rotation and the
# pad's drag on the surface: 9-17% in pad_disc_squeal's unstable modes) leaves it out-of-plane
AXIAL_SHARE = 0.75

# (still: the part does not move at all in the mode)
OUT_OF_PLANE, IN_PLANE, MIXED, STILL = "out-of-plane", "in-plane", "mixed", "still"

# the bytes of the block of Fourier rows formed at a time
FOURIER_BYTES = 64 * 2**20


def disc_motion(model, motion, U):
    """One dict per displacement U[:, j] (ndof, k complex) of the model: on the part that the
    rotation `motion` turns, "motion" (out-of-plane, in-plane, mixed or still), "axial_share"
    (of the part's kinetic energy), "order" (the nodal diameters of the motion that carries the
    mode; None for a mixed or still one) and "share" (that order's share of the motion's
    Fourier series)."""
    dofs = model.part_dofs(motion.part)
    axis = unit(motion.axis)
    x = model.parts[motion.part].mesh.points - np.asarray(motion.point, float)
    e1 = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    x1, x2 = x @ e1, x @ e2
    theta = np.arctan2(x2, x1)
    orders = _orders(theta, x, np.hypot(x1, x2))
    radial = np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2
    tangential = np.cross(axis, radial)
    u = np.asarray(U)[dofs].reshape(len(theta), 3, -1)
    axial = np.einsum("ndk,d->nk", u, axis)
    planar = [np.einsum("ndk,nd->nk", u, radial), np.einsum("ndk,nd->nk", u, tangential)]
    mass = model.lumped_mass[dofs[::3]]
    e_axial = mass @ np.abs(axial) ** 2
    e_total = e_axial + sum(mass @ np.abs(w) ** 2 for w in planar)
    axial_share = e_axial / np.maximum(e_total, 1e-300)
    n_axial, s_axial = _order(theta, mass, [axial], orders)
    n_planar, s_planar = _order(theta, mass, planar, orders)
    out = []
    for j, a in enumerate(axial_share):
        kind = (STILL if e_total[j] == 0 else OUT_OF_PLANE if a >= AXIAL_SHARE else
                IN_PLANE if a <= 1 - AXIAL_SHARE else MIXED)
        n, s = {OUT_OF_PLANE: (n_axial[j], s_axial[j]),
                IN_PLANE: (n_planar[j], s_planar[j])}.get(kind, (None, None))
        out.append({"motion": kind, "axial_share": float(a),
                    "order": None if n is None else int(n),
                    "share": None if s is None else float(s)})
    return out


def _orders(theta, points, radius):
    """The count of circumferential orders, 0 up, that the nodes tell apart: those below half
    the distinct angles (beyond, orders alias: N - n is n again), and below pi R / d, R the
    largest radius and d the median distance from a node to its nearest: an order of shorter
    wavelength than two such steps around the rim is not sampled by the mesh, its Fourier row
    reads where the nodes happen to lie (an unstructured mesh has as many angles as nodes)."""
    distinct = max(len(np.unique(np.round(theta, 6))) // 2, 1) + 1
    if len(points) < 2:
        return distinct
    step = np.median(cKDTree(points).query(points, k=2)[0][:, 1])
    resolved = int(np.ceil(np.pi * radius.max() / step)) + 1 if step > 0 else distinct
    return min(distinct, resolved)


def _order(theta, mass, W, orders):
    """(n (k,), share (k,)): the circumferential order of largest power summed over the
    components W (each (nodes, k)), and its share of the power of the `orders` first orders
    (_orders). Their Fourier rows are made a block at a time (FOURIER_BYTES): on a fine disc
    they are thousands of orders by its nodes, gigabytes held whole."""
    k = W[0].shape[1]
    if k == 0:
        return np.zeros(0, int), np.zeros(0)
    step = np.exp(-1j * theta)
    block = max(1, FOURIER_BYTES // (16 * len(theta)))
    mws = [mass[:, None] * w for w in W]
    best, power, total = np.zeros(k, int), np.full(k, -1.0), np.zeros(k)
    E = None
    for start in range(0, orders, block):
        stop = min(start + block, orders)
        # E[n] = E[n-1] E[1] row after row, from E[start-1]: the same products as one
        # cumulative product over every order
        rows = np.empty((stop - start + 1, len(theta)), complex)
        rows[0] = 1.0 if E is None else E[-1]
        rows[1:] = step
        np.cumprod(rows, axis=0, out=rows)
        E = rows[1:] if start else rows[:-1]
        c = 0.0
        for mw in mws:
            # an order n and its mirror -n are one nodal diameter: a standing or travelling
            # wave; conj(E) w as conj(E conj(w)), the same numbers: no conjugate copy of E
            c = c + np.abs(E @ mw) ** 2
            mirror = np.abs(E @ mw.conj()) ** 2
            if start == 0:
                mirror[0] = 0.0
            c = c + mirror
        n = np.argmax(c, axis=0)
        top = c[n, np.arange(k)]
        better = top > power
        best[better], power[better] = n[better] + start, top[better]
        total += c.sum(axis=0)
    return best, power / np.maximum(total, 1e-300)
