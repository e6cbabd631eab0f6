"""Branches of complex modes over a parameter (a mu map, a sweep's variants): each mode at one
value linked to a mode at the next, the points where a branch turns unstable as it couples, and
the table of the unstable modes at each value.

Linking. The modes at two neighbouring values are paired one to one by the assignment
(scipy.optimize.linear_sum_assignment) that minimizes the summed cost

    cost_ij = (1 - MAC_ij) + |lambda'_j - lambda_i| / max(|lambda_i|, |lambda'_j|),

MAC_ij = |x_i^H y_j|^2 / (|x_i|^2 |y_j|^2) the complex modal assurance criterion of the two
shapes (for a mode of a degenerate pair, DEGENERATE, the largest MAC a combination of the
pair's shapes reaches: the share of the other shape in their span). The MAC follows a mode
through a crossing in frequency, where sorting by frequency or
pairing the nearest eigenvalues can swap the two modes. The eigenvalue's relative move breaks the
MAC's ties: two modes that couple have one shape at the coupling point (their MAC tends to 1 as
the second power of their eigenvalues' distance, while the distance falls only as its first),
so there the MAC cannot tell the branches apart and the continuity of the eigenvalue does,
which keeps the growing member of a flutter pair on one branch and the decaying member on the
other. A pair whose MAC is below MAC_LINK is not linked: the branch ends there and the mode at
the next value starts a branch of its own (a mode that left the band, another that entered).
Without shapes (a sweep written before they were stored) the modes are linked by the
eigenvalue alone, and crossings in frequency may be swapped.

Shapes. The complex modes of each value live in their own reduced basis, so they are compared
on the model's dofs: at SAMPLE_NODES nodes drawn once from the model's free nodes (seeded, the
same nodes at every value of one model). A mode below fmax is smooth on a mesh that resolves
it, so a few hundred nodes scattered over the parts tell its shape from the others' as all
the nodes would, at a fraction of the product X (A z) on every dof.

Coupling points. A branch turns unstable (or stable again) between two values where its real
part crosses the growth an unstable mode exceeds (ComplexModes.unstable). Its partner is the
branch it has coupled with: of those whose real part moves the other way over the interval,
the nearest in frequency, if their eigenvalues have met (their real parts differ by more than
their frequencies: Re (lambda_a - lambda_b)^2 > 0); None for a mode that grows alone. The
value is interpolated where the pair meets when it meets in that interval (an undamped pair,
which turns unstable as it couples): at the zero of Re (lambda_a - lambda_b)^2, negative while
their frequencies differ and positive once their real parts split, and smooth in the
parameter through the coalescence where each eigenvalue is not (the growth rises as the square
root of mu - mu_c, which no straight line through two values follows), with the frequency of
the pair's mean eigenvalue (smooth there too). Else (a damped pair, whose real part crosses
smoothly after the coupling; a mode alone) it is where the real part crosses, linearly.
"""
import base64
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..io.tables import write_csv
from ..solve.mac import mac
from .modes import UNSTABLE_RTOL

MAC_LINK = 0.5          # a mode resembling the one at the previous value less is another mode
# modes whose eigenvalues differ by less than this fraction of |lambda| are one degenerate
# pair (a disc's doublet, split only by the pad and the mesh): any combination of their shapes
# is a mode, and the solver's choice among them is arbitrary
DEGENERATE = 1e-3
SAMPLE_NODES = 300      # nodes the shapes are compared at (three dofs each)
SAMPLE_SEED = 0


@dataclass(frozen=True)
class Step:
    """The complex modes at one value of the parameter."""
    value: float
    eigenvalues: np.ndarray     # (n,) lambda [1/s], imaginary part >= 0
    unstable: np.ndarray        # (n,) bool
    threshold: float = 0.0      # [1/s] the growth an unstable mode exceeds (cea.threshold)
    shapes: np.ndarray = None   # (p, n) complex, the modes at dofs, or None
    dofs: np.ndarray = None     # (p,) the model's dofs the shapes are taken at

    @property
    def floor(self):
        """(n,) the real part above which each mode is unstable (ComplexModes.unstable)."""
        return np.maximum(UNSTABLE_RTOL * np.abs(self.eigenvalues), self.threshold)


