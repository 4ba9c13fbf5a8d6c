"""The seven-step collaborative schedule (paper section 5, Figures 6-7; SPEC.md section 7).

The left cutter is the leading cutter, the right one the subsequent cutter. Steps, as the paper lists
them:
1. the leading cutter machines the tip region (single-sided), the subsequent waits at zero;
2. the leading cutter machines path n (the first collaborative path) up to S_vl, backs off and waits;
   the subsequent machines the tip region on its side, then path n up to the point of S_vl;
3. the leading cutter comes down: both machine path n symmetrically (at the same pair index, within
   the sync map's smoothing: core.schedule.motion.sync_map) up to S_vs / S_sl;
4. (later paths) symmetrical machining from E_vl / E_ss to S_vs / S_sl;
5. the subsequent cutter slows down through its variable region (sigmoid stage, core.schedule.sigmoid) while
   the leading one machines the variable and edge region of path n, turns, and machines the edge
   region of path n+1 up to S_vl; the two arrive at E_vs (path n) and S_vl (path n+1) together;
6. the leading cutter slows down through its variable region of path n+1 while the subsequent one
   finishes path n, turns and machines path n+1 up to E_ss; they arrive at E_vl and E_ss together;
7. after the last path both finish and return to zero.
Timing (SPEC.md section 7): the stage must last exactly as long as the other cutter's route, which
is much longer than twice the stage at the feed, so Eq. 22 alone cannot do it; core.schedule.sigmoid supplies
the paper's curve where it suffices and a plateau or a dwell at the bottom of the curve where it does
not. Where even that would exceed a_max (a short variable region), the stage starts earlier, inside
the internal region, by as many points as it needs (recorded per path). A cutter that would arrive
early waits (backed off at its turn) so that every synchronisation holds exactly.

Modes: 'collaborative' (above), 'symmetric' (both cutters at the same pair index everywhere, even at
the edges: unsafe, kept to show what the method avoids), 'single' (left cutter machines everything,
then the right one).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from core.errors import Cancelled, PathScheduleError, PlanningError
from core.paths.contours import TURN_LIFT
from core.paths.plan import PathPlan
from core.paths.regions import region_codes
from core.paths.tessellation import TriangleIndex
from core.schedule.builder import HOME_CLEARANCE, MoveBuilder, cut_duration, turn, turn_duration
from core.schedule.motion import Move, MoveTag, Samples, ramp_law, ramp_time
from core.schedule.movetable import MoveTable, build_tables
from core.schedule.safety import capsule_clearance, tip_spacing, transition_paths, unsafe_samples
from core.util.parallel import both, per_side, worth_threads


@dataclass(frozen=True)
class Schedule:
    """Both cutters' moves over the whole job, plus what the planner decided per path; with each
    cutter's moves as arrays (core.schedule.movetable.MoveTable), from which every sample is taken."""

    mode: str
    left: list[Move]
    right: list[Move]
    duration: float
    stages: list[dict]
    feed: float
    a_max: float
    left_table: MoveTable = field(repr=False, compare=False)
    right_table: MoveTable = field(repr=False, compare=False)

    def table(self, side: str) -> MoveTable:
        return self.left_table if side == "left" else self.right_table

    def sample(self, t: np.ndarray) -> tuple[Samples, Samples]:
        """Both cutters' positions at times t (n,) ms, the two in parallel threads for long columns (the
        array operations release the GIL; core.util.parallel.per_side)."""
        t = np.asarray(t, float)
        out = per_side(lambda side: self.table(side).sample(t), parallel=worth_threads(len(t)))
        return out["left"], out["right"]

    def speeds(self, side: str, t: np.ndarray) -> np.ndarray:
        """(n,) mm/ms: a cutter's tip speed along its path at times t (n,) ms, from the moves' speed
        laws (the derivative of the planned motion, not a difference of samples)."""
        return self.table(side).speeds(np.asarray(t, float))

    def times(self, period: float) -> np.ndarray:
        """The common time column, ms: every ``period`` ms from 0 to the end (end included), each
        instant on the CL tables' 1e-6 ms grid (core.output.files writes t to 1e-6 ms): the positions are
        computed at the times written, so that speeds and accelerations recomputed from the rows are
        exact (a period off the grid, e.g. at a feed of 1937.76 mm/min, put rows up to 5e-7 ms away
        from where they were sampled: 8e-5 of the speed over the 6-microsecond intervals round the
        edges, which read as 384 mm/s^2 of acceleration at a constant feed)."""
        n = int(np.ceil(self.duration / period))
        t = np.round(np.arange(n) * period, 6)
        end = np.ceil(self.duration * 1e6 - 1e-6) / 1e6
        return np.append(t[t < end - 5e-7], end)


