"""A lean not-a-knot cubic spline for many short fits (the path pipeline fits thousands).

Same interpolant as scipy.interpolate.CubicSpline(bc_type='not-a-knot') (tested against it), without
its input validation overhead, and with evaluation inside a known knot interval, which the arc-length
quadrature uses.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.linalg import solve_banded


class Cubic:
    """Piecewise cubic over knots x (n,) of values y (n, m).

    coef : (n-1, 4, m), value on interval i at d = t - x[i]: ((c0 d + c1) d + c2) d + c3.
    """

    __slots__ = ("x", "coef", "_dxyz")

    def __init__(self, x: np.ndarray, y: np.ndarray):
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        if y.ndim == 1:
            y = y[:, None]
        n = len(x)
        if n < 4:
            cs = CubicSpline(x, y, axis=0)
            self.x = x
            self.coef = np.transpose(cs.c, (1, 0, 2)).copy()
            self._dxyz = None
            return
        dx = np.diff(x)
        slope = np.diff(y, axis=0) / dx[:, None]
        a = np.zeros((3, n))
        b = np.empty((n, y.shape[1]))
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
        s = solve_banded((1, 1), a, b, overwrite_ab=True, overwrite_b=True, check_finite=False)
        t = (s[:-1] + s[1:] - 2.0 * slope) / dx[:, None]
        coef = np.empty((n - 1, 4, y.shape[1]))
        coef[:, 0] = t / dx[:, None]
        coef[:, 1] = (slope - s[:-1]) / dx[:, None] - t
        coef[:, 2] = s[:-1]
        coef[:, 3] = y[:-1]
        self.x = x
        self.coef = coef
        self._dxyz = None

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
        """|d(first three columns)/dt| at nodes (k, q), row j inside interval i[j] -> (k, q)."""
        if self._dxyz is None:
            c = self.coef[:, :, :3]
            self._dxyz = np.ascontiguousarray(np.stack([3.0 * c[:, 0], 2.0 * c[:, 1], c[:, 2]], axis=1))
        c = self._dxyz[i]  # (k, 3 coefficients, 3 columns)
        d = (nodes - self.x[i][:, None])[:, :, None]
        v = (c[:, None, 0] * d + c[:, None, 1]) * d + c[:, None, 2]
        return np.sqrt(np.einsum("kqj,kqj->kq", v, v))

    def __call__(self, t: np.ndarray, nu: int = 0, cols: slice = slice(None)) -> np.ndarray:
        t = np.asarray(t, float)
        return self.eval_in(self.interval(t), t, nu, cols)