@dataclass(frozen=True)
class Branches:
    """Complex modes at ordered values of a parameter, linked into branches.

    ``values`` (K,) the parameter's values, ascending; ``steps`` the modes at each; ``branch``
    the branch id of each mode at each value (``branch[k][j]``: mode j at value k), ids from 0
    in order of appearance; ``mac`` each mode's MAC with the mode it continues at the previous
    value (a degenerate pair's: the span's; NaN where a branch starts, or without shapes);
    ``linked_by`` ``"shapes"`` or ``"eigenvalues"`` (some value had no shapes, or shapes on
    other dofs); ``coupling`` one
    dict per point where a branch turns unstable or stable again (``branch``, ``partner``:
    the branch it couples with, or None; the parameter's value and ``frequency_hz`` there;
    ``becomes``: ``"unstable"`` or ``"stable"``); ``unstable_modes()`` the table of the
    unstable modes at each value; ``parameter`` the values' name (the tables' column).
    """
    parameter: str
    values: np.ndarray
    steps: tuple
    branch: tuple
    mac: tuple
    linked_by: str
    coupling: list

    @property
    def count(self):
        """How many branches."""
        return 1 + max((int(b.max()) for b in self.branch if len(b)), default=-1)

    def line(self, b):
        """(values, eigenvalues, unstable) of branch b, in order of the values."""
        found = [(s.value, s.eigenvalues[j], s.unstable[j]) for s, ids in zip(self.steps,
                 self.branch) for j in np.flatnonzero(ids == b)]
        values, lam, bad = zip(*found) if found else ((), (), ())
        return np.array(values, float), np.array(lam, complex), np.array(bad, bool)

    def unstable_modes(self):
        """One dict per unstable mode at each value, by value then frequency: the parameter's
        value (keyed by ``parameter``), ``branch``, ``frequency_hz`` [Hz], ``real`` [1/s] and
        ``damping_ratio`` (-real / |lambda|)."""
        rows = []
        for s, ids in zip(self.steps, self.branch):
            for j in np.flatnonzero(s.unstable):
                lam = s.eigenvalues[j]
                rows.append({self.parameter: float(s.value), "branch": int(ids[j]),
                             "frequency_hz": float(lam.imag / (2 * np.pi)),
                             "real": float(lam.real),
                             "damping_ratio": float(-lam.real / max(abs(lam), 1e-300))})
        return rows

    def write(self, unstable_path, coupling_path):
        """The table of unstable modes and the coupling points as CSV files; their paths."""
        write_csv(unstable_path, [self.parameter, "branch", "frequency_hz", "real",
                                   "damping_ratio"], self.unstable_modes())
        write_csv(coupling_path, ["branch", "partner", self.parameter, "frequency_hz",
                                   "becomes"], self.coupling)
        return [unstable_path, coupling_path]


def _alike(a, b):
    """(n, m) MAC of the modes at Step a with those at Step b, a mode of a degenerate pair
    (DEGENERATE) taken as the span of the pair: the largest MAC a combination of its shapes
    reaches (the share of the other shape in that span), whichever side is degenerate."""
    return np.maximum(_span_mac(a.eigenvalues, a.shapes, b.shapes),
                      _span_mac(b.eigenvalues, b.shapes, a.shapes).T)


def _span_mac(lam, X, Y):
    """(n, m) the share of each column of Y in the span of the columns of X whose eigenvalues
    (lam) lie within DEGENERATE of each one's: its MAC with that column alone if none."""
    out = mac(X, Y)
    close = np.abs(lam[:, None] - lam[None, :]) <= DEGENERATE * np.abs(lam)[:, None]
    norms = np.real(np.einsum("ij,ij->j", Y.conj(), Y))
    for i in np.flatnonzero(close.sum(axis=1) > 1):
        Q = np.linalg.qr(X[:, close[i]])[0]
        share = np.sum(np.abs(Q.conj().T @ Y) ** 2, axis=0)
        out[i] = np.where(norms > 0, share / np.where(norms > 0, norms, 1.0), 0.0)
    return out


