"""The minimum cutting feed in the staggered steps: where the seven steps' speed stages start and end.

In step 5 the subsequent cutter slows through its variable region of path n (S_vs..E_vs) while the
leading one cuts the rest of path n, turns, and cuts path n+1 up to S_vl; in step 6 the leading one
slows through S_vl..E_vl of path n+1 while the subsequent finishes path n, turns, and cuts path n+1
up to E_ss. Each stage lasts exactly as long as the other cutter's route, which is much longer than
the stage's stretch at the feed: on the sample a stage of 3 mm must take the 20 mm and the turn of the
other's route, and its plateau falls to a few mm/min, where a ball-nose cutter rubs instead of
cutting.

A stage is lengthened in space instead (paper section 6: a longer variable region; its duration
alone deepens the dip, core.schedule.sigmoid): step 5's stage starts earlier, ``shift`` points inside
the symmetrical stretch (S_vs moves in for both cutters: the leading's route grows by the same
stretch at the feed, the stage by it at its lower speed, so the stage's mean speed rises towards the
feed), and step 6's stage ends later (E_vl and E_ss move in along path n+1: the subsequent's route
grows by the stretch it cuts at the feed). The synchronisation points stay exact: they move, and both
cutters meet there as before. The shift is the smallest of 0, 1, 2, 4, ... points that keeps the
stage's lowest speed at or above the minimum feed; where no shift inside the symmetrical stretch does
(a path whose internal region is too short), the stage keeps its lowest speed, and the schedule's
stage record says so (``below_min_feed``).
"""

from __future__ import annotations

from core.errors import PlanningError
from core.schedule.builder import MoveBuilder, cut_duration, turn_duration
from core.schedule.sigmoid import speed_stage


def lowest_speed(b: MoveBuilder, side: str, pair, i: int, j: int, v0: float, duration: float) -> float:
    """mm/ms: the lowest speed of the stage over a cutter's stretch i..j lasting ``duration`` ms from
    and back to v0 (-1 where no stage keeps a_max; v0 where the stage is no slower than v0); with the
    machines' limits, its plateau (MoveBuilder.machine_stage)."""
    length = b.length(side, pair, i, j)
    if length <= 0 or v0 <= 0:
        return -1.0
    if b.limits is not None:
        return b.machine_stage(side, pair, i, j, v0, duration)[1]
    if duration * v0 <= length * (1 + 1e-12):
        return v0
    try:
        return float(speed_stage(length, v0, duration, b.a, b.profile).v_low)
    except PlanningError:
        return -1.0


def _shifts(limit: int) -> list[int]:
    out, k = [0], 1
    while k <= limit:
        out.append(k)
        k *= 2
    if limit > 0 and out[-1] != limit:
        out.append(limit)
    return out


def step5_start(b: MoveBuilder, p, start: int, i1: int, e1: int, v_in: float, onto: tuple
                ) -> tuple[int, float]:
    """(S_vs of path p as moved in, the stage's lowest speed mm/ms): the stage of the subsequent over
    S_vs..e1 against the leading's route from S_vs to the end of p, the turn and path q up to qa
    (entered at kl; ``onto`` = (q, qa, kl)). The symmetrical stretch from ``start`` (entered at v_in)
    keeps at least a point."""
    q, qa, kl = onto
    best = (i1, -1.0)
    turn_t = turn_duration(b, "left", p, q)
    tail = cut_duration(b, "left", q, 0, qa, 0.0, kl)
    n = len(p.u) - 1
    for shift in _shifts(max(i1 - start - 1, 0)):
        i = i1 - shift
        v_out = b.v
        vl0 = b.own_speed(p, i, "left", start, i, v_in, v_out)
        vs0 = b.own_speed(p, i, "right", start, i, v_in, v_out)
        length = b.length("right", p, i, e1)
        if vs0 <= 0 or length <= 0:
            continue
        route = cut_duration(b, "left", p, i, n, vl0, 0.0) + turn_t + tail
        low = lowest_speed(b, "right", p, i, e1, vs0, max(route, b.stage_time("right", p, i, e1, vs0)))
        if low > best[1]:
            best = (i, low)
        if low >= b.min_feed:
            return i, low
    return best


def step6_end(b: MoveBuilder, p, e1: int, vs0: float, q, qa: int, qe: int, q_speeds) -> tuple[int, float]:
    """(E_vl / E_ss of path q as moved in, the stage's lowest speed mm/ms): the stage of the leading
    over qa..E_vl against the subsequent's route from e1 to the end of p (entered at vs0), the turn
    and path q up to E_ss. ``q_speeds(qe)``: the leading's and the subsequent's speeds (kl, ks) at qe
    as q's symmetrical stretch from there gives them (0, 0 where it has none)."""
    best = (qe, -1.0)
    n = len(p.u) - 1
    head = cut_duration(b, "right", p, e1, n, vs0, 0.0) + turn_duration(b, "right", p, q)
    limit = max(len(q.u) - 2 - qe, 0)
    for shift in _shifts(limit):
        e = qe + shift
        kl, ks = q_speeds(e)
        length = b.length("left", q, qa, e)
        if kl <= 0 or length <= 0:
            break
        route = head + cut_duration(b, "right", q, 0, e, 0.0, ks)
        low = lowest_speed(b, "left", q, qa, e, kl, max(route, b.stage_time("left", q, qa, e, kl)))
        if low > best[1]:
            best = (e, low)
        if low >= b.min_feed:
            return e, low
    return best
