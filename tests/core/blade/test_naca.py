"""Section forms against published ordinates.

Tables: OpenProp (joaoantoniocardoso/OpenProp, SourceCode/GeometryFoil2D.m) for NACA 66 (DTRC
modified) thickness (Brockett 1966), NACA 65A010 thickness and the NACA a=0.8 mean lines; Abbott &
von Doenhoff (Theory of Wing Sections, appendix) for NACA 0012."""

import numpy as np
import pytest

from core.blade import naca
from core.errors import BladeInputError

# NACA 66 (DTRC modified), t/t0 (Brockett 1966 as tabulated in OpenProp)
NACA66 = {0.0: 0.0, 0.0125: 0.2088, 0.05: 0.4132, 0.1: 0.5814, 0.3: 0.9274, 0.45: 1.0, 0.5: 0.9924,
          0.7: 0.8070, 0.9: 0.3754, 0.95: 0.2286, 1.0: 0.0666}
# NACA a=0.8 f/f0 table ("v2" in OpenProp), normalised at x = 0.5, rounded to 1e-4
A08_X = [0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.45, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95]
A08_F = [0.0907, 0.1586, 0.2712, 0.3657, 0.4482, 0.5869, 0.6993, 0.8635, 0.9615, 0.9881, 1.0,
         0.9786, 0.8892, 0.7027, 0.3586, 0.1713]
# d(f/f0)/dx of eq. 4.26 at those stations as printed in OpenProp (normalised by the true max f)
A08_DF = [5.9401, 5.0195, 4.0795, 3.5128, 3.0982, 2.4861, 2.0214, 1.2915, 0.6771, 0.3846, 0.0913,
          -0.5315, -1.2937, -2.7092, -3.7653, -3.6654]
# NACA 0012, y/c in percent (Abbott & von Doenhoff)
NACA0012 = {0.0125: 1.894, 0.1: 4.683, 0.3: 6.002, 0.5: 5.294, 0.9: 1.448, 1.0: 0.126}


