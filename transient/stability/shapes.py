"""What a complex mode looks like on a brake: the rotating part's motion and nodal diameters
(stability.diameters), the share of the motion each part carries, and which elastic mode of
each other part alone (the pad on its abutments) its motion there resembles: which disc mode
and which pad mode couple."""
import numpy as np

from ..solve.lowrank import block_columns
from ..solve.mac import mac
from ..solve.realmaps import real_times
from .diameters import disc_motion
from .rigid import RIGID_RTOL


def part_shares(model, M, U):
    """[{part: share of the mode's kinetic energy u^H M u}] for each column u of U (ndof, k)."""
    energy = np.real(U.conj() * real_times(M, U))
    total = np.maximum(energy.sum(axis=0), 1e-300)
    parts = {name: energy[model.part_dofs(name)].sum(axis=0) / total for name in model.parts}
    return [{name: float(share[k]) for name, share in parts.items()} for k in range(U.shape[1])]


def still_parts(case, model):
    """The parts no rotation turns (the pad): those whose own modes describe a mode."""
    turned = {m.part for m in case.motion.values() if m.kind == "rotation"}
    return [p for p in model.parts if p not in turned]


def describe(case, model, basis, modes, which, fmax, own=None):
    """One dict per mode index in which: frequency, real part, damping ratio, whether it is
    unstable, the parts' energy shares, the rotating parts' motion and nodal diameters
    (diameters.disc_motion) and the still parts' elastic modes it resembles. basis: (X, A),
    the modes' coordinates z are X (A z) on the model's dofs. The still parts' own modes up
    to fmax [Hz], or own: {part: part_modes(model, part, fmax)} made already."""
    # the parts that do not turn (the pad): which of their own modes the motion resembles
    still = still_parts(case, model)
    if own is None and len(which):
        own = {part: part_modes(model, part, fmax) for part in still}
    # a block of modes at a time: each mode's descriptors are its own, and the modes'
    # complex fields side by side would be the model's size times the modes
    width = block_columns(model.ndof)
    return [row for start in range(0, len(which), width)
            for row in _described(case, model, basis, modes, which[start:start + width],
                                  still, fmax, own)]


def _described(case, model, basis, modes, which, still, fmax, own):
    X, A = basis
    U = real_times(X, A @ modes.vectors[:, which])
    rotations = {m.part: disc_motion(model, m, U)
                 for m in case.motion.values() if m.kind == "rotation"}
    matched = matched_part_modes(model, U, still, fmax, own) if len(which) else {}
    out = []
    shares = part_shares(model, model.M, U)
    for k, j in enumerate(which):
        row = {"mode": int(j + 1), "frequency_hz": float(modes.frequency_hz[j]),
               "real": float(modes.real[j]), "damping_ratio": float(modes.damping_ratio[j]),
               "unstable": bool(modes.unstable[j]), "shares": shares[k]}
        if rotations:
            row["nodal_diameters"] = {part: found[k] for part, found in rotations.items()}
        if matched:
            row["part_modes"] = {part: {"mode": int(i[k] + 1), "frequency_hz": float(f[k]),
                                        "mac": float(alike[k])}
                                 for part, (i, f, alike) in matched.items()}
        out.append(row)
    return out


PART_MODES_TOL = 1e-6   # a match by MAC needs shapes, not eigenvalues to round-off (0.9 -> 0.5 s
#                         for pad_disc's pad, 9530 dofs, with 1e-12)


def part_modes(model, part, fmax, shift_hz=1.0):
    """The normal modes of one part alone, on its own supports (contact left out), up to fmax
    [Hz]: (frequencies, shapes on the part's free dofs, those dofs, the part's mass there), its
    rigid modes (a pad free along the axis between its abutments) among them."""
    from ..model.dofs import restricted
    from ..solve.modes import normal_modes
    dofs = model.part_dofs(part)
    dofs = dofs[~model.fixed[dofs]]
    # the part's block by the package's column remapping (SciPy's fancy indexing of the whole
    # model's K and M took 0.6 s on pad_disc)
    K, M = restricted((model.K, model.M), dofs, dofs)
    modes = normal_modes(K, M, None, count=20, fmax=fmax, shift=-shift_hz, tol=PART_MODES_TOL)
    return modes.frequencies, modes.shapes, dofs, M


def elastic(frequencies, stiffness, mass):
    """The modes of these frequencies [Hz] that strain a part of diagonal stiffness and mass
    (its K_ii and M_ii): omega^2 above RIGID_RTOL of max K_ii / M_ii (at most the largest
    eigenvalue), where a rigid mode's sits at the eigensolver's round-off (1e-3 Hz on the small
    pad_disc's pad, whose first elastic mode is at 2.5 kHz; the bound 0.3 Hz)."""
    ratio = np.max(stiffness / np.maximum(mass, 1e-300))
    return (2 * np.pi * np.asarray(frequencies)) ** 2 > RIGID_RTOL * ratio


def matched_part_modes(model, U, parts, fmax, own=None):
    """{part: (index (k,), frequency (k,), MAC (k,))}: for each displacement U[:, j], the
    elastic mode of each part alone that its motion on the part resembles most (the modal
    assurance criterion in the part's mass), indexed among all the part's modes, rigid ones
    first; own: {part: part_modes(model, part, fmax)} made already. A rigid mode is never the
    match: the part's motion in a mode of the assembly carries rigid motion (the pad riding on
    the disc's contact stiffness) that says nothing of which of its modes couples."""
    out = {}
    stiffness = model.K.diagonal()
    for part in parts:
        f, Phi, dofs, M = own[part] if own else part_modes(model, part, fmax)
        keep = np.flatnonzero(elastic(f, stiffness[dofs], M.diagonal()))
        f, Phi = f[keep], Phi[:, keep]
        if Phi.shape[1] == 0:
            continue
        alike = mac(Phi, U[dofs], M)
        best = np.argmax(alike, axis=0)
        out[part] = (keep[best], f[best], alike[best, np.arange(U.shape[1])])
    return out
