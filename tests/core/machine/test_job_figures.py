"""plan.json's "job" figures (core.machine.job_figures) and the command line's summary of them, against
independent computations from the CL tables the plan wrote (a loop over their rows), and the job's
time-optimal estimate against the job and against each move timed alone."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from core.machine.job_figures import (
    KINDS,
    optimal_move_times,
    optimum,
    stretch_kinds,
    stretch_times,
    synchronised,
)
from core.machine.optimum import Limits, traverse_time
from core.schedule.movetable import WAIT


@pytest.fixture(scope="module")
def written(coarse_plan):
    """The sample's coarse plan written by the command line (once per session): (its stdout, plan.json's
    schedule figures, the CL rows per side: t, step, path, cutting, tips)."""
    out, run = coarse_plan
    fig = json.loads((out / "plan.json").read_text())["schedule"]
    rows = {}
    for side in ("left", "right"):
        a = np.loadtxt(out / f"{side}_cl.csv", delimiter=",", skiprows=1, usecols=(0, 1, 3, 4, 5, 6, 7))
        rows[side] = {"t": a[:, 0], "step": a[:, 1].astype(int), "path": a[:, 2].astype(int),
                      "cutting": a[:, 3] > 0, "tips": a[:, 4:7]}
    return run.stdout, fig, rows


def _by_loop(r, feed_mm_ms, min_feed_mm_ms):
    """One cutter's cutting figures from its CL rows, one row interval at a time, and per path on which
    it cuts below the minimum feed: [first time s, seconds, slowest mm/min]."""
    total = slow = crawl = 0.0
    episodes, was = 0, False
    per_path: dict = {}
    t, tips = r["t"], r["tips"]
    for k in range(len(t) - 1):
        dt = t[k + 1] - t[k]
        cuts = bool(r["cutting"][k] and r["cutting"][k + 1] and r["path"][k] == r["path"][k + 1])
        v = float(np.linalg.norm(tips[k + 1] - tips[k])) / dt
        is_crawl = cuts and v < 0.05 * feed_mm_ms
        if cuts:
            total += dt
            crawl += dt if is_crawl else 0.0
            if v < min_feed_mm_ms:
                slow += dt
                got = per_path.setdefault(int(r["path"][k]), [t[k] / 1000.0, 0.0, np.inf])
                got[1] += dt / 1000.0
                got[2] = min(got[2], v * 60000.0)
        episodes += int(is_crawl and not was)
        was = is_crawl
    return total / 1000.0, slow / 1000.0, crawl / 1000.0, episodes, per_path


def test_cutting_speeds_from_the_written_rows(written):
    _, fig, rows = written
    job = fig["job"]
    feed = fig["feed_mm_min"] / 60000.0
    assert job["min_feed_mm_min"] == pytest.approx(0.3 * fig["feed_mm_min"])  # (the default)
    min_feed = job["min_feed_mm_min"] / 60000.0
    both = np.zeros(4)
    listed = {(item["side"], item["path"]): item for item in job["below_min_feed"]}
    for side in ("left", "right"):
        total, slow, crawl, episodes, per_path = _by_loop(rows[side], feed, min_feed)
        got = job["cutting"][side]
        # (the CL tables' positions carry 10 decimals: a row interval's speed to about 1e-8 mm/ms)
        assert got["cutting_time_s"] == pytest.approx(total, abs=2e-3)
        assert got["below_min_feed_s"] == pytest.approx(slow, abs=0.05)
        assert got["share_below_min_feed"] == pytest.approx(slow / total, abs=1e-4)
        assert sum(got["below_min_feed_by_reason_s"].values()) == pytest.approx(got["below_min_feed_s"], abs=0.01)
        assert got["below_5pct_feed_s"] == pytest.approx(crawl, abs=0.05)
        assert abs(got["episodes_below_5pct_feed"] - episodes) <= max(2, episodes // 100)
        # every path on which the cutter cuts below the minimum feed is listed, with its figures
        mine = {path: item for (s, path), item in listed.items() if s == side}
        big = {path for path, (_, seconds, _) in per_path.items() if seconds > 0.01}
        assert big <= set(mine) <= set(per_path)
        for path in big:
            first, seconds, lowest = per_path[path]
            item = mine[path]
            assert item["below_s"] == pytest.approx(seconds, abs=0.02)
            assert item["first_at_s"] == pytest.approx(first, abs=0.01)
            assert item["lowest_mm_min"] == pytest.approx(lowest, abs=0.2)
            assert item["reason"] == max(item["by_reason_s"], key=item["by_reason_s"].get)
        both += (total, slow, crawl, episodes)
    assert job["cutting"]["both"]["share_below_min_feed"] == pytest.approx(both[1] / both[0], abs=1e-4)
    assert job["cutting"]["both"]["episodes_below_5pct_feed"] == sum(
        job["cutting"][s]["episodes_below_5pct_feed"] for s in ("left", "right"))
    # the sample's tip paths slow down round their ends: the figures are not empty
    assert job["cutting"]["both"]["below_min_feed_s"] > 0
    seconds = [item["below_s"] for item in job["below_min_feed"]]
    assert seconds == sorted(seconds, reverse=True)


def test_times_and_steps_from_the_written_rows(written):
    _, fig, rows = written
    job = fig["job"]
    t = rows["left"]["t"]
    assert job["time_on_machines_s"] == pytest.approx(t[-1] / 1000.0, abs=1e-3)
    assert job["time_at_feed_s"] == fig["machine"]["time_at_feed_s"]
    assert job["machines_over_feed"] == pytest.approx(job["time_on_machines_s"] / job["time_at_feed_s"], abs=1e-4)
    per = {str(k): 0.0 for k in range(1, 8)}
    for k in range(len(t) - 1):  # an interval counts for the earlier of the two cutters' steps
        per[str(min(rows["left"]["step"][k], rows["right"]["step"][k]))] += (t[k + 1] - t[k]) / 1000.0
    for step, seconds in per.items():
        assert job["step_time_s"][step] == pytest.approx(seconds, abs=2e-3)
    assert sum(job["step_time_at_feed_s"].values()) == pytest.approx(job["time_at_feed_s"], abs=0.01)
    for step in per:  # the machine clock only slows the schedule down
        assert job["step_time_s"][step] >= job["step_time_at_feed_s"][step] - 1e-3


def test_stretch_times_from_the_written_rows(written):
    """Each kind's machine time against the row intervals in which a cutter is in a move of that kind's
    step and cutting state (up to a period at each end of each move), and the kinds with the waits
    adding up to both cutters' whole job."""
    _, fig, rows = written
    st = fig["job"]["stretches"]
    assert set(st) <= set(KINDS)
    t = rows["left"]["t"]
    period = t[1] - t[0]
    in_step1 = 0.0
    r = rows["left"]
    for k in range(len(t) - 1):
        if r["step"][k] == 1 and r["cutting"][k]:
            in_step1 += (t[k + 1] - t[k]) / 1000.0
    # (a move's ends fall between rows: at most a period each, and each end is a change of path or of
    # cutting in the rows)
    changes = int(np.count_nonzero(np.diff(r["path"]) != 0) + np.count_nonzero(np.diff(r["cutting"].astype(int))))
    assert st["tip step 1"]["machine_s"] == pytest.approx(in_step1, abs=(changes + 2) * period / 1000.0)
    assert st["tip step 1"]["machine_s"] >= st["tip step 1"]["at_feed_s"] - 1e-3


