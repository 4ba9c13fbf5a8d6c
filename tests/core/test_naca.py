"""Section forms against their published ordinates (OpenProp's tables of Brockett 1966 and the
NACA a=0.8 mean line)."""

import numpy as np
import pytest

from core import naca
from core.errors import BladeInputError

# NACA 66 (DTRC modified) t/t0, Brockett (1966) as tabulated in OpenProp
PUBLISHED_T = {0.0125: 0.2088, 0.1: 0.5814, 0.3: 0.9274, 0.45: 1.0, 0.7: 0.8070, 0.9: 0.3754, 1.0: 0.0666}
# NACA a=0.8 f/f0 (tabulated, rounded to 1e-4; normalised at x = 0.5)
PUBLISHED_F = {0.0125: 0.0907, 0.1: 0.4482, 0.3: 0.8635, 0.5: 1.0, 0.8: 0.7027, 0.95: 0.1713}


@pytest.mark.parametrize("x, t", PUBLISHED_T.items())
def test_naca66_mod_ordinates(x, t):
    assert naca.thickness("NACA 66 mod", np.array([x]))[0] == pytest.approx(t, abs=1e-12)


def test_naca66_max_and_nose():
    x = np.linspace(0, 1, 200001)
    t = naca.thickness("NACA 66 mod", x)
    assert t.max() == pytest.approx(1.0, abs=1e-6) and x[np.argmax(t)] == pytest.approx(0.45, abs=1e-3)
    # rounded nose: t ~ sqrt(x) near the LE
    small = np.array([1e-6, 4e-6])
    ts = naca.thickness("NACA 66 mod", small)
    assert ts[1] / ts[0] == pytest.approx(2.0, rel=0.02)


@pytest.mark.parametrize("x, f", PUBLISHED_F.items())
def test_a08_meanline_against_table(x, f):
    # analytic mean line, normalised to its true maximum (the table normalises at x = 0.5, 0.07 % lower)
    assert naca.meanline("NACA a=0.8", np.array([x]))[0][0] == pytest.approx(f, abs=1e-3)


def test_a08_max_and_slope():
    x = np.linspace(0.001, 0.999, 9981)
    f, df = naca.meanline("NACA a=0.8", x)
    assert f.max() == pytest.approx(1.0, abs=1e-8)
    num = np.gradient(f, x)
    assert np.allclose(df[5:-5], num[5:-5], rtol=1e-3, atol=1e-3)


def test_names_are_forgiving_and_unknown_raises():
    a = naca.thickness("  naca 66   MOD ", np.array([0.3]))
    assert a[0] == pytest.approx(0.9274)
    with pytest.raises(BladeInputError, match="accepted: NACA 66 mod"):
        naca.thickness("NACA 16", np.array([0.3]))
    with pytest.raises(BladeInputError, match="accepted: NACA a=0.8"):
        naca.meanline("NACA a=1.0", np.array([0.3]))
