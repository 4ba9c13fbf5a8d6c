"""Where the timeline's jumps land, as time sample indices of a shown plan (no Qt here): a contour's
start, the step boundaries, the violations and the minimum spacing or clearance. ``None`` when
there is nowhere to go."""

from __future__ import annotations

import numpy as np

from ..plan_data import PlanData


def contour_start(data: PlanData, contour: int) -> int | None:
    """The first sample at which either cutter cuts contour ``contour`` (else is on it)."""
    tl = data.timeline
    best = None
    for s in (tl.left, tl.right):
        for on in (s.path == contour) & s.cutting, s.path == contour:
            hit = np.flatnonzero(on)
            if len(hit):
                best = int(hit[0]) if best is None else min(best, int(hit[0]))
                break
    return best


def contour_range(data: PlanData) -> tuple[int, int]:
    tl = data.timeline
    paths = np.concatenate([tl.left.path, tl.right.path])
    paths = paths[paths >= 0]
    return (int(paths.min()), int(paths.max())) if len(paths) else (0, 0)


def contour_at(data: PlanData, i: int) -> int:
    """The contour at sample i: the one cut (the left cutter's when both cut), else the left's."""
    tl = data.timeline
    for s in (tl.left, tl.right):
        if s.cutting[i] and s.path[i] >= 0:
            return int(s.path[i])
    return int(max(tl.left.path[i], tl.right.path[i]))


def _after(starts: np.ndarray, i: int, direction: int) -> int | None:
    if direction > 0:
        later = starts[starts > i]
        return int(later[0]) if len(later) else None
    earlier = starts[starts < i]
    return int(earlier[-1]) if len(earlier) else None


def step_boundary(data: PlanData, i: int, direction: int) -> int | None:
    """The next (+1) or previous (-1) sample where the step changes (the previous one: the start
    of the current step band, or of the band before when at its start); the job's ends last."""
    starts = np.concatenate([[0], np.flatnonzero(np.diff(data.step)) + 1, [len(data.step) - 1]])
    return _after(starts, i, direction)


def step_start(data: PlanData, step: int) -> int | None:
    """The first sample of step ``step`` (1-7)."""
    hit = np.flatnonzero(data.step == step)
    return int(hit[0]) if len(hit) else None


def violation_starts(data: PlanData) -> np.ndarray:
    d = np.asarray(data.danger, bool)
    return np.flatnonzero(d & ~np.concatenate([[False], d[:-1]]))


def violation(data: PlanData, i: int, direction: int) -> int | None:
    """The first sample of the next (+1) or previous (-1) violation (a run of danger samples)."""
    return _after(violation_starts(data), i, direction)


def minimum(data: PlanData, what: str) -> int:
    """The sample of the minimum 'spacing' (tip spacing) or 'clearance' (capsule clearance)."""
    return int(np.argmin(getattr(data, what)))
