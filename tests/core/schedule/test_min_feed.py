"""The minimum cutting feed in the schedule: a speed stage that would cut below it is cut at speed and
waited out off the blade (core.schedule.builder.MoveBuilder.lifted_stage). Checked against the same
schedule with the paper's stages, sampled on a fine time column: the synchronisation points and the
job's duration are the same, no cutting cutter runs below the minimum except while it starts or
stops at rest, the waiting cutter is off the blade, and the safety rule holds."""

from __future__ import annotations

import numpy as np
import pytest

from core.schedule.motion import ramp_time
from core.schedule.safety import capsule_clearance, tip_spacing, unsafe_samples
from core.schedule.steps import ScheduleOptions, checked_schedule

MIN_FEED = 300.0  # mm/min, at the feed 1000


@pytest.fixture(scope="module")
def both(sample_paths):
    """(paths, the schedule with the paper's stages, the schedule with MIN_FEED), both checked."""
    plan = sample_paths(dr=2.0)
    paper, _, bad_paper = checked_schedule(plan, ScheduleOptions())
    kept, _, bad_kept = checked_schedule(plan, ScheduleOptions(min_feed=MIN_FEED))
    assert not bad_paper and not bad_kept  # (the safety rule holds round every transition)
    return plan, paper, kept


def test_the_stages_below_the_minimum_are_lifted(both):
    _, paper, kept = both
    lows = [s for s in paper.stages if s.get("kind") not in ("wait", "constant")]
    lifted = [s for s in kept.stages if s.get("kind") == "lifted"]
    assert lows and len(lifted) >= len(lows) // 2
    for s in lifted:
        assert s["wait_ms"] >= 0.0 and s["duration_ms"] > 0.0


def test_synchronisation_points_and_duration_are_kept(both):
    """The stages last as long as the paper's: the job and every instant at which both cutters start a
    move together are the same."""
    _, paper, kept = both
    assert kept.duration == pytest.approx(paper.duration, abs=1e-6)

    def common(sch):
        return np.intersect1d(np.round(sch.left_table.t0, 6), np.round(sch.right_table.t0, 6))

    shared = np.intersect1d(common(paper), common(kept))
    assert len(shared) >= 0.9 * len(common(paper))
    for sch in (paper, kept):
        for side in ("left", "right"):
            tab = sch.table(side)
            steps = tab.step[np.searchsorted(tab.t0, shared, side="right") - 1]
            assert steps.min() >= 1


def _speeds(sch, side, t):
    smp = sch.table(side).sample(t)
    v = np.linalg.norm(np.diff(smp.tips, axis=0), axis=1) / np.diff(t)
    cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == smp.path[1:])
    return smp, v, cut


def _rests(sch, side) -> np.ndarray:
    """ms: the instants at which a cutter stands still, from its moves' speed laws (a move that starts
    or ends at rest)."""
    out = []
    for m in (sch.left if side == "left" else sch.right):
        law = m.law
        if law.duration <= 0:
            continue
        if float(law.speed(0.0)) <= 1e-12:
            out.append(m.t0)
        if float(law.speed(law.duration)) <= 1e-12:
            out.append(m.t1)
    return np.array(sorted(out))


def test_no_cutting_below_the_minimum_but_starting_or_stopping(both):
    """On a 2 ms column: every interval in which a cutter cuts below the minimum feed in steps 5-7 lies
    within a ramp's time from the feed of an instant at which it stands still (a stop at a corner, a
    path's end, the lifted stage's stop and start); with the paper's stages the stages cut below it
    for far longer."""
    _, paper, kept = both
    dt = 2.0
    t = np.arange(0.0, kept.duration, dt)
    v_min = MIN_FEED / 60000.0
    ramp = ramp_time(1000.0 / 60000.0, 500e-6) + 2 * dt  # ms: a ramp from rest to the feed at a_max
    slow_time = {}
    for name, sch in (("paper", paper), ("kept", kept)):
        total = 0.0
        for side in ("left", "right"):
            smp, v, cut = _speeds(sch, side, t)
            slow = cut & np.isin(smp.step[:-1], (5, 6, 7)) & (v < v_min)
            total += dt * slow.sum()
            if name == "kept" and slow.any():
                rests = _rests(sch, side)
                mid = t[:-1][slow] + 0.5 * dt
                at = np.clip(np.searchsorted(rests, mid), 1, len(rests) - 1)
                near = np.minimum(np.abs(rests[at] - mid), np.abs(rests[at - 1] - mid))
                assert (near <= ramp).all(), (side, mid[near > ramp][:5])
        slow_time[name] = total
    assert slow_time["kept"] < 0.1 * slow_time["paper"]


def test_the_waiting_cutter_is_off_the_blade(both):
    """While a lifted stage waits, the cutter stands STAGE_LIFT from where it stopped, not cutting."""
    from core.schedule.builder import STAGE_LIFT

    _, _, kept = both
    found = 0
    for side in ("left", "right"):
        moves = kept.left if side == "left" else kept.right
        for a, b, c in zip(moves[:-2], moves[1:-1], moves[2:], strict=True):
            if a.cutting and not b.cutting and type(c.law).__name__ == "WaitLaw" and a.step in (5, 6, 7) \
                    and b.path == a.path and len(b.points) == 2:
                assert np.linalg.norm(b.points[-1] - a.points[-1]) == pytest.approx(STAGE_LIFT, abs=1e-9)
                assert np.allclose(c.points[0], b.points[-1])
                found += 1
    assert found > 0


def test_the_safety_rule_holds_on_a_fine_column(both):
    plan, paper, kept = both
    t = np.arange(0.0, kept.duration, 5.0)
    left, right = kept.sample(t)
    at, between = tip_spacing(left.tips, right.tips)
    clear = capsule_clearance(left.tips, left.axes, right.tips, right.axes, plan.params.tool_radius,
                              plan.params.tool_length)
    assert not unsafe_samples(at, between, clear, plan.params.h_safe).any()
