"""The figures plan.json reports about the job the machines run (its "job" section): the time at the
feed and on the machines, each step's cycle time both ways, how fast the cutters cut (from the rows:
the share of each cutter's cutting time below 30 % of the feed, the episodes in which a cutting cutter
runs below 5 % of it), and the job against its time-optimal estimate, in total and per kind of stretch.

- **Time at the feed**: the schedule's own duration (the feed, a_max and the paper's speed stages,
  before the machine clock slows it for the axes and the chord tolerance).
- **Cutting speed**: per row interval, the chord between its two rows over the period (what the
  written CL tables give); an interval cuts when both its rows cut the same path. An episode is a run
  of consecutive slow cutting intervals of one cutter.
- **Time-optimal job** (``optimum``): every move of each cutter at its time-optimal traversal
  (core.machine.optimum) from the speed it enters with to the speed it leaves with in the schedule,
  the rapid moves at their rapid speed, waits taking none; between two instants at which both
  cutters start a move (the schedule's synchronisation points) the longer of the two cutters' sums.
- **Kinds of stretch** (``stretch_kinds``, by move): the tip paths of step 1 and of step 2 (cutting
  in the tip region), the symmetric internal stretches (both cutters on one master law), the speed
  stages (the variable regions), the staggered edge stretches (the other cutting moves of steps 5 and
  6), the other cutting moves (the first and last paths' edge stretches, steps 2 and 7), and the
  moves in the air (turns, approaches, back-offs, the way home). Per kind, the machine time of its
  moves (both cutters) against their time at the feed and at the optimum. A speed stage lasts as long
  as the other cutter's route in the schedule (the synchronisation), far longer than its free
  traversal: its kind's figure against the optimum counts that wait; the whole job's counts it once.

Units: ms and mm inside; plan.json gets s and shares.
"""

from __future__ import annotations

import numpy as np

from core.machine.optimum import Limits, fastest, knots, path_caps, run_times
from core.machine.tables import TimeWarp
from core.paths.regions import REGION_CODE
from core.schedule.builder import RAPID_FACTOR
from core.schedule.movetable import MAPPED, PLATEAU_LOGISTIC, PLATEAU_SEPTIC, SIGMOID, WAIT, MoveTable
from core.schedule.step_times import step_times
from core.schedule.steps import Schedule
from core.schedule.timeline import Timeline
from core.util.parallel import SIDES, per_side
from core.util.rowwise import row_norm

KINDS = ("tip step 1", "tip step 2", "staggered steps 5-6", "variable", "symmetric internal", "other cutting",
         "not cutting")
#: a cutting cutter below this share of the feed counts as slow, and below CRAWL_SHARE as crawling
SLOW_SHARE = 0.3
CRAWL_SHARE = 0.05


def stretch_kinds(table: MoveTable) -> np.ndarray:
    """(m,) index into KINDS of each of a cutter's moves (module docstring; -1: a wait)."""
    kind = np.full(len(table.kind), KINDS.index("other cutting"))
    tip = table.regions[np.minimum(table.poly.off, max(len(table.regions) - 1, 0))] == REGION_CODE["tip"]
    kind[np.isin(table.step, (5, 6))] = KINDS.index("staggered steps 5-6")
    kind[np.isin(table.kind, (SIGMOID, PLATEAU_LOGISTIC, PLATEAU_SEPTIC))] = KINDS.index("variable")
    kind[table.kind == MAPPED] = KINDS.index("symmetric internal")
    kind[table.step == 1] = KINDS.index("tip step 1")
    kind[(table.step == 2) & tip] = KINDS.index("tip step 2")
    kind[~table.cutting] = KINDS.index("not cutting")
    kind[table.kind == WAIT] = -1
    return kind


def optimal_move_times(limits: Limits, side: str, table: MoveTable) -> np.ndarray:
    """(m,) ms: each of a cutter's moves at its time-optimal traversal (core.machine.optimum) from its
    entry to its exit speed in the schedule, cutting at the feed and in the air at the rapid speed, all
    moves in one pass; waits and moves of no length take none."""
    out = np.zeros(len(table.kind))
    size, off = table.poly.size, table.poly.off
    moving = np.flatnonzero((table.kind != WAIT) & (size >= 2) & (table.poly.last - table.poly.first > 1e-9))
    if moving.size == 0:
        return out
    idx = np.concatenate([np.arange(o, o + n) for o, n in zip(off[moving], size[moving], strict=True)])
    k = knots(table.points[idx], table.axes[idx], table.poly.x[idx], size[moving])
    cruise = np.where(table.cutting[moving], limits.feed, RAPID_FACTOR * limits.feed)
    caps = path_caps(limits, side, k, np.repeat(cruise, k.size))
    v_in = table.speed(moving, np.zeros(len(moving)))
    v_out = table.speed(moving, table.dur[moving])
    out[moving] = run_times(caps, fastest(caps, v_in, v_out))
    return out


