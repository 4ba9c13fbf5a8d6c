"""The figures plan.json reports about the job the machines run: its time against the time-optimal
job under the same limits and against the time at the feed, how fast the cutters cut (the share of
cutting time below the minimum feed, the episodes below 5 % of the feed), each step's share of the
cycle, and where and why the feed was cut.

- **Time-optimal job** (``optimum``): every move of each cutter at its own time-optimal traversal
  (core.machine.optimum.fastest) from its entry to its exit speed, waits taking none, and between two
  instants at which both cutters start a move (the schedule's synchronisation points) the longer of
  the two cutters' sums. A move timed on its profile already counts its own duration.
- **Kinds of stretch**: tip paths of step 1 and of step 2, symmetric stretches (both cutters on one
  master law), speed stages (the variable regions), the other cutting moves of steps 2-7 (the
  staggered edge stretches), and the non-cutting moves.

Units: ms and mm inside; plan.json gets s, mm/min and shares.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from core.errors import PlanningError
from core.machine.tables import TimeWarp
from core.paths.regions import REGION_CODE
from core.schedule.motion import ramp_law
from core.schedule.movetable import MAPPED, PLATEAU_LOGISTIC, PLATEAU_SEPTIC, PROFILE, SIGMOID, WAIT
from core.schedule.optimum import Limits, durations, fastest, knots, path_caps
from core.schedule.steps import Schedule
from core.schedule.timeline import Timeline
from core.util.rowwise import row_norm

KINDS = ("tip step 1", "tip step 2", "staggered", "variable", "symmetric", "not cutting")
#: a cutter below this share of the feed while cutting counts as an episode of crawling
CRAWL_SHARE = 0.05
TIP = REGION_CODE["tip"]


def move_kinds(schedule: Schedule, side: str) -> np.ndarray:
    """(m,) index into KINDS of each of a cutter's moves (-1: a wait)."""
    tab = schedule.table(side)
    kind = np.full(len(tab.kind), KINDS.index("staggered"))
    first = tab.poly.off
    tip = tab.regions[first] == TIP
    kind[np.isin(tab.kind, (SIGMOID, PLATEAU_LOGISTIC, PLATEAU_SEPTIC))] = KINDS.index("variable")
    kind[tab.kind == MAPPED] = KINDS.index("symmetric")
    kind[(tab.step == 1)] = KINDS.index("tip step 1")
    kind[(tab.step == 2) & tip] = KINDS.index("tip step 2")
    kind[~tab.cutting] = KINDS.index("not cutting")
    kind[tab.kind == WAIT] = -1  # (a wait takes no time at the optimum: it is in no kind)
    return kind


def optimal_durations(schedule: Schedule, side: str, limits: Limits) -> np.ndarray:
    """(m,) ms: each of a cutter's moves at its time-optimal traversal from its entry to its exit speed
    (waits: 0; a move timed on its profile: its own duration; a rapid move at three times the feed)."""
    tab = schedule.table(side)
    out = np.zeros(len(tab.kind))
    for j, m in enumerate(tab.moves):
        law: Any = m.law
        if tab.kind[j] == WAIT or law.duration <= 0:
            continue
        if tab.kind[j] == PROFILE or len(m.points) < 2 or m.cum[-1] <= 1e-9:
            out[j] = law.duration
            continue
        v0, v1 = (float(x) for x in law.speed(np.array([0.0, law.duration])))
        cruise = limits.feed if m.cutting else 3.0 * limits.feed
        lim = limits if cruise == limits.feed else replace(limits, feed=cruise)
        s, kt, ka = knots(m.points, m.axes, m.cum, 4 if len(m.points) > 2 else 32)
        if len(s) < 2:
            out[j] = law.duration
            continue
        out[j] = float(durations(s, fastest(path_caps(lim, side, kt, ka, s), v0, v1)).sum())
    return out


def _synchronised(starts: dict, busy: dict) -> float:
    """ms: the job whose moves (starting at ``starts[side]`` in the schedule) take ``busy[side]`` ms
    each: between two synchronisation points (instants at which both cutters start a move) the
    longer of the two cutters' sums."""
    common = np.union1d(np.intersect1d(np.round(starts["left"], 6), np.round(starts["right"], 6)), [0.0, np.inf])
    per = []
    for side in ("left", "right"):
        seg = np.searchsorted(common, np.round(starts[side], 6), side="right") - 1
        per.append(np.bincount(seg, weights=busy[side], minlength=len(common)))
    return float(np.maximum(per[0], per[1]).sum())


def machine_times(warp: TimeWarp, tau: np.ndarray) -> np.ndarray:
    """(k,) ms on the machines' clock of schedule instants tau (the warp is monotone)."""
    return np.interp(tau, warp.schedule_t, warp.t)