def test_the_summary_prints_the_written_figures(written):
    stdout, fig, _ = written
    job = fig["job"]
    m = re.search(r"schedule ([0-9.]+) min \(([0-9.]+) at the feed; ([0-9.]+) % of the cutting time below the "
                  r"minimum feed ([0-9.]+) mm/min\)", stdout)
    assert m, stdout
    assert float(m[1]) == pytest.approx(fig["total_time_s"] / 60, abs=0.051)
    assert float(m[2]) == pytest.approx(job["time_at_feed_s"] / 60, abs=0.051)
    assert float(m[3]) == pytest.approx(100 * job["cutting"]["both"]["share_below_min_feed"], abs=0.051)
    assert float(m[4]) == pytest.approx(job["min_feed_mm_min"], abs=1e-6)
    # the reasons line: each reason's minutes, and the path where it lasts longest
    why = re.search(r"below the minimum feed: (.*); longest on the (left|right) cutter's path (\d+) \(step (\d)", stdout)
    assert why, stdout
    for name, minutes in re.findall(r"([a-z ]+?) ([0-9.]+) min", why[1]):
        seconds = job["cutting"]["both"]["below_min_feed_by_reason_s"][name.strip()]
        assert float(minutes) == pytest.approx(seconds / 60, abs=0.051)
    worst = job["below_min_feed"][0]
    assert (why[2], int(why[3]), int(why[4])) == (worst["side"], worst["path"], worst["step"])


