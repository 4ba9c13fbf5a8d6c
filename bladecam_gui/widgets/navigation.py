"""Where the timeline's jumps land, as time sample indices of a shown plan (no Qt here): a contour's
start, the seven steps' starts, the violations and the minimum spacing or clearance. ``None`` when
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
    d = np.asarray(data.danger, bool)
    return np.flatnonzero(d & ~np.concatenate([[False], d[:-1]]))


def violation(data: PlanData, i: int, direction: int) -> int | None:
    """The first sample of the next (+1) or previous (-1) violation (a run of danger samples)."""
    return _after(violation_starts(data), i, direction)


def minimum(data: PlanData, what: str) -> int:
    """The sample of the minimum 'spacing' (tip spacing) or 'clearance' (capsule clearance)."""
    return int(np.argmin(getattr(data, what)))


#: the kinds of a violation (a run of consecutive samples that break the safety rule)
SPACING, CLEARANCE = "tip spacing", "tool clearance"


def violation_list(data: PlanData) -> dict[str, np.ndarray]:
    """Every violation of a shown plan: a run of consecutive time samples that break the safety rule
    (data.danger; the timeline's red marks), one row each, in time order. Columns (k,): 'start',
    'end' (sample indices, inclusive), 't0', 't1' (ms), 'step' (at the start), 'left', 'right' (each
    cutter's path at the start), 'spacing_n' (samples and intervals between two samples of the run
    where the tip spacing is below h_safe), 'clearance_n' (samples where the tool capsules touch),
    'min_spacing' (mm, at or between samples), 'min_clearance' (mm), 'depth_spacing' (mm below
    h_safe, >= 0), 'depth_clearance' (mm of overlap of the capsules, >= 0) and 'kind' (str:
    SPACING, CLEARANCE or both joined by ' + ')."""
    from core.schedule.safety import violations

    tl, safety = data.timeline, data.result.safety
    d = np.asarray(data.danger, bool)
    f = np.diff(np.concatenate([[0], d.astype(np.int8), [0]]))
    start, end = np.flatnonzero(f == 1), np.flatnonzero(f == -1) - 1
    h = data.result.plan.params.h_safe
    bad_at, bad_between, bad_clear = violations(safety.at, safety.between, safety.clearance, h)
    if len(start) == 0:
        empty = np.zeros(0)
        return {name: empty for name in ("start", "end", "t0", "t1", "step", "left", "right", "spacing_n",
                                         "clearance_n", "min_spacing", "min_clearance", "depth_spacing",
                                         "depth_clearance")} | {"kind": np.zeros(0, object)}

    def run_sum(flags: np.ndarray, stop: np.ndarray) -> np.ndarray:  # flags[start:stop] per run
        c = np.concatenate([[0], np.cumsum(flags, dtype=np.int64)])
        return c[stop] - c[start]

    def run_min(values: np.ndarray, stop: np.ndarray) -> np.ndarray:  # min of values[start:stop] per run
        padded = np.concatenate([values, [np.inf]])
        bounds = np.column_stack([start, np.minimum(np.maximum(stop, start + 1), len(values))]).ravel()
        return np.where(stop > start, np.minimum.reduceat(padded, bounds)[::2], np.inf)

    # the intervals inside a run are start..end-1 (a violating interval marks both its samples)
    spacing_n = run_sum(bad_at, end + 1) + run_sum(bad_between, end)
    clearance_n = run_sum(bad_clear, end + 1)
    min_spacing = np.minimum(run_min(safety.at, end + 1), run_min(safety.between, end))
    min_clearance = run_min(safety.clearance, end + 1)
    kind = np.array([" + ".join(n for n, c in ((SPACING, a), (CLEARANCE, b)) if c) or SPACING
                     for a, b in zip(spacing_n, clearance_n, strict=True)], object)
    return {"start": start, "end": end, "t0": tl.t[start], "t1": tl.t[end], "step": data.step[start],
            "left": tl.left.path[start], "right": tl.right.path[start], "spacing_n": spacing_n,
            "clearance_n": clearance_n, "min_spacing": min_spacing, "min_clearance": min_clearance,
            "depth_spacing": np.maximum(h - min_spacing, 0.0),
            "depth_clearance": np.maximum(-min_clearance, 0.0), "kind": kind}