def _bounds(pair, reg) -> tuple[int, int, int, int]:
    """(S_vl, E_vl, S_vs, E_vs) clamped into the pair (N points)."""
    n = len(pair.u) - 1
    bd = reg.boundaries
    return (min(bd["S_vl"], n), min(bd["E_vl"], n), min(bd["S_vs"], n), min(bd["E_vs"], n))


def _collaborative(b: MoveBuilder, items) -> None:
    L, S = b.cut["left"], b.cut["right"]
    tip = [p for p, r in items if r.is_tip]
    coll = [(p, r) for p, r in items if not r.is_tip]
    if b.resume is not None:  # the paths before the first changed margin are as in the last round
        k0, step, start, moving = b.restore(b.resume)
    else:
        for k, p in enumerate(tip):                                     # step 1
            b.single_path("left", p, 1, first=(k == 0))
        if not coll:
            S.wait_until(L.t, 1, -1)
            for k, p in enumerate(tip):
                b.single_path("right", p, 2, first=(k == 0))
            return
        p0, r0 = coll[0]
        a0, e0, i0, _ = _bounds(p0, r0)
        tips, axes, _ = b.stretch("left", p0, 0, 0)                    # step 2 (leading)
        b.travel("left", tips[0], axes[0], 2, p0.index, "turn" if tip else "idle",
                 lift=TURN_LIFT if tip else HOME_CLEARANCE)
        b.cut_from_rest("left", p0, 0, a0, 2)
        lift = _park_lift(b, p0, a0, TURN_LIFT if tip else HOME_CLEARANCE)
        back = L.tip + lift * b.backoff(L.tip, L.axis)
        seat_tip, seat_axis = L.tip.copy(), L.axis.copy()
        L.add(ramp_law(lift, b.rapid, b.a), [L.tip, back], [L.axis, L.axis], MoveTag(2, p0.index, False, "idle"))
        S.wait_until(b.cut["left"].moves[len(tip) and sum(1 for m in L.moves if m.step == 1) - 1].t1
                     if tip else 0.0, 1, -1)
        for k, p in enumerate(tip):                                     # step 2 (subsequent)
            b.single_path("right", p, 2, first=(k == 0))
        tips, axes, _ = b.stretch("right", p0, 0, 0)
        b.travel("right", tips[0], axes[0], 2, p0.index, "turn" if tip else "idle",
                 lift=TURN_LIFT if tip else HOME_CLEARANCE)
        b.cut_from_rest("right", p0, 0, a0, 2)
        # step 3: meet at S_vl. The leading comes down only once the subsequent stands at S_vl: while
        # the subsequent still cuts the edge stretch before it, the pair spacing there is below h_safe
        # and the leading's tip above its seat came within it (BladeX, dR 3: 1.702 < 1.7036 mm)
        down = ramp_law(lift, b.rapid, b.a)
        t_meet = max(S.t, L.t) + down.duration
        S.wait_until(t_meet, 2, p0.index, "edge" if a0 > 0 else "idle")
        L.wait_until(t_meet - down.duration, 2, p0.index)
        L.add(down, [L.tip, seat_tip], [L.axis, seat_axis], MoveTag(3, p0.index, False, "variable"))
        step = 3
        start = a0
        moving = False  # do the cutters enter the symmetrical stretch at speed (after stages)?
        k0 = 0
    for k in range(k0, len(coll)):
        p, r = coll[k]
        b.snapshot(p.index, k, step, start, moving)
        n = len(p.u) - 1
        last = k == len(coll) - 1
        i1, e1, m = _symmetric_end(b, p, r, start)
        has_stage = e1 > i1
        v_in, v_out = (b.v if moving else 0.0), (b.v if has_stage else 0.0)
        b.symmetric(p, start, i1, v_in, v_out, step)
        vl0 = b.own_speed(p, i1, "left", start, i1, v_in, v_out) if has_stage else 0.0
        vs0 = b.own_speed(p, i1, "right", start, i1, v_in, v_out) if has_stage else 0.0
        if last:
            # the subsequent reaches its edge only once the leading has backed off all the way
            t_lead = (cut_duration(b, "left", p, i1, n, vl0, 0.0)
                      + ramp_law(HOME_CLEARANCE, b.rapid, b.a).duration)
            b.cut_with_stops("left", p, i1, n, vl0, 0.0, 7)
            rec = _stage_or_wait(b, "right", p, i1, e1, vs0, t_lead, 7)
            b.stages.append({"path": p.index, "cutter": "right", "stage": "end of job", "sync_shift_points": m,
                             **rec})
            b.cut_with_stops("right", p, e1, n, vs0, 0.0, 7)
            break
        q, s = coll[k + 1]
        qa, qe, q_vs, _ = _bounds(q, s)
        if m > 0 and qe > qa:
            shift = min(m, q_vs - qe - 1)
            qa, qe = qa + max(shift, 0), qe + max(shift, 0)
        q_end, q_e1, _ = _symmetric_end(b, q, s, qe)  # q's symmetrical stretch: qe..q_end, as built next
        q_out = b.v if q_e1 > q_end else 0.0
        kl = b.own_speed(q, qe, "left", qe, q_end, b.v, q_out) if qe > qa else 0.0
        ks = b.own_speed(q, qe, "right", qe, q_end, b.v, q_out) if qe > qa else 0.0
        # step 5: leading runs to S_vl(q) while the subsequent slows through its variable region
        t5 = (cut_duration(b, "left", p, i1, n, vl0, 0.0) + turn_duration(b, "left", p, q)
              + cut_duration(b, "left", q, 0, qa, 0.0, kl))
        t5_min = b.length("right", p, i1, e1) / vs0 if has_stage else 0.0
        b.cut_with_stops("left", p, i1, n, vl0, 0.0, 5)
        turn(b, "left", q, 5, wait=max(t5_min - t5, 0.0))
        b.cut_with_stops("left", q, 0, qa, 0.0, kl, 5)
        rec = _stage_or_wait(b, "right", p, i1, e1, vs0, max(t5, t5_min), 5)
        b.stages.append({"path": p.index, "cutter": "right", "stage": "S_vs -> E_vs", "sync_shift_points": m,
                         **rec})
        # step 6: subsequent finishes p and runs to E_ss(q) while the leading slows through S_vl..E_vl
        t6 = (cut_duration(b, "right", p, e1, n, vs0, 0.0) + turn_duration(b, "right", p, q)
              + cut_duration(b, "right", q, 0, qe, 0.0, ks))
        t6_min = b.length("left", q, qa, qe) / kl if qe > qa else 0.0
        b.cut_with_stops("right", p, e1, n, vs0, 0.0, 6)
        turn(b, "right", q, 6, wait=max(t6_min - t6, 0.0))
        b.cut_with_stops("right", q, 0, qe, 0.0, ks, 6)
        rec = _stage_or_wait(b, "left", q, qa, qe, kl, max(t6, t6_min), 6)
        b.stages.append({"path": q.index, "cutter": "left", "stage": "S_vl -> E_vl", "sync_shift_points": m,
                         **rec})
        # the two now stand at E_vl / E_ss of q together
        t_sync = max(L.t, S.t)
        L.wait_until(t_sync, 6, q.index, "variable")
        S.wait_until(t_sync, 6, q.index, "variable")
        step, start, moving = 4, qe, qe > qa