def synchronised(starts: dict, busy: dict) -> float:
    """ms: the job whose moves (starting at ``starts[side]`` ms in the schedule) take ``busy[side]`` ms
    each: between two synchronisation points (instants at which both cutters start a move) the longer
    of the two cutters' sums."""
    common = np.union1d(np.intersect1d(np.round(starts["left"], 6), np.round(starts["right"], 6)), [0.0])
    per = []
    for side in SIDES:
        seg = np.searchsorted(common, np.round(starts[side], 6), side="right") - 1
        per.append(np.bincount(seg, weights=busy[side], minlength=len(common)))
    return float(np.maximum(per[0], per[1]).sum())


def stretch_times(schedule: Schedule, warp: TimeWarp, optimal: dict | None = None) -> dict:
    """Per kind of stretch (KINDS, both cutters; the kinds present): the seconds its moves take on the
    machines and at the feed (in the schedule), and with ``optimal`` (per side, (m,) ms per move:
    ``optimal_move_times``) at the optimum, with the machines' time over it."""
    out = {}
    for k, name in enumerate(KINDS):
        on = feed = best = 0.0
        for side in SIDES:
            tab = schedule.table(side)
            sel = stretch_kinds(tab) == k
            t0, dur = tab.t0[sel], tab.dur[sel]
            on += float((np.interp(t0 + dur, warp.schedule_t, warp.t) - np.interp(t0, warp.schedule_t, warp.t)).sum())
            feed += float(dur.sum())
            best += float(optimal[side][sel].sum()) if optimal is not None else 0.0
        if feed <= 0:
            continue
        out[name] = {"machine_s": round(on / 1000.0, 3), "at_feed_s": round(feed / 1000.0, 3)}
        if optimal is not None:
            out[name].update({"optimal_s": round(best / 1000.0, 3),
                              "machine_over_optimal": round(on / best, 4) if best > 0 else None})
    return out


def optimum(schedule: Schedule, warp: TimeWarp, limits: Limits) -> dict:
    """The job against its time-optimal estimate (module docstring), in total and per kind of stretch."""
    opt = per_side(lambda side: optimal_move_times(limits, side, schedule.table(side)))
    total = synchronised({side: schedule.table(side).t0 for side in SIDES}, opt)
    job = float(warp.t[-1] - warp.t[0])
    return {"time_optimal_s": round(total / 1000.0, 3),
            "machines_over_optimal": round(job / total, 4) if total > 0 else None,
            "stretches": stretch_times(schedule, warp, opt)}


def cutting_speeds(tl: Timeline, feed: float) -> dict:
    """How fast each cutter cuts, from the rows (module docstring): per cutter and both together, the
    cutting time, the share of it below SLOW_SHARE of the feed (mm/ms), and the episodes below
    CRAWL_SHARE of it with their time."""
    dt = np.diff(tl.t)
    out = {}
    for side, smp in zip(SIDES, (tl.left, tl.right), strict=True):
        cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == smp.path[1:])
        speed = row_norm(np.diff(smp.tips, axis=0)) / np.where(dt > 0, dt, np.inf)
        crawl = cut & (speed < CRAWL_SHARE * feed)
        out[side] = {"cutting_time_s": float(dt[cut].sum()) / 1000.0,
                     "below_30pct_feed_s": float(dt[cut & (speed < SLOW_SHARE * feed)].sum()) / 1000.0,
                     "episodes_below_5pct_feed": int(np.count_nonzero(crawl[1:] & ~crawl[:-1]) + crawl[:1].sum()),
                     "below_5pct_feed_s": float(dt[crawl].sum()) / 1000.0}
    out["both"] = {key: out["left"][key] + out["right"][key] for key in out["left"]}
    for fig in out.values():
        total = fig["cutting_time_s"]
        fig["share_below_30pct_feed"] = round(fig["below_30pct_feed_s"] / total, 6) if total > 0 else 0.0
        for key in ("cutting_time_s", "below_30pct_feed_s", "below_5pct_feed_s"):
            fig[key] = round(fig[key], 3)
    return out


def job_figures(schedule: Schedule, tl: Timeline, warp: TimeWarp, limits: Limits | None = None) -> dict:
    """plan.json's "job": the time at the feed and on the machines, each step's cycle time on the
    machines and at the feed (core.schedule.step_times: an interval counts for the earlier of the two
    cutters' steps), how fast the cutters cut (``cutting_speeds``), each kind of stretch's time on the
    machines and at the feed (``stretch_times``), and with ``limits`` the job against its time-optimal
    estimate (``optimum``: the stretches with their optimal time too)."""
    at_feed, on_machines = schedule.duration / 1000.0, float(tl.t[-1] - tl.t[0]) / 1000.0
    out = {"time_at_feed_s": round(at_feed, 3), "time_on_machines_s": round(on_machines, 3),
           "machines_over_feed": round(on_machines / at_feed, 4) if at_feed > 0 else None,
           "step_time_s": step_times(tl.t, tl.left.step, tl.right.step),
           "step_time_at_feed_s": step_times(warp.schedule_t, tl.left.step, tl.right.step),
           "cutting": cutting_speeds(tl, schedule.feed / 60000.0),
           "stretches": stretch_times(schedule, warp)}
    if limits is not None:
        out.update(optimum(schedule, warp, limits))
    return out
