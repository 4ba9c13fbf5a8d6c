"""The figures plan.json reports about the job the machines run (its "job" section): the time at the
feed and on the machines, each step's cycle time both ways, how fast the cutters cut (from the rows:
the share of each cutter's cutting time below the minimum cutting feed and why, the paths where it
happens, the episodes in which a cutting cutter runs below 5 % of the feed), and the job against its
time-optimal estimate, in total and per kind of stretch.

- **Time at the feed**: the schedule's own duration (the feed, a_max and the paper's speed stages,
  before the machine clock slows it for the axes and the chord tolerance).
- **Cutting speed**: per row interval, the chord between its two rows over the period (what the
  written CL tables give); an interval cuts when both its rows cut the same path. An episode is a run
  of consecutive crawling intervals of one cutter.
- **Why below the minimum feed** (SLOW_REASONS, per row interval): the schedule itself is that slow
  there (its speed at both rows below the minimum: the paper's speed stage in a variable region, or a
  start from or stop to rest), or the machine clock slows it: the other machine, where this one's
  own caps alone (TimeWarp.own_scale) would let it cut at the minimum feed (the clock is shared, so
  that every synchronisation and spacing of the schedule holds), else this machine's own chord
  tolerance or axes (TimeWarp.slowed_for).
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

from typing import Any

import numpy as np

from core.machine.optimum import Limits, knots, limits_of, profile, segment
from core.machine.tables import SLOWED_FOR, TimeWarp
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
#: a cutting cutter below this share of the feed counts as crawling (below the minimum feed: slow)
CRAWL_SHARE = 0.05
#: why a cutter cuts below the minimum feed: the schedule's own speed (the method's speed stage in a
#: variable region; a start from or a stop to rest), or the machine clock (this machine's axes or chord
#: tolerance; the other machine's limits, which the shared clock imposes on both)
SLOW_REASONS = ("speed stage", "start or stop", "axes", "chord", "other machine")


def minutes_by_reason(job: dict) -> str:
    """The minutes both cutters cut below the minimum feed per reason (plan.json's schedule.job), longest
    first, e.g. "axes 10.2 min, other machine 3.8 min"; '' when they never do."""
    by = job["cutting"]["both"]["below_min_feed_by_reason_s"]
    return ", ".join(f"{name} {seconds / 60:.1f} min" for name, seconds in
                     sorted(by.items(), key=lambda item: -item[1]) if seconds > 0)


def slow_feed_line(job: dict) -> str:
    """One line on why the cutters cut below the minimum feed (plan.json's schedule.job): the seconds
    per reason, longest first, and the path where it lasts longest; '' when they never do."""
    if not job["below_min_feed"]:
        return ""
    reasons = minutes_by_reason(job)
    worst = job["below_min_feed"][0]
    return (f"below the minimum feed: {reasons}; longest on the {worst['side']} cutter's path {worst['path']} "
            f"(step {worst['step']}, from t = {worst['first_at_s']:.1f} s: {worst['below_s']:.1f} s, "
            f"{worst['reason']}); every path in plan.json schedule.job.below_min_feed")


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
    v_in = table.speed(moving, np.zeros(len(moving)))
    v_out = table.speed(moving, table.dur[moving])
    seg = segment(limits.machine, side, k)
    out[moving] = profile(seg, limits_of(limits, np.repeat(cruise, k.size)), v_in, v_out).run_times()
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


def _slow_reasons(schedule: Schedule, warp: TimeWarp, side: str, slow: np.ndarray, min_feed: float) -> np.ndarray:
    """(n - 1,) int8 per row interval, index into SLOW_REASONS of why a cutter cuts below ``min_feed``
    (mm/ms) there (-1 where ``slow`` is False): the schedule's own speed (a speed stage, or a start or
    stop), else the clock: the other machine where this one's own limits would allow the minimum feed
    (TimeWarp.own_scale), else this one's axes or chord tolerance (TimeWarp.slowed_for)."""
    k = np.flatnonzero(slow)  # (only the intervals below the minimum feed are explained)
    tab = schedule.table(side)
    v0, v1 = tab.speeds(warp.schedule_t[k]), tab.speeds(warp.schedule_t[k + 1])
    stage = np.isin(tab.kind[tab.owner(warp.schedule_t[k])], (SIGMOID, PLATEAU_LOGISTIC, PLATEAU_SEPTIC))
    why = np.where(stage, SLOW_REASONS.index("speed stage"), SLOW_REASONS.index("start or stop"))
    clocked = np.maximum(v0, v1) >= min_feed
    own = warp.own_scale[side] if warp.own_scale is not None else warp.scale
    alone = np.maximum(own[k] * v0, own[k + 1] * v1) >= min_feed
    chord = (warp.slowed_for[k] == SLOWED_FOR.index("chord") if warp.slowed_for is not None
             else np.zeros(len(k), bool))
    mine = np.where(chord, SLOW_REASONS.index("chord"), SLOW_REASONS.index("axes"))
    out = np.full(len(slow), -1, np.int8)
    out[k] = np.where(clocked, np.where(alone, SLOW_REASONS.index("other machine"), mine), why)
    return out


def cutting_speeds(tl: Timeline, schedule: Schedule, warp: TimeWarp, min_feed: float) -> tuple[dict, list]:
    """How fast each cutter cuts, from the rows (module docstring): per cutter and both together, the
    cutting time, the share of it below ``min_feed`` (mm/ms) with its seconds by reason
    (SLOW_REASONS), and the episodes below CRAWL_SHARE of the feed with their time; and the paths on
    which a cutter cuts below the minimum feed, longest first (``slow_paths``)."""
    dt = np.diff(tl.t)
    feed = schedule.feed / 60000.0
    out: dict[str, dict[str, Any]] = {}
    paths: list[dict] = []
    for side, smp in zip(SIDES, (tl.left, tl.right), strict=True):
        cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == smp.path[1:])
        speed = row_norm(np.diff(smp.tips, axis=0)) / np.where(dt > 0, dt, np.inf)
        slow = cut & (speed < min_feed)
        crawl = cut & (speed < CRAWL_SHARE * feed)
        why = _slow_reasons(schedule, warp, side, slow, min_feed)
        by = np.bincount(why[slow], weights=dt[slow], minlength=len(SLOW_REASONS)) / 1000.0
        out[side] = {"cutting_time_s": float(dt[cut].sum()) / 1000.0,
                     "below_min_feed_s": float(dt[slow].sum()) / 1000.0,
                     "below_min_feed_by_reason_s": dict(zip(SLOW_REASONS, by.tolist(), strict=True)),
                     "episodes_below_5pct_feed": int(np.count_nonzero(crawl[1:] & ~crawl[:-1]) + crawl[:1].sum()),
                     "below_5pct_feed_s": float(dt[crawl].sum()) / 1000.0}
        paths += slow_paths(side, tl.t, smp, speed, why)
    out["both"] = {key: out["left"][key] + out["right"][key] for key in out["left"]
                   if key != "below_min_feed_by_reason_s"}
    out["both"]["below_min_feed_by_reason_s"] = {
        name: out["left"]["below_min_feed_by_reason_s"][name] + out["right"]["below_min_feed_by_reason_s"][name]
        for name in SLOW_REASONS}
    for fig in out.values():
        total = fig["cutting_time_s"]
        fig["share_below_min_feed"] = round(fig["below_min_feed_s"] / total, 6) if total > 0 else 0.0
        for key in ("cutting_time_s", "below_min_feed_s", "below_5pct_feed_s"):
            fig[key] = round(fig[key], 3)
        fig["below_min_feed_by_reason_s"] = {k: round(v, 3) for k, v in fig["below_min_feed_by_reason_s"].items()}
    paths.sort(key=lambda item: -item["below_s"])
    return out, paths