#: how far the parked leading keeps from the subsequent's route, as a multiple of h_safe
PARK_MARGIN = 1.05


def _park_lift(b: MoveBuilder, p0, a0: int, approach_lift: float) -> float:
    """How far the leading backs off above its seat at S_vl of the first collaborative path p0 while
    the subsequent comes down onto p0's start (from ``approach_lift`` above it) and cuts the edge
    stretch up to S_vl: TURN_LIFT, or more where the parked tip would come within PARK_MARGIN h_safe
    of that route (a thick tool on a short edge stretch: r 2.18 mm, dd 0.5 mm on the sample came
    to 2.33 mm at h_safe 2.53)."""
    h = PARK_MARGIN * b.plan.params.h_safe
    seat, axis = p0.left_tip[a0], b.backoff(p0.left_tip[a0], p0.left_axis[a0])
    route = np.vstack([p0.right_tip[0] + approach_lift * b.backoff(p0.right_tip[0], p0.right_axis[0]),
                       p0.right_tip[:a0 + 1]])
    a, e = route[:-1], route[1:] - route[:-1]
    ee = np.maximum(np.einsum("ij,ij->i", e, e), 1e-300)
    lift = TURN_LIFT
    for lift in TURN_LIFT * np.array([1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0]):
        q = seat + lift * axis
        s = np.clip(np.einsum("ij,ij->i", q - a, e) / ee, 0.0, 1.0)
        if np.linalg.norm(a + s[:, None] * e - q, axis=1).min() >= h:
            break
    return float(lift)


