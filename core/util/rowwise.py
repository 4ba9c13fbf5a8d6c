"""Row-wise reductions of narrow arrays (a time column's (n, 2) .. (n, 12) rows), column by column.

numpy reduces an (n, k) C-order array along its rows (``a.max(axis=1)``, ``np.linalg.norm(a,
axis=1)``, ``(a * b).sum(1)``) with an inner loop k long, started again for every row: on the plan's
tables that is 4-60 times slower than combining the k columns with whole-column ufuncs. These give
the same values, bitwise: a maximum does not depend on its order (NaN propagates the same way), and
for k < 8 numpy's add.reduce sums a row from its first element to its last, one after the other,
which is the order used here (from 8 on numpy sums pairwise: those rows are left to numpy).
"""

from __future__ import annotations

import numpy as np

#: from this many columns on, numpy's add.reduce sums a row pairwise (not in order)
_PAIRWISE_FROM = 8


def row_max(a: np.ndarray) -> np.ndarray:
    """(n,) the largest value of each row of an (n, k) array, as a.max(axis=1)."""
    k = a.shape[1]
    if k == 0 or len(a) == 0:
        return a.max(axis=1)  # (numpy's own error or empty result)
    if k > 8:  # halve first: one pass over half the columns, then the rest
        h = k // 2
        b = np.maximum(a[:, :h], a[:, h:2 * h])
        return row_max(np.column_stack([b, a[:, 2 * h:]]) if k % 2 else b)
    out = a[:, 0].copy()
    for j in range(1, k):
        np.maximum(out, a[:, j], out=out)
    return out


def row_sum_of_products(a: np.ndarray, b: np.ndarray | None = None) -> np.ndarray:
    """(n,) the sum over each row of a * b (a * a when b is None), as (a * b).sum(axis=1)."""
    b = a if b is None else b
    k = a.shape[1]
    if k >= _PAIRWISE_FROM or k == 0 or len(a) == 0:
        return (a * b).sum(axis=1)
    out = a[:, 0] * b[:, 0]
    out += 0.0  # (numpy's sum starts from +0.0: a row of -0.0 sums to +0.0)
    for j in range(1, k):
        out += a[:, j] * b[:, j]
    return out


def row_norm(a: np.ndarray) -> np.ndarray:
    """(n,) the Euclidean length of each row of a real (n, k) array, as np.linalg.norm(a, axis=1)."""
    out = row_sum_of_products(a)
    return np.sqrt(out, out=out)
