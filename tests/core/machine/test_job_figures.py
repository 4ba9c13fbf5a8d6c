"""plan.json's "job" figures (core.machine.job_figures) against independent computations from the rows
of a machine-timed plan, and the minimum feed rule of the speed stages (core.schedule.min_feed)."""

from __future__ import annotations

import numpy as np
import pytest

from core.planner import Planner
from core.records import PlanJob, PlanParameters


@pytest.fixture(scope="module")
def result():
    return Planner().plan(PlanJob(params=PlanParameters(dr=4.0, dd=0.5), axes=True))


def _cut_intervals(smp):
    """Per row interval: whether it cuts (both rows cutting one path), by a loop."""
    out = []
    for k in range(len(smp.cutting) - 1):
        out.append(bool(smp.cutting[k] and smp.cutting[k + 1] and smp.path[k] == smp.path[k + 1]))
    return out


def test_cutting_speeds_from_the_rows(result):
    job = result.figures["job"]
    tl = result.timeline
    feed = result.plan.params.feed
    min_feed = result.plan.params.min_feed
    total = below_min = below_30 = crawl = 0.0
    episodes = 0
    for smp in (tl.left, tl.right):
        cut = _cut_intervals(smp)
        was_slow = False
        for k, c in enumerate(cut):
            dt = tl.t[k + 1] - tl.t[k]
            v = float(np.linalg.norm(smp.tips[k + 1] - smp.tips[k])) / dt * 60000.0  # mm/min
            slow = c and v < 0.05 * feed
            if c:
                total += dt
                below_min += dt if v < min_feed else 0.0
                below_30 += dt if v < 0.3 * feed else 0.0
                crawl += dt if slow else 0.0
            episodes += int(slow and not was_slow)
            was_slow = slow
    got = job["cutting"]
    assert got["cutting_time_s"] == pytest.approx(total / 1000.0, abs=2e-3)
    assert got["share_below_min_feed"] == pytest.approx(below_min / total, abs=2e-6)
    assert got["share_below_30pct_feed"] == pytest.approx(below_30 / total, abs=2e-6)
    assert got["time_below_5pct_feed_s"] == pytest.approx(crawl / 1000.0, abs=2e-3)
    assert got["episodes_below_5pct_feed"] == episodes


def test_times_and_steps_from_the_rows(result):
    job = result.figures["job"]
    tl = result.timeline
    assert job["time_on_machines_s"] == pytest.approx(tl.t[-1] / 1000.0, abs=1e-3)
    assert job["job_over_optimal"] == pytest.approx(job["time_on_machines_s"] / job["time_optimal_s"], abs=1e-3)
    # the optimum is a lower bound of the job, per kind of stretch too (round-off aside)
    assert job["time_optimal_s"] <= job["time_on_machines_s"] * (1 + 1e-6)
    for kind in job["per_kind"].values():
        assert kind["ratio"] >= 0.99
    for step, got in job["steps"].items():
        s = int(step)
        dt = np.diff(tl.t)
        left = sum(d for d, st in zip(dt, tl.left.step[:-1], strict=True) if st == s)
        either = sum(d for d, a, b in zip(dt, tl.left.step[:-1], tl.right.step[:-1], strict=True) if s in (a, b))
        assert got["left_s"] == pytest.approx(left / 1000.0, abs=2e-3)
        assert got["either_s"] == pytest.approx(either / 1000.0, abs=2e-3)
    assert result.figures["machine"]["time_at_feed_s"] == job["time_at_feed_s"]
    assert job["time_at_feed_s"] < job["time_on_machines_s"]


def test_feed_cuts_cover_the_slow_cutting_rows(result):
    """Every row interval in which a cutter cuts below 97 % of the feed lies in a reported feed cut of
    that cutter, and each cut's lowest speed is the rows' own."""
    job = result.figures["job"]
    tl = result.timeline
    feed = result.plan.params.feed
    cuts = job["feed_cuts"]
    assert cuts, "the sample's tip paths slow down round their ends"
    for side, smp in (("left", tl.left), ("right", tl.right)):
        mine = [c for c in cuts if c["side"] == side]
        starts = np.array([c["t0_s"] for c in mine])
        ends = np.array([c["t1_s"] for c in mine])
        cut = _cut_intervals(smp)
        for k in np.flatnonzero(cut)[::7]:
            v = float(np.linalg.norm(smp.tips[k + 1] - smp.tips[k])) / (tl.t[k + 1] - tl.t[k]) * 60000.0
            if v < 0.97 * feed * (1 - 1e-6):
                t = tl.t[k] / 1000.0
                assert ((starts <= t + 1e-3) & (ends >= t - 1e-3)).any(), (side, t, v)


def test_speed_stages_keep_the_minimum_feed_or_say_why(result):
    """A machine-timed speed stage's lowest speed is at least the minimum feed, unless its record says
    why not (and plan.json lists it with its time)."""
    params = result.plan.params
    listed = {(s["path"], s["cutter"]) for s in result.figures["job"]["stages_below_min_feed"]}
    stages = [s for s in result.schedule.stages if s.get("kind") == "machine plateau"]
    assert stages
    for st in stages:
        if st["lowest_speed_mm_min"] < params.min_feed * (1 - 1e-6):
            assert "below_min_feed" in st and (st["path"], st["cutter"]) in listed, st
