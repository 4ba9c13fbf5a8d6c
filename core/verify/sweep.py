"""verify's clearances along the rows of a plan and between them, from few evaluations (used by
core.verify.assembly; its own code, shared with nothing of the planner's).

Between two rows the machines move each part's pose from one row's to the next's: the ball centre
along the straight line, the axis turning along the great circle between the two (the centres
linear, the axes normalised, as ``poses_between`` makes them). A point of the axis at s mm from the
ball centre then moves at most |dc| + |s| theta (theta: the angle the axis turns; a chord of the
arc is no longer than the arc), so a part whose axis points lie within s_max of the centre moves at
most |dc| + s_max theta between two rows (``motion``, ``reach``: summed along the rows), and a
clearance C at one row bounds every pose up to the motion M since from below by C - M (distances
are 1-Lipschitz in the points). Hence:
- rows between two measured ones a < b are at least max(v_a - M(a, j), v_b - M(j, b)), and every
  pose between them at least (v_a + v_b - M(a, b)) / 2 (``bounded``);
- a row interval whose bound allows a collision (< -TOLERANCE) is measured at interpolated poses,
  halving it up to HALVINGS times (``between_rows``); what is still unresolved then counts as a
  collision at its own bound.
Which rows are measured is the compiled sweeps' (core.verify._distance.step_rows).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from core.verify.distance import turns

#: mm: a clearance below -TOLERANCE is a collision (the stated tolerance, kept; how the blade's
#: tessellation's own error counts: core.verify.assembly's docstring)
TOLERANCE = 1e-3
#: halvings of a row interval whose bound allows a collision
HALVINGS = 6


def motion(centres: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows' moves (n - 1,) mm of the ball centres (n, 3) mm and turns (n - 1,) rad of the unit
    axes (n, 3): an axis point at most s_max mm from the ball centre moves at most move + s_max turn
    between two rows (``reach``; module docstring)."""
    if len(centres) < 2:
        return np.zeros(0), np.zeros(0)
    return np.linalg.norm(np.diff(centres, axis=0), axis=1), turns(axes)


def reach(moves: tuple[np.ndarray, np.ndarray], s_max: float) -> np.ndarray:
    """(n,) mm: the cumulative bound of how far any axis point at most s_max mm from the ball centre
    moves along the n rows (``motion``'s moves and turns): 0 at the first row. It grows with s_max:
    the bound of the part reaching farthest holds for every part nearer the centre."""
    return np.concatenate([[0.0], np.cumsum(moves[0] + s_max * moves[1])])


