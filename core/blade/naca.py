"""Propeller section forms: normalised thickness and mean-line (camber) distributions.

x is the chordwise fraction x/c from the leading edge (0) to the trailing edge (1). Thickness forms
return t/t0 (max 1.0); mean lines return f/f0 (max 1.0) and its slope d(f/f0)/dx. The caller scales
by the section's t0 and f0 (core.blade.table).

Sources of the ordinates
------------------------
Tabulated forms are taken from OpenProp (B. Epps, MIT; open-source propeller design code),
repository ``joaoantoniocardoso/OpenProp``, file ``SourceCode/GeometryFoil2D.m``
(commit 521e1c07c81d3dc9d246c325a3be344323b17298):

- ``NACA 66 mod`` (alias ``NACA 66 (DTRC modified)``): the DTMB/DTRC modified NACA 66 thickness
  form (Brockett 1966, DTMB report 1780), t/t0 at 18 stations; max at x = 0.45, blunt TE with
  t/t0 = 0.0666 at x = 1.
- ``NACA 65A010``: NACA 65A010 thickness (t/c in percent, 26 stations), divided by its max
  (4.995 % at x = 0.40); TE t/t0 = 0.0042.
- ``NACA a=0.8 (modified)``: the modified a=0.8 mean line, f/c and slope df/dx for c_li = 1 at 26
  stations (max f/c = 6.651 % in the table at x = 0.50).

Tabulated thicknesses are interpolated with a monotone cubic (PCHIP) in s = sqrt(x): the rounded
nose has t ~ sqrt(x), i.e. t is linear in s at the LE, which PCHIP in x could not follow. PCHIP
reproduces every tabulated ordinate exactly and keeps the table's max (at a tabulated station,
slope zero there). The modified a=0.8 mean line is a cubic Hermite spline through the tabulated
ordinates *and* slopes; it peaks slightly aft of x = 0.5 (f/c = 1.0007 x the tabulated 6.651 %),
so it is normalised by that true max: table ordinates are reproduced exactly up to this constant.

Analytic forms:

- ``NACA a=0.8``: the NACA a-series mean line, Abbott & von Doenhoff, *Theory of Wing Sections*,
  eq. 4.26, with a = 0.8, normalised by its true max (f/c = 0.0679434 per unit c_li at
  x = 0.51533). The published a=0.8 table (as in OpenProp) is normalised at x = 0.5 instead, so its
  ordinates are 1.0007 x ours. The slope is -ln(x) singular at the LE: it is evaluated at
  x = max(x, X_SLOPE_MIN) (finite; the nose orientation is conventionally taken at x = 0.005
  anyway). It is finite at x = a and at the TE; the camber is 0 at both ends.
- ``NACA 00xx`` (alias ``NACA 4-digit``): the 4-digit thickness polynomial, normalised by its max
  (at x = 0.2998); TE t/t0 = 0.021.
- ``elliptic``, ``parabolic`` thickness; ``parabolic`` mean line (4 x (1 - x)).

Names are matched case-insensitively, ignoring whitespace.
"""

from __future__ import annotations

import numpy as np

from core.errors import BladeInputError
from core.util.spline import Curve1D, find_root, hermite, pchip

#: smallest x at which the a=0.8 mean-line slope is evaluated (log-singular at x = 0)
X_SLOPE_MIN = 1e-9

# ----------------------------------------------------------------------------- tables (OpenProp)
#: NACA 66 (DTRC modified): x/c and t/t0
NACA66_X = np.array([0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.45, 0.5, 0.6,
                     0.7, 0.8, 0.9, 0.95, 1.0])
NACA66_T = np.array([0.0, 0.2088, 0.2932, 0.4132, 0.5050, 0.5814, 0.7042, 0.8000, 0.9274, 0.9904,
                     1.0, 0.9924, 0.9306, 0.8070, 0.6220, 0.3754, 0.2286, 0.0666])
#: x/c (percent) of the 26-station NACA tables (65A010 thickness, a=0.8 modified mean line)
_X26 = np.array([0, 0.5, 0.75, 1.25, 2.5, 5, 7.5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65,
                 70, 75, 80, 85, 90, 95, 100]) / 100
