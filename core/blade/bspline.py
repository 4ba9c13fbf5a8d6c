"""A tensor-product B-spline surface evaluated with numpy, vectorised over points: the values and the
partial derivatives of a CAD face's NURBS surface in homogeneous coordinates (core.blade.cad.Patch).

Written here rather than taken from scipy.interpolate (NdBSpline), whose import alone takes about as
long as reading a CAD blade and cutting its first section. The basis functions and their derivatives
are those of The NURBS Book (Piegl and Tiller, algorithm A2.3), each step done for all points at once.
"""

from __future__ import annotations

import numpy as np


def basis(knots: np.ndarray, degree: int, x: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """The B-spline basis functions of ``degree`` on ``knots`` that are nonzero at x (n,): (span (n,) int,
    values (n, degree + 1)), values[:, j] the ``order``-th derivative of basis function
    span - degree + j at x. An x outside the knots' range is evaluated on the first or last span."""
    t, p, n = np.asarray(knots, float), int(degree), len(x)
    last = len(t) - p - 2
    span = np.clip(np.searchsorted(t, x, side="right") - 1, p, last)
    ndu = np.zeros((p + 1, p + 1, n))
    ndu[0, 0] = 1.0
    left, right = np.zeros((p + 1, n)), np.zeros((p + 1, n))
    for j in range(1, p + 1):
        left[j] = x - t[span + 1 - j]
        right[j] = t[span + j] - x
        saved = np.zeros(n)
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]  # (the knot differences, below the diagonal)
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    if order == 0:
        return span, ndu[:, p].T.copy()
    out = np.zeros((p + 1, n))
    for r in range(p + 1):
        a = np.zeros((2, p + 1, n))
        a[0, 0] = 1.0
        s1, s2 = 0, 1
        d = np.zeros(n)
        for k in range(1, order + 1):
            d = np.zeros(n)
            rk, pk = r - k, p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d = d + a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d = d + a[s2, k] * ndu[r, pk]
            s1, s2 = s2, s1
        out[r] = d
    factor = 1.0
    for k in range(order):
        factor *= p - k
    return span, (out * factor).T


class TensorSpline:
    """S(u, v) = sum_ij N_i(u) M_j(v) c_ij: knots (tu, tv), coefficients c (nu, nv, d), degrees (p, q)."""

    def __init__(self, knots: tuple[np.ndarray, np.ndarray], coefficients: np.ndarray, degrees: tuple[int, int]):
        self.knots = tuple(np.asarray(k, float) for k in knots)
        self.c = np.asarray(coefficients, float)
        self.degrees = tuple(int(d) for d in degrees)

    def __call__(self, uv: np.ndarray, nu: tuple[int, int] = (0, 0)) -> np.ndarray:
        """S (or its partial derivative of orders ``nu``) at the parameters uv (n, 2): (n, d)."""
        uv = np.asarray(uv, float)
        (p, q), (tu, tv) = self.degrees, self.knots
        su, bu = basis(tu, p, uv[:, 0], nu[0])
        sv, bv = basis(tv, q, uv[:, 1], nu[1])
        iu = su[:, None] - p + np.arange(p + 1)[None, :]
        iv = sv[:, None] - q + np.arange(q + 1)[None, :]
        c = self.c[iu[:, :, None], iv[:, None, :]]  # (n, p + 1, q + 1, d)
        return np.einsum("ni,nj,nijd->nd", bu, bv, c)
