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

import numpy as np

from core.machine.tables import TimeWarp
from core.paths.regions import REGION_CODE
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
    """(m,) index into KINDS of each of a cutter's moves."""
    tab = schedule.table(side)
    kind = np.full(len(tab.kind), KINDS.index("staggered"))
    first = tab.poly.off
    tip = tab.regions[first] == TIP
    kind[np.isin(tab.kind, (SIGMOID, PLATEAU_LOGISTIC, PLATEAU_SEPTIC))] = KINDS.index("variable")
    kind[tab.kind == MAPPED] = KINDS.index("symmetric")
    kind[(tab.step == 1)] = KINDS.index("tip step 1")
    kind[(tab.step == 2) & tip] = KINDS.index("tip step 2")
    kind[~tab.cutting] = KINDS.index("not cutting")
    return kind


def optimal_durations(schedule: Schedule, side: str, limits: Limits) -> np.ndarray:
    """(m,) ms: each of a cutter's moves at its time-optimal traversal from its entry to its exit speed
    (waits: 0; a move timed on its profile: its own duration; a rapid move at three times the feed)."""
    tab = schedule.table(side)
    out = np.zeros(len(tab.kind))
    for j, m in enumerate(tab.moves):
        if tab.kind[j] == WAIT or m.law.duration <= 0:
            continue
        if tab.kind[j] == PROFILE or len(m.points) < 2 or m.cum[-1] <= 1e-9:
            out[j] = m.law.duration
            continue
        v0, v1 = (float(x) for x in m.law.speed(np.array([0.0, m.law.duration])))
        cruise = limits.feed if m.cutting else 3.0 * limits.feed
        lim = limits if cruise == limits.feed else replace(limits, feed=cruise)
        s, kt, ka = knots(m.points, m.axes, m.cum, 4 if len(m.points) > 2 else 32)
        if len(s) < 2:
            out[j] = m.law.duration
            continue
        out[j] = float(durations(s, fastest(path_caps(lim, side, kt, ka, s), v0, v1)).sum())
    return out


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
    # the synchronisation points: instants at which both cutters start a move
    common = np.intersect1d(np.round(t0["left"], 6), np.round(t0["right"], 6))
    common = np.union1d(common, [0.0, np.inf])
    busy = {}
    for side in ("left", "right"):
        seg = np.searchsorted(common, np.round(t0[side], 6), side="right") - 1
        busy[side] = np.bincount(seg, weights=opt[side], minlength=len(common))
    total = float(np.maximum(busy["left"], busy["right"]).sum())
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