def optimum(schedule: Schedule, warp: TimeWarp, limits: Limits) -> dict:
    """The job against its time-optimal estimate (module docstring), in total and per kind of stretch
    (machine time over optimal time of the moves of that kind, both cutters)."""
    opt, t0, t1, kinds = {}, {}, {}, {}
    for side in ("left", "right"):
        tab = schedule.table(side)
        opt[side] = optimal_durations(schedule, side, limits)
        t0[side], t1[side] = tab.t0, tab.t0 + tab.dur
        kinds[side] = move_kinds(schedule, side)
    total = _synchronised(t0, opt)
    per_kind = {}
    for k, name in enumerate(KINDS):
        on, best = 0.0, 0.0
        for side in ("left", "right"):
            sel = kinds[side] == k
            on += float((machine_times(warp, t1[side][sel]) - machine_times(warp, t0[side][sel])).sum())
            best += float(opt[side][sel].sum())
        if best > 0:
            per_kind[name] = {"machine_s": round(on / 1000.0, 3), "optimal_s": round(best / 1000.0, 3),
                              "ratio": round(on / best, 4)}
    job = float(warp.t[-1])
    return {"time_optimal_s": round(total / 1000.0, 3), "job_over_optimal": round(job / total, 4) if total else 0.0,
            "per_kind": per_kind}


def cutting_speeds(tl: Timeline, feed: float, min_feed: float) -> dict:
    """How fast the cutters cut, from the rows (both cutters): the cutting time, the share of it below
    ``min_feed`` and below 30 % of the feed, and the episodes (runs of row intervals cutting one path)
    below CRAWL_SHARE of the feed; feed and min_feed in mm/ms. A row interval cuts when both its rows
    cut the same path; its speed is the chord over the period."""
    dt = np.diff(tl.t)
    total, below_min, below_30, episodes, crawl_s = 0.0, 0.0, 0.0, 0, 0.0
    for smp in (tl.left, tl.right):
        cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == smp.path[1:])
        speed = row_norm(np.diff(smp.tips, axis=0)) / np.where(dt > 0, dt, np.inf)
        total += float(dt[cut].sum())
        below_min += float(dt[cut & (speed < min_feed)].sum())
        below_30 += float(dt[cut & (speed < 0.3 * feed)].sum())
        slow = cut & (speed < CRAWL_SHARE * feed)
        crawl_s += float(dt[slow].sum())
        episodes += int(np.count_nonzero(slow[1:] & ~slow[:-1]) + (slow[0] if len(slow) else 0))
    return {"cutting_time_s": round(total / 1000.0, 3),
            "min_feed_mm_min": round(min_feed * 60000.0, 3),
            "share_below_min_feed": round(below_min / total, 6) if total else 0.0,
            "share_below_30pct_feed": round(below_30 / total, 6) if total else 0.0,
            "episodes_below_5pct_feed": episodes, "time_below_5pct_feed_s": round(crawl_s / 1000.0, 3)}


def step_breakdown(tl: Timeline) -> dict:
    """Per step (1-7), the seconds of the job each cutter spends in it, and the job's seconds in which
    either cutter is in it (the steps of the two cutters overlap: steps 2, 5 and 6)."""
    dt = np.diff(tl.t)
    out = {}
    for step in range(1, 8):
        left, right = tl.left.step[:-1] == step, tl.right.step[:-1] == step
        out[str(step)] = {"left_s": round(float(dt[left].sum()) / 1000.0, 3),
                          "right_s": round(float(dt[right].sum()) / 1000.0, 3),
                          "either_s": round(float(dt[left | right].sum()) / 1000.0, 3)}
    return out


#: why the feed was cut where a cutter cuts slower than FEED_CUT of the feed (``feed_cuts``)
FEED_CUT = 0.97
CUT_REASONS = ("axis speed", "axis acceleration", "tip acceleration", "minimum feed stage", "chord or curvature")


