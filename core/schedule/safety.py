"""Safety figures of a sampled schedule: tip spacing (at and between samples) and capsule clearance.

Each tool body is a capsule: the ball of radius r swept along the axis from the ball centre for the
tool's stick-out length. Between two samples both tips move linearly, so the smallest tip distance
on that interval has a closed form.
"""

from __future__ import annotations

import numpy as np

from core.util.parallel import ROW_BLOCK
from core.util.polyline import ball_centres


def _columns(*arrays: np.ndarray) -> list[np.ndarray]:
    """(n, 3) arrays -> (3, n) contiguous copies: products and sums of components then run on whole
    rows of memory (several times faster than reductions along a length-3 axis)."""
    return [np.ascontiguousarray(np.asarray(v, float).T) for v in arrays]


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (3, n) arrays -> (n,)."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def tip_spacing(tips_l: np.ndarray, tips_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3), (n, 3) mm -> (at samples (n,), minimum on each interval (n-1,)) mm (in blocks of rows)."""
    n = len(tips_l)
    at, between = np.empty(n), np.empty(max(n - 1, 0))
    for lo in range(0, n, ROW_BLOCK):
        hi = min(lo + ROW_BLOCK, n)
        a, b = _tip_spacing(tips_l[lo:hi + 1], tips_r[lo:hi + 1])  # (one row more: the interval after)
        at[lo:hi], between[lo:min(hi, n - 1)] = a[:hi - lo], b
    return at, between


def _tip_spacing(tips_l: np.ndarray, tips_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    tl, tr = _columns(tips_l, tips_r)
    d = tl - tr
    at = np.sqrt(_dot(d, d))
    a, b = d[:, :-1], d[:, 1:] - d[:, :-1]
    bb = _dot(b, b)
    s = np.clip(np.where(bb > 0, -_dot(a, b) / np.where(bb > 0, bb, 1.0), 0.0), 0.0, 1.0)
    g = a + s * b
    return at, np.sqrt(_dot(g, g))


def segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Smallest distance between segments p0-p1 and q0-q1, row by row: (n, 3) each -> (n,)."""
    p0, p1, q0, q1 = _columns(p0, p1, q0, q1)
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = _dot(d1, d1), _dot(d2, d2)
    b, c, f = _dot(d1, d2), _dot(d1, r), _dot(d2, r)
    denom = a * e - b * b
    s = np.where(denom > 1e-12, np.clip((b * f - c * e) / np.where(denom > 1e-12, denom, 1.0), 0, 1), 0.0)
    t = np.where(e > 0, (b * s + f) / np.where(e > 0, e, 1.0), 0.0)
    t_c = np.clip(t, 0, 1)
    s = np.where(t != t_c, np.clip(np.where(a > 0, (b * t_c - c) / np.where(a > 0, a, 1.0), 0.0), 0, 1), s)
    g = r + d1 * s - d2 * t_c
    return np.sqrt(_dot(g, g))


def capsule_clearance(tips_l, axes_l, tips_r, axes_r, tool_radius: float, stick_out: float) -> np.ndarray:
    """(n,) mm: distance between the two tool capsules (negative = they overlap); in blocks of rows."""
    n = len(tips_l)
    out = np.empty(n)
    for lo in range(0, n, ROW_BLOCK):
        hi = min(lo + ROW_BLOCK, n)
        out[lo:hi] = _capsule_clearance(tips_l[lo:hi], axes_l[lo:hi], tips_r[lo:hi], axes_r[lo:hi],
                                        tool_radius, stick_out)
    return out


def _capsule_clearance(tips_l, axes_l, tips_r, axes_r, tool_radius: float, stick_out: float) -> np.ndarray:
    cl, cr = ball_centres(tips_l, axes_l, tool_radius), ball_centres(tips_r, axes_r, tool_radius)
    return segment_distance(cl, cl + stick_out * axes_l, cr, cr + stick_out * axes_r) - 2 * tool_radius


#: mm: how far below h_safe a tip spacing (or below 0 a clearance) must be to count as a violation; a
#: margin for rounding only (the tables' tips are written to 1e-10 mm)
VIOLATION_TOL = 1e-9


def violations(at: np.ndarray, between: np.ndarray, clearance: np.ndarray, h_safe: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The safety rule of the collaborative method, the one used by the schedule, its figures and the
    workbench: the tip spacing must stay at least h_safe at the samples (n,) and between them (n-1,),
    and the two tool capsules must not overlap (clearance (n,) >= 0). Returns the violating samples,
    intervals and clearances as bool masks of the same shapes."""
    return at < h_safe - VIOLATION_TOL, between < h_safe - VIOLATION_TOL, clearance < -VIOLATION_TOL


def unsafe_samples(at: np.ndarray, between: np.ndarray, clearance: np.ndarray, h_safe: float) -> np.ndarray:
    """(n,) bool: the samples that break the safety rule (``violations``), a sample next to a violating
    interval included."""
    bad_at, bad_between, bad_clear = violations(at, between, clearance, h_safe)
    bad = bad_at | bad_clear
    bad[:-1] |= bad_between
    bad[1:] |= bad_between
    return bad


def transition_paths(left_path: np.ndarray, right_path: np.ndarray) -> set[int]:
    """The paths round whose transitions samples fall, from both cutters' path indices there (-1: a
    cutter on no path): the lower index of the two cutters' (the path the later one is leaving), or the
    one path when only one cutter is on a path."""
    lp, rp = np.asarray(left_path), np.asarray(right_path)
    key = np.where((lp >= 0) & (rp >= 0), np.minimum(lp, rp), np.maximum(lp, rp))
    return {int(k) for k in np.unique(key[key >= 0])}