def poses_between(centres: np.ndarray, axes: np.ndarray, rows: np.ndarray, frac: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The poses a fraction frac (m,) of the way from each of rows (m,) to the next: centres
    (m, 3) mm linear, unit axes (m, 3) normalised."""
    nxt = np.minimum(rows + 1, len(centres) - 1)
    c = centres[rows] + frac[:, None] * (centres[nxt] - centres[rows])
    w = axes[rows] + frac[:, None] * (axes[nxt] - axes[rows])
    return c, w / np.linalg.norm(w, axis=1, keepdims=True)


def bounded(values: np.ndarray, measured: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """(n,) mm: the rows' values where measured, elsewhere the better bound from the measured rows
    before and after them (module docstring); reach (n,) mm the cumulative motion."""
    rows = np.flatnonzero(measured)
    k = np.clip(np.searchsorted(rows, np.arange(len(values)), side="right") - 1, 0, len(rows) - 1)
    k_next = np.minimum(k + 1, len(rows) - 1)
    before = values[rows[k]] - np.abs(reach - reach[rows[k]])
    after = values[rows[k_next]] - np.abs(reach[rows[k_next]] - reach)
    return np.where(measured, values, np.maximum(before, after))


@dataclass(frozen=True)
class Hidden:
    """A pose between two rows found colliding (or left unresolved by HALVINGS halvings: its bound):
    the row before it, the fraction of the way to the next, and the clearance, mm (negative)."""

    row: int
    frac: float
    value: float


def between_rows(values: np.ndarray, reach: np.ndarray, evaluate_at: Callable[[np.ndarray, np.ndarray], np.ndarray],
                 tolerance: float = TOLERANCE) -> list[Hidden]:
    """The poses between two rows that collide though neither row does: each interval whose bound
    (v_i + v_(i+1) - motion) / 2 lies below -tolerance is measured at its middle
    (``evaluate_at(rows, frac)`` (m,) mm), its halves checked the same way, up to HALVINGS times
    (module docstring). ``values`` (n,) mm lower bounds at the rows, ``reach`` (n,) mm."""
    if len(values) < 2:
        return []
    lo_v, hi_v, span = values[:-1], values[1:], np.diff(reach)
    rows = np.flatnonzero((lo_v >= -tolerance) & (hi_v >= -tolerance) & (0.5 * (lo_v + hi_v - span) < -tolerance))
    lo_f, hi_f = np.zeros(len(rows)), np.ones(len(rows))
    lo_v, hi_v, span = lo_v[rows], hi_v[rows], span[rows]
    found: list[Hidden] = []
    for _ in range(HALVINGS):
        if not rows.size:
            return found
        mid = 0.5 * (lo_f + hi_f)
        v = evaluate_at(rows, mid)
        hit = v < -tolerance
        found += [Hidden(int(r), float(f), float(x)) for r, f, x in zip(rows[hit], mid[hit], v[hit], strict=True)]
        rows, lo_f, hi_f, lo_v, hi_v, span, mid, v = _kept(~hit, rows, lo_f, hi_f, lo_v, hi_v, span, mid, v)
        rows = np.concatenate([rows, rows])
        lo_f, hi_f = np.concatenate([lo_f, mid]), np.concatenate([mid, hi_f])
        lo_v, hi_v = np.concatenate([lo_v, v]), np.concatenate([v, hi_v])
        span = np.concatenate([span, span]) * 0.5
        rows, lo_f, hi_f, lo_v, hi_v, span = _kept(0.5 * (lo_v + hi_v - span) < -tolerance, rows, lo_f, hi_f, lo_v,
                                                   hi_v, span)
    bound = 0.5 * (lo_v + hi_v - span)  # (still open after HALVINGS halvings: counted at its bound)
    return found + [Hidden(int(r), float(f), float(b)) for r, f, b in zip(rows, 0.5 * (lo_f + hi_f), bound,
                                                                         strict=True)]


def _kept(mask: np.ndarray, *arrays: np.ndarray) -> list[np.ndarray]:
    """Each array's rows where mask holds."""
    return [x[mask] for x in arrays]


@dataclass(frozen=True)
class Stretch:
    """Rows first..last (a run of colliding rows, or one row before a colliding pose between two
    rows: ``between``), the deepest row and its depth, mm (positive)."""

    first: int
    last: int
    row: int
    depth: float
    between: bool = False


def stretches(values: np.ndarray, hidden: list[Hidden], tolerance: float = TOLERANCE) -> list[Stretch]:
    """The collision stretches of a clearance along the rows (values (n,) mm): runs of rows below
    -tolerance, then each colliding pose between two rows (``hidden``) as a stretch of its own."""
    out = []
    idx = np.flatnonzero(values < -tolerance)
    if idx.size:
        cuts = np.flatnonzero(np.diff(idx) > 1)
        for lo, hi in zip(np.r_[0, cuts + 1], np.r_[cuts, len(idx) - 1], strict=True):
            first, last = int(idx[lo]), int(idx[hi])
            k = first + int(np.argmin(values[first:last + 1]))
            out.append(Stretch(first, last, k, float(-values[k])))
    # (one pose per interval: the deepest)
    deepest: dict[int, Hidden] = {}
    for h in hidden:
        if h.row not in deepest or h.value < deepest[h.row].value:
            deepest[h.row] = h
    out += [Stretch(h.row, h.row, h.row, -h.value, between=True) for h in deepest.values()]
    return out
