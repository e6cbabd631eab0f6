"""Contact law parameters of a pair, packed for the kernels (kernels/laws.py evaluates them)."""
import numpy as np

from ..kernels.codes import BILATERAL, EXPONENTIAL, LINEAR

NAMES = {"exponential": EXPONENTIAL, "linear": LINEAR, "bilateral": BILATERAL}


def law_params(spec, k):
    """(code, params) of a validated [contact.NAME.law] table; k: the pair's stiffness density."""
    code = NAMES[spec.kind]
    params = np.zeros(4)
    if code == EXPONENTIAL:
        p0, lam = spec.p0, spec.lam
        # the law turns linear where the pressure reaches p_lin
        params[:3] = p0, lam, -np.log(spec.p_lin / p0) / lam
    else:
        params[0] = k
    return code, params
