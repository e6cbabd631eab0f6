"""Contact laws: the one-call evaluation agrees with the pressure and potential read apart,
and p = -dPhi/dg, k_t = -dp/dg, continuous through the linear continuation."""
import numpy as np
import pytest

from transient.kernels.codes import BILATERAL, EXPONENTIAL, LINEAR
from transient.kernels.laws import potential, pressure, pressure_potential

PARAMS = {EXPONENTIAL: np.array([1e4, 5e5, -np.log(1e9 / 1e4) / 5e5, 0.0]),
          LINEAR: np.array([5e11, 0, 0, 0.0]), BILATERAL: np.array([5e11, 0, 0, 0.0])}


@pytest.mark.parametrize("code", [EXPONENTIAL, LINEAR, BILATERAL])
def test_one_pass_evaluation_matches_and_derivatives_hold(code):
    params = PARAMS[code]
    for g in np.linspace(-1e-4, 2e-5, 241):
        p, kt, phi = pressure_potential(code, params, g)
        assert (p, kt) == pytest.approx(pressure(code, params, g), rel=1e-14, abs=1e-300)
        assert phi == pytest.approx(potential(code, params, g), rel=1e-14, abs=1e-300)
        h = 1e-12
        if code == LINEAR and abs(g) < 2 * h:
            continue                    # the kink of the unilateral law
        dphi = (potential(code, params, g + h) - potential(code, params, g - h)) / (2 * h)
        assert -dphi == pytest.approx(p, rel=1e-4, abs=1e-6 * max(p, 1.0))
        dp = (pressure(code, params, g + h)[0] - pressure(code, params, g - h)[0]) / (2 * h)
        assert -dp == pytest.approx(kt, rel=1e-4, abs=1.0)
