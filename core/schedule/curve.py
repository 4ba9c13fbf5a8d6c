"""The smooth curve through a cutter's polyline: what the rows are sampled from.

A cutter's move follows a polyline (tips and unit tool axes at its vertices, 0.2 mm apart along a
contour path). Sampled straight between the vertices, the motion turns at every vertex: the axis
velocities jump there by v |dq/ds_after - dq/ds_before|, which lands within one row interval when the
rows are closer than the vertices, and bounds the speed by a_lim period / |jump| rather than by the
path's own curvature, sqrt(a_lim / |d2q/ds2|) (at a tenth of the feed, ten times lower). The rows are
therefore sampled from a C1 cubic Hermite curve through the vertices, parameterised by the polyline's
arc length s, with tangents from the three-point (non-uniform) difference at inner vertices and the
end segment's direction at a move's first and last vertex (a move that starts or ends at a corner
leaves and enters it straight). The curve passes through every vertex, its velocity is continuous,
and its acceleration is the path's curvature to O(h); it strays from the polyline by about
h^2 kappa / 8 (2e-4 mm on the sample's ball-centre paths, h 0.2 mm).

Units: mm.
"""

from __future__ import annotations

import numpy as np

#: mm: segments shorter than this count as zero length (a junction's two vertices, whose arc lengths
#: along a chain differ by round-off)
MIN_SEGMENT = 1e-12


def tangents(points: np.ndarray, s: np.ndarray, size: np.ndarray) -> np.ndarray:
    """(n, k) d(points)/ds at each vertex of runs of vertices laid end to end (``size`` (m,) vertices
    per run, s (n,) each run's own nondecreasing arc length): the three-point difference inside a run,
    the end segment's direction at its ends; zero-length segments are skipped (a run of coincident
    vertices takes its neighbours' difference), and a run of one point has tangent 0."""
    n = len(points)
    out = np.zeros_like(points, dtype=float)
    if n < 2:
        return out
    h = np.diff(s)
    d = np.diff(points, axis=0)
    run = np.repeat(np.arange(len(size)), size)
    inner = run[:-1] == run[1:]
    real = inner & (h > MIN_SEGMENT)
    slope = np.where(real[:, None], d / np.where(real, h, 1.0)[:, None], np.nan)
    # each vertex's previous and next real segment within its run (forward / backward fill)
    idx = np.where(real, np.arange(n - 1), -1)
    prev_seg = np.maximum.accumulate(np.concatenate([[-1], idx]))          # last real segment ending <= i
    nxt = np.where(real, np.arange(n - 1), n)
    next_seg = np.minimum.accumulate(np.concatenate([nxt, [n]])[::-1])[::-1]  # first real segment >= i
    has_prev = (prev_seg >= 0) & (run[np.clip(prev_seg, 0, n - 2)] == run)
    has_next = (next_seg < n - 1) & (run[np.clip(next_seg, 0, n - 2)] == run)
    pa = np.clip(prev_seg, 0, n - 2)
    nb = np.clip(next_seg, 0, n - 2)
    h0, h1 = np.where(has_prev, h[pa], 0.0), np.where(has_next, h[nb], 0.0)
    m0 = np.where(has_prev[:, None], np.nan_to_num(slope[pa]), 0.0)
    m1 = np.where(has_next[:, None], np.nan_to_num(slope[nb]), 0.0)
    both = has_prev & has_next
    w = np.where(both, h1 / np.where(both, h0 + h1, 1.0), 0.0)
    out = np.where(both[:, None], w[:, None] * m0 + (1.0 - w[:, None]) * m1,
                   np.where(has_next[:, None], m1, m0))
    return out


def segment_rows(points: np.ndarray, tangent: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(n - 1, 4k) per segment (vertex i to i + 1): its start point, chord, and the two end tangents
    times the segment's length: the coefficients ``evaluate`` takes."""
    h = np.diff(s)[:, None]
    return np.hstack([points[:-1], np.diff(points, axis=0), tangent[:-1] * h, tangent[1:] * h])


def evaluate(rows: np.ndarray, f: np.ndarray, k: int = 3) -> np.ndarray:
    """(m, k) points at fractions f (m,) in [0, 1] of segments given by ``segment_rows`` (m, 4k)."""
    f = f[:, None]
    f2 = f * f
    p0, d, t0, t1 = rows[:, :k], rows[:, k:2 * k], rows[:, 2 * k:3 * k], rows[:, 3 * k:4 * k]
    return p0 + d * (f2 * (3.0 - 2.0 * f)) + t0 * (f * (f2 - 2.0 * f + 1.0)) + t1 * (f2 * (f - 1.0))


def derivative(rows: np.ndarray, f: np.ndarray, k: int = 3) -> np.ndarray:
    """(m, k) d(point)/df at fractions f of segments (``evaluate``); divide by the segment's length
    for d/ds."""
    f = f[:, None]
    d, t0, t1 = rows[:, k:2 * k], rows[:, 2 * k:3 * k], rows[:, 3 * k:4 * k]
    return d * (6.0 * f * (1.0 - f)) + t0 * ((3.0 * f - 4.0) * f + 1.0) + t1 * ((3.0 * f - 2.0) * f)
