"""What the workbench prepares from core's results (no window): drawn paths, bands, the safety rule's
rows, the jobs it plans (with the axis tables, the first one started ahead) and cancel reaching core."""

import numpy as np
import pytest

from bladecam_gui.plan_data import (
    DISPLAY_TOLERANCE,
    PlanJob,
    new_planner,
    path_lines,
    prepare,
    sample_job,
    step_bands,
)
from bladecam_gui.style import REGIONS
from core.errors import Cancelled
from core.records import PlanParameters

from .conftest import _CACHE, COARSE


@pytest.fixture(scope="module")
def coarse_plan():
    """The sample's coarse plan (shared with the window tests' cache: the same job, immutable)."""
    job = PlanJob("sample", "z", PlanParameters(**COARSE).resolved(), axes=True)
    if "sample" not in _CACHE:
        _CACHE["sample"] = prepare(job, None, new_planner())
    assert _CACHE["sample"].job == job
    return _CACHE["sample"]


def test_danger_is_the_safety_rule_of_core(coarse_plan):
    """The rows the plots mark as dangerous are those core's one safety rule marks (spacing below h_safe
    at or next to a row, or the tools overlapping), recomputed here from the figures shown."""
    data = coarse_plan
    h = data.result.plan.params.h_safe
    at, between = data.spacing, data.result.safety.between
    expect = (at < h - 1e-9) | (data.clearance < -1e-9)
    expect[:-1] |= between < h - 1e-9
    expect[1:] |= between < h - 1e-9
    np.testing.assert_array_equal(data.danger, expect)
    violations = int((at < h - 1e-9).sum() + (between < h - 1e-9).sum())
    assert data.result.figures["spacing_violations"] == violations


def test_drawn_paths_keep_every_region_change_and_end(coarse_plan):
    plan = coarse_plan.result.plan
    full, thin = path_lines(plan, 0.0), path_lines(plan)
    assert len(thin.points) < len(full.points) / 1.5
    # every drawn point is a planned point, and each region keeps its segments
    planned = {tuple(p) for p in np.round(full.points, 9)}
    assert all(tuple(p) in planned for p in np.round(thin.points, 9))
    for name, (code, _) in REGIONS.items():
        assert (full.region == code).any() == (thin.region == code).any(), name
    # both ends of every pair path are drawn
    ends = np.concatenate([[pair.left_tip[0], pair.left_tip[-1], pair.right_tip[0], pair.right_tip[-1]]
                           for pair in plan.pairs])
    drawn = {tuple(p) for p in np.round(thin.points, 9)}
    assert all(tuple(p) in drawn for p in np.round(ends, 9))
    # cells are 2-point lines between consecutive kept points of one path
    cells = thin.cells.reshape(-1, 3)
    assert (cells[:, 0] == 2).all() and (cells[:, 2] == cells[:, 1] + 1).all()
    assert len(cells) == len(thin.points) - 2 * len(plan.pairs)
    # every planned point lies within about the display tolerance of the drawn chord over it
    for tol in (DISPLAY_TOLERANCE, 4 * DISPLAY_TOLERANCE):
        lines = path_lines(plan, tolerance=tol)
        worst = 0.0
        drawn = {tuple(p) for p in np.round(lines.points, 9)}
        for pair in plan.pairs:
            for tip in (pair.left_tip, pair.right_tip):
                kept = [k for k, p in enumerate(np.round(tip, 9)) if tuple(p) in drawn]
                for a, b in zip(kept[:-1], kept[1:], strict=True):
                    u = tip[b] - tip[a]
                    q = tip[a + 1:b] - tip[a]
                    s = np.clip(q @ u / (u @ u), 0.0, 1.0)
                    worst = max(worst, float(np.linalg.norm(q - s[:, None] * u, axis=1).max(initial=0.0)))
        assert tol / 4 < worst < 1.5 * tol


def test_bands_and_samples(coarse_plan):
    data = coarse_plan
    t = data.timeline.t
    b = step_bands(t, data.step)
    assert b[0, 0] == 0.0 and b[-1, 1] == t[-1]
    np.testing.assert_array_equal(b[1:, 0], b[:-1, 1])  # contiguous
    assert (np.diff(b[:, 2]) != 0).all()
    assert data.index_at(-5.0) == 0 and data.index_at(1e12) == len(t) - 1
    mid = 0.5 * (t[10] + t[11])
    assert data.index_at(mid - 1e-6) == 10 and data.index_at(mid + 1e-6) == 11
    assert data.spacing.shape == data.clearance.shape == data.speed_left.shape == t.shape
    assert data.speed_left.max() <= 3.0 * data.result.plan.params.feed * 1.001  # rapids at 3 x the feed


def test_the_workbench_plans_the_job_an_export_writes(coarse_plan):
    """Every job the workbench plans (the first one, started ahead at launch, and the state's) asks
    for the axis tables; the plan shown has them on its time column, the rows t = k * period."""
    from bladecam_gui.state import WorkbenchState

    params = PlanParameters(**COARSE).resolved()
    assert sample_job(params) == WorkbenchState(params=params).job() == coarse_plan.job
    assert sample_job().axes
    res = coarse_plan.result
    for side in ("left", "right"):
        np.testing.assert_array_equal(res.axes[side].t, res.timeline.t)
    k = res.timeline.t / res.period
    np.testing.assert_allclose(k, np.round(k), rtol=0, atol=1e-6)


def test_prepare_stops_when_cancelled():
    job = PlanJob("sample", "z", PlanParameters(**COARSE).resolved())
    with pytest.raises(Cancelled):
        prepare(job, None, new_planner(), cancelled=lambda: True)
