"""The band a mesh resolves: its frequencies lie below a bound known from K and the lumped mass
in one pass over K (Gershgorin), so a frequency key beyond it is refused before an eigensolver
looks for modes that do not exist (every mode of the model, or an overflow of (2 pi f)^2)."""
import numpy as np

from ..errors import CaseError

# the consistent mass's highest frequency is at most sqrt(27) times the lumped one on hex8
# (M_c >= M_l / 27), and was 0.75-1.7 times the lumped Gershgorin bound on hex8, hex20, tet4,
# tet10, wedge6 and wedge15 bars
MARGIN = 6.0
ROWS = 100_000          # rows of K per pass: |K| is never copied whole


def highest_hz(model):
    """An upper bound [Hz] of every natural frequency of the model's mesh (MARGIN times
    max_i sqrt(sum_j |K_ij| / m_i) / 2 pi over its free dofs)."""
    K, free = model.K.tocsr(), ~model.fixed
    top = 0.0
    for start in range(0, K.shape[0], ROWS):
        indptr = K.indptr[start:start + ROWS + 1]
        # (a zero after the data: reduceat takes an index at its end for a trailing empty row)
        data = np.append(np.abs(K.data[indptr[0]:indptr[-1]]), 0.0)
        rows = np.where(np.diff(indptr) > 0, np.add.reduceat(data, indptr[:-1] - indptr[0]),
                        0.0)
        mass = model.lumped_mass[start:start + ROWS]
        held = free[start:start + ROWS] & (mass > 0)
        if held.any():
            top = max(top, float(np.max(rows[held] / mass[held])))
    return MARGIN * np.sqrt(top) / (2 * np.pi)


def check_band(case, model, keys):
    """CaseError naming the first of keys ((key, frequency [Hz]) pairs) whose frequency's
    magnitude is above every mode of the mesh."""
    keys = [(key, f) for key, f in keys if f]
    if not keys:
        return
    top = highest_hz(model)
    for key, f in keys:
        if abs(f) > top:
            raise CaseError(case.path, key, f"{f:g} Hz is beyond every mode of the mesh (they "
                            f"lie below {top:.3g} Hz, a bound from its stiffness and mass): "
                            "expected at most that")


def check_modes_band(case, model):
    """check_band on the keys of `transient modes` (solver.modes)."""
    check_band(case, model, [("solver.modes.fmax", case.solver.modes.fmax),
                             ("solver.modes.shift", case.solver.modes.shift)])
