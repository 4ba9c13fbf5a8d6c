"""Where the timeline's jumps land, as time sample indices of a shown plan (no Qt here): a contour's
start, the seven steps' starts, the violations and the minimum spacing or clearance. ``None`` when
there is nowhere to go."""

from __future__ import annotations

import numpy as np

from ..plan_data import PlanData
from ..verdict import Violations, find_violations


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


def step_starts(data: PlanData) -> dict[int, int]:
    """step (1-7) -> its first sample, for the steps the plan has, in time order (steps 4-6 repeat per
    contour: step 5's first sample comes before step 4's, the first path starting symmetrically in
    step 3)."""
    step = np.asarray(data.step)
    steps, first = np.unique(step, return_index=True)
    order = np.argsort(first)
    return {int(steps[k]): int(first[k]) for k in order}


def step_boundary(data: PlanData, i: int, direction: int) -> int | None:
    """The next (+1) or previous (-1) start of one of the seven steps (step_starts: the samples
    Alt+1 ... Alt+7 go to, in time order), then the job's end."""
    starts = np.array(sorted(set(step_starts(data).values()) | {len(data.step) - 1}))
    return _after(starts, i, direction)


def step_start(data: PlanData, step: int) -> int | None:
    """The first sample of step ``step`` (1-7)."""
    hit = np.flatnonzero(data.step == step)
    return int(hit[0]) if len(hit) else None


def violation_starts(data: PlanData) -> np.ndarray:
    """The first sample of each violation (verdict.Violations: a run of danger samples)."""
    return np.asarray(violations_of(data).rows["start"], np.int64)


def violation(data: PlanData, i: int, direction: int) -> int | None:
    """The first sample of the next (+1) or previous (-1) violation (a run of danger samples)."""
    return _after(violation_starts(data), i, direction)


def minimum(data: PlanData, what: str) -> int:
    """The sample of the minimum 'spacing' (tip spacing) or 'clearance' (capsule clearance)."""
    return int(np.argmin(getattr(data, what)))


def violations_of(data: PlanData) -> Violations:
    """The violations of a shown plan with its schedule (verdict.Violations): those found with the plan
    (plan_data.prepare), or found here for a PlanData made without them."""
    if data.violations is not None:
        return data.violations
    return find_violations(data.result, data.danger, data.step)


def violation_list(data: PlanData) -> dict[str, np.ndarray]:
    """Every violation of a shown plan, one row per run of consecutive time samples that break the
    safety rule or collide (data.danger; the timeline's red marks), in time order: the columns of
    verdict.Violations.rows."""
    return violations_of(data).rows