def test_naca66_mod_reproduces_every_tabulated_ordinate():
    t = naca.thickness("NACA 66 mod", naca.NACA66_X)
    np.testing.assert_allclose(t, naca.NACA66_T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("x, t", NACA66.items())
def test_naca66_mod_published_ordinates(x, t):
    assert naca.thickness("NACA 66 mod", np.array([x]))[0] == pytest.approx(t, abs=1e-12)


@pytest.mark.parametrize("form, x_max", [("NACA 66 mod", 0.45), ("NACA 65A010", 0.40),
                                         ("NACA 00xx", 0.2998), ("elliptic", 0.5),
                                         ("parabolic", 0.5)])
def test_thickness_max_is_one_at_the_right_station(form, x_max):
    x = np.linspace(0, 1, 200001)
    t = naca.thickness(form, x)
    assert t.max() == pytest.approx(1.0, abs=1e-6)
    assert x[np.argmax(t)] == pytest.approx(x_max, abs=2e-4)
    assert t[0] == 0.0 and np.all(t >= 0) and np.all(np.isfinite(t))


def test_naca66_interpolant_is_smooth_and_unimodal():
    x = np.linspace(0, 1, 20001)
    t = naca.thickness("NACA 66 mod", x)
    d = np.diff(t)
    assert np.all(d[x[1:] <= 0.45] > 0) and np.all(d[x[:-1] >= 0.45] < 0)


@pytest.mark.parametrize("form", ["NACA 66 mod", "NACA 65A010", "NACA 00xx", "elliptic"])
def test_rounded_nose_thickness_goes_like_sqrt_x(form):
    t = naca.thickness(form, np.array([1e-7, 4e-7]))
    assert t[1] / t[0] == pytest.approx(2.0, rel=0.01)


def test_naca65a010_ordinates():
    t = naca.thickness("NACA 65A010", np.array([0.0125, 0.1, 0.4, 0.9, 1.0]))
    np.testing.assert_allclose(t, np.array([1.183, 3.04, 4.995, 1.188, 0.021]) / 4.995, atol=1e-12)


@pytest.mark.parametrize("x, y", NACA0012.items())
def test_naca00xx_against_published_naca0012(x, y):
    # 0012: t0/c = 0.12, y = t/2; the formula's own max is 1.00029 x 0.12 / 2, within the rounding
    assert naca.thickness("NACA 00xx", np.array([x]))[0] == pytest.approx(y / 6.0, abs=5e-4)


def test_a08_analytic_matches_the_table():
    x = np.array(A08_X)
    f, _ = naca.meanline("NACA a=0.8", x)
    # the table is normalised at x = 0.5: same shape within its 1e-4 rounding
    f_at_half = naca.meanline("NACA a=0.8", np.array([0.5]))[0][0]
    np.testing.assert_allclose(f / f_at_half, A08_F, rtol=0, atol=1.2e-4)
    # normalised to the true max (ours) the ordinates are 0.07 % lower
    assert f_at_half == pytest.approx(0.99930, abs=1e-5)
    np.testing.assert_allclose(f, A08_F, rtol=0, atol=1e-3)


@pytest.mark.parametrize("x, f", [(0.1, 0.4482), (0.5, 1.0), (0.8, 0.7027)])
def test_a08_published_ordinates(x, f):
    assert naca.meanline("NACA a=0.8", np.array([x]))[0][0] == pytest.approx(f, abs=1e-3)


def test_a08_slope_matches_openprop_values():
    _, df = naca.meanline("NACA a=0.8", np.array(A08_X))
    np.testing.assert_allclose(df, A08_DF, rtol=0, atol=1e-3)


def test_a08_max_location_and_value():
    # OpenProp: max(F) == 0.067943423879 at x/c == 0.5153285 (c_li = 1)
    assert naca.A08_XMAX == pytest.approx(0.5153285, abs=1e-6)
    assert naca.A08_F0 == pytest.approx(0.067943423879, abs=1e-10)
    f, df = naca.meanline("NACA a=0.8", np.array([naca.A08_XMAX]))
    assert f[0] == pytest.approx(1.0, abs=1e-12) and df[0] == pytest.approx(0.0, abs=1e-9)


def test_a08_modified_reproduces_the_table_up_to_its_true_max():
    x = naca._X26
    f, df = naca.meanline("NACA a=0.8 (modified)", x)
    scale = naca.A08MOD_F0 / 0.06651
    assert scale == pytest.approx(1.0, abs=1e-3)
    np.testing.assert_allclose(f * scale, naca.A08MOD_FOC / 6.651, rtol=0, atol=1e-12)
    np.testing.assert_allclose(df * naca.A08MOD_F0, naca.A08MOD_DFDX, rtol=0, atol=1e-12)
    for xs, fs in [(0.1, 2.981), (0.5, 6.651), (0.8, 4.673)]:
        assert naca.meanline("NACA a=0.8 (modified)", np.array([xs]))[0][0] == pytest.approx(
            fs / 6.651, abs=1e-3)


@pytest.mark.parametrize("form", naca.MEANLINE_FORMS)
def test_meanline_max_ends_and_finite_slope(form):
    x = np.linspace(0, 1, 200001)
    f, df = naca.meanline(form, x)
    assert f.max() == pytest.approx(1.0, abs=1e-6)
    assert f[0] == 0.0 and abs(f[-1]) < 1e-12
    assert np.all(np.isfinite(df)) and f.shape == df.shape == x.shape
    d = np.diff(f)  # one hump: rises to the max, then falls
    i = np.argmax(f)
    assert np.all(d[: i - 1] > 0) and np.all(d[i + 1:] < 0)


@pytest.mark.parametrize("form", naca.MEANLINE_FORMS)
def test_meanline_slope_against_numerical_derivative(form):
    x = np.linspace(0.002, 0.998, 997) + 1.37e-4  # off the table knots (C1 there, not C2)
    h = 1e-6
    num = (naca.meanline(form, x + h)[0] - naca.meanline(form, x - h)[0]) / (2 * h)
    np.testing.assert_allclose(naca.meanline(form, x)[1], num, rtol=1e-5, atol=1e-5)


def test_a08_le_slope_is_clipped_finite():
    _, df = naca.meanline("NACA a=0.8", np.array([0.0, 1e-12, 1.0]))
    assert np.all(np.isfinite(df)) and df[0] == df[1] > 20
    assert df[2] == pytest.approx(-3.0003, abs=1e-3)


def test_vectorised_shapes_and_clipping():
    x = np.linspace(0, 1, 12).reshape(3, 4)
    assert naca.thickness("NACA 66 mod", x).shape == (3, 4)
    f, df = naca.meanline("NACA a=0.8", x)
    assert f.shape == df.shape == (3, 4)
    assert naca.thickness("NACA 66 mod", np.array([-0.1, 1.1])).tolist() == pytest.approx([0.0, 0.0666], abs=1e-15)


def test_names_are_forgiving():
    assert naca.thickness("  naca 66   MOD ", np.array([0.3]))[0] == pytest.approx(0.9274)
    assert naca.thickness("NACA66 (DTRC Modified)", np.array([0.3]))[0] == pytest.approx(0.9274)
    assert naca.meanline("naca A=0.8", np.array([0.5]))[0][0] == pytest.approx(0.9993, abs=1e-4)
    assert "NACA 66 mod" in naca.THICKNESS_FORMS and "NACA a=0.8" in naca.MEANLINE_FORMS


@pytest.mark.parametrize("func, name, forms", [(naca.thickness, "NACA 16", naca.THICKNESS_FORMS),
                                               (naca.meanline, "NACA a=1.0", naca.MEANLINE_FORMS),
                                               (naca.thickness, None, naca.THICKNESS_FORMS)])
def test_unknown_form_raises_and_lists_accepted(func, name, forms):
    with pytest.raises(BladeInputError) as info:
        func(name, np.array([0.3]))
    msg = str(info.value)
    assert repr(name) in msg and all(repr(f) in msg for f in forms)
