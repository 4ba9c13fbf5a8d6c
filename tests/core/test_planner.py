"""core.planner.Planner: the one place that knows what a parameter change invalidates, timings as a
record, and a safe plan where the schedule's synchronisation margins cannot make a path safe."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from core.errors import PlanningError
from core.planner import STAGE_INPUTS, Planner, stage_key
from core.records import PlanJob, PlanParameters, Timings
from core.schedule.safety import tip_spacing
from core.schedule.timeline import SafetyProfile

from ..conftest import COARSE as COARSE_PARAMS

COARSE = PlanParameters(**COARSE_PARAMS)


@pytest.fixture(scope="module")
def kept():
    """A planner keeping the sample's coarse paths with their fitted curves, and its job."""
    planner = Planner(keep=True)
    job = PlanJob("sample", "z", COARSE, axes=False)
    return planner, job, planner.plan(job, until="paths")


def test_each_input_invalidates_its_stage_and_the_later_ones(kept):
    planner, job, res = kept
    p = job.params.resolved()
    assert planner.reuse(job) == "schedule"
    for name in ("feed", "a_max", "mode"):
        changed = replace(job, params=replace(p, **{name: {"feed": 800.0, "a_max": 300.0, "mode": "single"}[name]}))
        assert planner.reuse(changed) == "schedule", name
    for change in ({"profile": "smooth"}, {"period": 5.0}, {"axes": True}, {"machine": "other.toml"},
                   {"chord_tol": 0.01}):
        assert planner.reuse(replace(job, **change)) == "schedule", change
    for name, value in (("h_safe", 2.2), ("k_max", 0.12)):
        assert planner.reuse(replace(job, params=replace(p, **{name: value}))) == "regions", name
    for name, value in (("dd", 0.4), ("tool_radius", 2.0), ("dr", 3.0), ("tool_length", 30.0)):
        assert planner.reuse(replace(job, params=replace(p, **{name: value}))) == "none", name
    assert planner.reuse(replace(job, axis="x")) == "none" and planner.reuse(replace(job, source="x.csv")) == "none"
    # the record lists every PlanJob field and every PlanParameters field once; but axes, which says
    # only whether the result keeps the axis tables (the job is the same either way)
    names = [n for names in STAGE_INPUTS.values() for n in names]
    job_fields = {"source", "axis", "profile", "period", "chord_tol", "machine", "tool"}
    assert {f.name for f in fields(PlanJob)} == job_fields | {"params", "axes"}
    assert sorted(names) == sorted(job_fields | {f"params.{f}" for f in p.as_dict()})
    assert stage_key(job, "paths")[:2] == ("sample", "z")


def test_new_regions_reuse_the_paths_and_match_a_fresh_plan(kept):
    planner, job, res = kept
    other = replace(job, params=replace(job.params, h_safe=2.2))
    again = Planner(keep=True).plan(other, until="paths")
    reused = Planner.seeded(res.plan).plan(other, until="paths")
    assert reused.reused == "regions" and reused.plan.paths is res.plan.paths
    for a, b, ra, rb in zip(reused.plan.pairs, again.plan.pairs, reused.plan.regions, again.plan.regions,
                            strict=True):
        assert np.array_equal(a.left_tip, b.left_tip) and np.array_equal(ra.labels, rb.labels)
    # a schedule input alone reuses the regions: the same pairs, the job's parameters
    feed = Planner.seeded(res.plan).plan(replace(job, params=replace(job.params, feed=800.0)), until="paths")
    assert feed.reused == "schedule" and feed.plan.pairs is res.plan.pairs and feed.plan.params.feed == 800.0


def test_timings_come_back_as_a_record_and_nothing_is_written_into_the_input(kept):
    _, job, res = kept
    before = dict(res.plan.timings)
    whole = Planner.seeded(res.plan).plan(job)
    assert isinstance(whole.timings, Timings) and "schedule_s" in whole.timings
    assert {"contour_paths_s", "regions_s", "paths_wall_s"} <= set(whole.timings)
    assert dict(res.plan.timings) == before and "schedule_s" not in res.plan.timings
    assert whole.timings.plus(x=1.0)["x"] == 1.0 and "x" not in whole.timings


def test_bad_inputs_are_refused_before_anything_is_loaded():
    planner = Planner()
    with pytest.raises(PlanningError, match="period-ms"):
        planner.plan(PlanJob("no such blade.csv", period=-1.0))
    with pytest.raises(PlanningError, match="until"):
        planner.plan(PlanJob(), until="schedule")


