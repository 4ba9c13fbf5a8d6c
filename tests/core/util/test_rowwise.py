"""Row-wise reductions column by column (core.util.rowwise) against numpy's own, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from core.util.rowwise import row_max, row_norm, row_sum_of_products


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bit for bit: the same values, NaN where NaN, and the same sign of zero."""
    return (a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
            and np.array_equal(np.signbit(a), np.signbit(b)))


def _rows(k: int, n: int = 5000, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed + k)
    a = rng.normal(size=(n, k)) * np.exp(rng.uniform(-30, 30, size=(n, 1)))
    a[1] = -0.0  # a row of negative zeros
    a[2, 0] = np.nan
    a[3, -1] = np.inf
    a[4, 0], a[4, -1] = -np.inf, np.inf
    a[5] = 0.0
    a[5, k // 2] = -0.0
    return a


@pytest.mark.parametrize("k", range(1, 14))
def test_row_reductions_equal_numpys_bit_for_bit(k):
    a = _rows(k)
    b = _rows(k, seed=100)
    with np.errstate(invalid="ignore", over="ignore"):
        assert _same(row_max(a), a.max(axis=1))
        assert _same(row_sum_of_products(a, b), (a * b).sum(axis=1))
        assert _same(row_sum_of_products(a), (a * a).sum(axis=1))
        assert _same(row_norm(a), np.linalg.norm(a, axis=1))


def test_row_reductions_of_slices_and_empty_columns():
    """Columns that are a slice of a wider array (rows not contiguous), and no rows at all."""
    wide = _rows(12)
    part = wide[:, 3:6]
    assert not part.flags.c_contiguous
    with np.errstate(invalid="ignore"):
        assert _same(row_max(part), part.max(axis=1))
        assert _same(row_norm(part), np.linalg.norm(part, axis=1))
    empty = np.zeros((0, 3))
    assert row_max(empty).shape == row_norm(empty).shape == (0,)