def track(parameter, steps):
    """Branches of the complex modes at each Step (ordered by value on return)."""
    from scipy.optimize import linear_sum_assignment
    steps = tuple(sorted(steps, key=lambda s: s.value))
    by_shapes = all(s.shapes is not None for s in steps) and all(
        np.array_equal(s.dofs, steps[0].dofs) for s in steps)
    first = len(steps[0].eigenvalues) if steps else 0
    branch, links = [np.arange(first)], [np.full(first, np.nan)]
    count = first
    for a, b in zip(steps[:-1], steps[1:]):
        la, lb = a.eigenvalues, b.eigenvalues
        move = np.abs(lb[None, :] - la[:, None]) / np.maximum(
            np.maximum(np.abs(la)[:, None], np.abs(lb)[None, :]), 1e-300)
        alike = _alike(a, b) if by_shapes else np.ones(move.shape)
        rows, cols = linear_sum_assignment(1.0 - alike + move)
        ids, link = np.full(len(lb), -1), np.full(len(lb), np.nan)
        for i, j in zip(rows, cols):
            if alike[i, j] >= MAC_LINK:
                ids[j], link[j] = branch[-1][i], alike[i, j] if by_shapes else np.nan
        new = np.flatnonzero(ids < 0)
        ids[new] = count + np.arange(len(new))
        count += len(new)
        branch.append(ids)
        links.append(link)
    return Branches(parameter, np.array([s.value for s in steps], float), steps, tuple(branch),
                    tuple(links), "shapes" if by_shapes else "eigenvalues",
                    _coupling(parameter, steps, branch))


def _coupling(parameter, steps, branch):
    """The points where a branch turns unstable or stable between two values (by value, then
    frequency)."""
    points = []
    for k, (a, b) in enumerate(zip(steps[:-1], steps[1:])):
        at = {int(i): j for j, i in enumerate(branch[k])}
        after = np.array([j for j, i in enumerate(branch[k + 1]) if int(i) in at], int)
        before = np.array([at[int(branch[k + 1][j])] for j in after], int)
        lam0, lam1 = a.eigenvalues[before], b.eigenvalues[after]
        floor0, floor1 = a.floor[before], b.floor[after]
        for m in np.flatnonzero(a.unstable[before] != b.unstable[after]):
            n = _partner(lam0, lam1, m)
            t = None if n is None else _at_coupling(lam0[[m, n]], lam1[[m, n]], floor0[m],
                                                    floor1[m])
            if t is not None:
                omega = 0.5 * ((1 - t) * (lam0[m] + lam0[n]) + t * (lam1[m] + lam1[n])).imag
            else:
                g0, g1 = lam0[m].real - floor0[m], lam1[m].real - floor1[m]
                t = g0 / (g0 - g1)
                omega = ((1 - t) * lam0[m] + t * lam1[m]).imag
            points.append({"branch": int(branch[k + 1][after[m]]),
                           "partner": None if n is None else int(branch[k + 1][after[n]]),
                           parameter: float(a.value + t * (b.value - a.value)),
                           "frequency_hz": float(omega / (2 * np.pi)),
                           "becomes": "unstable" if b.unstable[after[m]] else "stable"})
    return sorted(points, key=lambda p: (p[parameter], p["frequency_hz"]))