def _symmetric_end(b: MoveBuilder, p, r, start: int) -> tuple[int, int, int]:
    """(i1, e1, m): where path p's symmetrical stretch from ``start`` ends (S_vs) and the subsequent's
    stage ends (E_vs), both moved m points inside the path by a synchronisation margin (the last
    path's too: its end-of-job stage is staggered like the others)."""
    _, _, i1, e1 = _bounds(p, r)
    m = b.margins.get(p.index, 0)
    if m and e1 > i1:
        # the synchronisation lies m points further inside both paths (a longer variable region)
        m = min(m, i1 - start - 1)
        i1, e1 = i1 - max(m, 0), e1 - max(m, 0)
    return i1, e1, m


def _stage_or_wait(b: MoveBuilder, side, pair, i, j, v0, duration, step) -> dict:
    """The stage i..j, or a wait where there is none. The leading cutter's stage in step 6 has the
    subsequent coming after it along the same path: where it is waited out off the blade, it waits
    ahead of the paper's stage (MoveBuilder.lifted_stage); the subsequent's, in steps 5 and 7, has the
    leading coming back towards it on the next path: it waits behind."""
    if j > i and v0 > 0:
        return b.stage(side, pair, i, j, v0, duration, step, ahead=step == 6)
    b.cut[side].wait_until(b.cut[side].t + duration, step, pair.index, "variable")
    return {"kind": "wait", "length_mm": 0.0, "duration_ms": round(duration, 3)}


def _symmetric_mode(b: MoveBuilder, items) -> None:
    for k, (p, _) in enumerate(items):
        for side in ("left", "right"):
            tips, axes, _ = b.stretch(side, p, 0, 0)
            if k == 0:
                b.travel(side, tips[0], axes[0], 1, p.index, "idle", lift=HOME_CLEARANCE)
            else:
                turn(b, side, p, 4)
        t = max(b.cut["left"].t, b.cut["right"].t)
        for side in ("left", "right"):
            b.cut[side].wait_until(t, 1 if k == 0 else 4, p.index, "turn")
        b.symmetric(p, 0, len(p.u) - 1, 0.0, 0.0, 3 if k == 0 else 4)


