"""core.blade.bspline against scipy's NdBSpline: values and partial derivatives of tensor-product
B-splines of degrees 1 to 5, with repeated inner knots, at random points and at the ends."""

import numpy as np
import pytest
from scipy.interpolate import NdBSpline

from core.blade.bspline import TensorSpline


def clamped(rng, degree: int, inner: int) -> np.ndarray:
    k = np.sort(rng.random(inner))
    k = np.concatenate([k, k[:1]])  # (one inner knot twice)
    return np.sort(np.concatenate([np.zeros(degree + 1), k, np.ones(degree + 1)]))


@pytest.mark.parametrize("p,q", [(1, 1), (2, 3), (3, 3), (5, 2)])
def test_values_and_derivatives_are_scipys(p, q):
    rng = np.random.default_rng(p * 10 + q)
    tu, tv = clamped(rng, p, 6), clamped(rng, q, 4)
    c = rng.normal(size=(len(tu) - p - 1, len(tv) - q - 1, 4))
    uv = rng.random((400, 2))
    uv[:4] = [[0, 0], [1, 1], [0, 1], [tu[p + 3], tv[q + 2]]]
    ours, ref = TensorSpline((tu, tv), c, (p, q)), NdBSpline((tu, tv), c, (p, q))
    for nu in [(0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1)]:
        if nu[0] > p or nu[1] > q:
            continue
        want = ref(uv, nu=nu)
        assert np.abs(ours(uv, nu=nu) - want).max() <= 1e-12 * max(1.0, np.abs(want).max()), nu
