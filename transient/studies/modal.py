"""Two modal models of one structure compared (`transient plot modal-frf`): their modes with
the contact tied as each case says (solve.tied), each mode of the first paired with its MAC
partner in the second, the frequency shifts, and the transfer function between two sensors.

The paper's figure 11 is such a pair: a rich contact rule tied exactly against the regularized
centre rule, where the rich rule's locking raises the frequencies."""
from dataclasses import dataclass

import numpy as np

from ..contact.pair import build_contact
from ..errors import CaseError
from ..model import build_model
from ..model.band import check_modes_band
from ..solve.modes import mac_pairs, receptance
from ..solve.tied import contact_modes
from ..shared import stage_key

POINTS = 4000     # frequencies of the transfer function


@dataclass(frozen=True)
class ModalComparison:
    """Two modal models of one structure compared (`compare`), each mode of the first with
    its partner in the second."""
    frequencies: tuple     # (fa, fb) each model's frequencies [Hz]
    partner: np.ndarray    # (len(fa),) index of each mode's partner in fb (-1: none)
    mac: np.ndarray        # (len(fa),) MAC of the pair (nan when paired by order)
    shifts: np.ndarray     # (len(fa),) 100 (fb[partner] / fa - 1) [%]
    by_order: np.ndarray   # (min(len(fa), len(fb)),) 100 (fb / fa - 1) mode by mode [%], as
    #                        the paper plots them
    f: np.ndarray          # (POINTS,) frequencies of the transfer functions [Hz]
    transfer: tuple        # (Ha, Hb) [m/N]
    ties: tuple            # each model's solve.tied.Tie
    pairs: tuple           # each model's contact pairs


def sensor_row(case, model, name, key):
    """The (ndof,) observation row of a sensor, refused when the model clamps what it sees."""
    row = model.sensors[model.sensor_names.index(name)].toarray().ravel()
    if not np.any(row[model.free]):
        raise CaseError(case.path, key, f"sensor '{name}' observes clamped dofs only: no "
                        "force goes in there, and no motion comes out")
    return row


def compare(case_a, case_b, sensor_in, sensor_out, damping, fmax=None):
    """The ModalComparison of two cases of one structure: modes by their solver.modes (tie
    included), pairs by MAC when both share a model (shared.stage_key), else by order."""
    model_a = build_model(case_a)
    # one structure: the second model is the first's with its own loads and sensors
    shared = stage_key(case_a, "model") == stage_key(case_b, "model")
    model_b = build_model(case_b, model_a if shared else None)
    rows = [(sensor_row(c, m, sensor_in, "--input"), sensor_row(c, m, sensor_out, "--output"))
            for c, m in ((case_a, model_a), (case_b, model_b))]
    for case, model in ((case_a, model_a), (case_b, model_b)):
        check_modes_band(case, model)
    results = []
    for case, model in ((case_a, model_a), (case_b, model_b)):
        pairs = build_contact(case, model)
        modes, tie = contact_modes(case, model, pairs)
        results.append((modes, tie, pairs))
    (ma, tie_a, pairs_a), (mb, tie_b, pairs_b) = results
    fa, fb = ma.frequencies, mb.frequencies
    if shared:
        partner, mac = mac_pairs(ma.shapes, mb.shapes, model_a.M)
    else:
        partner = np.where(np.arange(len(fa)) < len(fb), np.arange(len(fa)), -1)
        mac = np.full(len(fa), np.nan)
    shifts = np.where(partner >= 0, 100 * (fb[partner] / fa - 1), np.nan)
    n = min(len(fa), len(fb))
    by_order = 100 * (fb[:n] / fa[:n] - 1)
    top = fmax or 1.05 * max(fa.max(initial=0.0), fb.max(initial=0.0))
    f = np.linspace(0.0, top, POINTS)
    transfer = tuple(receptance(m, a, b, f, damping) for m, (a, b) in zip((ma, mb), rows))
    return ModalComparison((fa, fb), partner, mac, shifts, by_order, f, transfer,
                           (tie_a, tie_b), (pairs_a, pairs_b))
