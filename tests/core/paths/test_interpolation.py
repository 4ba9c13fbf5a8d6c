"""Double-curve interpolation: exact arc length, equal steps, the y-parametrisation and its fallback."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from core.errors import PlanningError
from core.paths.interpolation import double_curve_interpolation, equidistant_params, fit_curve


def wavy(n=40, amp=3.0):
    y = np.linspace(-50, 60, n)
    return np.column_stack([100 + amp * np.sin(y / 9), y, 0.02 * y**2 / 10 + np.cos(y / 13)])


def test_y_parametrisation_used_for_monotonic_paths():
    c = fit_curve(wavy())
    assert c.mode == "y"
    # y = t exactly, x = f(y), z = g(y)
    t = np.linspace(c.t[0], c.t[-1], 17)
    assert np.allclose(c.point(t)[:, 1], t)


def test_fallback_for_non_monotonic_y():
    th = np.linspace(0, 1.5 * np.pi, 60)
    pts = np.column_stack([np.cos(th) * 20, np.sin(th) * 20, th])
    assert fit_curve(pts).mode == "arc"


@pytest.mark.parametrize("pts", [wavy(), wavy(25, 8.0)])
def test_arc_length_matches_quadrature_of_the_spline(pts):
    c = fit_curve(pts)

    def speed(t):
        d = c.spline(np.array([t]), 1)[0, :3]
        return float(np.sqrt(d @ d))

    # independent: adaptive quadrature over the whole curve, knot by knot
    total = sum(quad(speed, a, b, epsabs=1e-13, epsrel=1e-13)[0] for a, b in zip(c.t[:-1], c.t[1:]))
    assert c.length == pytest.approx(total, abs=1e-6)
    t_mid = 0.37 * c.t[0] + 0.63 * c.t[-1]
    part = sum(quad(speed, a, min(b, t_mid), epsabs=1e-13)[0] for a, b in zip(c.t[:-1], c.t[1:]) if a < t_mid)
    assert float(c.arc_length(np.array([t_mid]))[0]) == pytest.approx(part, abs=1e-6)


def test_param_at_inverts_arc_length():
    c = fit_curve(wavy())
    s = np.linspace(0, c.length, 333)
    t = c.param_at(s)
    assert np.abs(c.arc_length(t) - s).max() < 1e-6


@settings(max_examples=25, deadline=None)
@given(dd=st.floats(0.05, 2.0), amp=st.floats(0.0, 10.0))
def test_equal_spacing(dd, amp):
    c = fit_curve(wavy(50, amp))
    t, s = equidistant_params(c, dd)
    step = np.diff(s)
    assert np.allclose(step, step[0]) and step[0] <= dd + 1e-12
    if c.length > 100 * dd:
        assert step[0] == pytest.approx(dd, rel=0.01)
    # straight-line distance of neighbours ~ the arc step (curvature is small at this scale)
    chord = np.linalg.norm(np.diff(c.point(t), axis=0), axis=1)
    assert np.all(chord <= step + 1e-8) and np.all(chord > 0.98 * step)


def test_double_curve_orientation_from_tips_and_tails():
    tips = wavy()
    normal = np.column_stack([np.zeros(len(tips)), np.zeros(len(tips)), np.ones(len(tips))])
    tails = tips + 40.0 * normal
    res = double_curve_interpolation(tips, tails, 0.5)
    assert np.allclose(np.linalg.norm(res.axes, axis=1), 1.0)
    assert np.allclose(res.axes, [0, 0, 1], atol=1e-9)
    assert len(res.tips) == int(np.ceil(fit_curve(tips).length / 0.5)) + 1


def test_bad_step():
    with pytest.raises(PlanningError, match="dd"):
        equidistant_params(fit_curve(wavy()), 0.0)
