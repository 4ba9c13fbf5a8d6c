"""Lean piecewise cubics: the not-a-knot cubic spline for many short fits (the path pipeline fits
thousands), PCHIP and cubic Hermite interpolants, and a bracketed root finder.

The same interpolants as scipy.interpolate's CubicSpline(bc_type='not-a-knot'), PchipInterpolator and
CubicHermiteSpline (tested against them), without their input validation overhead, with evaluation
inside a known knot interval (which the arc-length quadrature uses), and without importing
scipy.interpolate and scipy.optimize, which cost about 0.4 s at every start of the command line.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_banded


class Cubic:
    """Piecewise cubic over knots x (n,) of values y (n, m).

    coef : (n-1, 4, m), value on interval i at d = t - x[i]: ((c0 d + c1) d + c2) d + c3.
    """

    __slots__ = ("x", "coef", "_dxyz")

    def __init__(self, x: np.ndarray, y: np.ndarray, dydx: np.ndarray | None = None):
        """Knots x (n,), increasing; values y (n,) or (n, m); dydx None: the not-a-knot spline (for
        n = 3 the parabola through the points, for n = 2 the line); else the cubic Hermite
        interpolant with these derivatives (same shape as y)."""
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        if y.ndim == 1:
            y = y[:, None]
        dx = np.diff(x)
        slope = np.diff(y, axis=0) / dx[:, None]
        if dydx is not None:
            s = np.asarray(dydx, float).reshape(y.shape)
        else:
            s = _not_a_knot_slopes(x, dx, slope, y.shape[1])
        t = (s[:-1] + s[1:] - 2.0 * slope) / dx[:, None]
        coef = np.empty((len(x) - 1, 4, y.shape[1]))
        coef[:, 0] = t / dx[:, None]
        coef[:, 1] = (slope - s[:-1]) / dx[:, None] - t
        coef[:, 2] = s[:-1]
        coef[:, 3] = y[:-1]
        self.x = x
        self.coef = coef
        self._dxyz: np.ndarray | None = None

    def interval(self, t: np.ndarray) -> np.ndarray:
        """(k,) parameters -> (k,) interval indices (clamped to the ends)."""
        return np.clip(np.searchsorted(self.x, t, side="right") - 1, 0, len(self.x) - 2)

    def eval_in(self, i: np.ndarray, t: np.ndarray, nu: int = 0, cols: slice = slice(None)) -> np.ndarray:
        """Value (nu=0) or first derivative (nu=1) at t (k,) known to lie in intervals i (k,)."""
        c = self.coef[i][:, :, cols]
        d = (t - self.x[i])[:, None]
        if nu == 0:
            return ((c[:, 0] * d + c[:, 1]) * d + c[:, 2]) * d + c[:, 3]
        return (3.0 * c[:, 0] * d + 2.0 * c[:, 1]) * d + c[:, 2]

    def speed_nodes(self, i: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """|d(first three columns)/dt| at nodes (k, q), row j inside interval i[j] -> (k, q).

        The squared speed is a quartic in d = t - x[i] per interval (v = a d^2 + b d + c:
        |v|^2 = a.a d^4 + 2 a.b d^3 + (b.b + 2 a.c) d^2 + 2 b.c d + c.c), its coefficients built once."""
        if self._dxyz is None:
            c = self.coef[:, :, :3]
            a, b, cc = 3.0 * c[:, 0], 2.0 * c[:, 1], c[:, 2]
            dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731
            self._dxyz = np.ascontiguousarray(np.column_stack(
                [dot(a, a), 2.0 * dot(a, b), dot(b, b) + 2.0 * dot(a, cc), 2.0 * dot(b, cc), dot(cc, cc)]))
        q = self._dxyz[i]  # (k, 5)
        d = nodes - self.x[i][:, None]
        v2 = (((q[:, 0:1] * d + q[:, 1:2]) * d + q[:, 2:3]) * d + q[:, 3:4]) * d + q[:, 4:5]
        return np.sqrt(np.maximum(v2, 0.0))

    def __call__(self, t: np.ndarray, nu: int = 0, cols: slice = slice(None)) -> np.ndarray:
        t = np.asarray(t, float)
        return self.eval_in(self.interval(t), t, nu, cols)


def _not_a_knot_slopes(x: np.ndarray, dx: np.ndarray, slope: np.ndarray, m: int) -> np.ndarray:
    """(n, m) first derivatives at the knots of the not-a-knot cubic spline."""
    n = len(x)
    if n == 2:
        return np.vstack([slope, slope])
    if n == 3:  # the parabola through the three points
        a = (slope[1] - slope[0]) / (x[2] - x[0])
        return np.vstack([slope[0] + a * (x[0] - x[1]), slope[0] + a * (x[1] - x[0]),
                          slope[0] + a * (2 * x[2] - x[0] - x[1])])
    a = np.zeros((3, n))
    b = np.empty((n, m))
    a[1, 1:-1] = 2.0 * (dx[:-1] + dx[1:])
    a[0, 2:] = dx[:-1]
    a[-1, :-2] = dx[1:]
    b[1:-1] = 3.0 * (dx[1:, None] * slope[:-1] + dx[:-1, None] * slope[1:])
    d0 = x[2] - x[0]
    a[1, 0] = dx[1]
    a[0, 1] = d0
    b[0] = ((dx[0] + 2.0 * d0) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d0
    d1 = x[-1] - x[-3]
    a[1, -1] = dx[-2]
    a[-1, -2] = d1
    b[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d1 + dx[-1]) * dx[-2] * slope[-1]) / d1
    return solve_banded((1, 1), a, b, overwrite_ab=True, overwrite_b=True, check_finite=False)


def _pchip_edge(h0, h1, m0, m1):
    """One-sided three-point derivative at an end, kept shape-preserving (as scipy's PCHIP)."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    mask = np.sign(d) != np.sign(m0)
    mmm = ~mask & (np.sign(m0) != np.sign(m1)) & (np.abs(d) > 3.0 * np.abs(m0))
    return np.where(mask, 0.0, np.where(mmm, 3.0 * m0, d))


class Curve1D:
    """A piecewise cubic y(x) of one variable: scalars or arrays in, the same shape out; outside the
    knots the end pieces continue (as scipy's PPoly with extrapolate=True).

    x : (n,) knots; c : (4, n - 1) coefficients in scipy's PPoly layout (highest power first)."""

    __slots__ = ("_cubic",)

    def __init__(self, cubic: Cubic):
        self._cubic = cubic

    @property
    def x(self) -> np.ndarray:
        return self._cubic.x

    @property
    def c(self) -> np.ndarray:
        return self._cubic.coef[:, :, 0].T

    def __call__(self, t, nu: int = 0) -> np.ndarray:
        t = np.asarray(t, float)
        return self._cubic(t.ravel(), nu)[:, 0].reshape(t.shape)

    def derivative(self) -> Curve1D:
        """The first derivative, as a piecewise cubic (leading coefficient 0)."""
        c = self._cubic.coef
        d = Cubic.__new__(Cubic)
        d.x, d._dxyz = self._cubic.x, None
        d.coef = np.stack([np.zeros_like(c[:, 0]), 3.0 * c[:, 0], 2.0 * c[:, 1], c[:, 2]], axis=1)
        return Curve1D(d)

    def critical_points(self) -> np.ndarray:
        """Sorted x inside the knots where the derivative vanishes (the roots, piece by piece, of
        3 c0 d^2 + 2 c1 d + c2 on [0, h])."""
        c = self._cubic.coef[:, :, 0]
        h = np.diff(self.x)
        qa, qb, qc = 3.0 * c[:, 0], 2.0 * c[:, 1], c[:, 2]
        out = []
        for i in range(len(h)):
            if qa[i] != 0:
                disc = qb[i] ** 2 - 4 * qa[i] * qc[i]
                if disc < 0:
                    continue
                r = math.sqrt(disc)
                q = -0.5 * (qb[i] + math.copysign(r, qb[i]))  # stable quadratic roots
                roots = [q / qa[i]] + ([qc[i] / q] if q != 0 else [])
            elif qb[i] != 0:
                roots = [-qc[i] / qb[i]]
            else:
                roots = []
            out += [self.x[i] + d for d in roots if 0.0 <= d <= h[i]]
        return np.unique(np.array(out, float))


def spline(x: np.ndarray, y: np.ndarray) -> Curve1D:
    """The not-a-knot cubic spline through (x, y), both (n,), n >= 2."""
    return Curve1D(Cubic(x, y))


def hermite(x: np.ndarray, y: np.ndarray, dydx: np.ndarray) -> Curve1D:
    """The cubic Hermite interpolant with values y and derivatives dydx at the knots x, all (n,)."""
    return Curve1D(Cubic(x, y, dydx))


def pchip(x: np.ndarray, y: np.ndarray) -> Curve1D:
    """The shape-preserving PCHIP interpolant (Fritsch-Butland weighted harmonic means, one-sided
    three-point ends; scipy's PchipInterpolator) through (x, y), both (n,), n >= 2."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    h = np.diff(x)
    m = np.diff(y) / h
    if len(x) == 2:
        return hermite(x, y, np.array([m[0], m[0]]))
    sm = np.sign(m)
    flat = (sm[1:] != sm[:-1]) | (m[1:] == 0) | (m[:-1] == 0)
    w1 = 2 * h[1:] + h[:-1]
    w2 = h[1:] + 2 * h[:-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        whmean = (w1 / m[:-1] + w2 / m[1:]) / (w1 + w2)
        inner = np.where(flat, 0.0, 1.0 / np.where(flat, 1.0, whmean))
    d = np.concatenate([_pchip_edge(h[:1], h[1:2], m[:1], m[1:2]), inner,
                        _pchip_edge(h[-1:], h[-2:-1], m[-1:], m[-2:-1])])
    return hermite(x, y, d)


def find_root(f, a: float, b: float, xtol: float = 1e-15) -> float:
    """A root of the continuous f on [a, b] with f(a), f(b) of opposite signs (or zero), by bisection
    until the bracket is below xtol (plus 4 eps |x|)."""
    fa, fb = float(f(a)), float(f(b))
    if fa == 0:
        return a
    if fb == 0:
        return b
    if (fa > 0) == (fb > 0):
        raise ValueError(f"find_root: f({a}) and f({b}) have the same sign")
    while abs(b - a) > xtol + 4 * np.finfo(float).eps * max(abs(a), abs(b)):
        mid = 0.5 * (a + b)
        if mid in (a, b):
            break
        fm = float(f(mid))
        if fm == 0:
            return mid
        if (fm > 0) == (fa > 0):
            a, fa = mid, fm
        else:
            b, fb = mid, fm
    return a if abs(fa) <= abs(fb) else b