def slow_paths(side: str, t: np.ndarray, smp, speed: np.ndarray, why: np.ndarray) -> list[dict]:
    """Per path on which one cutter cuts below the minimum feed (``why`` >= 0 on those row intervals,
    index into SLOW_REASONS): its step, when it first does (s), for how long in all (s), its slowest
    speed (mm/min), the reason that holds longest, and the seconds by reason."""
    k = np.flatnonzero(why >= 0)
    if k.size == 0:
        return []
    dt = np.diff(t)[k]
    path = smp.path[k]
    ids, first, inverse = np.unique(path, return_index=True, return_inverse=True)
    per = np.zeros((len(ids), len(SLOW_REASONS)))
    np.add.at(per, (inverse, why[k]), dt)
    lowest = np.full(len(ids), np.inf)
    np.minimum.at(lowest, inverse, speed[k])
    out = []
    for i, pid in enumerate(ids.tolist()):
        row = per[i] / 1000.0
        out.append({"side": side, "path": int(pid), "step": int(smp.step[k[first[i]]]),
                    "first_at_s": round(float(t[k[first[i]]]) / 1000.0, 3),
                    "below_s": round(float(row.sum()), 3), "lowest_mm_min": round(float(lowest[i]) * 60000.0, 1),
                    "reason": SLOW_REASONS[int(np.argmax(row))],
                    "by_reason_s": {name: round(float(x), 3) for name, x in zip(SLOW_REASONS, row, strict=True)
                                    if x > 0}})
    return out


def job_figures(schedule: Schedule, tl: Timeline, warp: TimeWarp, min_feed: float,
                limits: Limits | None = None) -> dict:
    """plan.json's "job": the time at the feed and on the machines, each step's cycle time on the
    machines and at the feed (core.schedule.step_times: an interval counts for the earlier of the two
    cutters' steps), how fast the cutters cut (``cutting_speeds``), each kind of stretch's time on the
    machines and at the feed (``stretch_times``), and with ``limits`` the job against its time-optimal
    estimate (``optimum``: the stretches with their optimal time too)."""
    at_feed, on_machines = schedule.duration / 1000.0, float(tl.t[-1] - tl.t[0]) / 1000.0
    cutting, slow = cutting_speeds(tl, schedule, warp, min_feed / 60000.0)
    out = {"time_at_feed_s": round(at_feed, 3), "time_on_machines_s": round(on_machines, 3),
           "machines_over_feed": round(on_machines / at_feed, 4) if at_feed > 0 else None,
           "step_time_s": step_times(tl.t, tl.left.step, tl.right.step),
           "step_time_at_feed_s": step_times(warp.schedule_t, tl.left.step, tl.right.step),
           "min_feed_mm_min": round(min_feed, 3), "cutting": cutting, "below_min_feed": slow,
           "stretches": stretch_times(schedule, warp)}
    if limits is not None:
        out.update(optimum(schedule, warp, limits))
    return out