#: NACA 65A010: t/c in percent
NACA65A010_TOC = np.array([0, 0.765, 0.928, 1.183, 1.623, 2.182, 2.65, 3.04, 3.658, 4.127, 4.483,
                           4.742, 4.912, 4.995, 4.983, 4.863, 4.632, 4.304, 3.899, 3.432, 2.912,
                           2.352, 1.771, 1.188, 0.604, 0.021])
#: NACA a=0.8 (modified), c_li = 1: f/c in percent and slope df/dx
A08MOD_FOC = np.array([0, 0.281, 0.396, 0.603, 1.055, 1.803, 2.432, 2.981, 3.903, 4.651, 5.257,
                       5.742, 6.120, 6.394, 6.571, 6.651, 6.631, 6.508, 6.274, 5.913, 5.401,
                       4.673, 3.607, 2.452, 1.226, 0])
A08MOD_DFDX = np.array([0.53699, 0.47539, 0.44004, 0.39531, 0.33404, 0.27149, 0.23378, 0.20618,
                        0.16546, 0.13452, 0.10873, 0.08595, 0.06498, 0.04507, 0.02559, 0.00607,
                        -0.01404, -0.03537, -0.05887, -0.08610, -0.12058, -0.18034, -0.23430,
                        -0.24521, -0.24521, -0.24521])

_NACA66 = pchip(np.sqrt(NACA66_X), NACA66_T)
_NACA65A010 = pchip(np.sqrt(_X26), NACA65A010_TOC / NACA65A010_TOC.max())


def _hermite_max(spl: Curve1D) -> float:
    """Exact max of a piecewise cubic on its breakpoint interval (ends and interior extrema)."""
    cand = np.concatenate([spl.x[[0, -1]], spl.critical_points()])
    return float(np.max(spl(cand[np.isfinite(cand)])))


_A08MOD_SPL = hermite(_X26, A08MOD_FOC / 100, A08MOD_DFDX)
#: true max f/c of the modified a=0.8 mean line (c_li = 1), slightly aft of x = 0.5
A08MOD_F0 = _hermite_max(_A08MOD_SPL)
_A08MOD_DSPL = _A08MOD_SPL.derivative()

# ----------------------------------------------------------------------------- analytic forms
_A = 0.8
_G = -1.0 / (1 - _A) * (_A**2 * (np.log(_A) / 2 - 0.25) + 0.25)
_H = 1.0 / (1 - _A) * ((1 - _A) ** 2 * np.log(1 - _A) / 2 - (1 - _A) ** 2 / 4) + _G
_K = 1.0 / (2 * np.pi * (_A + 1))  # c_li / (2 pi (a + 1)) with c_li = 1


def _xlogx(u: np.ndarray) -> np.ndarray:
    """u ln|u| with its limit 0 at u = 0."""
    au = np.abs(u)
    return u * np.log(np.where(au > 0, au, 1.0))


def _a08_camber(x: np.ndarray) -> np.ndarray:
    """f/c of the a=0.8 mean line for c_li = 1 (eq. 4.26), x in [0, 1]; 0 at both ends."""
    ca, c1 = _A - x, 1 - x
    p = 0.5 * ca * _xlogx(ca) - 0.5 * c1 * _xlogx(c1) + 0.25 * (c1**2 - ca**2)
    return _K * (p / (1 - _A) - _xlogx(x) + _G - _H * x)


def _a08_slope(x: np.ndarray) -> np.ndarray:
    """d(f/c)/dx of the a=0.8 mean line for c_li = 1; finite for x > 0."""
    x = np.maximum(x, X_SLOPE_MIN)
    return _K * ((_xlogx(1 - x) - _xlogx(_A - x)) / (1 - _A) - np.log(x) - 1 - _H)


#: x of the max camber of the a=0.8 mean line, and the max f/c for c_li = 1
A08_XMAX = find_root(lambda x: float(_a08_slope(np.array(x))), 0.4, 0.6, xtol=1e-15)
A08_F0 = float(_a08_camber(np.array(A08_XMAX)))


