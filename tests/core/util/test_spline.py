import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from core.util.spline import Cubic


@pytest.mark.parametrize("n", [2, 3, 4, 5, 17, 200])
def test_same_as_scipy_not_a_knot(n):
    rng = np.random.default_rng(n)
    x = np.cumsum(rng.uniform(0.1, 2.0, n))
    y = rng.normal(size=(n, 4))
    ours, ref = Cubic(x, y), CubicSpline(x, y, axis=0)
    t = np.linspace(x[0] - 0.1, x[-1] + 0.1, 997)
    assert np.allclose(ours(t), ref(t), atol=1e-9 * max(1, np.abs(y).max()))
    assert np.allclose(ours(t, 1), ref(t, 1), atol=1e-8 * max(1, np.abs(y).max()))


@pytest.mark.parametrize("n", [2, 3, 4, 9, 60])
def test_pchip_and_hermite_same_as_scipy(n):
    from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

    from core.util.spline import hermite, pchip

    rng = np.random.default_rng(10 + n)
    x = np.cumsum(rng.uniform(0.05, 1.5, n))
    y = np.cumsum(rng.normal(size=n))  # ups and downs, flat steps: every branch of PCHIP
    if n > 4:
        y[3] = y[2]
    t = np.linspace(x[0] - 0.3, x[-1] + 0.3, 1501)  # outside: the end pieces continue
    ours, ref = pchip(x, y), PchipInterpolator(x, y, extrapolate=True)
    np.testing.assert_allclose(ours(t), ref(t), rtol=0, atol=1e-12 * np.abs(y).max())
    np.testing.assert_allclose(ours.derivative()(t), ref.derivative()(t), rtol=0, atol=1e-11 * np.abs(y).max())
    np.testing.assert_allclose(ours.c, ref.c, rtol=1e-12, atol=1e-12)
    assert ours(1.0 * x[1]).shape == () and float(ours(x[1])) == pytest.approx(y[1], abs=1e-14)
    d = rng.normal(size=n)
    np.testing.assert_allclose(hermite(x, y, d)(t), CubicHermiteSpline(x, y, d)(t), rtol=0, atol=1e-11 * np.abs(y).max())


def test_critical_points_and_root():
    from scipy.interpolate import CubicHermiteSpline

    from core.util.spline import find_root, hermite

    rng = np.random.default_rng(5)
    x = np.linspace(0, 3, 8)
    y, d = rng.normal(size=8), rng.normal(size=8)
    ours = hermite(x, y, d).critical_points()
    ref = np.unique(CubicHermiteSpline(x, y, d).derivative().roots(extrapolate=False))
    np.testing.assert_allclose(ours, ref[np.isfinite(ref)], atol=1e-12)
    assert find_root(lambda v: v * v - 2.0, 0.0, 2.0) == pytest.approx(np.sqrt(2.0), abs=1e-15)
    assert find_root(np.cos, 0.0, 3.0, xtol=1e-12) == pytest.approx(np.pi / 2, abs=1e-12)
    with pytest.raises(ValueError, match="same sign"):
        find_root(lambda v: v * v + 1.0, -1.0, 1.0)