def test_synchronised_takes_the_longer_cutter_between_common_starts():
    """Moves starting together at 0 and 10: the left's 3 + 4 and the right's 5 between them, then 2 and
    1 + 1: 7 + 2."""
    starts = {"left": np.array([0.0, 3.0, 10.0]), "right": np.array([0.0, 10.0, 11.0])}
    busy = {"left": np.array([3.0, 4.0, 2.0]), "right": np.array([5.0, 1.0, 1.0])}
    assert synchronised(starts, busy) == pytest.approx(9.0)


@pytest.fixture(scope="module")
def coarse(coarse_result):
    return coarse_result  # (the sample's coarse plan in memory, once per session)


def test_the_optimum_is_each_move_alone_and_below_the_job(coarse):
    p = coarse.plan.params
    limits = Limits(coarse.machine, coarse.period, 0.001, p.tool_radius, p.feed / 60000.0, p.a_max / 1e6)
    tab = coarse.schedule.table("left")
    opt = optimal_move_times(limits, "left", tab)
    assert (opt[tab.kind == WAIT] == 0).all()
    kinds = stretch_kinds(tab)
    for name in ("tip step 1", "symmetric internal", "staggered steps 5-6"):
        j = int(np.flatnonzero(kinds == KINDS.index(name))[0])
        m = tab.moves[j]
        v0, v1 = (float(x) for x in m.law.speed(np.array([0.0, m.law.duration])))
        assert opt[j] == pytest.approx(traverse_time(limits, "left", m.points, m.axes, v0, v1), rel=1e-9), name
    fig = optimum(coarse.schedule, coarse.warp, limits)
    assert fig["machines_over_optimal"] >= 1.0
    for name, k in fig["stretches"].items():
        if name != "variable":  # (a speed stage lasts as long as the other cutter's route: slower by design)
            assert k["machine_over_optimal"] >= 0.99, name


def test_the_kinds_and_the_waits_make_up_each_cutters_job(coarse):
    """Every move is of one kind or a wait: the kinds' times with the waits' add up to both cutters'
    time in the schedule and on the machines (each up to its last move's end)."""
    sch, warp = coarse.schedule, coarse.warp
    st = stretch_times(sch, warp)
    at_feed = sum(k["at_feed_s"] for k in st.values())
    machine = sum(k["machine_s"] for k in st.values())
    for side in ("left", "right"):
        tab = sch.table(side)
        waits = tab.kind == WAIT
        end = float((tab.t0 + tab.dur).max())
        at_feed += float(tab.dur[waits].sum()) / 1000.0 - end / 1000.0
        t_end = float(np.interp(end, warp.schedule_t, warp.t))
        on_waits = sum(float(np.interp(t0 + d, warp.schedule_t, warp.t) - np.interp(t0, warp.schedule_t, warp.t))
                       for t0, d in zip(tab.t0[waits], tab.dur[waits], strict=True))
        machine += on_waits / 1000.0 - t_end / 1000.0
    assert at_feed == pytest.approx(0.0, abs=0.01)
    assert machine == pytest.approx(0.0, abs=0.01)
    tab = sch.table("left")
    kinds = stretch_kinds(tab)
    tip1 = kinds == KINDS.index("tip step 1")
    assert tip1.any() and (tab.step[tip1] == 1).all() and tab.cutting[tip1].all()
    sym = kinds == KINDS.index("symmetric internal")
    assert sym.any() and tab.cutting[sym].all()
