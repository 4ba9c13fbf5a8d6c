"""The collaborative schedule's safety rounds (core.schedule.steps.checked_schedule): each round moves
every violating transition at once, by twice its last move when it breaks the rule again; a transition
whose margin no longer moves its synchronisation is given up at once; and what the rounds found
carries over to the next schedule of the same paths (the planner's, after some paths went single-sided).

The whole-job check here is a stand-in that flags chosen transitions until their synchronisation lies
a chosen number of points inside the paths (read back from the schedule's own stage records), so that
the rounds' arithmetic is checked on a real schedule of the sample blade without a blade that needs it."""

from __future__ import annotations

import numpy as np
import pytest

from core.schedule.steps import ScheduleMemory, ScheduleOptions, checked_schedule, sync_shifts


@pytest.fixture(scope="module")
def plan(sample_paths):
    return sample_paths(dr=4.0)


def _transitions(plan) -> list[int]:
    """Two collaborative paths from the middle of the blade that hand over to a next collaborative path
    (long enough for every shift tried here)."""
    coll = [p.index for p, r in zip(plan.pairs, plan.regions, strict=True) if not r.is_tip]
    return coll[len(coll) // 2:len(coll) // 2 + 2]


class NeedsShift:
    """A whole-job check that flags path ``k``'s transition while its synchronisation shift is below
    ``need[k]`` points; records the shifts it saw per call."""

    def __init__(self, need: dict[int, int]):
        self.need, self.seen = need, []

    def __call__(self, sch) -> set[int]:
        shifts = sync_shifts(sch)
        self.seen.append({k: shifts.get(k, 0) for k in self.need})
        return {k for k, n in self.need.items() if shifts.get(k, 0) < n}


def _step(plan) -> int:
    return max(2, int(np.ceil(0.5 / plan.params.dd)))


def test_a_round_moves_every_violating_transition_and_doubles_its_move(plan):
    """Two transitions needing 5 and 11 moves' worth of points are safe after 3 and 4 flagged rounds
    (1 + 2 + 4 + 8 steps >= 11), both in the same rounds; one step per round took 11."""
    step = _step(plan)
    a, b = _transitions(plan)[:2]
    check = NeedsShift({a: 5 * step, b: 11 * step})
    sch, _, bad = checked_schedule(plan, ScheduleOptions(max_rounds=8), whole_job=check)
    assert not bad
    assert len(check.seen) == 5  # rounds flagged with shifts 0, 1, 3, 7 steps, then clean at 15
    assert [s[b] for s in check.seen] == [0, step, 3 * step, 7 * step, 15 * step]
    assert [s[a] for s in check.seen] == [0, step, 3 * step, 7 * step, 7 * step]
    assert sync_shifts(sch)[a] == 7 * step and sync_shifts(sch)[b] == 15 * step


def test_a_transition_whose_margin_no_longer_moves_is_given_up_at_once(plan):
    """A transition that no margin can fix (flagged whatever its shift) ends the rounds as soon as its
    synchronisation stops moving (the symmetrical stretch used up), long before max_rounds."""
    a = _transitions(plan)[0]
    check = NeedsShift({a: 10**9})
    sch, _, bad = checked_schedule(plan, ScheduleOptions(max_rounds=40), whole_job=check)
    assert bad == {a}
    shifts = [s[a] for s in check.seen]
    assert shifts[-1] == shifts[-2] > 0  # (it stopped moving, and that ended it)
    assert len(check.seen) < 12


def test_what_the_rounds_found_carries_over_to_the_next_schedule(plan):
    """The planner's next schedule of the same paths (after some went single-sided) starts from the
    margins the last one found: it is safe at its first build, and a forgotten path starts over."""
    step = _step(plan)
    a, b = _transitions(plan)[:2]
    memory = ScheduleMemory()
    checked_schedule(plan, ScheduleOptions(max_rounds=8), whole_job=NeedsShift({a: 3 * step, b: 3 * step}),
                     memory=memory)
    assert memory.margins[a] >= 3 * step and memory.margins[b] >= 3 * step
    again = NeedsShift({a: 3 * step, b: 3 * step})
    checked_schedule(plan, ScheduleOptions(max_rounds=8), whole_job=again, memory=memory)
    assert len(again.seen) == 1
    memory.forget({a})
    assert a not in memory.margins and a not in memory.memo.get("pairs", {})
    assert b in memory.margins and b in memory.memo["pairs"]