def feed_cuts(tl: Timeline, tables: dict, machine_limits: tuple[np.ndarray, np.ndarray], feed: float,
              a_max: float) -> list[dict]:
    """Where and why the feed was cut, as data for the feed plot: runs of row intervals in which a
    cutting cutter runs below FEED_CUT of the feed, each with its side, start and end (s), its lowest
    speed (mm/min) and the reason (CUT_REASONS) read from the rows: an axis at 90 % or more of its
    speed limit, else of its acceleration limit, else the tip accelerating along the path at 90 % of
    a_max (a ramp), else a speed stage (the variable region of steps 5 and 6), else the chord
    tolerance or the path's curvature. ``machine_limits``: the axes' (v_lim, a_lim) mm/ms, mm/ms^2."""
    v_lim, a_lim = machine_limits
    dt = np.diff(tl.t)
    out = []
    variable = REGION_CODE["variable"]
    for side, smp in (("left", tl.left), ("right", tl.right)):
        cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == smp.path[1:])
        speed = row_norm(np.diff(smp.tips, axis=0)) / np.where(dt > 0, dt, np.inf)
        slow = cut & (speed < FEED_CUT * feed)
        if not slow.any():
            continue
        vel = tables[side].velocities
        v_share = (np.abs(vel) / v_lim).max(axis=1)
        a_share = (np.abs(np.diff(vel, axis=0)) / (np.where(dt > 0, dt, np.inf)[:, None] * a_lim)).max(axis=1)
        tip_acc = np.abs(np.gradient(speed, tl.t[:-1])) if len(speed) > 1 else np.zeros_like(speed)
        reason = np.full(len(dt), CUT_REASONS.index("chord or curvature"))
        stage = (smp.step[:-1] >= 5) & (smp.step[:-1] <= 6) & (smp.code[:-1] == variable)
        reason[stage] = CUT_REASONS.index("minimum feed stage")
        reason[tip_acc >= 0.9 * a_max] = CUT_REASONS.index("tip acceleration")
        reason[a_share >= 0.9] = CUT_REASONS.index("axis acceleration")
        reason[np.maximum(v_share[:-1], v_share[1:]) >= 0.9] = CUT_REASONS.index("axis speed")
        key = np.where(slow, reason, -1)
        edges = np.flatnonzero(np.diff(np.concatenate([[-1], key, [-1]])) != 0)
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            if key[a] < 0:
                continue
            out.append({"side": side, "t0_s": round(float(tl.t[a]) / 1000.0, 3),
                        "t1_s": round(float(tl.t[b]) / 1000.0, 3), "reason": CUT_REASONS[key[a]],
                        "lowest_mm_min": round(float(speed[a:b].min()) * 60000.0, 3)})
    return sorted(out, key=lambda r: r["t0_s"])


def time_at_feed(schedule: Schedule, feed: float, a_max: float) -> float:
    """ms: the job at the feed: each move at its cruise speed (the feed cutting, three times it in
    the air) from its entry to its exit speed with quintic ramps within a_max and no machine limit,
    waits none, and between two synchronisation points the longer of the two cutters' sums (as
    ``optimum``)."""
    busy, starts = {}, {}
    for side in ("left", "right"):
        tab = schedule.table(side)
        d = np.zeros(len(tab.kind))
        for j, m in enumerate(tab.moves):
            law: Any = m.law
            if tab.kind[j] == WAIT or law.duration <= 0:
                continue
            length = float(m.cum[-1]) if len(m.cum) else 0.0
            v0, v1 = (float(x) for x in law.speed(np.array([0.0, law.duration])))
            cruise = feed if m.cutting else 3.0 * feed
            try:
                d[j] = ramp_law(length, cruise, a_max, min(v0, cruise), min(v1, cruise)).duration
            except PlanningError:
                d[j] = length / cruise
        busy[side], starts[side] = d, tab.t0
    return _synchronised(starts, busy)


def job_figures(schedule: Schedule, tl: Timeline, warp: TimeWarp, tables: dict, limits: Limits,
                min_feed: float) -> dict:
    """plan.json's "job": the job's time at the feed, on the machines and time-optimal (in total and
    per kind of stretch), how fast the cutters cut (below ``min_feed`` mm/ms, below 30 % of the feed,
    below 5 %), the seconds per step, where and why the feed was cut (``feed_cuts``), and the speed
    stages that run below the minimum feed with the reason (their start on the machines' clock)."""
    at_feed = time_at_feed(schedule, limits.feed, limits.a_max)
    below = []
    for st in schedule.stages:
        if "below_min_feed" in st:
            start = float(machine_times(warp, np.array([st.get("start_ms", 0.0)]))[0]) / 1000.0
            below.append({"path": st["path"], "cutter": st["cutter"], "time_s": round(start, 3),
                          **st["below_min_feed"]})
    return {"time_at_feed_s": round(at_feed / 1000.0, 3),
            "time_on_machines_s": round(float(tl.t[-1]) / 1000.0, 3),
            **optimum(schedule, warp, limits),
            "cutting": cutting_speeds(tl, limits.feed, min_feed),
            "stages_below_min_feed": below,
            "steps": step_breakdown(tl),
            "feed_cuts": feed_cuts(tl, tables, (limits.v_lim, limits.a_lim), limits.feed, limits.a_max)}