def _single_mode(b: MoveBuilder, items) -> None:
    for k, (p, _) in enumerate(items):
        b.single_path("left", p, 1, first=(k == 0))
    b.go_home("left", 1)
    b.cut["right"].wait_until(b.cut["left"].t, 1, -1)
    for k, (p, _) in enumerate(items):
        b.single_path("right", p, 2, first=(k == 0))


@dataclass(frozen=True)
class ScheduleOptions:
    """How a plan is scheduled: mode ('collaborative' | 'symmetric' | 'single'), feed mm/min, a_max
    mm/s^2, speed profile ('sigmoid' | 'smooth'), the period ms of the time column its safety check
    samples (None: dd at the feed), the rounds of that check at most, and the minimum cutting feed
    mm/min (a speed stage that would cut slower is cut at speed and waited out off the blade:
    MoveBuilder.lifted_stage; 0: the paper's stages as they are)."""

    mode: str = "collaborative"
    feed: float = 1000.0
    a_max: float = 500.0
    profile: str = "sigmoid"
    period: float | None = None
    max_rounds: int = 8
    min_feed: float = 0.0


def build_schedule(plan: PathPlan, mode: str = "collaborative", feed: float = 1000.0, a_max: float = 500.0,
                   profile: str = "sigmoid", period: float | None = None, max_rounds: int = 8,
                   cancel=None) -> Schedule:
    """Both cutters' timed moves for a path plan. feed in mm/min, a_max in mm/s^2 (converted here).

    Collaborative mode checks its own result on the time column (``period`` ms, default dd / feed):
    where the tip spacing drops below h_safe or the tools touch around a transition from path n to
    n+1 (core.schedule.safety.violations), that transition's synchronisation moves a few points
    further inside both paths, and the schedule is rebuilt (at most ``max_rounds`` times).
    ``cancel()`` returning True between rounds stops it (core.errors.Cancelled).
    """
    return checked_schedule(plan, ScheduleOptions(mode, feed, a_max, profile, period, max_rounds), cancel)[0]


@dataclass
class ScheduleMemory:
    """What the safety rounds of one schedule find, for the next schedule of nearly the same paths (the
    planner's, after some paths went single-sided): the synchronisation margins (points by path index:
    the transition from that path on) and the builds' per-pair figures (MoveBuilder.memo); ``index``:
    the blade index the moves in the air are measured against (the planner's one for the blade; None:
    each build makes its own, AirMoves.blade_index)."""

    margins: dict[int, int] = field(default_factory=dict)
    memo: dict = field(default_factory=dict)
    index: TriangleIndex | None = None

    def forget(self, indices: set[int]) -> None:
        """Drop what was found for the paths ``indices``, whose pairs are replaced (made single-sided):
        their margins and their figures in the memo (MoveBuilder.pair_memo); the rest stays valid."""
        for index in indices:
            self.margins.pop(index, None)
            self.memo.get("pairs", {}).pop(index, None)


