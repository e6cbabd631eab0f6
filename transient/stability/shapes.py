"""What a complex mode looks like on a brake: the nodal diameter of the rotating part, the share
of the motion each part carries, and which mode of each other part alone (the pad on its
abutments) its motion there resembles: which disc mode and which pad mode couple."""
import numpy as np

from ..mesh.mesh import unit


def nodal_diameters(model, motion, U):
    """(n (k,), share (k,)): for each displacement U[:, j] (ndof, k complex), the
    circumferential order n of the axial motion of the part that a rotation turns, and the
    share of that order in it (|c_n|^2 / sum |c_k|^2)."""
    part = model.parts[motion.part]
    dofs = model.part_dofs(motion.part).reshape(-1, 3)
    axis = unit(motion.axis)
    x = part.mesh.points - np.asarray(motion.point, float)
    e1 = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    theta = np.arctan2(x @ np.cross(axis, e1), x @ e1)
    W = np.einsum("ndk,d->nk", U.reshape(len(U) // 3, 3, U.shape[1])[dofs[:, 0] // 3], axis)
    # up to half the distinct angles of the nodes: beyond, orders alias (N - n is n again)
    angles = len(np.unique(np.round(theta, 6)))
    # E[n] = exp(-i n theta) as powers of E[1] (a product a row: one exp a node instead of
    # one per order and node, 0.1 s on pad_disc's disc)
    E = np.empty((max(angles // 2, 1) + 1, len(theta)), complex)
    E[0] = 1.0
    E[1:] = np.exp(-1j * theta)
    np.cumprod(E, axis=0, out=E)
    # an order n and its mirror -n are one nodal diameter: a standing or travelling wave
    c = np.abs(E @ W) ** 2
    # conj(E) W as conj(E conj(W)), the same numbers: no conjugate copy of E (nodes x orders)
    c[1:] += np.abs(E[1:] @ W.conj()) ** 2
    n = np.argmax(c, axis=0)
    return n, c[n, np.arange(len(n))] / np.maximum(c.sum(axis=0), 1e-300)


def nodal_diameter(model, motion, u):
    """(n, share) of one displacement u (ndof,): nodal_diameters."""
    n, share = nodal_diameters(model, motion, np.asarray(u)[:, None])
    return int(n[0]), float(share[0])


def part_shares(model, M, U):
    """[{part: share of the mode's kinetic energy u^H M u}] for each column u of U (ndof, k)."""
    energy = np.real(U.conj() * real_times(M, U))
    total = np.maximum(energy.sum(axis=0), 1e-300)
    parts = {name: energy[model.part_dofs(name)].sum(axis=0) / total for name in model.parts}
    return [{name: float(share[k]) for name, share in parts.items()} for k in range(U.shape[1])]


def real_times(R, Z):
    """R Z for a real R (dense or sparse) and a complex Z (n, k), as one real product with
    [Re Z, Im Z]: NumPy and SciPy make a complex copy of R otherwise (the size of the whole
    basis X), and two products read R twice."""
    k = Z.shape[1]
    Y = R @ np.hstack([Z.real, Z.imag])
    return Y[:, :k] + 1j * Y[:, k:]


def still_parts(case, model):
    """The parts no rotation turns (the pad): those whose own modes describe a mode."""
    turned = {m.part for m in case.motion.values() if m.kind == "rotation"}
    return [p for p in model.parts if p not in turned]


def describe(case, model, basis, modes, which, fmax, own=None):
    """One dict per mode index in which: frequency, real part, the rotating parts' nodal
    diameter and the parts' energy shares. basis: (X, A), the modes' coordinates z are
    X (A z) on the model's dofs. The still parts' own modes up to fmax [Hz], or own:
    {part: part_modes(model, part, fmax)} made already."""
    X, A = basis
    U = real_times(X, A @ modes.vectors[:, which])
    rotations = {m.part: nodal_diameters(model, m, U)
                 for m in case.motion.values() if m.kind == "rotation"}
    # the parts that do not turn (the pad): which of their own modes the motion resembles
    still = still_parts(case, model)
    matched = matched_part_modes(model, U, still, fmax, own) if len(which) else {}
    out = []
    shares = part_shares(model, model.M, U)
    for k, j in enumerate(which):
        row = {"mode": int(j + 1), "frequency_hz": float(modes.frequency_hz[j]),
               "real": float(modes.real[j]), "shares": shares[k]}
        if rotations:
            row["nodal_diameters"] = {part: {"order": int(n[k]), "share": float(share[k])}
                                      for part, (n, share) in rotations.items()}
        if matched:
            row["part_modes"] = {part: {"mode": int(i[k] + 1), "frequency_hz": float(f[k]),
                                        "mac": float(mac[k])}
                                 for part, (i, f, mac) in matched.items()}
        out.append(row)
    return out


PART_MODES_TOL = 1e-6   # a match by MAC needs shapes, not eigenvalues to round-off (0.9 -> 0.5 s
#                         for pad_disc's pad, 9530 dofs, with 1e-12)


def part_modes(model, part, fmax, shift_hz=1.0):
    """The normal modes of one part alone, on its own supports (contact left out), up to fmax
    [Hz]: (frequencies, shapes on the part's free dofs, those dofs, the part's mass there)."""
    from ..model.dofs import restricted
    from ..solve.modes import normal_modes
    dofs = model.part_dofs(part)
    dofs = dofs[~model.fixed[dofs]]
    # the part's block by the package's column remapping (SciPy's fancy indexing of the whole
    # model's K and M took 0.6 s on pad_disc)
    K, M = restricted((model.K, model.M), dofs, dofs)
    modes = normal_modes(K, M, None, count=20, fmax=fmax, shift=-shift_hz, tol=PART_MODES_TOL)
    return modes.frequencies, modes.shapes, dofs, M


def matched_part_modes(model, U, parts, fmax, own=None):
    """{part: (index (k,), frequency (k,), MAC (k,))}: for each displacement U[:, j], the mode
    of each part alone that its motion on the part resembles most (the modal assurance
    criterion in the part's mass); own: {part: part_modes(model, part, fmax)} made already."""
    out = {}
    for part in parts:
        f, Phi, dofs, M = own[part] if own else part_modes(model, part, fmax)
        if Phi.shape[1] == 0:
            continue
        Up = U[dofs]
        MUp = real_times(M, Up)
        cross = np.abs(real_times(Phi.T, MUp)) ** 2
        norms = np.einsum("ij,ij->j", Phi, M @ Phi)[:, None] * np.real(
            np.einsum("ij,ij->j", Up.conj(), MUp))[None, :]
        mac = cross / np.maximum(norms, 1e-300)
        best = np.argmax(mac, axis=0)
        out[part] = (best, f[best], mac[best, np.arange(U.shape[1])])
    return out