def test_paths_the_margins_cannot_make_safe_are_machined_single_sided():
    """With one round of synchronisation margins the sample's collaborative schedule breaks the safety
    rule round some transitions: those paths go single-sided (tip region, reason and warning
    recorded), and the plan keeps the rule everywhere, checked here on its time column."""
    params = PlanParameters()  # (the defaults: no coarser dR or smaller table found leaves a path unsafe)
    planner = Planner(workers=2, safety_rounds=1)
    full = planner.plan(PlanJob(params=params, axes=False), until="paths").plan
    res = planner.plan(PlanJob(params=params, axes=False))  # (on the same paths, planned once)
    assert res.reused == "schedule"
    moved = [pair.index for pair, a, b in zip(res.plan.pairs, full.regions, res.plan.regions, strict=True)
             if b.is_tip and not a.is_tip]
    assert moved, "one round of margins no longer leaves an unsafe transition: pick another case"
    for pair, reg in zip(res.plan.pairs, res.plan.regions, strict=True):
        if pair.index in moved:
            assert pair.kind == "single" and (reg.labels == "tip").all() and "safety rule" in reg.reason
    assert any(f"{moved[0]}" in w and "single-sided" in w for w in res.plan.warnings)
    assert res.safe and res.figures["spacing_violations"] == 0 and res.figures["capsule_violations"] == 0
    tl = res.timeline
    at, between = tip_spacing(tl.left.tips, tl.right.tips)
    h = params.resolved().h_safe
    assert min(at.min(), between.min()) >= h - 1e-9
    assert not SafetyProfile.of(tl, params.tool_radius, params.tool_length, h).unsafe.any()


def test_a_runaway_job_is_refused_by_the_planner_itself():
    """The work budget is the planner's: the workbench's re-plans are refused as the command line's
    are, at once and before any path is planned."""
    import time

    planner = Planner(keep=True)
    t0 = time.perf_counter()
    with pytest.raises(PlanningError, match="too big to compute.*--dd"):
        planner.plan(PlanJob(params=PlanParameters(dd=1e-3), axes=False))
    assert time.perf_counter() - t0 < 5.0 and planner.reuse(PlanJob(params=PlanParameters(dd=1e-3))) == "none"


def test_an_h_safe_change_turns_only_the_new_pairs_within_reach(monkeypatch):
    """The planner keeps the pairs it turned within the machines' reach: after an h_safe change only
    the pairs that changed (the paths newly in or out of the tip region) are done again, and the plan
    is the one a fresh planner makes."""
    import core.machine.reach as pp

    smoothed = []
    real = pp.single_sided_axes

    def counting(centres, *args):
        smoothed.append(len(centres))
        return real(centres, *args)

    monkeypatch.setattr(pp, "single_sided_axes", counting)
    planner = Planner(keep=True)
    job = PlanJob("sample", "z", COARSE, axes=False)
    first = planner.plan(job)
    tips_before = sum(r.is_tip for r in first.plan.regions)
    smoothed.clear()
    other = replace(job, params=replace(COARSE, h_safe=2.2))
    again = planner.plan(other)
    tips_after = sum(r.is_tip for r in again.plan.regions)
    assert tips_after > tips_before
    assert max(smoothed) <= tips_after - tips_before  # (per side: only the paths new to the tip region)
    fresh = Planner().plan(other)
    assert np.array_equal(again.timeline.t, fresh.timeline.t)
    np.testing.assert_allclose(again.timeline.left.tips, fresh.timeline.left.tips, atol=1e-9)
    np.testing.assert_allclose(again.timeline.right.axes, fresh.timeline.right.axes, atol=1e-9)


def test_a_speed_stage_that_cannot_keep_a_max_makes_its_path_single_sided(monkeypatch):
    """A path whose variable region is too short for its speed stage within a_max is machined
    single-sided with the reason recorded, every such path of a build at once, and the plan is
    safe: a valid job is never refused for it (the stages of two paths are made to fail here). With
    the paper's stages only (a minimum feed of 0); with a minimum feed the stage is cut at speed and
    waited out off the blade instead, and the paths stay collaborative."""
    import core.schedule.builder as builder

    real = builder.speed_stage
    failing: dict = {}

    def stage(length, *args):
        if len(failing) < 2 and length not in failing:
            failing[length] = True
        if length in failing:
            raise PlanningError(f"speed stage: {length:.4f} mm needs more than a_max (test)")
        return real(length, *args)

    monkeypatch.setattr(builder, "speed_stage", stage)
    res = Planner().plan(PlanJob("sample", "z", replace(COARSE, min_feed=0.0), axes=False))
    assert res.safe
    reason = "its speed stage cannot keep a_max (a variable region too short for the feed)"
    moved = [r for r in res.plan.regions if r.reason == reason]
    assert len(moved) == 2 and all(r.is_tip for r in moved)
    assert any("machined single-sided: its speed stage" in w for w in res.plan.warnings)
    lifted = Planner().plan(PlanJob("sample", "z", COARSE, axes=False))
    assert lifted.safe and not [r for r in lifted.plan.regions if r.reason == reason]
    lengths = {round(k, 6) for k in failing}
    hit = [s for s in lifted.schedule.stages if s.get("length_mm") in lengths]
    assert hit and all(s["kind"] == "lifted" for s in hit)


def test_a_released_planner_keeps_nothing_and_plans_again_from_the_start():
    """``release`` (the command line before its check, which then reuses the memory) forgets every
    stage kept: the blade, the paths, the blade index; the next plan builds them again."""
    planner = Planner(workers=1)
    job = PlanJob("sample", "z", PlanParameters(**COARSE_PARAMS))
    planner.plan(job, until="paths")
    assert planner.reuse(job) == "schedule" and planner.cache.slot("blade") is not None
    planner.release()
    assert all(planner.cache.slot(stage) is None for stage in ("blade", "paths", "reach", "mesh"))
    assert planner.reuse(job) == "none"
    assert planner.plan(job, until="paths").reused == "none"