def _at_coupling(pair0, pair1, floor0, floor1):
    """Where in [0, 1] (the interval's fraction) the first mode of a pair crosses its floor
    (floor0 at the start, floor1 at the end) as the pair meets or parts (eigenvalues pair0 at
    the start, pair1 at the end); None if the pair does not meet or part in the interval, or
    the mode crosses on the side where the two are apart. Meeting at the zero t_m of Re
    (lambda_a - lambda_b)^2 (linear), the mode's real part leaves the pair's mean (linear) as
    the square root of the distance from t_m, to its value at the end: a coalescence's
    law."""
    d0, d1 = ((pair0[0] - pair0[1]) ** 2).real, ((pair1[0] - pair1[1]) ** 2).real
    if not d0 * d1 < 0:
        return None
    t_m = d0 / (d0 - d1)
    apart, end = (1.0, pair1) if d1 > 0 else (0.0, pair0)
    excess = end[0].real - end.real.mean()
    mean0, mean1 = pair0.real.mean(), pair1.real.mean()

    def above(t):
        """The mode's real part less its floor at t."""
        mean = (1 - t) * mean0 + t * mean1
        grown = np.sqrt(max((t - t_m) / (apart - t_m), 0.0))
        return mean + excess * grown - ((1 - t) * floor0 + t * floor1)
    lo, hi = sorted((t_m, apart))
    if (above(lo) > 0) == (above(hi) > 0):
        return None
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (above(mid) > 0) == (above(lo) > 0):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _partner(lam0, lam1, m):
    """The mode (index) mode m couples with at the second value (lam0, lam1: the modes present
    at both, in one order): of those whose real part moves the other way, the nearest in
    frequency, if their real parts differ more than their frequencies there (Re (lambda_m -
    lambda_n)^2 > 0: their eigenvalues have met); None if none."""
    rise = lam1.real - lam0.real
    other = np.flatnonzero(rise * rise[m] < 0)
    if not len(other):
        return None
    n = other[np.argmin(np.abs(lam1.imag[other] - lam1.imag[m]))]
    return int(n) if ((lam1[m] - lam1[n]) ** 2).real > 0 else None


def sample_dofs(model):
    """The dofs of SAMPLE_NODES nodes drawn (seeded) from those with a free dof, ascending."""
    nodes = np.flatnonzero(~model.fixed.reshape(-1, 3).all(axis=1))
    if len(nodes) > SAMPLE_NODES:
        nodes = np.sort(np.random.default_rng(SAMPLE_SEED).choice(nodes, SAMPLE_NODES,
                                                                   replace=False))
    return (3 * nodes[:, None] + np.arange(3)).ravel()


def observed(analysis, dofs=None):
    """(dofs, shapes (p, n)): an Analysis's complex modes on the model's dofs (sample_dofs
    by default), from its basis (X, A): the rows of X at those dofs only."""
    if dofs is None:
        dofs = sample_dofs(analysis.model)
    X, A = analysis.basis
    pick = sp.csr_matrix((np.ones(len(dofs)), (np.arange(len(dofs)), dofs)),
                         shape=(len(dofs), X.shape[0]))
    # X's rows kept sparse where X is (the full model's injection of its free dofs: dense,
    # they would be the size of the model times the sample)
    return dofs, np.asarray((pick @ X) @ (A @ analysis.modes.vectors))


def step_of(value, analysis):
    """The Step of an Analysis (stability.stage) at a value."""
    modes = analysis.modes
    dofs, shapes = observed(analysis)
    return Step(float(value), modes.eigenvalues, modes.unstable, modes.threshold, shapes, dofs)


def shapes_record(dofs, shapes):
    """A JSON-ready record of shapes at dofs (a sweep's modes file): the dofs and the shapes
    as base64 of little-endian complex64, row-major (p, n)."""
    data = np.ascontiguousarray(shapes, dtype="<c8")
    return {"dofs": [int(d) for d in dofs], "shape": list(data.shape),
            "complex64": base64.b64encode(data.tobytes()).decode("ascii")}


def read_shapes(record):
    """(dofs, shapes) of a shapes_record."""
    data = np.frombuffer(base64.b64decode(record["complex64"]), dtype="<c8")
    return (np.asarray(record["dofs"], int),
            data.reshape(record["shape"]).astype(complex))
