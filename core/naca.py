"""Propeller section forms: normalised thickness and meanline distributions.

Ordinates (x = x/c from the LE):
- Thickness ``NACA 66 mod`` (NACA 66, DTRC/DTMB modified; Brockett 1966, DTMB report 1780): the t/t0
  table as tabulated in OpenProp (Epps & Kimball, MIT licence), GeometryFoil2D.m, interpolated by a
  monotone cubic (PCHIP) in the stretched variable sqrt(x) so that the rounded nose (t ~ sqrt(x))
  is reproduced. The form has a blunt TE (t/t0 = 0.0666 at x = 1).
- Meanline ``NACA a=0.8``: the analytic a-series mean line (Abbott & von Doenhoff, Theory of Wing
  Sections, eq. 4.26 with a = 0.8) normalised to max camber 1; tested against OpenProp's tabulated
  f/f0 ordinates.
- Also: ``elliptic`` and ``parabolic`` thickness, ``parabolic`` meanline (analytic).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from .errors import BladeInputError

#: NACA 66 (DTRC modified) thickness, t/t0 at x/c (OpenProp GeometryFoil2D.m)
NACA66_X = np.array([0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.45, 0.5, 0.6, 0.7, 0.8,
                     0.9, 0.95, 1.0])
NACA66_T = np.array([0.0, 0.2088, 0.2932, 0.4132, 0.5050, 0.5814, 0.7042, 0.8000, 0.9274, 0.9904, 1.0,
                     0.9924, 0.9306, 0.8070, 0.6220, 0.3754, 0.2286, 0.0666])
#: NACA a=0.8 meanline, f/f0 at x/c (OpenProp GeometryFoil2D.m, tabulated variant)
A08_X = NACA66_X
A08_F = np.array([0.0, 0.0907, 0.1586, 0.2712, 0.3657, 0.4482, 0.5869, 0.6993, 0.8635, 0.9615, 0.9881,
                  1.0, 0.9786, 0.8892, 0.7027, 0.3586, 0.1713, 0.0])

_NACA66 = PchipInterpolator(np.sqrt(NACA66_X), NACA66_T)
_A = 0.8
_G = -1.0 / (1 - _A) * (_A**2 * (np.log(_A) / 2 - 0.25) + 0.25)
_H = 1.0 / (1 - _A) * ((1 - _A) ** 2 * np.log(1 - _A) / 2 - (1 - _A) ** 2 / 4) + _G


def _a08_raw(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Camber and slope of the a=0.8 mean line for c_li = 1 (before normalisation)."""
    x = np.clip(np.asarray(x, float), 1e-12, 1 - 1e-12)
    ca = _A - x
    ca = np.where(np.abs(ca) < 1e-12, 1e-12, ca)
    c1 = 1 - x
    k = 1.0 / (2 * np.pi * (_A + 1))
    p = 0.5 * ca**2 * np.log(np.abs(ca)) - 0.5 * c1**2 * np.log(c1) + 0.25 * (c1**2 - ca**2)
    f = k * (p / (1 - _A) - x * np.log(x) + _G - _H * x)
    df = k * ((-ca * np.log(np.abs(ca)) + c1 * np.log(c1)) / (1 - _A) - np.log(x) - 1 - _H)
    return f, df


_XS = np.linspace(0.3, 0.7, 40001)
_A08_MAX = float(_a08_raw(_XS)[0].max())


def _norm(name: str) -> str:
    return " ".join(name.lower().split())


def _naca66(x):
    return _NACA66(np.sqrt(np.clip(x, 0.0, 1.0)))


def _elliptic(x):
    return np.sqrt(np.clip(1 - (2 * x - 1) ** 2, 0.0, None))


def _parabolic_t(x):
    return 1 - (2 * x - 1) ** 2


def _a08(x):
    f, df = _a08_raw(x)
    f = f / _A08_MAX
    f = np.where((x <= 0) | (x >= 1), 0.0, f)
    return f, df / _A08_MAX


def _parabolic_m(x):
    return 1 - (2 * x - 1) ** 2, -4 * (2 * x - 1)


_THICKNESS = {"naca 66 mod": _naca66, "naca 66 (dtrc modified)": _naca66, "elliptic": _elliptic,
              "parabolic": _parabolic_t}
_MEANLINE = {"naca a=0.8": _a08, "parabolic": _parabolic_m}
THICKNESS_FORMS = ("NACA 66 mod", "NACA 66 (DTRC modified)", "elliptic", "parabolic")
MEANLINE_FORMS = ("NACA a=0.8", "parabolic")


def thickness(form: str, x: np.ndarray) -> np.ndarray:
    """x : (n,) float, chordwise fraction from the LE, 0..1 -> (n,) float, thickness / max thickness."""
    fn = _THICKNESS.get(_norm(form))
    if fn is None:
        raise BladeInputError(f"unknown thickness form {form!r}; accepted: {', '.join(THICKNESS_FORMS)}")
    return fn(np.asarray(x, float))


def meanline(form: str, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x : (n,) float 0..1 -> (camber / max camber, d(camber / max camber)/dx), both (n,) float.

    The a=0.8 slope is logarithmically singular at x = 0 and 1; it is evaluated at 1e-12 from the
    ends there (finite, steep)."""
    fn = _MEANLINE.get(_norm(form))
    if fn is None:
        raise BladeInputError(f"unknown meanline form {form!r}; accepted: {', '.join(MEANLINE_FORMS)}")
    return fn(np.asarray(x, float))
