"""plan.json's collaboration figures (core.schedule.figures.collaboration) against a brute-force
count over the time column's intervals, and the path counts against the regions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.planner import Planner
from core.records import PlanJob, PlanParameters


@pytest.fixture(scope="module")
def result():
    return Planner().plan(PlanJob(params=PlanParameters(dr=4.0, dd=0.5), axes=False))


def _brute_force(res):
    tl, p = res.timeline, res.plan.params
    n = len(tl.t)
    sides = (tl.left, tl.right)
    centre = [s.tips + p.tool_radius * s.axes for s in sides]
    # distance between the ball centres across the left tool axis (the torsional lever arm)
    d = centre[0] - centre[1]
    off = np.linalg.norm(np.cross(d, tl.left.axes), axis=1)
    length = {"collaborative": 0.0, "supported": 0.0, "single_sided": 0.0}
    time_ms = {"collaborative": 0.0, "supported": 0.0, "single_sided": 0.0}
    for i in range(n - 1):
        both = all(s.cutting[i] and s.cutting[i + 1] for s in sides)
        supported = both and off[i] < 1e-3 and off[i + 1] < 1e-3
        coll_any = tip_any = False
        for s in sides:
            if not (s.cutting[i] and s.cutting[i + 1]):
                continue
            seg = math.dist(s.tips[i], s.tips[i + 1])
            if s.region[i] == "tip":
                length["single_sided"] += seg
                tip_any = True
            else:
                length["collaborative"] += seg
                coll_any = True
                if supported:
                    length["supported"] += seg
        dt = tl.t[i + 1] - tl.t[i]
        if coll_any:
            time_ms["collaborative"] += dt
            if supported:
                time_ms["supported"] += dt
        elif tip_any:
            time_ms["single_sided"] += dt
    return length, {k: v / 1000.0 for k, v in time_ms.items()}


def test_collaboration_figures_match_a_brute_force_count(result):
    fig = result.figures["collaboration"]
    length, time_s = _brute_force(result)
    for k in length:
        assert fig["cutting_length_mm"][k] == pytest.approx(length[k], rel=1e-6, abs=1e-3), k
        assert fig["job_time_s"][k] == pytest.approx(time_s[k], rel=1e-6, abs=1e-3), k
    total_length = length["collaborative"] + length["single_sided"]
    assert fig["cutting_length_share"]["collaborative"] == pytest.approx(length["collaborative"] / total_length,
                                                                          abs=1e-6)
    job = (result.timeline.t[-1] - result.timeline.t[0]) / 1000.0
    assert fig["job_time_share"]["single_sided"] == pytest.approx(time_s["single_sided"] / job, abs=1e-6)
    assert fig["cutting_length_share"]["supported"] == pytest.approx(
        result.figures["support"]["supported_cutting_share"], abs=1e-6)


def test_collaboration_paths_count_the_regions(result):
    fig = result.figures["collaboration"]
    regions = result.plan.regions
    tip = [r for r in regions if r.is_tip]
    assert fig["paths"] == {"total": len(regions), "collaborative": len(regions) - len(tip),
                            "single_sided": len(tip),
                            "collaborative_share": round((len(regions) - len(tip)) / len(regions), 6)}
    assert sum(fig["tip_reasons"].values()) == len(tip)
    assert 0 < fig["paths"]["collaborative"] < fig["paths"]["total"]


@pytest.mark.parametrize("mode", ["symmetric", "single"])
def test_the_other_modes_are_wholly_symmetric_or_single_sided(mode):
    res = Planner().plan(PlanJob(params=PlanParameters(dr=6.0, dd=0.5, mode=mode), axes=False))
    fig = res.figures["collaboration"]
    n = len(res.plan.regions)
    if mode == "symmetric":
        assert fig["paths"]["collaborative"] == n and fig["cutting_length_mm"]["single_sided"] == 0.0
        assert fig["cutting_length_share"]["collaborative"] == 1.0 and fig["tip_reasons"] == {}
    else:
        assert fig["paths"]["single_sided"] == n and fig["cutting_length_mm"]["collaborative"] == 0.0
        assert fig["cutting_length_share"]["single_sided"] == 1.0 and fig["tip_reasons"] == {"single mode": n}
        assert fig["job_time_s"]["supported"] == 0.0


def test_step_times_walk_the_time_column(result):
    """plan.json's step_time_s: each interval between two samples counted for the job's step at its
    first sample (the earlier of the two cutters' steps), by walking the column; they add up to the
    total time."""
    tl = result.timeline
    walked = dict.fromkeys(range(1, 8), 0.0)
    left, right = tl.left.step.tolist(), tl.right.step.tolist()
    t = tl.t.tolist()
    for i in range(len(t) - 1):
        walked[min(left[i], right[i])] += (t[i + 1] - t[i]) / 1000.0
    fig = result.figures["step_time_s"]
    assert set(fig) == {str(k) for k in range(1, 8)}
    for k in range(1, 8):
        assert fig[str(k)] == pytest.approx(walked[k], abs=2e-3)
    assert sum(fig.values()) == pytest.approx(result.figures["total_time_s"], abs=1e-2)
    assert all(fig[str(k)] > 0 for k in range(1, 8))  # the sample's plan has every step


def test_step_times_of_a_plan_without_collaborative_paths():
    """The leading cutter returns (its step 7) while the subsequent one machines the tip region: that
    time is step 2's, and step 7 only the time both spend returning."""
    from core.schedule.step_times import step_times

    t = np.arange(0.0, 7000.0, 1000.0)  # ms
    left = np.array([1, 1, 7, 7, 7, 7, 7])
    right = np.array([1, 1, 2, 2, 2, 7, 7])
    assert step_times(t, left, right) == {"1": 2.0, "2": 3.0, "3": 0.0, "4": 0.0, "5": 0.0, "6": 0.0,
                                          "7": 1.0}
