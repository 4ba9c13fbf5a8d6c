import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from core.spline import Cubic


@pytest.mark.parametrize("n", [2, 3, 4, 5, 17, 200])
def test_same_as_scipy_not_a_knot(n):
    rng = np.random.default_rng(n)
    x = np.cumsum(rng.uniform(0.1, 2.0, n))
    y = rng.normal(size=(n, 4))
    ours, ref = Cubic(x, y), CubicSpline(x, y, axis=0)
    t = np.linspace(x[0] - 0.1, x[-1] + 0.1, 997)
    assert np.allclose(ours(t), ref(t), atol=1e-9 * max(1, np.abs(y).max()))
    assert np.allclose(ours(t, 1), ref(t, 1), atol=1e-8 * max(1, np.abs(y).max()))