def checked_schedule(plan: PathPlan, options: ScheduleOptions = ScheduleOptions(), cancel=None,
                     whole_job: Callable[[Schedule], set[int]] | None = None,
                     memory: ScheduleMemory | None = None
                     ) -> tuple[Schedule, tuple[Samples, Samples] | None, set[int]]:
    """build_schedule, with both cutters on ``times(period)`` as its last whole-job safety check sampled
    them (None when no such check ran: the other modes, or ``whole_job`` given), and the paths round
    whose transitions the collaborative schedule still breaks the safety rule (AlignedPair.index; empty
    when it keeps it). ``whole_job(schedule)``: a further check of the whole job, run once the
    schedule keeps the rule on ``times(period)`` (the planner's: on the machines' rows), returning the
    paths round whose transitions it breaks the rule. ``memory``: the margins and per-pair figures of
    an earlier schedule of nearly the same paths to start from (ScheduleMemory), grown here in place.

    Each round moves every violating transition's synchronisation further inside its paths at once,
    by twice the last move when the same transition breaks the rule again (0.5 mm, then 1, 2, 4 ...),
    so a transition that needs a long variable region has it within a few rounds; a transition whose
    margin no longer moves its synchronisation (the symmetrical stretch is used up) is given up at
    once. The rounds end when no transition breaks the rule, when every one that does is given up, or
    after ``max_rounds``."""
    mode, feed, a_max, period = options.mode, options.feed, options.a_max, options.period
    if mode not in ("collaborative", "symmetric", "single"):
        raise PlanningError(f"mode must be collaborative, symmetric or single, got {mode!r}")
    if not (np.isfinite(feed) and feed > 0 and np.isfinite(a_max) and a_max > 0):
        raise PlanningError(f"feed ({feed} mm/min) and a_max ({a_max} mm/s^2) must be positive numbers")
    v = feed / 60000.0
    if ramp_time(v, a_max / 1e6) > 60000:
        raise PlanningError(f"a_max = {a_max} mm/s^2 is impossible for a feed of {feed} mm/min: reaching "
                            "the feed would take over a minute")
    period = period or plan.params.dd / v
    memory = ScheduleMemory() if memory is None else memory
    margins = memory.margins
    step_points = max(2, int(np.ceil(0.5 / plan.params.dd)))
    grow: dict[int, int] = {}  # each transition's next move, doubled each time it breaks the rule again
    shifted: dict[int, int] = {}  # each transition's synchronisation shift in the last build, points
    previous: MoveBuilder | None = None
    changed: set[int] = set()
    for _ in range(options.max_rounds):
        if cancel is not None and cancel():
            raise Cancelled()
        sch, previous = _build_once(plan, options, memory, (previous, changed))
        if mode != "collaborative":
            return sch, None, set()
        bad, samples = _violating(sch, plan, period, whole_job)
        if not bad:
            return sch, samples, set()
        now = sync_shifts(sch)
        stuck = {key for key in bad if key in shifted and now.get(key, 0) <= shifted[key]}
        if stuck == bad:
            break
        shifted = now
        for key in bad - stuck:
            grow[key] = 2 * grow[key] if key in grow else step_points
            margins[key] = margins.get(key, 0) + grow[key]
        changed = bad - stuck
    return sch, samples, bad


def _violating(sch: Schedule, plan: PathPlan, period: float, whole_job: Callable[[Schedule], set[int]] | None
               ) -> tuple[set[int], tuple[Samples, Samples] | None]:
    """The paths round whose transitions ``sch`` breaks the safety rule, the cheapest check that finds
    any first: where the cutters hand over (steps 5 and 6, where the spacing can fall) on ``times
    (period)``, then the whole job there, then ``whole_job`` (when given); with both cutters' samples
    of the whole job on ``times(period)`` when that check was the last to run (else None)."""
    bad = _unsafe_transitions(sch, plan, period, HANDOVER_STEPS)[0]
    if bad:
        return bad, None
    bad, samples = _unsafe_transitions(sch, plan, period)
    if bad or whole_job is None:
        return bad, samples
    return whole_job(sch), None


def sync_shifts(sch: Schedule) -> dict[int, int]:
    """The points by which each transition's synchronisation lies inside its paths in ``sch`` (its
    stages' ``sync_shift_points``, by the path the subsequent cutter leaves)."""
    return {s["path"]: s["sync_shift_points"] for s in sch.stages
            if s["cutter"] == "right" and "sync_shift_points" in s}


#: the steps in which the two cutters work near each other on different stretches (paper Figure 7)
HANDOVER_STEPS = (5, 6)