def _naca00xx_half(x: np.ndarray) -> np.ndarray:
    return 0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1015 * x**4


_N4_XMAX = find_root(lambda x: 0.2969 / (2 * np.sqrt(x)) - 0.126 - 0.7032 * x + 0.8529 * x**2
                  - 0.406 * x**3, 0.2, 0.4, xtol=1e-15)
_N4_MAX = float(_naca00xx_half(np.array(_N4_XMAX)))

# ----------------------------------------------------------------------------- registry


def _t_naca66(x):
    return _NACA66(np.sqrt(x))


def _t_naca65a010(x):
    return _NACA65A010(np.sqrt(x))


def _t_naca00xx(x):
    return _naca00xx_half(x) / _N4_MAX


def _t_elliptic(x):
    return np.sqrt(np.maximum(4 * x * (1 - x), 0.0))


def _t_parabolic(x):
    return 4 * x * (1 - x)


def _m_a08(x):
    f = np.where((x <= 0) | (x >= 1), 0.0, _a08_camber(x) / A08_F0)
    return f, _a08_slope(x) / A08_F0


def _m_a08mod(x):
    return _A08MOD_SPL(x) / A08MOD_F0, _A08MOD_DSPL(x) / A08MOD_F0


def _m_parabolic(x):
    return 4 * x * (1 - x), 4 - 8 * x


_THICKNESS = {"NACA 66 mod": _t_naca66, "NACA 66 (DTRC modified)": _t_naca66,
              "NACA 65A010": _t_naca65a010, "NACA 00xx": _t_naca00xx,
              "NACA 4-digit": _t_naca00xx, "elliptic": _t_elliptic, "parabolic": _t_parabolic}
_MEANLINE = {"NACA a=0.8": _m_a08, "NACA a=0.8 (modified)": _m_a08mod,
             "parabolic": _m_parabolic}
THICKNESS_FORMS: tuple[str, ...] = tuple(_THICKNESS)
MEANLINE_FORMS: tuple[str, ...] = tuple(_MEANLINE)


def _key(name: str) -> str:
    return "".join(name.lower().split())


_T_BY_KEY = {_key(k): v for k, v in _THICKNESS.items()}
_M_BY_KEY = {_key(k): v for k, v in _MEANLINE.items()}


def _lookup(table: dict, form: object, kind: str, accepted: tuple[str, ...]):
    fn = table.get(_key(form)) if isinstance(form, str) else None
    if fn is None:
        raise BladeInputError(f"unknown {kind} form {form!r}; accepted: "
                              + ", ".join(repr(a) for a in accepted)
                              + " (case and spaces are ignored)")
    return fn


def thickness(form: str, x: np.ndarray) -> np.ndarray:
    """x : (n,) float, chordwise fraction from the LE, 0..1 -> (n,) float, t / t0.

    Max 1.0 at the form's max-thickness station, 0 at the LE with t ~ sqrt(x) (rounded nose); the
    TE value is the form's own (NACA 66 mod: 0.0666). x outside 0..1 is clipped. Any shape of x
    is accepted and kept. Raises BladeInputError for an unknown form name."""
    fn = _lookup(_T_BY_KEY, form, "thickness", THICKNESS_FORMS)
    return fn(np.clip(np.asarray(x, dtype=float), 0.0, 1.0))


def meanline(form: str, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x : (n,) float 0..1 -> (f / f0, d(f / f0)/dx), both (n,) float.

    Camber 0 at both ends, max 1.0. The slope is finite for every x; for the analytic
    ``NACA a=0.8`` it is log-singular at the LE and is evaluated at max(x, X_SLOPE_MIN) there.
    x outside 0..1 is clipped. Raises BladeInputError for an unknown form name."""
    fn = _lookup(_M_BY_KEY, form, "meanline", MEANLINE_FORMS)
    return fn(np.clip(np.asarray(x, dtype=float), 0.0, 1.0))
