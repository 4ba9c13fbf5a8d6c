"""Benchmark: the job the machines run on the sample at the defaults, against the time-optimal job
under the same limits (core.machine.job_figures.optimum), in total and per kind of stretch; the job
against its time at the feed (the same schedule built without the machines' limits); how fast the
cutters cut (share of cutting time below 30 % of the feed, episodes below 5 %); and the plan's wall
time, each beside calib.py's time in the same run.

Run: .venv/bin/python tests/benchmarks/bench_job.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from core.machine.caps import machine_limits  # noqa: E402
from core.machine.job_figures import cutting_speeds, optimum  # noqa: E402
from core.planner import Planner  # noqa: E402
from core.records import PlanJob  # noqa: E402
from core.schedule.steps import build_schedule  # noqa: E402
from tests.benchmarks.common import calib  # noqa: E402


def main() -> None:
    ref = calib()
    job = PlanJob(axes=False)
    t0 = time.perf_counter()
    res = Planner(workers=2).plan(job)
    wall = time.perf_counter() - t0
    p = res.plan.params
    limits = machine_limits(res.machine, res.period, job.resolved_chord_tol(), p.tool_radius, p.feed / 60000.0,
                            p.a_max / 1e6)
    at_feed = build_schedule(res.plan, p.mode, p.feed,
                             p.a_max, job.profile, res.period, max_rounds=1).duration
    opt = optimum(res.schedule, res.warp, limits)
    speeds = cutting_speeds(res.timeline, p.feed / 60000.0, 0.3 * p.feed / 60000.0)
    job_s = float(res.timeline.t[-1]) / 1000.0
    print(f"calib.py: {ref:.3f} s")
    print(f"plan (sample, defaults, no tables written): {wall:.1f} s wall = {wall / ref:.1f}x calib")
    print(f"job on the machines      {job_s / 60:8.1f} min")
    ratio = opt["job_over_optimal"]
    print(f"time-optimal job         {opt['time_optimal_s'] / 60:8.1f} min  (job / optimum {ratio:.3f})")
    print(f"time at the feed         {at_feed / 60000:8.1f} min  (job / feed time {job_s * 1000 / at_feed:.3f})")
    for name, k in opt["per_kind"].items():
        print(f"  {name:14s} machine {k['machine_s'] / 60:7.1f} min  optimal {k['optimal_s'] / 60:7.1f} min  "
              f"ratio {k['ratio']:.3f}")
    print(f"cutting time below 30 % of the feed: {100 * speeds['share_below_30pct_feed']:.1f} % of "
          f"{speeds['cutting_time_s'] / 60:.1f} min; episodes below 5 %: {speeds['episodes_below_5pct_feed']} "
          f"({speeds['time_below_5pct_feed_s']:.1f} s)")


if __name__ == "__main__":
    main()