def _unsafe_transitions(sch: Schedule, plan: PathPlan, period: float, steps: tuple[int, ...] | None = None
                        ) -> tuple[set[int], tuple[Samples, Samples] | None]:
    """The paths (the lower index of the two cutters') at whose samples on the time column the safety
    rule breaks (core.schedule.safety.violations); only at the samples where either cutter is in one
    of ``steps`` when given. Also returns both cutters' samples on the whole column (None with
    ``steps``)."""
    if steps is None:
        left, right = whole = sch.sample(sch.times(period))
        next_to = None
    else:
        whole = None
        t = sch.times(period)
        inside = np.zeros(len(t) + 1, np.int64)  # +1 where a move of those steps starts, -1 after it
        for tab in (sch.left_table, sch.right_table):
            sel = np.isin(tab.step, steps)
            np.add.at(inside, np.searchsorted(t, tab.t0[sel], side="left"), 1)
            np.add.at(inside, np.searchsorted(t, tab.t0[sel] + tab.dur[sel], side="right"), -1)
        idx = np.flatnonzero(np.cumsum(inside)[:-1] > 0)
        if idx.size == 0:
            return set(), None
        left, right = sch.sample(t[idx])
        next_to = np.diff(idx) == 1  # "between samples" only for neighbours on the time column
    (at, between), clear = both(  # (the spacing and the clearance in two threads for long columns)
        lambda: tip_spacing(left.tips, right.tips),
        lambda: capsule_clearance(left.tips, left.axes, right.tips, right.axes, plan.params.tool_radius,
                                  plan.params.tool_length), parallel=worth_threads(len(left.tips)))
    if next_to is not None:
        between = np.where(next_to, between, np.inf)
    bad = unsafe_samples(at, between, clear, plan.params.h_safe)
    return transition_paths(left.path[bad], right.path[bad]), whole


def _build_once(plan: PathPlan, options: ScheduleOptions, memory: ScheduleMemory,
                since: tuple[MoveBuilder | None, set[int]]) -> tuple[Schedule, MoveBuilder]:
    """One build of the schedule with the margins of ``memory``; ``since``: the previous round's
    builder (None in the first) and the paths whose margins changed since: a collaborative build
    resumes at the first changed path. ``memory``: the margins, the plan's per-pair figures
    (MoveBuilder.memo) and the blade index."""
    mode, feed, a_max = options.mode, options.feed, options.a_max
    previous, changed = since
    b = MoveBuilder(plan, feed, a_max, options.profile, memory.memo, memory.index)
    if memory.index is None:
        memory.index = b.blade_index()
    b.min_feed = options.min_feed / 60000.0
    b.margins = memory.margins
    b.regions = {p.index: region_codes(r.labels) for p, r in zip(plan.pairs, plan.regions, strict=True)}
    if previous is not None:
        first = min(changed, default=None)
        snap = previous.snapshots.get(first) if first is not None else None
        if snap is not None:
            b.resume = snap
            b.snapshots = {key: s for key, s in previous.snapshots.items() if s[0] < snap[0]}
    items = list(zip(plan.pairs, plan.regions, strict=True))
    {"collaborative": _collaborative, "symmetric": _symmetric_mode, "single": _single_mode}[mode](b, items)
    if b.failed_stages:
        first = min(b.failed_stages)
        more = len(b.failed_stages) - 1
        raise PathScheduleError(set(b.failed_stages), b.failed_stages[first]
                                + (f" (and {more} more paths)" if more else ""))
    for side in ("left", "right"):
        b.go_home(side, 7)
    end = max(b.cut["left"].t, b.cut["right"].t)
    for side in ("left", "right"):
        b.cut[side].wait_until(end, 7, -1)
    left, right = b.cut["left"].moves, b.cut["right"].moves
    return Schedule(mode, left, right, end, b.stages, feed, a_max, *build_tables(left, right)), b
